//! Section 3: ensembles of Table S1 scenes in one dispatch, per launch.

use crate::common::counts_from_env;
use crate::gpu_timing::{ensemble_step_seconds, table_s1};
use slipfront::engines::gpu::context::GpuContext;
use slipfront::engines::gpu::kernel_choice::{launches, Launch};
use slipfront::engines::gpu::GpuOptions;
use slipfront::Model;

/// Section 3: ensembles of 1 to 1024 Table S1 scenes (`s1` with a seed
/// each) in one dispatch, each launch's aggregate rate and its speed-up
/// over one scene alone.
pub fn of_table_s1(s1: &Model, ctx: &GpuContext, quick: bool, min_seconds: f64) {
    // 3. Ensembles of Table S1 scenes.
    let counts = counts_from_env(
        "SLIPFRONT_GPU_TABLE_SCENES",
        if quick {
            &[1, 4, 16]
        } else {
            &[1, 4, 16, 64, 256, 1024]
        },
    );
    print_header();
    let blocks = s1.n_blocks() as f64;
    // Scene counts outermost, so that a loan cut short has every
    // kernel's row at the smaller counts before any at the largest. The
    // single-workgroup kernels at each of ENSEMBLE_THREADS, as a
    // sweep's measurement times them (how many scenes share an SM
    // depends on their threads).
    let tried = launches_tried(s1, ctx);
    // SLIPFRONT_GPU_TABLE_LAUNCHES=resident/1024,one-step-lanes: only those.
    let launches_wanted: Option<Vec<String>> = std::env::var("SLIPFRONT_GPU_TABLE_LAUNCHES")
        .ok()
        .map(|list| list.split(',').map(|n| n.trim().to_string()).collect());
    let mut alone = vec![None; tried.len()];
    for &n in &counts {
        let models: Vec<Model> = (1..=n).map(table_s1).collect();
        for (&launch, alone) in tried.iter().zip(alone.iter_mut()) {
            let wanted = match &launches_wanted {
                Some(w) => w.contains(&launch.name()),
                None => !launch.bond_patches,
            };
            if !wanted {
                continue;
            }
            row(&models, launch, blocks, alone, min_seconds);
        }
    }
}

fn print_header() {
    println!("## 3. Ensembles of Table S1 scenes in one dispatch\n");
    println!(
        "Speed-up: the ensemble's aggregate rate over the same kernel's rate for one scene \
         alone (what running the scenes one at a time gets).\n"
    );
    println!("Host CPU / wall: as in section 1.\n");
    println!(
        "| scenes | kernel | µs per ensemble step | aggregate block-steps/s | speed-up | \
         host CPU / wall |"
    );
    println!("| ---: | --- | ---: | ---: | ---: | ---: |");
}

/// The launches an ensemble of `s1` scenes may take, each also with its
/// bulk forces by patches.
fn launches_tried(s1: &Model, ctx: &GpuContext) -> Vec<Launch> {
    let mut tried = launches(s1, 2, GpuOptions::default(), &ctx.limits);
    // The launches with their bulk forces by patches too, but only
    // where SLIPFRONT_GPU_TABLE_LAUNCHES names them
    // (`resident/1024/bond-patches`).
    let patched: Vec<_> = tried.iter().map(|l| l.with_bond_patches()).collect();
    tried.extend(patched);
    tried
}

/// The row of `launch` on the ensemble of `models` (`blocks` a scene).
/// `alone` is the launch's block-steps/s on one scene: the first count's
/// rate a scene, kept for the speed-up of the larger counts.
fn row(models: &[Model], launch: Launch, blocks: f64, alone: &mut Option<f64>, min_seconds: f64) {
    let n = models.len();
    let result = ensemble_step_seconds(models, launch.options(GpuOptions::default()), min_seconds);
    match result {
        Ok((per_step, host)) => {
            let rate = n as f64 * blocks / per_step;
            let one = *alone.get_or_insert(blocks / per_step);
            println!(
                "| {n} | {} | {:.2} | {rate:.3e} | {:.1}× | {:.2} |",
                launch.name(),
                per_step * 1e6,
                rate / one,
                host
            );
        }
        Err(e) => println!("| {n} | {} | not run: {e} | | | |", launch.name()),
    }
}
