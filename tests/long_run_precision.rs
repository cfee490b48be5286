//! Long-run accuracy of f32, the CI-sized version of
//! `benches/long_run_precision.rs`: the precursors scene driven 5× faster
//! (V = 2 mm/s) for 0.065 s (≈ 2.9e5 steps), long enough for three growing
//! precursors. CPU f32 mixed must reproduce f64's precursors (count,
//! lengths, start time and F/F_N within 0.1%), as f64 does under a 1e-6
//! change of the drive speed. Plain f32 displacements (the engines before
//! mixed precision) are the negative control: measured, their third
//! rupture grows across the whole interface (a full event at 0.0630 s
//! instead of a 52.5 mm precursor; with the junction sums in the order
//! before the GPU v2 lanes it was a 55 mm precursor 4.6% late), so the
//! comparison must flag them.
//!
//! The GPU engine's run of this scene is in the bench
//! (`cargo bench --bench long_run_precision -- --gpu`), not here: lavapipe
//! took 8 to 15 minutes of CI's 90 for its 2.9e5 steps,
//! while CI's GPU tests hold every kernel to the CPU's rupture counts and
//! times on shorter windows (tests/gpu_engine.rs).

use slipfront::app::runner::{run_scene, RunOptions};
use slipfront::engines::backend::{make_engine, Backend, Precision};
use slipfront::io::compare::{outcome_mismatch, RunOutcome};
use slipfront::io::output::reader::RunFile;
use slipfront::model::scenario::Scenario;
use slipfront::Model;

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/tromborg2014_precursors.toml"
);
const V: f64 = 2.0e-3;

/// The scene run on the CPU engine in `precision`.
fn outcome(label: &str, precision: Precision, velocity: f64) -> RunOutcome {
    let set = vec![
        format!("loading.drive.velocity={velocity}"),
        "time.end=0.065".to_string(),
    ];
    let s = Scenario::load(std::path::Path::new(SCENE), &set).unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    let mut e =
        make_engine(&m, Backend::Cpu, precision, 1).unwrap_or_else(|e| panic!("{label}: {e}"));
    let dir = Scratch::new("long-run", &label.replace(' ', "_"));
    let path = dir.join("run.mcap");
    let opts = RunOptions {
        fast_forward: None,
        output: Some(path.clone()),
        ..RunOptions::default()
    };
    run_scene(e.as_mut(), &s, &opts).unwrap();
    let run = RunFile::read(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    RunOutcome::from_run(&run, 1e-3)
}

#[test]
fn f32_mixed_keeps_the_precursors_of_f64_and_plain_f32_does_not() {
    let cases = [
        ("f64", Precision::F64, V),
        ("f64 perturbed", Precision::F64, V * (1.0 + 1e-6)),
        ("f32 mixed", Precision::F32, V),
        ("f32 plain", Precision::F32Plain, V),
    ];
    let outcomes: Vec<RunOutcome> = std::thread::scope(|sc| {
        let runs: Vec<_> = cases
            .iter()
            .map(|&(l, p, v)| sc.spawn(move || outcome(l, p, v)))
            .collect();
        runs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let reference = &outcomes[0];
    for ((label, ..), o) in cases.iter().zip(&outcomes) {
        println!("{label:>14}: {}", o.describe());
    }
    // The scene must contain what is compared: three precursors longer
    // than one block and no full event yet.
    let extended = reference.precursors.iter().filter(|p| p.0 > 5e-3).count();
    assert!(extended >= 3, "{}", reference.describe());
    for k in [1, 2] {
        assert_eq!(
            outcome_mismatch(reference, &outcomes[k], 1e-3),
            Vec::<String>::new(),
            "{}",
            cases[k].0
        );
    }
    assert!(
        !outcome_mismatch(reference, &outcomes[3], 1e-3).is_empty(),
        "plain f32 must depart from f64: {}",
        outcomes[3].describe()
    );
}
