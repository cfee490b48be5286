//! Block-steps per second of the engines on the Table S1 scene and on a
//! 1024×256 lattice with junctions. `cargo bench --bench throughput`;
//! prints a Markdown table (see BENCHMARKS.md for recorded results).
//! SLIPFRONT_BENCH_GPU=1 adds the GPU kernels in mixed f32, and
//! SLIPFRONT_BENCH_GPU_F64=1 the same kernels in f64 (adapters with
//! SHADER_F64), to time f64 against mixed f32 on one card.

use slipfront::engines::backend::{make_engine, Backend, Precision};
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuPath};
use slipfront::{advance_to, Model};
use slipfront::{Engine, EngineError};
use std::time::Instant;

#[path = "support/bench_scene.rs"]
mod bench_scene;
use bench_scene::scene;

fn measure(model: &Model, engine: Result<Box<dyn Engine>, EngineError>) -> Option<(f64, String)> {
    let mut engine = engine.ok()?;
    // Warm up past the normal-load phase, then time at least ~2 s.
    advance_to(engine.as_mut(), model.prep_steps + 10).ok()?;
    let mut steps = 16u64;
    loop {
        let start = engine.steps_done();
        let t0 = Instant::now();
        // Every engine's advance returns when its steps have run (the GPU
        // engine waits for its last batch), so nothing is read back in the
        // timed span: a whole snapshot costs about 0.6 µs a block on the
        // host (measured through lavapipe at 2048×1024), seconds at
        // 8192×4096, and timing it made large lattices look slow.
        advance_to(engine.as_mut(), start + steps).ok()?;
        let dt = t0.elapsed().as_secs_f64();
        if dt > 2.0 || steps > 1 << 24 {
            return Some((
                steps as f64 * model.n_blocks() as f64 / dt,
                engine.describe(),
            ));
        }
        steps *= if dt < 0.2 { 8 } else { 2 };
    }
}

/// The GPU engine on `path`, in mixed f32 or in f64.
fn gpu_engine(
    model: &Model,
    path: GpuPath,
    precision: Precision,
) -> Result<Box<dyn Engine>, EngineError> {
    let opts = GpuOptions {
        path,
        ..GpuOptions::default()
    };
    Ok(match precision {
        Precision::F64 => Box::new(GpuEngine::<f64>::with_precision(model, opts)?),
        _ => Box::new(GpuEngine::with_options(model, opts)?),
    })
}

fn main() {
    let filter: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let gpu = std::env::var("SLIPFRONT_BENCH_GPU").is_ok();
    let gpu_f64 = std::env::var("SLIPFRONT_BENCH_GPU_F64").is_ok();
    let scaling = std::env::var("SLIPFRONT_BENCH_SCALING").is_ok();
    let mut sizes: Vec<(u32, u32)> = vec![(57, 31), (1024, 256)];
    if scaling {
        sizes = vec![
            (57, 31),
            (128, 64),
            (256, 128),
            (512, 256),
            (1024, 256),
            (1024, 512),
            (2048, 1024),
            (4096, 2048),
            // Issue 32's cliff: 9× below 4096×2048 on an H100 when a
            // snapshot was timed with the steps (GPU only: 33.5M blocks).
            (8192, 4096),
        ];
    }
    println!("| lattice | engine | block-steps/s | steps/s | bytes/block |");
    println!("| --- | --- | ---: | ---: | ---: |");
    for (nx, nz) in sizes {
        let name = format!("{nx}x{nz}");
        if !filter.is_empty() && !filter.iter().any(|f| name.contains(f.as_str())) {
            continue;
        }
        let model = scene(nx, nz);
        let n = model.n_blocks();
        let mut configs = Vec::new();
        // The CPU beyond 1024×512 takes minutes per measurement.
        if n <= 1024 * 512 {
            configs.extend([
                (Backend::Cpu, Precision::F64, 1),
                (Backend::Cpu, Precision::F64, 2),
                (Backend::Cpu, Precision::F32, 1),
                (Backend::Cpu, Precision::F32, 2),
                // The reference engine (the kernel twins): the CPU engine
                // issue 10's GPU/CPU ratio was first measured against.
                (Backend::CpuReference, Precision::F32, 1),
                // Plain f32 displacements: the cost of mixed precision.
                (Backend::Cpu, Precision::F32Plain, 1),
                (Backend::Cpu, Precision::F32Plain, 2),
            ]);
        }
        if gpu {
            configs.push((Backend::Gpu, Precision::F32, 0));
        }
        if gpu_f64 {
            configs.push((Backend::Gpu, Precision::F64, 0));
        }
        for (backend, precision, threads) in configs {
            let bytes = match precision {
                Precision::F64 => model.memory_bytes(8, 8),
                Precision::F32 => model.memory_bytes(4, 8),
                Precision::F32Plain => model.memory_bytes(4, 4),
            } as f64
                / n as f64;
            let paths = if backend == Backend::Gpu {
                vec![
                    Some(GpuPath::OneStep),
                    Some(GpuPath::OneStepLanes),
                    Some(GpuPath::Persistent),
                    Some(GpuPath::Resident),
                ]
            } else {
                vec![None]
            };
            for path in paths {
                let engine = match path {
                    Some(p) => gpu_engine(&model, p, precision),
                    None => make_engine(&model, backend, precision, threads),
                };
                match measure(&model, engine) {
                    Some((rate, what)) => println!(
                        "| {name} | {what} | {rate:.3e} | {:.3e} | {bytes:.1} |",
                        rate / n as f64
                    ),
                    None => println!(
                        "| {name} | {backend:?} {precision:?} {path:?} | unavailable | | |"
                    ),
                }
            }
        }
    }
}
