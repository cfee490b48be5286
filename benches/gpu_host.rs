//! The host's CPU a step of each GPU launch on the Table S1 scene, for
//! each way the host encodes a dispatch, alternating in one run:
//! - the default: the storage arrays in arenas (`GpuOptions::pack_arrays`)
//!   and each dispatch's step offset as an immediate
//!   (`GpuOptions::step_immediates`, session 56);
//! - the step offset by a dynamic offset into a table, group 1 bound again
//!   at each dispatch (session 55);
//! - that, with a buffer per array as well (before session 55).
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
//! A second table isolates the mechanism: a trivial kernel that binds N
//! storage arrays, dispatched 4000 times in one pass (a dynamic offset set
//! before each, as the engine did until session 56), the host's CPU to
//! encode a dispatch with the N arrays in N buffers and as N ranges of one
//! buffer, and as ranges of one buffer with the offset as an immediate.
//!
//! `cargo bench --bench gpu_host [-- ROUNDS]` (default 3; medians over the
//! rounds). Prints Markdown tables (BENCHMARKS.md).

use slipfront::app::runner::sample_plan;
use slipfront::engines::gpu::context::GpuContext;
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuPath};
use slipfront::engines::SamplePlan;
use slipfront::{Engine, EngineError};
use std::time::Instant;

#[path = "support/gpu_timing.rs"]
mod gpu_timing;
use gpu_timing::thread_cpu_seconds;
#[path = "support/thread_cpu.rs"]
#[allow(dead_code)] // gpu_timing's
mod thread_cpu;

/// (host CPU seconds, wall seconds) a step of `steps` steps after `warm`
/// steps of a fresh engine, recording `samples` on the device where given
/// (as a run with `-o` does; the samples are taken and dropped).
fn host_per_step(
    model: &slipfront::Model,
    opts: GpuOptions,
    samples: Option<&SamplePlan>,
    warm: u64,
    steps: u64,
) -> Result<(f64, f64), EngineError> {
    let mut e = GpuEngine::with_options(model, opts)?;
    if let Some(plan) = samples {
        if !e.record_samples(plan)? {
            return Err(EngineError::Gpu(
                "cannot record samples on the device".into(),
            ));
        }
    }
    e.advance(warm)?;
    e.take_samples();
    let (t0, cpu0) = (Instant::now(), thread_cpu_seconds());
    e.advance(steps)?;
    e.take_samples();
    let cpu = thread_cpu_seconds() - cpu0;
    let wall = t0.elapsed().as_secs_f64();
    Ok((cpu / steps as f64, wall / steps as f64))
}

/// How the bare kernel's arrays are bound and how it gets its offset.
#[derive(Clone, Copy, PartialEq)]
enum Bare {
    /// A buffer per array, the offset by a dynamic offset.
    BufferEach,
    /// Ranges of one buffer, the offset by a dynamic offset.
    OneBuffer,
    /// Ranges of one buffer, the offset as an immediate.
    OneBufferImmediate,
}

/// Host CPU µs to encode and finish one dispatch of a kernel binding
/// `arrays` storage arrays, bound as `how` says: the median of `rounds`
/// passes of 4000 dispatches.
fn bare_dispatch_us(ctx: &GpuContext, arrays: u32, how: Bare, rounds: usize) -> f64 {
    let immediate = how == Bare::OneBufferImmediate;
    let device = &ctx.device;
    let mut src = String::new();
    for b in 0..arrays {
        src += &format!("@group(0) @binding({b}) var<storage, read_write> a{b}: array<u32>;\n");
    }
    src += match immediate {
        true => "var<immediate> offset: u32;\n",
        false => "@group(1) @binding(0) var<storage, read> offset: u32;\n",
    };
    src += "@compute @workgroup_size(64) fn main(@builtin(global_invocation_id) g: vec3<u32>) {\n";
    for b in 0..arrays {
        src += &format!("    a{b}[g.x] += offset;\n");
    }
    src += "}\n";
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("bare dispatch"),
        source: wgpu::ShaderSource::Wgsl(src.into()),
    });
    let entry = |binding, read_only, dynamic| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: dynamic,
            min_binding_size: None,
        },
        count: None,
    };
    let arrays_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &(0..arrays)
            .map(|b| entry(b, false, false))
            .collect::<Vec<_>>(),
    });
    let offset_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[entry(0, true, true)],
    });
    let groups = [Some(&arrays_layout), Some(&offset_layout)];
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        // With the offset as an immediate, group 1 is not bound.
        bind_group_layouts: &groups[..if immediate { 1 } else { 2 }],
        immediate_size: if immediate { 4 } else { 0 },
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: Some(&layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    // 64 words an array (the kernel's workgroup), at aligned offsets.
    let align = u64::from(ctx.limits.min_storage_buffer_offset_alignment).max(256);
    let storage = |size| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    };
    let (each, one) = (
        (0..arrays).map(|_| storage(256)).collect::<Vec<_>>(),
        storage(align * u64::from(arrays)),
    );
    let entries: Vec<wgpu::BindGroupEntry> = (0..arrays)
        .map(|b| wgpu::BindGroupEntry {
            binding: b,
            resource: match how != Bare::BufferEach {
                true => wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &one,
                    offset: u64::from(b) * align,
                    size: wgpu::BufferSize::new(256),
                }),
                false => each[b as usize].as_entire_binding(),
            },
        })
        .collect();
    let arrays_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &arrays_layout,
        entries: &entries,
    });
    let offsets = storage(align * 64);
    let offset_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &offset_layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &offsets,
                offset: 0,
                size: wgpu::BufferSize::new(4),
            }),
        }],
    });
    const DISPATCHES: u32 = 4000;
    let mut each_round = Vec::new();
    for _ in 0..rounds {
        let cpu0 = thread_cpu_seconds();
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &arrays_group, &[]);
            for d in 0..DISPATCHES {
                match immediate {
                    true => pass.set_immediates(0, bytemuck::bytes_of(&(d % 64))),
                    false => {
                        let offset = (u64::from(d % 64) * align) as u32;
                        pass.set_bind_group(1, &offset_group, &[offset]);
                    }
                }
                pass.dispatch_workgroups(1, 1, 1);
            }
        }
        let commands = encoder.finish();
        each_round.push((thread_cpu_seconds() - cpu0) / f64::from(DISPATCHES) * 1e6);
        ctx.queue.submit([commands]);
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("the device runs the dispatches");
    }
    median(each_round)
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
    println!("adapter: {} ({:?})\n", ctx.info.name, ctx.info.backend);
    println!(
        "| storage arrays a dispatch binds | host CPU µs a dispatch, a buffer each | ranges of one buffer | ranges of one buffer, offset as an immediate |"
    );
    println!("| ---: | ---: | ---: | ---: |");
    for arrays in [1, 4, 12, 28] {
        let us = |how| bare_dispatch_us(&ctx, arrays, how, rounds.max(3));
        let immediate = match ctx.has_immediates() {
            true => format!("{:.2}", us(Bare::OneBufferImmediate)),
            false => "– (no immediates)".to_string(),
        };
        println!(
            "| {arrays} | {:.2} | {:.2} | {immediate} |",
            us(Bare::BufferEach),
            us(Bare::OneBuffer)
        );
    }
    println!();
    // A software adapter steps Table S1 at about a millisecond a step.
    let (warm, steps) = if software {
        (200, 1000)
    } else {
        (2000, 20_000)
    };
    println!(
        "Table S1 ({}×{}), {warm} steps' warm-up, then {steps} timed; medians of {rounds} rounds\n",
        model.nx, model.nz
    );
    // Table S1's output plan. Its first sample comes when driving starts,
    // after these steps, so the recording rows time what recording adds to
    // every dispatch: the recorder's arrays bound beside the state.
    let plan = sample_plan(&model, &gpu_timing::table_s1_scenario(1));
    let launches = [
        ("one-step", GpuPath::OneStep, false, false),
        ("one-step-lanes", GpuPath::OneStepLanes, false, false),
        (
            "one-step-lanes, recorder bound",
            GpuPath::OneStepLanes,
            false,
            true,
        ),
        ("tiled", GpuPath::Tiled, false, false),
        ("tiled, recorder bound", GpuPath::Tiled, false, true),
        ("tiled/chained", GpuPath::Tiled, true, false),
        ("persistent", GpuPath::Persistent, false, false),
        ("resident", GpuPath::Resident, false, false),
    ];
    // The ways to encode a dispatch, newest first: the default (arrays in
    // arenas, the step as an immediate), the step by a dynamic offset
    // (session 55's), and a buffer per array as well (before session 55).
    let ways = [(true, true), (true, false), (false, false)];
    println!(
        "Immediates for the step offset: {}\n",
        match ctx.has_immediates() {
            true => "yes",
            false => "no (the first two columns are the same way)",
        }
    );
    println!(
        "| launch | host CPU µs a step: arenas, step immediate (default) | arenas, step by dynamic offset | a buffer each, dynamic offset | default / dynamic offset | default / a buffer each | wall µs a step, default |"
    );
    println!("| --- | ---: | ---: | ---: | ---: | ---: | ---: |");
    for (name, path, chained_tiles, records) in launches {
        let mut figures: [Vec<(f64, f64)>; 3] = [Vec::new(), Vec::new(), Vec::new()];
        let mut failed = None;
        for _ in 0..rounds {
            for (k, (pack_arrays, step_immediates)) in ways.into_iter().enumerate() {
                let opts = GpuOptions {
                    path,
                    chained_tiles,
                    pack_arrays,
                    step_immediates,
                    ..GpuOptions::default()
                };
                let samples = records.then_some(&plan);
                match host_per_step(&model, opts, samples, warm, steps) {
                    Ok(f) => figures[k].push(f),
                    Err(e) => failed = Some(e.to_string()),
                }
            }
        }
        if let Some(why) = failed.filter(|_| figures.iter().any(Vec::is_empty)) {
            println!("| {name} | – | – | – | – | – | – ({why}) |");
            continue;
        }
        let cpu = |k: usize| median(figures[k].iter().map(|f| f.0 * 1e6).collect());
        let wall = |k: usize| median(figures[k].iter().map(|f| f.1 * 1e6).collect());
        // The ratio of each round's pair, then their median.
        let ratio = |k: usize| {
            median(
                figures[0]
                    .iter()
                    .zip(&figures[k])
                    .map(|(a, b)| a.0 / b.0)
                    .collect(),
            )
        };
        println!(
            "| {name} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} |",
            cpu(0),
            cpu(1),
            cpu(2),
            ratio(1),
            ratio(2),
            wall(0)
        );
    }
}
