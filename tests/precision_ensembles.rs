//! Is mixed f32 a sample from f64's outcome distribution? The statistical
//! precision test, sized for a 2-core CI machine (158 s alone, 2026-12-03;
//! the f32 ensemble is the slowest): five
//! perturbation ensembles of 24 runs of `scenarios/small_stick_slip.toml`
//! (0.3 s of stick-slip, about 20 events each), drive speed × (1 + k·1e-6),
//! the slider starting 1 cm along the track (`start.position`): where a
//! long run's slider is after its first hundred events. The track is
//! uniform, so in f64 that changes nothing (measured: smallest p 1.0 against
//! the slider at 0); in f32 it is where one ulp of a displacement (0.9 nm)
//! matters.
//!
//! - f64 against f64 under another perturbation (disjoint members) must
//!   pass: the yardstick of what chaos alone does;
//! - mixed f32 against f64 on the same members must pass;
//! - plain f32 (f32 displacements) against f64 on the same members must be
//!   flagged: the negative control (measured: its first full event
//!   0.009 ms late in all 24 runs, F/F_N below f64's, p 6e-14);
//! - f64 with μd 15 % higher (a shift of about one standard deviation of
//!   the event count and mean slip) must be flagged on the whole-run
//!   outcomes, so the test can see a physical bias of that size with 24
//!   runs a side.
//!
//! What is compared depends on the members:
//! - disjoint members: only the whole-run outcomes chaos has mixed (event
//!   and full-event counts, mean slip, precursors; `mixed_p_values`). In
//!   this small scene the first event comes before the chaos has grown and
//!   still moves with k, so two disjoint ensembles differ there by
//!   construction (measured: F/F_N at the first event p = 2e-5 between two
//!   f64 ensembles);
//! - the same members: every outcome, the first event too (a smooth
//!   function of k must be the same function in both).
//!
//! The verdict is the smallest p times the number of tests (Bonferroni)
//! against 0.01.

use slipfront::app::sweeps::compare::{compare_tables, Comparison};
use slipfront::app::sweeps::verdict::Members;
use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

const RUNS: usize = 24;
const ALPHA: f64 = 0.01;

fn ensemble(dir: &Path, name: &str, start: usize, precision: &str, set: &str) -> PathBuf {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/small_stick_slip.toml");
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(
        &file,
        format!(
            "base = \"{}\"\n\
             perturb = {{ key = \"loading.drive.velocity\", relative = 1e-6, count = {RUNS}, \
             start = {start} }}\n\
             [set]\n\"output.bulk_interval\" = 0.0\n\"start.position\" = 0.01\n{set}",
            scene.display()
        ),
    )
    .unwrap();
    let out = dir.join(name);
    let o = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(["sweep"])
        .arg(&file)
        .arg("-o")
        .arg(&out)
        .args([
            "--backend",
            "cpu",
            "--precision",
            precision,
            "--mcap",
            "none",
            "--quiet",
        ])
        .output()
        .expect("runs");
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

/// (Bonferroni-corrected smallest p, a report).
fn verdict(c: &Comparison, members: Members) -> (f64, String) {
    let tests = c.weighed_p_values(members).len();
    assert!(tests >= 5, "too few outcomes to compare: {tests}");
    let v = c.verdict(members).expect("tests ran");
    let report = format!(
        "{} vs {}: corrected p {:.3e} ({})",
        c.label_a,
        c.label_b,
        v.corrected,
        v.describe()
    );
    (v.corrected, report)
}

#[test]
fn mixed_f32_gives_the_f64_outcome_distribution_and_plain_f32_and_a_bias_are_seen() {
    let dir = Scratch::new("precision", "run");
    let f64_a = ensemble(&dir, "f64_a", 0, "f64", "");
    let f64_b = ensemble(&dir, "f64_b", RUNS, "f64", "");
    let f32_a = ensemble(&dir, "f32_a", 0, "f32", "");
    let plain_a = ensemble(&dir, "plain_a", 0, "f32-plain", "");
    let biased = ensemble(
        &dir,
        "f64_biased",
        0,
        "f64",
        "\"friction.dynamic_coefficient\" = 0.1955\n",
    );
    let compare =
        |a: &PathBuf, b: &PathBuf, members| verdict(&compare_tables(a, b).unwrap(), members);
    let (yardstick, r1) = compare(&f64_a, &f64_b, Members::Disjoint);
    let (mixed, r2) = compare(&f64_a, &f32_a, Members::Same);
    let (plain, r3) = compare(&f64_a, &plain_a, Members::Same);
    let (bias, r4) = compare(&f64_a, &biased, Members::Disjoint);
    println!("{r1}\n{r2}\n{r3}\n{r4}");
    assert!(yardstick >= ALPHA, "f64 differs from itself: {r1}");
    assert!(mixed >= ALPHA, "mixed f32 differs from f64: {r2}");
    assert!(plain < ALPHA, "plain f32 was not flagged: {r3}");
    assert!(bias < ALPHA, "the biased control was not flagged: {r4}");
    let _ = std::fs::remove_dir_all(&dir);
}
