//! Section 5: the CPU engine on all cores, and the GPU's best over it.

use crate::bench_scene;
use crate::gpu_timing::timed_advance;
use slipfront::advance_to;
use slipfront::engines::backend::{make_engine, Backend, Precision};

/// Section 5: the CPU's block-steps/s at each of `sizes` up to 1024×256,
/// against `best_gpu`, section 1's best kernel at each size (empty where
/// section 1 did not run).
pub fn against_gpu(sizes: &[(u32, u32)], best_gpu: &[((u32, u32), f64)], min_seconds: f64) {
    // 5. The CPU on all cores, and the GPU's best over it.
    println!("\n## 5. The CPU engine on all cores of this machine (mixed f32)\n");
    println!("| lattice | CPU block-steps/s | GPU best block-steps/s | GPU/CPU |");
    println!("| --- | ---: | ---: | ---: |");
    for &(nx, nz) in sizes {
        if nx as usize * nz as usize > 1024 * 256 {
            continue;
        }
        // Section 1's best kernel at this size, when it ran.
        let gpu_rate = best_gpu
            .iter()
            .find(|(size, _)| *size == (nx, nz))
            .map(|&(_, rate)| rate);
        let model = bench_scene::scene(nx, nz);
        let result = make_engine(&model, Backend::Cpu, Precision::F32, 0).and_then(|mut e| {
            advance_to(e.as_mut(), model.prep_steps + 16)?;
            timed_advance(|n| e.advance(n), min_seconds)
        });
        match result {
            Ok((dt, steps)) => {
                let cpu = model.n_blocks() as f64 * steps as f64 / dt;
                match gpu_rate {
                    Some(gpu) => {
                        println!("| {nx}×{nz} | {cpu:.3e} | {gpu:.3e} | {:.1}× |", gpu / cpu)
                    }
                    None => println!("| {nx}×{nz} | {cpu:.3e} | (section 1 not run) | |"),
                }
            }
            Err(e) => println!("| {nx}×{nz} | not run: {e} | | |"),
        }
    }
}
