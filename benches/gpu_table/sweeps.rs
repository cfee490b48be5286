//! Section 6: Table S1 points as one `sweep --backend gpu`, against the
//! same points one at a time.

use crate::common::counts_from_env;
use crate::thread_cpu;
use slipfront::app::sweeps::{run_sweep, KeepMcap, Sweep, SweepOptions};
use slipfront::engines::backend::{Backend, Precision};
use slipfront::engines::gpu::GpuOptions;
use slipfront::Model;
use std::path::Path;
use std::time::Instant;

/// Section 6: a sweep of Table S1 points for each count, its files in
/// `dir`.
pub fn table_s1_points(dir: &Path, quick: bool) {
    // 6. Table S1 points as one sweep.
    println!("\n## 6. Table S1 points as one sweep, 0.01 s of driving each\n");
    println!(
        "Block-steps/s of the runs count each point's normal-load phase; the sweep steps \
         that phase once for all of them, so block-steps/s stepped counts it once. Host \
         threads: CPU seconds per wall second by thread.\n"
    );
    println!(
        "| points | how | wall (s) | block-steps/s of the runs | block-steps/s stepped | \
         against one at a time | host threads |"
    );
    println!("| ---: | --- | ---: | ---: | ---: | ---: | --- |");
    let sweeps = counts_from_env(
        "SLIPFRONT_GPU_TABLE_SWEEPS",
        if quick { &[4] } else { &[64, 256] },
    );
    for &n in &sweeps {
        // One at a time only for the smaller sweep (64 points take
        // 75 s so on an H200).
        points_rows(dir, n, n == sweeps[0] && n <= 64);
    }
}

/// The rows of a sweep of `n` points: as one ensemble, not running ahead,
/// and (`one_at_a_time`) one point at a time.
fn points_rows(dir: &Path, n: usize, one_at_a_time: bool) {
    let sweep = table_s1_sweep(dir, n);
    let model = Model::from_scenario(&sweep.points[0].scenario, false).expect("model");
    // Each point's run has its normal-load phase, but the sweep
    // steps that phase once for all (`share_loading`): block-steps
    // of the runs, and block-steps the device stepped.
    let block_steps = n as f64 * model.total_steps() as f64 * model.n_blocks() as f64;
    let stepped =
        (n as f64 * model.drive_steps as f64 + model.prep_steps as f64) * model.n_blocks() as f64;
    let ahead = GpuOptions::default().run_ahead;
    // Untimed first: it times the kernels on this ensemble and
    // caches the choice, which the timed sweeps then share.
    let _ = sweep_wall(dir, &sweep, n, ahead);
    let together = sweep_wall(dir, &sweep, n, ahead);
    // The same without running ahead: what the device's wait for
    // the runners costs.
    let waiting = sweep_wall(dir, &sweep, n, 0);
    let alone = if one_at_a_time {
        Some(sweep_wall(dir, &sweep, 1, ahead))
    } else {
        None
    };
    for (how, wall) in [
        ("one ensemble", Some(&together)),
        ("one ensemble, not running ahead", Some(&waiting)),
        ("one at a time", alone.as_ref()),
    ] {
        match wall {
            Some(Ok((w, threads))) => {
                let against = match alone.as_ref() {
                    Some(Ok((a, _))) => format!("{:.1}×", a / w),
                    _ => String::new(),
                };
                println!(
                    "| {n} | {how} | {w:.1} | {:.3e} | {:.3e} | {against} | {threads} |",
                    block_steps / w,
                    stepped / w
                );
            }
            Some(Err(e)) => println!("| {n} | {how} | not run: {e} | | | | |"),
            None => {}
        }
    }
}

/// `points` seeds of the precursors scene, 0.01 s of driving each, as a
/// sweep file in `dir`.
fn table_s1_sweep(dir: &Path, points: usize) -> Sweep {
    let base = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/tromborg2014_precursors.toml"
    );
    let text = format!(
        "base = \"{base}\"\nseeds = {points}\n[set]\n\"time.end\" = 0.01\n\
         \"output.bulk_interval\" = 0.0\n"
    );
    let file = dir.join(format!("table_s1_{points}.toml"));
    std::fs::write(&file, text).expect("sweep file");
    Sweep::load(&file).expect("sweep")
}

/// Wall seconds of `sweep` on the GPU in mixed f32, `ensemble` scenes per
/// dispatch at most (1: one point at a time), the device running ahead of
/// the runners by `run_ahead` batches (0: it waits for them every chunk);
/// and the CPU its threads used per wall second.
fn sweep_wall(
    dir: &Path,
    sweep: &Sweep,
    ensemble: usize,
    run_ahead: usize,
) -> Result<(f64, String), String> {
    let out = dir.join(format!("sweep-{}-{ensemble}", sweep.points.len()));
    let _ = std::fs::remove_dir_all(&out);
    let threads = thread_cpu::ThreadCpu::start();
    let t0 = Instant::now();
    let report = run_sweep(
        sweep,
        &SweepOptions {
            out_dir: out.clone(),
            backend: Backend::Gpu,
            precision: Precision::F32,
            threads: 1,
            shard: None,
            keep_mcap: KeepMcap::None,
            progress: false,
            share_loading: true,
            ensemble,
            gpu: GpuOptions {
                run_ahead,
                ..slipfront::app::sweeps::default_gpu()
            },
            on_point: None,
        },
    )?;
    let wall = t0.elapsed().as_secs_f64();
    let threads = thread_cpu::per_wall(&threads.finish(), wall);
    let _ = std::fs::remove_dir_all(&out);
    if report.not_ok > 0 {
        return Err(format!("{} points not ok", report.not_ok));
    }
    Ok((wall, threads))
}
