//! The host's CPU a step of each GPU launch on the Table S1 scene, with
//! the storage arrays in arenas (`GpuOptions::pack_arrays`, the default)
//! and with a buffer each (as before session 55), alternating in one run.
//!
//! Why: wgpu tracks every buffer a dispatch binds, at every dispatch, and
//! the one-step launches encode a dispatch a step. On the H200 they were
//! host-bound at Table S1 (session 50: the host busy 0.77 of the wall at
//! 5.92 µs a step), so the host's CPU a step bounds their step time.
//!
//! What is timed: the CPU time of the thread that calls `advance` (it
//! encodes, submits and retires the batches; waiting costs it nothing),
//! and the wall time, over the steps after a warm-up. On a software
//! adapter (lavapipe) the device's work runs on the driver's own threads,
//! so the calling thread's CPU is still the host's part. The steps are the
//! scene's first (its normal-load phase): a dispatch costs the host the
//! same in every phase.
//!
//! `cargo bench --bench gpu_host [-- ROUNDS]` (default 3; medians over the
//! rounds). Prints a Markdown table (BENCHMARKS.md).

use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuPath};
use slipfront::{Engine, EngineError};
use std::time::Instant;

#[path = "support/gpu_timing.rs"]
mod gpu_timing;
#[path = "support/thread_cpu.rs"]
#[allow(dead_code)] // gpu_timing's
mod thread_cpu;

/// CPU seconds of the calling thread so far.
fn thread_cpu_seconds() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes the timespec it is given.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

/// (host CPU seconds, wall seconds) a step of `steps` steps after `warm`
/// steps of a fresh engine.
fn host_per_step(
    model: &slipfront::Model,
    opts: GpuOptions,
    warm: u64,
    steps: u64,
) -> Result<(f64, f64), EngineError> {
    let mut e = GpuEngine::with_options(model, opts)?;
    e.advance(warm)?;
    let (t0, cpu0) = (Instant::now(), thread_cpu_seconds());
    e.advance(steps)?;
    let cpu = thread_cpu_seconds() - cpu0;
    let wall = t0.elapsed().as_secs_f64();
    Ok((cpu / steps as f64, wall / steps as f64))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let rounds: usize = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .and_then(|a| a.parse().ok())
        .unwrap_or(3);
    let model = gpu_timing::table_s1(1);
    let ctx = slipfront::engines::gpu::context::shared().expect("an adapter");
    let software = ctx.is_software();
    println!("adapter: {} ({:?})", ctx.info.name, ctx.info.backend);
    // A software adapter steps Table S1 at about a millisecond a step.
    let (warm, steps) = if software {
        (200, 1000)
    } else {
        (2000, 50_000)
    };
    println!(
        "Table S1 ({}×{}), {warm} steps' warm-up, then {steps} timed; medians of {rounds} rounds\n",
        model.nx, model.nz
    );
    let launches = [
        ("one-step", GpuPath::OneStep, false),
        ("one-step-lanes", GpuPath::OneStepLanes, false),
        ("tiled", GpuPath::Tiled, false),
        ("tiled/chained", GpuPath::Tiled, true),
        ("persistent", GpuPath::Persistent, false),
        ("resident", GpuPath::Resident, false),
    ];
    println!(
        "| launch | host CPU µs a step, arrays in arenas | a buffer each | ratio | wall µs a step, arenas | a buffer each |"
    );
    println!("| --- | ---: | ---: | ---: | ---: | ---: |");
    for (name, path, chained_tiles) in launches {
        let mut figures: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
        let mut failed = None;
        for _ in 0..rounds {
            for (k, pack_arrays) in [true, false].into_iter().enumerate() {
                let opts = GpuOptions {
                    path,
                    chained_tiles,
                    pack_arrays,
                    ..GpuOptions::default()
                };
                match host_per_step(&model, opts, warm, steps) {
                    Ok(f) => figures[k].push(f),
                    Err(e) => failed = Some(e.to_string()),
                }
            }
        }
        if let Some(why) = failed.filter(|_| figures[0].is_empty() || figures[1].is_empty()) {
            println!("| {name} | – | – | – | – | – ({why}) |");
            continue;
        }
        let cpu = |k: usize| median(figures[k].iter().map(|f| f.0 * 1e6).collect());
        let wall = |k: usize| median(figures[k].iter().map(|f| f.1 * 1e6).collect());
        // The ratio of each round's pair, then their median.
        let ratio = median(
            figures[0]
                .iter()
                .zip(&figures[1])
                .map(|(a, b)| a.0 / b.0)
                .collect(),
        );
        println!(
            "| {name} | {:.2} | {:.2} | {ratio:.2} | {:.1} | {:.1} |",
            cpu(0),
            cpu(1),
            wall(0),
            wall(1)
        );
    }
}
