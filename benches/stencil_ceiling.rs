//! The ceiling of the adapter: a plain 9-point f32 lattice stencil (the
//! reference kernel of `../shared/gpu-device.md`: read 8 neighbours, one
//! leapfrog update per cell) in several thread shapes, against the same
//! stencil in one plain Rust thread, on the lattice sizes of the engine
//! benchmarks. It bounds what any kernel of this model can reach on the
//! adapter relative to the CPU: the model's step does strictly more work
//! per block than this stencil.
//!
//! `cargo bench --bench stencil_ceiling [-- 57x31 1024x256]`; prints a
//! Markdown table (see BENCHMARKS.md, GPU engine v2).

use slipfront::advance_to;
use slipfront::engines::backend::{make_engine, Backend, Precision};
use slipfront::engines::gpu::context;
use std::time::Instant;

#[path = "support/bench_scene.rs"]
mod bench_scene;
use bench_scene::scene;
use wgpu::util::DeviceExt;

const WORKGROUP: u32 = 64;

/// The stencil, with `CELLS` consecutive cells of a row per invocation.
/// `WINDOW` keeps the 3×3 neighbourhood in registers along the row (each
/// further cell loads 3 new columns' values instead of 9).
fn shader(cells: u32, window: bool) -> String {
    let body = if window {
        r#"
    // Sliding 3-wide window along x: columns x-1, x, x+1 of rows z-1..z+1.
    var a0 = load(x0 - 1, z - 1); var a1 = load(x0 - 1, z); var a2 = load(x0 - 1, z + 1);
    var b0 = load(x0, z - 1); var b1 = load(x0, z); var b2 = load(x0, z + 1);
    for (var r = 0; r < CELLS; r++) {
        let x = x0 + r;
        if x >= i32(p.nx) { break; }
        let c0 = load(x + 1, z - 1); let c1 = load(x + 1, z); let c2 = load(x + 1, z + 1);
        let f = K * (a0 + a1 + a2 + b0 + b2 + c0 + c1 + c2 - 8.0 * b1);
        update(x, z, b1, f);
        a0 = b0; a1 = b1; a2 = b2; b0 = c0; b1 = c1; b2 = c2;
    }
"#
    } else {
        r#"
    for (var r = 0; r < CELLS; r++) {
        let x = x0 + r;
        if x >= i32(p.nx) { break; }
        let u = load(x, z);
        var s = vec2<f32>(0.0);
        for (var dz = -1; dz <= 1; dz++) {
            for (var dx = -1; dx <= 1; dx++) {
                s += load(x + dx, z + dz);
            }
        }
        update(x, z, u, K * (s - 9.0 * u));
    }
"#
    };
    format!(
        r#"
struct Params {{ nx: u32, nz: u32, dt: f32, pad: u32 }}
@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> u_in: array<vec2<f32>>;
@group(0) @binding(2) var<storage, read> v_in: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> u_out: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read_write> v_out: array<vec2<f32>>;
const CELLS: i32 = {cells};
const K: f32 = 0.1;

// Out-of-lattice neighbours read as the cell's mirror: zero net force there.
fn load(x: i32, z: i32) -> vec2<f32> {{
    let cx = clamp(x, 0, i32(p.nx) - 1);
    let cz = clamp(z, 0, i32(p.nz) - 1);
    return u_in[u32(cz) * p.nx + u32(cx)];
}}

fn update(x: i32, z: i32, u: vec2<f32>, f: vec2<f32>) {{
    let i = u32(z) * p.nx + u32(x);
    let v = v_in[i] + p.dt * f;
    v_out[i] = v;
    u_out[i] = u + p.dt * v;
}}

@compute @workgroup_size({WORKGROUP})
fn main(@builtin(global_invocation_id) g: vec3<u32>) {{
    let per_row = (p.nx + u32(CELLS) - 1u) / u32(CELLS);
    if g.x >= per_row * p.nz {{ return; }}
    let z = i32(g.x / per_row);
    let x0 = i32(g.x % per_row) * CELLS;
    {body}
}}
"#
    )
}

/// The persistent shape: one workgroup of `PERSISTENT` threads loops over
/// `STEPS` steps inside the shader, a barrier between reading step n and
/// writing step n + 1 (ping-pong buffers in storage).
const PERSISTENT: u32 = 256;

fn persistent_shader(steps: u32) -> String {
    format!(
        r#"
struct Params {{ nx: u32, nz: u32, dt: f32, pad: u32 }}
@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read_write> u_a: array<vec2<f32>>;
@group(0) @binding(2) var<storage, read_write> v_a: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> u_b: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read_write> v_b: array<vec2<f32>>;
const K: f32 = 0.1;

fn load(odd: bool, x: i32, z: i32) -> vec2<f32> {{
    let i = u32(clamp(z, 0, i32(p.nz) - 1)) * p.nx + u32(clamp(x, 0, i32(p.nx) - 1));
    if odd {{ return u_b[i]; }}
    return u_a[i];
}}

@compute @workgroup_size({PERSISTENT})
fn main(@builtin(local_invocation_index) local: u32) {{
    let n = p.nx * p.nz;
    for (var s = 0u; s < {steps}u; s++) {{
        let odd = (s & 1u) == 1u;
        for (var i = local; i < n; i += {PERSISTENT}u) {{
            let x = i32(i % p.nx);
            let z = i32(i / p.nx);
            let u = load(odd, x, z);
            var sum = vec2<f32>(0.0);
            for (var dz = -1; dz <= 1; dz++) {{
                for (var dx = -1; dx <= 1; dx++) {{
                    sum += load(odd, x + dx, z + dz);
                }}
            }}
            let f = K * (sum - 9.0 * u);
            if odd {{
                let v = v_b[i] + p.dt * f;
                v_a[i] = v;
                u_a[i] = u + p.dt * v;
            }} else {{
                let v = v_a[i] + p.dt * f;
                v_b[i] = v;
                u_b[i] = u + p.dt * v;
            }}
        }}
        storageBarrier();
        workgroupBarrier();
    }}
}}
"#
    )
}

/// The same stencil on the CPU, one thread: the reference of the ratio.
fn cpu_step(
    nx: usize,
    nz: usize,
    dt: f32,
    u: &[[f32; 2]],
    v: &mut [[f32; 2]],
    out: &mut [[f32; 2]],
) {
    const K: f32 = 0.1;
    for z in 0..nz {
        for x in 0..nx {
            let i = z * nx + x;
            let mut s = [0.0f32; 2];
            for dz in -1i32..=1 {
                let cz = (z as i32 + dz).clamp(0, nz as i32 - 1) as usize;
                for dx in -1i32..=1 {
                    let cx = (x as i32 + dx).clamp(0, nx as i32 - 1) as usize;
                    let n = u[cz * nx + cx];
                    s[0] += n[0];
                    s[1] += n[1];
                }
            }
            for c in 0..2 {
                let f = K * (s[c] - 9.0 * u[i][c]);
                v[i][c] += dt * f;
                out[i][c] = u[i][c] + dt * v[i][c];
            }
        }
    }
}

fn cpu_rate(nx: usize, nz: usize) -> f64 {
    let n = nx * nz;
    let mut u: Vec<[f32; 2]> = (0..n).map(|i| [1e-3 * (i % 7) as f32, 0.0]).collect();
    let mut v = vec![[0.0f32; 2]; n];
    let mut out = vec![[0.0f32; 2]; n];
    let mut steps = 4u64;
    loop {
        let t0 = Instant::now();
        for _ in 0..steps {
            cpu_step(nx, nz, 1e-3, &u, &mut v, &mut out);
            std::mem::swap(&mut u, &mut out);
        }
        let dt = t0.elapsed().as_secs_f64();
        std::hint::black_box(&u);
        if dt > 1.0 {
            return steps as f64 * n as f64 / dt;
        }
        steps *= 4;
    }
}

/// Block-steps/s of slipfront's own CPU f32 engine (one thread) on the
/// throughput bench's scene of this size, driven so junctions rupture.
fn model_engine_rate(nx: u32, nz: u32) -> f64 {
    let model = scene(nx, nz);
    let mut engine = make_engine(&model, Backend::Cpu, Precision::F32, 1).expect("cpu engine");
    advance_to(engine.as_mut(), model.prep_steps + 10).expect("prepare");
    let mut steps = 16u64;
    loop {
        let start = engine.steps_done();
        let t0 = Instant::now();
        advance_to(engine.as_mut(), start + steps).expect("run");
        let dt = t0.elapsed().as_secs_f64();
        if dt > 1.5 {
            return steps as f64 * model.n_blocks() as f64 / dt;
        }
        steps *= 4;
    }
}

struct Pair {
    u: [wgpu::Buffer; 2],
    v: [wgpu::Buffer; 2],
}

/// What runs on the adapter: the WGSL, its workgroups per dispatch, the
/// steps one dispatch makes, and whether dispatches alternate the state
/// copies (one step each) or the shader does it (persistent).
struct Shape {
    source: String,
    workgroups: u32,
    steps_per_dispatch: u64,
    alternate: bool,
}

fn gpu_rate(ctx: &context::GpuContext, nx: u32, nz: u32, shape: &Shape) -> f64 {
    let device = &ctx.device;
    let n = (nx * nz) as usize;
    let init: Vec<[f32; 2]> = (0..n).map(|i| [1e-3 * (i % 7) as f32, 0.0]).collect();
    let storage = |label: &str| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(&init),
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let bufs = Pair {
        u: [storage("u0"), storage("u1")],
        v: [storage("v0"), storage("v1")],
    };
    let params: [u32; 4] = [nx, nz, 1e-3f32.to_bits(), 0];
    let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("params"),
        contents: bytemuck::cast_slice(&params),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("stencil"),
        source: wgpu::ShaderSource::Wgsl(shape.source.as_str().into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("stencil"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let layout = pipeline.get_bind_group_layout(0);
    let group = |from: usize| {
        let to = 1 - from;
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: bufs.u[from].as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: bufs.v[from].as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: bufs.u[to].as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: bufs.v[to].as_entire_binding(),
                },
            ],
        })
    };
    let groups = [group(0), group(1)];
    let run = |steps: u64| {
        let dispatches = steps.div_ceil(shape.steps_per_dispatch);
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &groups[0], &[]);
            for d in 0..dispatches {
                if shape.alternate {
                    pass.set_bind_group(0, &groups[(d % 2) as usize], &[]);
                }
                pass.dispatch_workgroups(shape.workgroups, 1, 1);
            }
        }
        ctx.queue.submit([encoder.finish()]);
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("poll");
    };
    run(4); // compile and warm up
    let mut steps = shape.steps_per_dispatch.max(8);
    loop {
        steps = steps.div_ceil(shape.steps_per_dispatch) * shape.steps_per_dispatch;
        let t0 = Instant::now();
        run(steps);
        let dt = t0.elapsed().as_secs_f64();
        if dt > 1.5 || steps >= 1 << 20 {
            return steps as f64 * n as f64 / dt;
        }
        steps *= if dt < 0.1 { 8 } else { 2 };
    }
}

fn main() {
    let sizes: Vec<(u32, u32)> = {
        let picked: Vec<(u32, u32)> = std::env::args()
            .skip(1)
            .filter_map(|a| {
                let (x, z) = a.split_once('x')?;
                Some((x.parse().ok()?, z.parse().ok()?))
            })
            .collect();
        if picked.is_empty() {
            vec![(57, 31), (1024, 256)]
        } else {
            picked
        }
    };
    let ctx = context::shared().expect("a GPU adapter (lavapipe or hardware)");
    println!("adapter: {}", ctx.describe());
    println!("| lattice | stencil | cell-updates/s | against one Rust thread |");
    println!("| --- | --- | ---: | ---: |");
    for (nx, nz) in sizes {
        let cpu = cpu_rate(nx as usize, nz as usize);
        println!("| {nx}×{nz} | CPU, one Rust thread | {cpu:.3e} | 1 |");
        for (cells, window) in [
            (1, false),
            (4, false),
            (16, false),
            (4, true),
            (16, true),
            (57, true),
        ] {
            let shape = Shape {
                source: shader(cells, window),
                workgroups: (nx.div_ceil(cells) * nz).div_ceil(WORKGROUP),
                steps_per_dispatch: 1,
                alternate: true,
            };
            let rate = gpu_rate(&ctx, nx, nz, &shape);
            let form = if window {
                "sliding window"
            } else {
                "independent"
            };
            println!(
                "| {nx}×{nz} | GPU, 1 dispatch per step, {cells} cell(s) per thread, {form} | {rate:.3e} | {:.3} |",
                rate / cpu
            );
        }
        // One workgroup holds the lattice only when it is small.
        if nx * nz <= 8192 {
            let steps = 64;
            let shape = Shape {
                source: persistent_shader(steps),
                workgroups: 1,
                steps_per_dispatch: steps as u64,
                alternate: false,
            };
            let rate = gpu_rate(&ctx, nx, nz, &shape);
            println!(
                "| {nx}×{nz} | GPU, persistent: one workgroup of {PERSISTENT}, {steps} steps per dispatch | {rate:.3e} | {:.3} |",
                rate / cpu
            );
        }
        let model = model_engine_rate(nx, nz);
        println!(
            "| {nx}×{nz} | slipfront's CPU f32 engine on the full model, one thread | {model:.3e} | {:.3} |",
            model / cpu
        );
    }
}
