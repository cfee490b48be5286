//! The GPU engine: state in storage buffers, one WGSL kernel per phase, many
//! steps encoded in one compute pass and one submit. The host writes the
//! loads of each step (a pure function of the step count, computed by
//! `step_params` as on the CPU) into a dynamically offset storage buffer and reads the
//! state back only when a snapshot is asked for.

pub mod context;
pub mod layout;
pub mod shaders;

use crate::engine::{blow_up, Engine, EngineError, Snapshot};
use crate::lattice::{block_flags, initial_displacement};
use crate::model::{Driver, Model};
use crate::real::{Coordinate, DoubleSingle};
use crate::step_params::{step_params, Consts};
use bytemuck::Zeroable;
use context::GpuContext;
use layout::{GpuConsts, GpuJunctionSpring, GpuStep};
use shaders::{Phase, Variant};
use wgpu::util::DeviceExt;

/// Steps encoded per submit.
const STEPS_PER_SUBMIT: u64 = 1024;
const WORKGROUP: u32 = 64;

struct Pipeline {
    pipeline: wgpu::ComputePipeline,
    /// Workgroups (x, y) for the phase's thread count.
    groups: (u32, u32),
}

/// The storage buffers, in binding order 1..=8.
struct StateBuffers {
    disp: wgpu::Buffer,
    vel: wgpu::Buffer,
    force: wgpu::Buffer,
    flags: wgpu::Buffer,
    contact: wgpu::Buffer,
    junction_spring: wgpu::Buffer,
    junction_state: wgpu::Buffer,
    slide: wgpu::Buffer,
}

pub struct GpuEngine {
    model: Model,
    consts: Consts<f32>,
    ctx: GpuContext,
    buffers: StateBuffers,
    step_buffer: wgpu::Buffer,
    step_stride: u64,
    state_group: wgpu::BindGroup,
    step_group: wgpu::BindGroup,
    pipelines: Vec<Pipeline>,
    variant: Variant,
    drive_origin: DoubleSingle,
    step: u64,
    staging: Vec<u8>,
}

fn groups_for(threads: usize) -> (u32, u32) {
    let groups = (threads as u32).div_ceil(WORKGROUP).max(1);
    let x = groups.min(65_535);
    (x, groups.div_ceil(x))
}

impl GpuEngine {
    /// Builds the engine on the best adapter (hardware, else lavapipe).
    pub fn new(model: &Model) -> Result<GpuEngine, EngineError> {
        GpuEngine::with_context(model, context::shared()?)
    }

    pub fn with_context(model: &Model, ctx: GpuContext) -> Result<GpuEngine, EngineError> {
        let consts = Consts::<f32>::new(model);
        let n = model.n_blocks();
        let nj = model.n_junctions();
        let limit = ctx.limits.max_storage_buffer_binding_size;
        let max_buffer = ctx.limits.max_buffer_size;
        for (name, bytes) in [
            ("block displacement", n as u64 * 16),
            ("junction spring", nj as u64 * 12),
        ] {
            if bytes > limit.min(max_buffer) {
                return Err(EngineError::Gpu(format!(
                    "the {name} buffer needs {bytes} bytes but {} allows at most {} per \
                     storage binding: use a smaller lattice or fewer junctions",
                    ctx.info.name,
                    limit.min(max_buffer)
                )));
            }
        }
        let device = &ctx.device;
        let storage = |label: &str, bytes: &[u8]| {
            // Zero-sized bindings are invalid: pad empty arrays to one element.
            let padded;
            let contents = if bytes.is_empty() {
                padded = vec![0u8; 48]; // a whole number of every element size
                &padded[..]
            } else {
                bytes
            };
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
            })
        };
        let disp: Vec<[DoubleSingle; 2]> = initial_displacement(model)
            .into_iter()
            .map(|u| u.map(DoubleSingle::from_f64))
            .collect();
        let zeros2 = |len: usize| vec![[0f32; 2]; len];
        let buffers = StateBuffers {
            disp: storage("disp", bytemuck::cast_slice(&disp)),
            vel: storage("vel", bytemuck::cast_slice(&zeros2(n))),
            force: storage("force", bytemuck::cast_slice(&zeros2(n))),
            flags: storage("flags", bytemuck::cast_slice(&block_flags(model))),
            contact: storage("contact", bytemuck::cast_slice(&zeros2(model.nx))),
            junction_spring: storage(
                "junction_spring",
                bytemuck::cast_slice(&vec![GpuJunctionSpring::zeroed(); nj]),
            ),
            junction_state: storage(
                "junction_state",
                bytemuck::cast_slice(&vec![[crate::cpu::PINNED, 0u32]; nj]),
            ),
            slide: storage("slide", bytemuck::cast_slice(&vec![[0i32; 2]; model.nx])),
        };
        let gpu_consts = GpuConsts::new(&consts, model.pressure_wave_speed() as f32);
        let consts_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("consts"),
            contents: bytemuck::bytes_of(&gpu_consts),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let step_stride = (ctx.limits.min_storage_buffer_offset_alignment as u64).max(256);
        let step_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("step loads"),
            size: step_stride * (STEPS_PER_SUBMIT + 1),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let b = &buffers;
        let state_buffers = [
            &consts_buffer,
            &b.disp,
            &b.vel,
            &b.force,
            &b.flags,
            &b.contact,
            &b.junction_spring,
            &b.junction_state,
            &b.slide,
        ];
        let bind_entries: Vec<wgpu::BindGroupEntry> = state_buffers
            .iter()
            .enumerate()
            .map(|(i, buf)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: buf.as_entire_binding(),
            })
            .collect();
        let state_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("state"),
            layout: &ctx.state_layout,
            entries: &bind_entries,
        });
        let step_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("step"),
            layout: &ctx.step_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &step_buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(context::STEP_LOADS_SIZE),
                }),
            }],
        });
        let variant = Variant::for_model(model);
        let mut pipelines = Vec::new();
        for (phase, constants) in &variant.phases {
            let pipeline = ctx.pipeline(*phase, constants);
            let threads = match phase {
                Phase::BulkForces | Phase::Verlet => n,
                Phase::Junctions | Phase::Coulomb => model.nx,
            };
            pipelines.push(Pipeline {
                pipeline,
                groups: groups_for(threads),
            });
        }
        ctx.check()?;
        let mut engine = GpuEngine {
            model: model.clone(),
            consts,
            ctx,
            buffers,
            step_buffer,
            step_stride,
            state_group,
            step_group,
            pipelines,
            variant,
            drive_origin: DoubleSingle::default(),
            step: 0,
            staging: vec![0u8; step_stride as usize * (STEPS_PER_SUBMIT as usize + 1)],
        };
        if model.prep_steps == 0 {
            engine.begin_driving()?;
        }
        engine.force_pass()?;
        Ok(engine)
    }

    /// Seconds per dispatch of each phase, each timed alone: `dispatches`
    /// dispatches of one pipeline in one pass and submit, waited for. The
    /// state is left meaningless (phases run out of order): use a throwaway
    /// engine.
    pub fn profile_phases(
        &mut self,
        dispatches: u32,
    ) -> Result<Vec<(&'static str, f64)>, EngineError> {
        let loads = GpuStep::new(
            &step_params(&self.consts, self.model.prep_steps),
            DoubleSingle::default(),
        );
        self.ctx
            .queue
            .write_buffer(&self.step_buffer, 0, bytemuck::bytes_of(&loads));
        let mut out = Vec::new();
        for (p, (phase, _)) in self.pipelines.iter().zip(&self.variant.phases) {
            let run = |n: u32| -> Result<f64, EngineError> {
                let start = std::time::Instant::now();
                let mut encoder = self
                    .ctx
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
                {
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("profile"),
                        timestamp_writes: None,
                    });
                    pass.set_bind_group(0, &self.state_group, &[]);
                    pass.set_bind_group(1, &self.step_group, &[0]);
                    pass.set_pipeline(&p.pipeline);
                    for _ in 0..n {
                        pass.dispatch_workgroups(p.groups.0, p.groups.1, 1);
                    }
                }
                self.ctx.queue.submit([encoder.finish()]);
                self.ctx
                    .device
                    .poll(wgpu::PollType::wait_indefinitely())
                    .map_err(|e| EngineError::Gpu(format!("device lost: {e}")))?;
                Ok(start.elapsed().as_secs_f64())
            };
            run(2)?; // warm-up
            out.push((phase.entry_point(), run(dispatches)? / dispatches as f64));
        }
        self.ctx.check()?;
        Ok(out)
    }

    /// The pipelines this scene built.
    pub fn variant(&self) -> &Variant {
        &self.variant
    }

    pub fn adapter(&self) -> String {
        self.ctx.describe()
    }

    /// Writes the loads of steps `first .. first + count` to the step
    /// buffer, one per stride.
    fn write_loads(&mut self, first: u64, count: u64) {
        for i in 0..count {
            let loads = GpuStep::new(&step_params(&self.consts, first + i), self.drive_origin);
            let at = (i * self.step_stride) as usize;
            self.staging[at..at + std::mem::size_of::<GpuStep>()]
                .copy_from_slice(bytemuck::bytes_of(&loads));
        }
        let bytes = (count * self.step_stride) as usize;
        self.ctx
            .queue
            .write_buffer(&self.step_buffer, 0, &self.staging[..bytes]);
    }

    /// Bulk forces and friction at the current state and step (at the
    /// start, and when driving starts).
    fn force_pass(&mut self) -> Result<(), EngineError> {
        self.write_loads(self.step, 1);
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("forces"),
            });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("forces"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, &self.state_group, &[]);
            pass.set_bind_group(1, &self.step_group, &[0]);
            dispatch(&mut pass, &self.pipelines[..self.pipelines.len() - 1]);
        }
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.check()
    }

    /// Once, when driving starts: fixes the driver origin and applies the
    /// trigger's initial junction forces (host code shared with the CPU).
    fn begin_driving(&mut self) -> Result<(), EngineError> {
        let snap = self.snapshot()?;
        if let Driver::SideSpring { row, .. } = self.model.driver {
            self.drive_origin = DoubleSingle::from_f64(snap.disp[row * self.model.nx][0]);
        }
        if self.model.trigger.is_some() {
            let anchors = crate::trigger::trigger_anchors(&self.model, &snap);
            let spring: Vec<GpuJunctionSpring> = anchors
                .iter()
                .zip(&snap.junction_stiffness)
                .map(|(a, k)| GpuJunctionSpring {
                    anchor: DoubleSingle::from_f64(*a),
                    stiffness: *k as f32,
                })
                .collect();
            self.ctx.queue.write_buffer(
                &self.buffers.junction_spring,
                0,
                bytemuck::cast_slice(&spring),
            );
        }
        Ok(())
    }

    /// Copies `buffers` into one staging buffer with one submit and one
    /// wait, and returns each buffer's bytes.
    fn read_buffers(&self, buffers: &[&wgpu::Buffer]) -> Result<Vec<Vec<u8>>, EngineError> {
        let total: u64 = buffers.iter().map(|b| b.size()).sum();
        let staging = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: total,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        let mut offset = 0;
        for b in buffers {
            encoder.copy_buffer_to_buffer(b, 0, &staging, offset, b.size());
            offset += b.size();
        }
        self.ctx.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.ctx
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| EngineError::Gpu(format!("device lost while reading back: {e}")))?;
        rx.recv()
            .map_err(|e| EngineError::Gpu(format!("readback: {e}")))?
            .map_err(|e| EngineError::Gpu(format!("readback: {e}")))?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| EngineError::Gpu(format!("readback: {e}")))?
            .to_vec();
        staging.unmap();
        self.ctx.check()?;
        let mut out = Vec::with_capacity(buffers.len());
        let mut at = 0usize;
        for b in buffers {
            let size = b.size() as usize;
            out.push(data[at..at + size].to_vec());
            at += size;
        }
        Ok(out)
    }
}

fn dispatch(pass: &mut wgpu::ComputePass<'_>, pipelines: &[Pipeline]) {
    for p in pipelines {
        pass.set_pipeline(&p.pipeline);
        pass.dispatch_workgroups(p.groups.0, p.groups.1, 1);
    }
}

fn cast_prefix<T: bytemuck::Pod>(bytes: &[u8], len: usize) -> Vec<T> {
    bytemuck::cast_slice::<u8, T>(bytes)[..len].to_vec()
}

impl Engine for GpuEngine {
    fn model(&self) -> &Model {
        &self.model
    }

    fn steps_done(&self) -> u64 {
        self.step
    }

    fn advance(&mut self, n: u64) -> Result<(), EngineError> {
        let prep = self.model.prep_steps;
        let mut left = n;
        while left > 0 {
            // A submit never crosses the start of driving: the forces of
            // that step wait for the driver origin and trigger.
            let mut k = left.min(STEPS_PER_SUBMIT);
            if self.step < prep {
                k = k.min(prep - self.step);
            }
            // Step i's update uses the loads of step + i, the force pass
            // after it those of step + i + 1.
            self.write_loads(self.step, k + 1);
            let mut encoder =
                self.ctx
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("steps"),
                    });
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("steps"),
                    timestamp_writes: None,
                });
                pass.set_bind_group(0, &self.state_group, &[]);
                let (forces, verlet) = self.pipelines.split_at(self.pipelines.len() - 1);
                for i in 0..k {
                    pass.set_bind_group(1, &self.step_group, &[(i * self.step_stride) as u32]);
                    dispatch(&mut pass, verlet);
                    if self.step + i + 1 != prep {
                        let at = ((i + 1) * self.step_stride) as u32;
                        pass.set_bind_group(1, &self.step_group, &[at]);
                        dispatch(&mut pass, forces);
                    }
                }
            }
            self.ctx.queue.submit([encoder.finish()]);
            self.step += k;
            left -= k;
            if self.step == prep {
                self.begin_driving()?;
                self.force_pass()?;
            }
        }
        self.ctx.check()
    }

    fn snapshot(&mut self) -> Result<Snapshot, EngineError> {
        let m = &self.model;
        let (n, nj) = (m.n_blocks(), m.n_junctions());
        let b = &self.buffers;
        let raw = self.read_buffers(&[
            &b.disp,
            &b.vel,
            &b.force,
            &b.contact,
            &b.junction_spring,
            &b.junction_state,
            &b.slide,
        ])?;
        let disp: Vec<[DoubleSingle; 2]> = cast_prefix(&raw[0], n);
        let vel: Vec<[f32; 2]> = cast_prefix(&raw[1], n);
        let force: Vec<[f32; 2]> = cast_prefix(&raw[2], n);
        let contact: Vec<[f32; 2]> = cast_prefix(&raw[3], m.nx);
        let spring: Vec<crate::cpu::JunctionSpring<DoubleSingle, f32>> =
            cast_prefix::<GpuJunctionSpring>(&raw[4], nj)
                .into_iter()
                .map(Into::into)
                .collect();
        let state: Vec<[u32; 2]> = cast_prefix(&raw[5], nj);
        let slide: Vec<[i32; 2]> = cast_prefix(&raw[6], m.nx);
        let limit = m.pressure_wave_speed();
        let snap = Snapshot::from_buffers(
            m, self.step, &disp, &vel, &force, &contact, &spring, &state, &slide,
        );
        // Blow-ups are found at readbacks (the GPU never stops to check).
        if let Some(i) = (0..n).find(|&i| {
            let (u, v) = (snap.disp[i], snap.vel_half[i]);
            !(u[0].is_finite() && u[1].is_finite() && v[0].abs() <= limit && v[1].abs() <= limit)
        }) {
            return Err(blow_up(m, self.step, i, snap.disp[i], snap.vel_half[i]));
        }
        Ok(snap)
    }

    fn describe(&self) -> String {
        format!(
            "gpu f32 mixed (f32+f32 coordinates) on {}",
            self.ctx.describe()
        )
    }
}
