//! Section 2: what `auto` chooses on Table S1, and the kernels it chooses
//! among by threads and tile shape.

use crate::common::{path_name, with_threads};
use crate::gpu_timing::solo_step_seconds;
use crate::tiles::tiled_grid;
use slipfront::engines::gpu::context::GpuContext;
use slipfront::engines::gpu::kernel_choice::measure_within;
use slipfront::engines::gpu::shaders::Kernel;
use slipfront::engines::gpu::GpuOptions;
use slipfront::Model;

/// Section 2's budget for stepping the normal-load phase before timing
/// (`auto`'s is 3 s): the bench always times from the start of driving.
const PREPARE_WITHOUT_BUDGET: f64 = 1e6;

/// Section 2 on `s1`, the Table S1 scene: `auto`'s choice timed both
/// ways, the persistent and resident kernels by threads, and the tiled
/// kernel by tile shape.
pub fn on_table_s1(s1: &Model, ctx: &GpuContext, quick: bool, min_seconds: f64) {
    // 2. The auto choice on Table S1.
    println!("\n## 2. What `auto` chooses on Table S1 (the precursors scene)\n");
    // As `auto` times (from the start of driving; here with no budget
    // for the load phase, which lavapipe takes 9 s to step), and as
    // builds before 2026-11-27 did (from the initial state, in the
    // normal-load phase, where no block keeps its junction sums):
    // whether the phase changes the choice on this GPU.
    for (how, budget) in [
        ("from the start of driving", PREPARE_WITHOUT_BUDGET),
        ("from the initial state", 0.0),
    ] {
        match measure_within::<f32>(std::slice::from_ref(s1), ctx, GpuOptions::default(), budget) {
            Ok(choice) => println!("Timed {how}: {}\n", choice.describe()),
            Err(e) => println!("Timed {how}: not measured: {e}\n"),
        }
    }
    by_threads(s1, min_seconds);
    tiled_grid(s1, quick, min_seconds);
}

/// The persistent and resident kernels on `s1` at 256, 512 and 1024
/// threads.
fn by_threads(s1: &Model, min_seconds: f64) {
    println!("| kernel | threads | µs/step | host CPU / wall |");
    println!("| --- | ---: | ---: | ---: |");
    for kernel in [Kernel::Persistent, Kernel::Resident] {
        for threads in [256, 512, 1024] {
            let figure =
                match solo_step_seconds(s1, with_threads(kernel, Some(threads)), min_seconds) {
                    Ok((s, host)) => format!("{:.2} | {host:.2}", s * 1e6),
                    Err(e) => format!("not run: {e} |"),
                };
            println!("| {} | {threads} | {figure} |", path_name(kernel));
        }
    }
    println!();
}
