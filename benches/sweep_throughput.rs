//! Sweep throughput: 64 points of the Table S1-size triggered scene
//! (8 prestresses × 8 seeds, 0.2 ms after the trigger) run as one
//! in-process sweep (one scene per thread, with and without the shared
//! normal-load phase) against 64 separate `slipfront run` processes one
//! after another (the shell-script way). Same points, same steps; each
//! configuration in its own timed pass, and the separate processes timed
//! first and last so drift on a noisy machine shows.
//!
//!     cargo bench --bench sweep_throughput [-- THREADS]

use slipfront::backend::{Backend, Precision};
use slipfront::sweep::{run_sweep, KeepMcap, Sweep, SweepOptions};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

const PRESTRESS: [f64; 8] = [0.2, 0.22, 0.24, 0.26, 0.28, 0.3, 0.32, 0.34];
const SEEDS: u32 = 8;

fn separate_processes(dir: &Path) -> f64 {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/triggered_front.toml");
    let out = dir.join("one.mcap");
    let started = Instant::now();
    for p in PRESTRESS {
        for seed in 1..=SEEDS {
            let status = Command::new(env!("CARGO_BIN_EXE_slipfront"))
                .args(["run", base.to_str().unwrap(), "--backend", "cpu"])
                .args(["--threads", "1", "--quiet", "-o", out.to_str().unwrap()])
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
    let out = dir.join(format!("sweep-{threads}-{share}"));
    let _ = std::fs::remove_dir_all(&out);
    let started = Instant::now();
    let report = run_sweep(
        sweep,
        &SweepOptions {
            out_dir: out,
            backend: Backend::Cpu,
            precision: Precision::F64,
            threads,
            shard: None,
            keep_mcap: KeepMcap::None,
            progress: false,
            share_loading: share,
            ensemble: 1,
        },
    )
    .unwrap();
    assert_eq!(report.ran, 64);
    assert_eq!(report.not_ok, 0);
    started.elapsed().as_secs_f64()
}

fn main() {
    let threads: usize = std::env::args()
        .filter_map(|a| a.parse().ok())
        .next()
        .unwrap_or(2);
    let dir = std::env::temp_dir().join(format!("slipfront-sweep-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/triggered_front.toml");
    let text = format!(
        "base = \"{}\"\nseeds = {SEEDS}\n[set]\n\"output.bulk_interval\" = 0.0\n[axes]\n\
         \"loading.trigger.shear_prestress\" = {:?}\n",
        base.display(),
        PRESTRESS
    );
    let file = dir.join("bench.toml");
    std::fs::write(&file, text).unwrap();
    let sweep = Sweep::load(&file).unwrap();
    let model = slipfront::Model::from_scenario(&sweep.points[0].scenario, false).unwrap();
    let block_steps = 64.0 * model.total_steps() as f64 * model.n_blocks() as f64;
    let first = separate_processes(&dir);
    let own = in_process(&dir, &sweep, threads, false);
    let shared = in_process(&dir, &sweep, threads, true);
    let last = separate_processes(&dir);
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
        println!(
            "| {name} | {wall:.1} | {:.0} | {:.2e} | {:.2}× |",
            64.0 * 3600.0 / wall,
            block_steps / wall,
            separate / wall
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
