//! The sweep engine against the reference engine (`CpuEngine`, the
//! original gather loop, kept for the tests), and the sweep engine on two
//! threads against one, on the same scene in one process, interleaved, so
//! that the machine's noise cancels in their ratio.
//! `cargo bench --bench cpu_engines [-- FILTER]`; prints a Markdown table
//! (recorded in BENCHMARKS.md, "CPU engine: sweep").
//!
//! SLIPFRONT_BENCH_SECONDS (default 2) sets the time per measurement.

use slipfront::engines::cpu::{CpuEngine, SweepEngine};
use slipfront::model::real::{Coordinate, DoubleSingle, Real};
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Engine, Model};
use std::time::Instant;

/// The Table S1 scene as the default job runs it, or (`driven`) with a
/// short normal-load phase and driven hard so that junctions keep
/// rupturing; `nx` × `nz` blocks at the same spacing.
fn scene(nx: u32, nz: u32, driven: bool) -> Model {
    let l = 0.14 / 56.0;
    let mut set = vec![
        format!("geometry.nx={nx}"),
        format!("geometry.nz={nz}"),
        format!("geometry.length={}", l * (nx - 1) as f64),
        format!("geometry.height={}", l * (nz - 1) as f64),
    ];
    if driven {
        set.extend([
            "loading.normal.ramp_time=2e-5".into(),
            "loading.normal.relax_time=2e-5".into(),
            "loading.drive.velocity=1.0".into(),
        ]);
    }
    let s = Scenario::parse(DEFAULT_SCENARIO, "bench", &set).expect("bench scene");
    Model::from_scenario(&s, false).expect("bench model")
}

/// Steps per second of `engine` over about `seconds`, after warming up
/// past the normal-load phase on the first call.
fn rate(engine: &mut dyn Engine, steps: u64) -> f64 {
    let start = engine.steps_done();
    let t0 = Instant::now();
    advance_to(engine, start + steps).expect("bench run");
    steps as f64 / t0.elapsed().as_secs_f64()
}

/// Median block-steps/s of engines `a` and `b` on `m`, measured in
/// alternation three times after both have stepped into driving.
fn compare(m: &Model, mut a: Box<dyn Engine>, mut b: Box<dyn Engine>, seconds: f64) -> (f64, f64) {
    advance_to(a.as_mut(), m.prep_steps + 1000).expect("warm-up");
    advance_to(b.as_mut(), m.prep_steps + 1000).expect("warm-up");
    // Size a round to ~seconds/6 of the slower engine, a.
    let probe = rate(a.as_mut(), 8);
    let steps = ((probe * seconds / 6.0) as u64).max(4);
    let (mut ra, mut rb) = (Vec::new(), Vec::new());
    for _ in 0..3 {
        ra.push(rate(a.as_mut(), steps));
        rb.push(rate(b.as_mut(), steps));
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2] * m.n_blocks() as f64
    };
    (median(&mut ra), median(&mut rb))
}

fn reference<T: Real, C: Coordinate<T>>(m: &Model) -> Box<dyn Engine> {
    Box::new(CpuEngine::<T, C>::new(m, 1).expect("reference"))
}

fn sweep<T: Real, C: Coordinate<T>>(m: &Model, threads: usize) -> Box<dyn Engine> {
    Box::new(SweepEngine::<T, C>::new(m, threads).expect("sweep"))
}

/// The reference and the sweep engine, or (`threads_vs_one`) the sweep
/// engine on two threads against itself on one.
fn pair<T: Real, C: Coordinate<T>>(m: &Model, threads_vs_one: bool, s: f64) -> (f64, f64) {
    if threads_vs_one {
        compare(m, sweep::<T, C>(m, 1), sweep::<T, C>(m, 2), s)
    } else {
        compare(m, reference::<T, C>(m), sweep::<T, C>(m, 1), s)
    }
}

fn main() {
    let filter: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let seconds: f64 = std::env::var("SLIPFRONT_BENCH_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2.0);
    println!("| lattice | phase | precision | engine a | engine b | a block-steps/s | b block-steps/s | b / a |");
    println!("| --- | --- | --- | --- | --- | ---: | ---: | ---: |");
    let mut scenes = vec![(57u32, 31u32, false), (57, 31, true), (1024, 256, true)];
    if std::env::var("SLIPFRONT_BENCH_SCALING").is_ok() {
        scenes.extend([(256, 128, true), (1024, 256, false)]);
    }
    for (nx, nz, driven) in scenes {
        let phase = if driven { "driven" } else { "stick" };
        let m = scene(nx, nz, driven);
        for precision in ["f64", "f32"] {
            for threads_vs_one in [false, true] {
                let (a_name, b_name) = if threads_vs_one {
                    ("sweep, 1 thread", "sweep, 2 threads")
                } else {
                    ("reference, 1 thread", "sweep, 1 thread")
                };
                let name = format!("{nx}x{nz} {phase} {precision} {b_name}");
                if !filter.iter().all(|f| name.contains(f.as_str())) {
                    continue;
                }
                let (a, b) = match precision {
                    "f64" => pair::<f64, f64>(&m, threads_vs_one, seconds),
                    _ => pair::<f32, DoubleSingle>(&m, threads_vs_one, seconds),
                };
                println!(
                    "| {nx}×{nz} | {phase} | {precision} | {a_name} | {b_name} | {a:.3e} | {b:.3e} | {:.2} |",
                    b / a
                );
            }
        }
    }
}
