//! Section 1: every kernel against lattice size, each scene alone.

use crate::bench_scene;
use crate::common::{options, path_name};
use crate::gpu_timing::solo_step_seconds;
use slipfront::engines::gpu::kernel_choice::candidates;
use slipfront::engines::gpu::shaders::Kernel;
use slipfront::engines::gpu::GpuOptions;

/// Section 1: a row for each kernel at each of `sizes`. Returns each
/// lattice's best block-steps/s, which section 5 sets against the CPU's.
pub fn against_size(sizes: &[(u32, u32)], min_seconds: f64) -> Vec<((u32, u32), f64)> {
    // 1. Kernels against lattice size.
    println!("## 1. Kernels against lattice size (each scene alone)\n");
    println!(
        "Host CPU / wall: CPU seconds of every thread of the process per wall second of the \
         timed span (near 1 or above: the host is the limit; near 0 on a hardware GPU: the \
         device).\n"
    );
    println!("| lattice | kernel | µs/step | block-steps/s | host CPU / wall |");
    println!("| --- | --- | ---: | ---: | ---: |");
    let mut best_gpu = Vec::new();
    for &(nx, nz) in sizes {
        best_gpu.push(((nx, nz), rows_at(nx, nz, min_seconds)));
    }
    best_gpu
}

/// The rows of lattice `nx`×`nz`: each kernel, the one-step ones also with
/// bond patches. Returns the best kernel's block-steps/s.
fn rows_at(nx: u32, nz: u32, min_seconds: f64) -> f64 {
    let model = bench_scene::scene(nx, nz);
    let mut best = f64::INFINITY;
    // The one-step kernels also with their bulk forces by 2×2
    // patches (a quarter of the threads: the large lattices' variant).
    let runs = candidates(&model).into_iter().flat_map(|kernel| {
        let one_step = matches!(kernel, Kernel::OneStep | Kernel::OneStepLanes);
        let patched = one_step.then_some((kernel, true));
        [(kernel, false)].into_iter().chain(patched)
    });
    for (kernel, bond_patches) in runs {
        let opts = GpuOptions {
            bond_patches,
            ..options(kernel)
        };
        let name = format!(
            "{}{}",
            path_name(kernel),
            if bond_patches { "/bond-patches" } else { "" }
        );
        match solo_step_seconds(&model, opts, min_seconds) {
            Ok((s, host)) => {
                best = best.min(s);
                println!(
                    "| {nx}×{nz} | {name} | {:.2} | {:.3e} | {host:.2} |",
                    s * 1e6,
                    model.n_blocks() as f64 / s
                );
            }
            Err(e) => println!("| {nx}×{nz} | {name} | not run: {e} | | |"),
        }
    }
    model.n_blocks() as f64 / best
}
