//! The precision study's instrument (`SLIPFRONT_F32_PROBE`, an f64 engine
//! with quantities held in f32): both CPU engines hold the same values (the
//! same bits), a probed run differs from a plain one, the run file says the
//! probe was on, and a misspelt quantity is refused.

use slipfront::io::output::reader::RunFile;
use std::path::Path;
use std::process::Command;

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

fn run(dir: &Path, name: &str, backend: &str, probe: Option<&str>) -> RunFile {
    let out = dir.join(format!("{name}.mcap"));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_slipfront"));
    cmd.current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["run", "scenarios/triggered_front.toml", "--t-end", "1e-4"])
        .args(["--backend", backend, "--precision", "f64", "--threads", "1"])
        .args(["--quiet", "--progress", "none", "-o"])
        .arg(&out)
        .env_remove("SLIPFRONT_F32_PROBE");
    if let Some(p) = probe {
        cmd.env("SLIPFRONT_F32_PROBE", p);
    }
    let o = cmd.output().expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    RunFile::read(&out).expect("reads")
}

fn series(r: &RunFile) -> Vec<(u64, u64, u64)> {
    r.global
        .iter()
        .map(|g| (g.step, g.kinetic_energy.to_bits(), g.ruptures))
        .collect()
}

#[test]
fn both_engines_hold_the_same_values_and_the_probe_changes_the_run() {
    let dir = Scratch::new("probe", "run");
    let probe = "forces,velocities,coordinates,junctions,draws";
    let sweep = run(&dir, "sweep", "cpu", Some(probe));
    let reference = run(&dir, "reference", "cpu-reference", Some(probe));
    let plain = run(&dir, "plain", "cpu", None);
    assert!(!series(&sweep).is_empty());
    assert_eq!(
        series(&sweep),
        series(&reference),
        "engines differ under the probe"
    );
    // The control: the probe is not a no-op (kinetic energy differs in its
    // low bits at least).
    assert_ne!(series(&sweep), series(&plain), "the probe changed nothing");
    let backend = |r: &RunFile| r.metadata.get("backend").cloned().unwrap_or_default();
    assert!(
        backend(&sweep).contains("SLIPFRONT_F32_PROBE=forces,velocities"),
        "{}",
        backend(&sweep)
    );
    assert!(!backend(&plain).contains("PROBE"), "{}", backend(&plain));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_unknown_quantity_is_refused() {
    let o = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["run", "scenarios/triggered_front.toml", "--t-end", "1e-5"])
        .args(["--backend", "cpu", "--quiet"])
        .env("SLIPFRONT_F32_PROBE", "forces,speeds")
        .output()
        .expect("runs");
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("unknown quantity `speeds`"), "{err}");
}
