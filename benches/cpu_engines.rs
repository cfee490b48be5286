//! The sweep engine against the reference engine (`CpuEngine`, today's
//! gather loop, kept for the tests) on the same scene in one process,
//! interleaved, so that the machine's noise cancels in their ratio.
//! `cargo bench --bench cpu_engines [-- FILTER]`; prints a Markdown table
//! (recorded in BENCHMARKS.md, "CPU engine: sweep").
//!
//! SLIPFRONT_BENCH_SECONDS (default 2) sets the time per measurement.

use slipfront::cpu::{CpuEngine, SweepEngine};
use slipfront::real::{Coordinate, DoubleSingle, Real};
use slipfront::scenario::{Scenario, DEFAULT_SCENARIO};
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

/// Median block-steps/s of the reference and the sweep engine (with
/// `threads`), measured in alternation `rounds` times.
fn compare<T: Real, C: Coordinate<T>>(m: &Model, threads: usize, seconds: f64) -> (f64, f64) {
    let mut reference = CpuEngine::<T, C>::new(m, 1).expect("reference");
    let mut sweep = SweepEngine::<T, C>::new(m, threads).expect("sweep");
    // Past the normal-load phase, into driving.
    advance_to(&mut reference, m.prep_steps + 1000).expect("warm-up");
    advance_to(&mut sweep, m.prep_steps + 1000).expect("warm-up");
    // Size a round to ~seconds/6 of the reference.
    let probe = rate(&mut reference, 8);
    let steps = ((probe * seconds / 6.0) as u64).max(4);
    let rounds = 3;
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..rounds {
        a.push(rate(&mut reference, steps));
        b.push(rate(&mut sweep, steps));
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2] * m.n_blocks() as f64
    };
    (median(&mut a), median(&mut b))
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
    println!(
        "| lattice | phase | precision | sweep threads | reference block-steps/s | \
         sweep block-steps/s | sweep / reference |"
    );
    println!("| --- | --- | --- | ---: | ---: | ---: | ---: |");
    for (nx, nz, driven) in [(57u32, 31u32, false), (57, 31, true), (1024, 256, true)] {
        let phase = if driven { "driven" } else { "stick" };
        let m = scene(nx, nz, driven);
        for precision in ["f64", "f32"] {
            for threads in [1usize, 2] {
                let name = format!("{nx}x{nz} {phase} {precision} {threads}");
                if !filter.iter().all(|f| name.contains(f.as_str())) {
                    continue;
                }
                let (a, b) = match precision {
                    "f64" => compare::<f64, f64>(&m, threads, seconds),
                    _ => compare::<f32, DoubleSingle>(&m, threads, seconds),
                };
                println!(
                    "| {nx}×{nz} | {phase} | {precision} | {threads} | {a:.3e} | {b:.3e} | {:.2} |",
                    b / a
                );
            }
        }
    }
}
