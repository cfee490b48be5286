//! Sweep throughput: 64 points of the Table S1-size triggered scene
//! (8 prestresses × 8 seeds, 0.2 ms after the trigger) run as one
//! in-process sweep (one scene per thread, with and without the shared
//! normal-load phase) against 64 separate `slipfront run` processes one
//! after another (the shell-script way). Same points, same steps; each
//! configuration in its own timed pass, and the separate processes timed
//! first and last so drift on a noisy machine shows.
//!
//!     cargo bench --bench sweep_throughput [-- THREADS]
//!
//! With `gpu [SEEDS]`: the GPU engine, the same points (SEEDS seeds per
//! prestress, 8 by default) as one in-process sweep whose points run as
//! ensembles (one dispatch for all) against the same sweep with
//! `--ensemble 1` (one point at a time on the GPU engine), each with and
//! without the shared normal-load phase; the ensemble passes first and last.
//! `shared-only` leaves out the pair without sharing (three passes, not five:
//! the 64-point lavapipe run takes over half an hour).
//!
//! `separate` instead times the GPU sweep against separate `slipfront run
//! --backend gpu` processes, the baseline of the CPU table.
//!
//!     cargo bench --bench sweep_throughput -- gpu [SEEDS] [shared-only|separate]

use slipfront::app::sweeps::{run_sweep, KeepMcap, Sweep, SweepOptions};
use slipfront::engines::backend::Backend;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

const PRESTRESS: [f64; 8] = [0.2, 0.22, 0.24, 0.26, 0.28, 0.3, 0.32, 0.34];
const SEEDS: u32 = 8;

/// The points as separate `slipfront run` processes on `backend` ("cpu" or
/// "gpu"), one after another: what a user without `sweep` would do.
fn separate_processes(dir: &Path, backend: &str, seeds: u32) -> f64 {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/triggered_front.toml");
    let out = dir.join("one.mcap");
    let started = Instant::now();
    for p in PRESTRESS {
        for seed in 1..=seeds {
            let status = Command::new(env!("CARGO_BIN_EXE_slipfront"))
                .args(["run", base.to_str().unwrap(), "--backend", backend])
                .args([
                    "--threads",
                    "1",
                    "--quiet",
                    "--force",
                    "-o",
                    out.to_str().unwrap(),
                ])
                .args(["--set", &format!("loading.trigger.shear_prestress={p}")])
                .args(["--set", &format!("time.seed={seed}")])
                .args(["--set", "output.bulk_interval=0.0"])
                .stdout(std::process::Stdio::null())
                .status()
                .unwrap();
            assert!(status.success());
        }
    }
    started.elapsed().as_secs_f64()
}

fn in_process(dir: &Path, sweep: &Sweep, threads: usize, share: bool) -> f64 {
    sweep_on(dir, sweep, Backend::Cpu, threads, share, 1)
}

fn sweep_on(
    dir: &Path,
    sweep: &Sweep,
    backend: Backend,
    threads: usize,
    share: bool,
    ensemble: usize,
) -> f64 {
    let out = dir.join(format!("sweep-{backend:?}-{threads}-{share}-{ensemble}"));
    let _ = std::fs::remove_dir_all(&out);
    let started = Instant::now();
    let report = run_sweep(
        sweep,
        &SweepOptions {
            out_dir: out,
            backend,
            precision: backend.default_precision(),
            threads,
            shard: None,
            keep_mcap: KeepMcap::None,
            progress: false,
            share_loading: share,
            ensemble,
            gpu: slipfront::app::sweeps::default_gpu(),
            on_point: None,
        },
    )
    .unwrap();
    assert_eq!(report.ran, sweep.points.len());
    assert_eq!(report.not_ok, 0);
    started.elapsed().as_secs_f64()
}

/// The bench's sweep: 8 prestresses × `seeds` seeds of the triggered scene.
fn bench_sweep(dir: &Path, seeds: u32) -> Sweep {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/triggered_front.toml");
    let text = format!(
        "base = \"{}\"\nseeds = {seeds}\n[set]\n\"output.bulk_interval\" = 0.0\n[axes]\n\
         \"loading.trigger.shear_prestress\" = {:?}\n",
        base.display(),
        PRESTRESS
    );
    let file = dir.join("bench.toml");
    std::fs::write(&file, text).unwrap();
    Sweep::load(&file).unwrap()
}

/// The title and header of a GPU table: the scene, the adapter, the columns.
fn gpu_table_header(model: &slipfront::Model, n: usize, against: &str) {
    let adapter = slipfront::engines::gpu::context::shared()
        .unwrap()
        .describe();
    println!(
        "{n} points of {} ({} x {} blocks, {} steps each) on {adapter}",
        model.name,
        model.nx,
        model.nz,
        model.total_steps()
    );
    println!("| configuration | wall (s) | scenes/hour | block-steps/s | {against} |");
    println!("| --- | --- | --- | --- | --- |");
}

/// GPU ensembles against the same points one at a time on the GPU engine.
fn gpu_bench(dir: &Path, seeds: u32, with_own_loading: bool) {
    let sweep = bench_sweep(dir, seeds);
    let n = sweep.points.len();
    let model = slipfront::Model::from_scenario(&sweep.points[0].scenario, false).unwrap();
    let block_steps = n as f64 * model.total_steps() as f64 * model.n_blocks() as f64;
    let ensemble_first = sweep_on(dir, &sweep, Backend::Gpu, 1, true, n);
    let alone_shared = sweep_on(dir, &sweep, Backend::Gpu, 1, true, 1);
    let (ensemble_own, alone_own) = if with_own_loading {
        (
            sweep_on(dir, &sweep, Backend::Gpu, 1, false, n),
            sweep_on(dir, &sweep, Backend::Gpu, 1, false, 1),
        )
    } else {
        (f64::NAN, f64::NAN)
    };
    let ensemble_last = sweep_on(dir, &sweep, Backend::Gpu, 1, true, n);
    gpu_table_header(&model, n, "vs one at a time");
    for (name, wall, against) in [
        (
            "ensemble of all points, shared loading (first pass)",
            ensemble_first,
            alone_shared,
        ),
        (
            "ensemble of all points, shared loading (last pass)",
            ensemble_last,
            alone_shared,
        ),
        (
            "one point at a time, shared loading",
            alone_shared,
            alone_shared,
        ),
        (
            "ensemble of all points, each its own loading",
            ensemble_own,
            alone_own,
        ),
        (
            "one point at a time, each its own loading",
            alone_own,
            alone_own,
        ),
    ] {
        if wall.is_nan() {
            continue;
        }
        println!(
            "| {name} | {wall:.1} | {:.0} | {:.2e} | {:.2}× |",
            n as f64 * 3600.0 / wall,
            block_steps / wall,
            against / wall
        );
    }
}

/// The GPU sweep (ensembles, shared loading) against the points as
/// separate `slipfront run --backend gpu` processes one after another, the
/// baseline the CPU table uses too; the in-process sweep first and last.
fn gpu_separate_bench(dir: &Path, seeds: u32) {
    let sweep = bench_sweep(dir, seeds);
    let n = sweep.points.len();
    let model = slipfront::Model::from_scenario(&sweep.points[0].scenario, false).unwrap();
    let block_steps = n as f64 * model.total_steps() as f64 * model.n_blocks() as f64;
    let ensemble_first = sweep_on(dir, &sweep, Backend::Gpu, 1, true, n);
    let alone_shared = sweep_on(dir, &sweep, Backend::Gpu, 1, true, 1);
    let separate = separate_processes(dir, "gpu", seeds);
    let ensemble_last = sweep_on(dir, &sweep, Backend::Gpu, 1, true, n);
    gpu_table_header(&model, n, "vs separate");
    for (name, wall) in [
        (
            format!("{n} separate `slipfront run --backend gpu`"),
            separate,
        ),
        (
            "in-process sweep, one point at a time, shared loading".into(),
            alone_shared,
        ),
        (
            "in-process sweep, ensembles, shared loading (first pass)".into(),
            ensemble_first,
        ),
        (
            "in-process sweep, ensembles, shared loading (last pass)".into(),
            ensemble_last,
        ),
    ] {
        println!(
            "| {name} | {wall:.1} | {:.0} | {:.2e} | {:.2}× |",
            n as f64 * 3600.0 / wall,
            block_steps / wall,
            separate / wall
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dir = std::env::temp_dir().join(format!("slipfront-sweep-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    if let Some(at) = args.iter().position(|a| a == "gpu") {
        let seeds = args
            .get(at + 1)
            .and_then(|s| s.parse().ok())
            .unwrap_or(SEEDS);
        if args.iter().any(|a| a == "separate") {
            gpu_separate_bench(&dir, seeds);
        } else {
            gpu_bench(&dir, seeds, !args.iter().any(|a| a == "shared-only"));
        }
        let _ = std::fs::remove_dir_all(&dir);
        return;
    }
    let threads: usize = args
        .iter()
        .filter_map(|a| a.parse().ok())
        .next()
        .unwrap_or(2);
    let sweep = bench_sweep(&dir, SEEDS);
    let model = slipfront::Model::from_scenario(&sweep.points[0].scenario, false).unwrap();
    let block_steps = 64.0 * model.total_steps() as f64 * model.n_blocks() as f64;
    let first = separate_processes(&dir, "cpu", SEEDS);
    let own = in_process(&dir, &sweep, threads, false);
    let shared = in_process(&dir, &sweep, threads, true);
    let last = separate_processes(&dir, "cpu", SEEDS);
    let separate = 0.5 * (first + last);
    println!(
        "64 points of {} ({} x {} blocks, {} steps each), {threads} scene thread(s)",
        model.name,
        model.nx,
        model.nz,
        model.total_steps()
    );
    println!("| configuration | wall (s) | scenes/hour | block-steps/s | vs separate |");
    println!("| --- | --- | --- | --- | --- |");
    for (name, wall) in [
        ("64 separate `slipfront run` (first pass)", first),
        ("64 separate `slipfront run` (last pass)", last),
        ("in-process sweep, each point its own loading", own),
        ("in-process sweep, shared normal-load phases", shared),
    ] {
        if wall.is_nan() {
            continue;
        }
        println!(
            "| {name} | {wall:.1} | {:.0} | {:.2e} | {:.2}× |",
            64.0 * 3600.0 / wall,
            block_steps / wall,
            separate / wall
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
