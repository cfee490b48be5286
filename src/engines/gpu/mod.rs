//! The GPU engine: state in storage buffers, and one of three kernels:
//!
//! - `one_step` (any lattice): one dispatch per step, forces, friction and
//!   the leapfrog update fused, reading the state of step n from one buffer
//!   pair and writing step n+1 to the other (and its form with junction
//!   lanes, `one_step_lanes`);
//! - `persistent_steps` (small lattices): one workgroup loops over up to
//!   4096 steps inside one dispatch, with barriers between the phases; its
//!   resident form holds u and v in workgroup memory for the whole
//!   dispatch (lattices that fit it);
//! - `tiled_steps` (small lattices, `tiles`): a workgroup per column tile
//!   steps its tile and a halo for a few steps per dispatch, leaving the
//!   state where the one-step kernel would.
//!
//! Steps go in batches (one submit each, `batches`) whose loads the
//! kernels compute from the batch's first step. After each batch the kernel's blow-up
//! status is copied to a staging buffer and mapped asynchronously; at most
//! `IN_FLIGHT` batches are queued, so a blow-up stops the run within a
//! batch or two and `advance` returns only when its steps have run. A
//! runner that writes output asks it to run ahead (`Engine::run_ahead`):
//! `advance` then returns with up to `GpuOptions::run_ahead` batches still
//! running, whose samples and blow-ups the next call reports, so the
//! device works while the host writes; whatever reads or writes the state
//! waits for them first.
//!
//! The engine computes in mixed f32 (`GpuEngine`, every adapter) or in f64
//! (`GpuEngine::<f64>`, adapters with SHADER_F64): the same kernels,
//! generated in either precision (`precision`, `shaders`).
//!
//! The same engine steps an ensemble (`ensemble`): many scenes of one
//! lattice shape in one dispatch, each with its own constants, batch and
//! slice of every buffer (`scene_state`); `lockstep` hands its scenes to
//! separate runners. A solo run is an ensemble of one: the same compiled
//! kernels, so a scene's bits do not depend on the scenes beside it.

mod arena;
mod batch_sizes;
mod batches;
mod bindings;
mod buffers;
pub mod compile;
pub mod context;
mod device_timer;
pub mod driver_stats;
pub mod ensemble;
pub mod kernel_choice;
pub mod layout;
pub mod lockstep;
mod loop_budget;
pub mod options;
pub mod phase_clocks;
pub mod precision;
pub mod readback;
mod recorder;
mod scene_state;
pub mod shaders;
pub mod spirv;
mod step_kernel;
pub mod tiles;

use crate::engines::step_params::Consts;
use crate::engines::{
    Engine, EngineError, EngineState, PlannedAndComputed, Sample, SamplePlan, Snapshot,
};
use crate::model::real::precision_name;
use crate::model::scenario::FrictionLaw;
use crate::model::Model;
use arena::Region;
use batch_sizes::*;
use buffers::{state_group, Buffers, Shape};
use compile::{KernelBuild, KernelSource};
use context::GpuContext;
pub use device_timer::DispatchTimes;
use layout::GpuJunctionSpring;
use options::*;
pub use options::{
    Arithmetic, GpuOptions, GpuOutput, GpuPath, PERSISTENT_THREADS, RESIDENT_THREADS,
};
pub use precision::GpuReal;
use precision::{Coord, Packed};
pub use step_kernel::AdapterTraits;
use step_kernel::{kernel_sources, KernelPlan};

use shaders::{Kernel, LaneMerge, Variant};
use std::collections::VecDeque;

/// Group 1 of `kernel`: the step offset (dynamic) and the scenes' batches.
fn batch_group(ctx: &GpuContext, kernel: Kernel, b: &Buffers) -> wgpu::BindGroup {
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("batch"),
        layout: &ctx.batch_layout,
        entries: &ctx.bindings(kernel).entries(
            1,
            &[
                (context::STEP_OFFSET, b.step_offsets.head_binding(4)),
                ("batch", b.batches.binding()),
                ("scene_batches", b.batches.binding()),
            ],
        ),
    })
}

/// One scene: its model, constants and where it stands.
struct Scene<T: GpuReal> {
    model: Model,
    consts: Consts<T>,
    drive_origin: Coord<T>,
    /// `force` and `contact` hold the forces of the current state.
    forces_ready: bool,
    /// The blow-up that stopped this scene (an ensemble's others go on).
    failure: Option<EngineError>,
}

/// The entry point of the tiled and one-step kernels' modules that
/// finishes a batch's samples (shaders/record_batch.wgsl).
const RECORD_BATCH_FINISH: &str = "record_batch_finish";

/// The tiled kernel's tiles and its entry point besides its steps.
struct TiledKernel {
    geometry: tiles::TileGeometry,
    /// The halo gather, dispatched before a batch's first dispatch.
    gather: wgpu::ComputePipeline,
}

/// The GPU engine over one scene (`GpuEngine::new`), or over an ensemble of
/// scenes of one lattice shape stepped together (`ensemble::GpuEnsemble`),
/// computing in `T`: f32 (mixed, double-single coordinates) or f64.
pub struct GpuEngine<T: GpuReal = f32> {
    scenes: Vec<Scene<T>>,
    /// Steps an ensemble: a scene's blow-up stops only that scene, and
    /// output samples come from host snapshots.
    ensemble: bool,
    shape: Shape,
    ctx: GpuContext,
    buffers: Buffers,
    kernel: Kernel,
    /// Its bulk forces by 2×2 patches (`GpuOptions::bond_patches`).
    bond_patches: bool,
    pipeline: wgpu::ComputePipeline,
    /// The tiled kernel's tiles and its other entry points.
    tiles: Option<TiledKernel>,
    /// The tiled kernel's rounds chained in one dispatch, and how.
    chain: Option<tiles::TileChain>,
    /// Both state copies (one step) or copy 0 (persistent).
    state_group: wgpu::BindGroup,
    batch_group: wgpu::BindGroup,
    /// Workgroups (x, y) of a one-step dispatch of one scene.
    groups: (u32, u32),
    /// The workgroups of a one-step dispatch of one scene that hold
    /// blocks (the rest of `groups`' x · y pads it): a sample's partials.
    step_workgroups: u32,
    /// Threads of a persistent, resident or tiled workgroup.
    persistent_threads: u32,
    /// Scenes a persistent workgroup steps, each on
    /// `persistent_threads / group_scenes` threads.
    group_scenes: u32,
    /// Steps per persistent dispatch (bounded on software adapters).
    steps_per_dispatch: u64,
    /// Steps the persistent kernel has been asked to run (mod 2³²).
    persistent_steps: u32,
    variant: Variant,
    /// The step pipeline's override constants (the one-step kernels'
    /// recording variant adds `STEP_RECORDS`; the tiled kernel's,
    /// `TILE_RECORDS`, replaces its pipeline once it records).
    constants: Vec<(&'static str, f64)>,
    /// Where the kernel's junction lanes merge first (`GpuOptions::lane_shuffle`)
    /// and which run-time checks its modules carry (`GpuOptions::shader_checks`).
    build: KernelBuild,
    /// The most lane tree levels a workgroup has merged in subgroups
    /// (`GpuStatus::lane_levels`), over every batch read back.
    lane_levels: u32,
    /// The copy of u and v that holds the current state.
    current: usize,
    /// Steps submitted (every scene is at this step).
    step: u64,
    in_flight: VecDeque<batches::InFlight>,
    /// Batches `advance` may leave running (0: it waits for all).
    lead: usize,
    /// What `run_ahead` sets `lead` to (`GpuOptions::run_ahead`).
    run_ahead_batches: usize,
    spare_staging: Vec<wgpu::Buffer>,
    /// Each batch's pass timed on the device, where the adapter can.
    timer: Option<device_timer::DeviceTimer>,
    /// Dispatches that stepped the lattice (forces-only passes included).
    dispatches: u64,
    /// Dispatches that only record output (the batches' record finishes).
    output_dispatches: u64,
    /// Where output samples are made (the option).
    output: GpuOutput,
    /// Output samples recorded on the device, scene by scene.
    recorder: Option<recorder::Recorder<T>>,
    /// The one-step kernel's recording variant (`STEP_RECORDS`), for the
    /// step dispatches of samples.
    record_step: Option<wgpu::ComputePipeline>,
    /// After a batch's steps, where the kernel records in partials (the
    /// tiled and one-step kernels): each sample's partials added, and
    /// which samples were due decided in order (the fast cadence).
    record_finish: Option<wgpu::ComputePipeline>,
    /// Samples read back and not yet taken.
    samples: Vec<Vec<Sample>>,
    /// Why `auto` took this kernel, when it measured.
    choice: Option<kernel_choice::KernelChoice>,
}

/// The mixed-precision engine (every adapter).
impl GpuEngine {
    /// Builds the engine on the best adapter (hardware, else lavapipe).
    pub fn new(model: &Model) -> Result<GpuEngine, EngineError> {
        GpuEngine::with_options(model, GpuOptions::default())
    }

    pub fn with_options(model: &Model, opts: GpuOptions) -> Result<GpuEngine, EngineError> {
        GpuEngine::with_context(model, context::shared()?, opts)
    }

    pub fn with_context(
        model: &Model,
        ctx: GpuContext,
        opts: GpuOptions,
    ) -> Result<GpuEngine, EngineError> {
        GpuEngine::with_precision_and_context(model, ctx, opts)
    }
}

impl<T: GpuReal> GpuEngine<T> {
    const DISP_BYTES: usize = std::mem::size_of::<[Coord<T>; 2]>();
    const REAL_PAIR_BYTES: usize = std::mem::size_of::<[T; 2]>();
    const PACKED_BYTES: usize = std::mem::size_of::<Packed<T>>();
    const SPRING_BYTES: usize = std::mem::size_of::<GpuJunctionSpring<T>>();
    const SUMS_BYTES: usize = std::mem::size_of::<layout::GpuSampleSums<T>>();

    /// The buffers that grow fastest with the lattice, and their bytes per
    /// scene: an ensemble holds every scene's part of each in one binding.
    fn largest_buffers(model: &Model) -> [(&'static str, usize); 2] {
        let shape = Shape::of(model);
        [
            ("block displacement", shape.blocks * Self::DISP_BYTES),
            ("junction spring", shape.junctions * Self::SPRING_BYTES),
        ]
    }

    /// The most bytes one storage binding may hold on an adapter.
    fn binding_limit(limits: &wgpu::Limits) -> u64 {
        limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
    }

    /// The most scenes like `model` that one ensemble can hold on an
    /// adapter with `limits` (at least 1: a scene alone that does not fit
    /// fails at build, saying which buffer).
    pub fn scenes_that_fit(model: &Model, limits: &wgpu::Limits) -> usize {
        let limit = Self::binding_limit(limits);
        Self::largest_buffers(model)
            .iter()
            .filter(|(_, bytes)| *bytes > 0)
            .map(|(_, bytes)| (limit / *bytes as u64) as usize)
            .min()
            .unwrap_or(usize::MAX)
            .max(1)
    }

    /// The engine in precision `T` (`GpuEngine::<f64>::with_precision`) on
    /// the best adapter; f64 fails on an adapter without SHADER_F64.
    pub fn with_precision(model: &Model, opts: GpuOptions) -> Result<GpuEngine<T>, EngineError> {
        GpuEngine::with_precision_and_context(model, context::shared()?, opts)
    }

    /// The engine of one scene; `auto` on a hardware adapter (and
    /// `measure` anywhere) first times the kernels on this scene
    /// (`kernel_choice`).
    pub fn with_precision_and_context(
        model: &Model,
        ctx: GpuContext,
        opts: GpuOptions,
    ) -> Result<GpuEngine<T>, EngineError> {
        ctx.check_precision::<T>()?;
        let cache = kernel_choice::ChoiceCache::default_location();
        let (opts, choice) = kernel_choice::resolve::<T>(model, &ctx, opts, &cache)?;
        let mut engine = GpuEngine::build(std::slice::from_ref(model), ctx, opts, false)?;
        engine.choice = choice;
        Ok(engine)
    }

    /// The measured choice behind this engine's kernel, if `auto` measured.
    pub fn kernel_choice(&self) -> Option<&kernel_choice::KernelChoice> {
        self.choice.as_ref()
    }

    /// Fails where one scene-major buffer of `models` is larger than a
    /// storage binding may be, or there are more scenes than workgroups a
    /// dispatch may have in a dimension.
    fn check_bindings(
        models: &[Model],
        ctx: &GpuContext,
        ensemble: bool,
    ) -> Result<(), EngineError> {
        let scene_count = models.len();
        let limit = Self::binding_limit(&ctx.limits);
        let what = if ensemble {
            format!(" of {scene_count} scenes")
        } else {
            String::new()
        };
        for (name, per_scene) in Self::largest_buffers(&models[0]) {
            let bytes = (scene_count * per_scene) as u64;
            if bytes > limit {
                return Err(EngineError::Gpu(format!(
                    "the {name} buffer{what} needs {bytes} bytes but {} allows at most {limit} per \
                     storage binding: use a smaller lattice{}",
                    ctx.info.name,
                    if ensemble {
                        ", fewer junctions or fewer scenes"
                    } else {
                        " or fewer junctions"
                    }
                )));
            }
        }
        let max_groups = ctx.limits.max_compute_workgroups_per_dimension as usize;
        if scene_count > max_groups {
            return Err(EngineError::Gpu(format!(
                "{scene_count} scenes in one dispatch: {} allows at most {max_groups}",
                ctx.info.name
            )));
        }
        Ok(())
    }

    /// The sources of the pipelines `model` would step with under `opts` on
    /// an adapter like `adapter` (what `kernel_sources` gives of an engine
    /// built there), without a device: for asking another device's
    /// compiler (`driver_stats`).
    pub fn kernel_sources_on(
        model: &Model,
        opts: GpuOptions,
        adapter: &AdapterTraits,
    ) -> Result<Vec<KernelSource>, EngineError> {
        let plan = step_kernel::plan::<T>(model, opts, adapter)?;
        let k = plan.step_kernel.kernel;
        Ok(kernel_sources::<T>(
            k,
            plan.build,
            plan.step_kernel.geometry.is_some(),
            &plan.constants,
        ))
    }

    /// The engine over `models`, which share one lattice shape and time
    /// schedule (checked by the caller), with the same kernels for one
    /// scene or many; `ensemble`: a blow-up stops only its scene.
    fn build(
        models: &[Model],
        ctx: GpuContext,
        opts: GpuOptions,
        ensemble: bool,
    ) -> Result<GpuEngine<T>, EngineError> {
        ctx.check_precision::<T>()?;
        let model = &models[0];
        let scene_count = models.len();
        let shape = Shape::of(model);
        Self::check_bindings(models, &ctx, ensemble)?;
        let KernelPlan {
            step_kernel,
            variant,
            constants,
            build,
        } = step_kernel::plan::<T>(model, opts, &AdapterTraits::of(&ctx))?;
        let kernel = step_kernel.kernel;
        if step_kernel.chain.is_some() && ctx.is_software() && scene_count > 1 {
            // llvmpipe hands each of its threads a run of a dispatch's
            // workgroups, so two scenes' tiles share a thread and wait on
            // each other's.
            return Err(EngineError::Gpu(format!(
                "{} runs a run of a dispatch's workgroups on each of its threads, so the chained \
                 tiles of {scene_count} scenes would wait on tiles queued behind them: chained \
                 tiles run one scene at a time on a software adapter",
                ctx.info.name
            )));
        }
        let persistent_threads = step_kernel.threads;
        let group_scenes = step_kernel.group_scenes;
        let geometry = step_kernel.geometry;
        let device = &ctx.device;
        let buffers = Buffers::new::<T>(
            device,
            &ctx.limits,
            models,
            shape,
            geometry,
            opts.pack_arrays,
        );
        let placeholders = buffers.record_placeholders.each_ref().map(Region::binding);
        let state_group = state_group(&ctx, kernel, &buffers, placeholders);
        let batch_group = batch_group(&ctx, kernel, &buffers);
        let pipeline = ctx.pipeline::<T>(kernel, build, &constants);
        let tiles = geometry.map(|geometry| {
            let entry = |name| ctx.pipeline_of::<T>(kernel, build, name, &constants);
            TiledKernel {
                geometry,
                gather: entry(
                    kernel
                        .gather_entry_point()
                        .expect("the tiled kernel gathers"),
                ),
            }
        });
        // A device that refused the engine's own SPIR-V just now was given
        // wgpu's modules (`GpuContext::refuse_own_spirv`).
        let build = KernelBuild {
            workgroup_barriers: build.workgroup_barriers && ctx.has_own_spirv(),
            strict_arithmetic: build.strict_arithmetic && ctx.has_own_spirv(),
            ..build
        };
        // Without the engine's own SPIR-V the clock reads nothing.
        if build.phase_clocks && !ctx.has_own_spirv() {
            return Err(EngineError::Gpu(format!(
                "GPU option phase_clocks: {} refused the engine's own SPIR-V ({}), so its \
                 kernels cannot read the clock",
                ctx.info.name,
                ctx.own_spirv_refused().unwrap_or_default()
            )));
        }
        let groups = step_kernel.groups(model);
        let step_workgroups = step_kernel.workgroups(model);
        let steps_per_dispatch = match geometry {
            Some(g) => g.halo as u64,
            None => opts
                .steps_per_dispatch
                .unwrap_or_else(|| {
                    persistent_steps_per_dispatch(
                        model,
                        kernel,
                        step_kernel.scene_threads(),
                        opts.lane_run,
                        ctx.is_software(),
                    )
                })
                .clamp(1, PERSISTENT_BATCH),
        };
        ctx.check()?;
        let scenes = models
            .iter()
            .map(|m| Scene {
                model: m.clone(),
                consts: Consts::<T>::new(m),
                drive_origin: Coord::<T>::default(),
                forces_ready: false,
                failure: None,
            })
            .collect();
        let timer = device_timer::DeviceTimer::new(&ctx);
        let mut engine = GpuEngine {
            scenes,
            ensemble,
            shape,
            ctx,
            buffers,
            kernel,
            bond_patches: step_kernel.bond_patches,
            pipeline,
            tiles,
            chain: step_kernel.chain,
            state_group,
            batch_group,
            groups,
            step_workgroups,
            persistent_threads,
            group_scenes,
            steps_per_dispatch,
            persistent_steps: 0,
            variant,
            constants,
            build,
            lane_levels: 0,
            current: 0,
            step: 0,
            in_flight: VecDeque::new(),
            lead: 0,
            run_ahead_batches: opts.run_ahead,
            spare_staging: Vec::new(),
            timer,
            dispatches: 0,
            output_dispatches: 0,
            output: opts.output,
            recorder: None,
            record_step: None,
            record_finish: None,
            samples: vec![Vec::new(); scene_count],
            choice: None,
        };
        if model.prep_steps == 0 {
            engine.begin_driving()?;
        }
        Ok(engine)
    }

    /// The override constants this scene compiled with.
    pub fn variant(&self) -> &Variant {
        &self.variant
    }

    /// The kernel that steps this scene.
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// The tiled kernel's tiles (None for the other kernels).
    pub fn tile_geometry(&self) -> Option<tiles::TileGeometry> {
        self.tiles.as_ref().map(|t| t.geometry)
    }

    /// The tiled kernel's chain of rounds a dispatch, where chained.
    pub fn tile_chain(&self) -> Option<tiles::TileChain> {
        self.chain
    }

    /// Whether this engine runs on a software adapter (lavapipe).
    pub fn is_software(&self) -> bool {
        self.ctx.is_software()
    }

    pub fn adapter(&self) -> String {
        self.ctx.describe()
    }

    /// The sources of the pipelines this engine steps with, as it gave them
    /// to wgpu: the step kernel, and the tiled kernel's halo gather. Output
    /// kernels are not among them.
    pub fn kernel_sources(&self) -> Vec<KernelSource> {
        kernel_sources::<T>(
            self.kernel,
            self.build,
            self.tiles.is_some(),
            &self.constants,
        )
    }

    /// The host has the sample of `step` (or it is not one to take).
    fn mark_sampled(&mut self, step: u64) {
        if let Some(rec) = self.recorder.as_mut() {
            rec.recorded_through = Some(step);
        }
    }

    /// Scene `scene`'s output samples from now on recorded on the device,
    /// at `plan`'s cadences (`Engine::record_samples`); false where they
    /// cannot be (then the host takes snapshots). An ensemble records every
    /// scene at the first plan asked for; a scene asking for other
    /// cadences gets false.
    fn record_samples_of(&mut self, scene: usize, plan: &SamplePlan) -> Result<bool, EngineError> {
        // The persistent and tiled kernels record in their steps, each
        // reducing a sample across its workgroup: a power of two of
        // threads (shaders/record_common.wgsl).
        let in_steps = self.kernel.is_persistent() || self.kernel == Kernel::Tiled;
        let reducible = self.scene_threads().is_power_of_two();
        if self.output == GpuOutput::Host || (in_steps && !reducible) {
            return Ok(false);
        }
        // The batches in flight finish first (a blow-up among them is
        // reported here, with its step, not at the next advance).
        self.drain()?;
        if let Some(rec) = self.recorder.as_mut() {
            if !rec.samples_like(plan) {
                return Ok(false);
            }
            rec.set_plan(&self.ctx.queue, scene, plan);
            return Ok(true);
        }
        let models: Vec<Model> = self.scenes.iter().map(|s| s.model.clone()).collect();
        let model = &models[0];
        let site = match (self.kernel, self.tiles.as_ref()) {
            (Kernel::Tiled, Some(tiles)) => recorder::RecordSite::Tiles {
                tiles: tiles.geometry.tiles,
            },
            (k, _) if k.is_persistent() => recorder::RecordSite::Persistent,
            _ => recorder::RecordSite::Steps {
                partials: self.step_workgroups,
            },
        };
        match recorder::Recorder::new(&self.ctx, &models, plan, site, self.buffers.packed) {
            Ok(mut rec) => {
                // The host has taken the samples up to here (none before
                // driving, and none at its first step).
                rec.recorded_through = Some(self.step.max(model.prep_steps));
                let records = rec.state_bindings();
                self.state_group = state_group(&self.ctx, self.kernel, &self.buffers, records);
                let (kernel, build) = (self.kernel, self.build);
                match site {
                    // The one-step kernels' recording variant steps the
                    // samples' steps (shaders/record_step.wgsl).
                    recorder::RecordSite::Steps { .. } => {
                        let constants = step_kernel::step_recording_constants::<T>(&self.constants);
                        self.record_step = Some(self.ctx.pipeline::<T>(kernel, build, &constants));
                    }
                    // The tiled kernel's recording variant steps every
                    // batch from now on (shaders/tiled.wgsl TILE_RECORDS).
                    recorder::RecordSite::Tiles { .. } => {
                        self.constants.push(("TILE_RECORDS", 1.0));
                        self.pipeline = self.ctx.pipeline::<T>(kernel, build, &self.constants);
                    }
                    recorder::RecordSite::Persistent => {}
                }
                // The finish reduces a sample across its workgroup: the
                // one-step kernels' slots are their recording variant's.
                let finish_constants = match site {
                    recorder::RecordSite::Steps { .. } => {
                        Some(step_kernel::step_recording_constants::<T>(&self.constants))
                    }
                    recorder::RecordSite::Tiles { .. } => Some(self.constants.clone()),
                    recorder::RecordSite::Persistent => None,
                };
                self.record_finish = finish_constants.map(|constants| {
                    self.ctx
                        .pipeline_of::<T>(kernel, build, RECORD_BATCH_FINISH, &constants)
                });
                self.recorder = Some(rec);
                Ok(true)
            }
            // Records this adapter cannot hold: host snapshots, the
            // reference path, record the same samples.
            Err(_) => Ok(false),
        }
    }

    /// Scene `scene`'s samples recorded on the device since the last call.
    fn take_samples_of(&mut self, scene: usize) -> Vec<Sample> {
        std::mem::take(&mut self.samples[scene])
    }

    /// Seconds the device has spent in the passes of the batches retired
    /// so far (None where the adapter has no timestamp queries). Against
    /// the wall time of the same steps it says whether the device or the
    /// host set the pace.
    pub fn device_seconds(&self) -> Option<f64> {
        self.timer.as_ref().map(|t| t.busy_seconds())
    }

    /// Levels of the junction lane tree the kernel's workgroups merged in
    /// subgroups in the batches read back so far: 0 where every lane's sum
    /// went through storage (no subgroups, `GpuOptions::lane_shuffle`
    /// false, a one-step kernel, or lanes that do not fit the subgroups),
    /// 3 for runs of 8 lanes (lavapipe), 5 for 32 (NVIDIA).
    pub fn lane_shuffle_levels(&self) -> u32 {
        self.lane_levels
    }

    /// Times each dispatch of the batches from now on, where the adapter
    /// has timestamps inside passes (an attribution for benchmarks: the
    /// timestamps between dispatches add a little device time); whether
    /// it has. Waits for the batches running.
    pub fn time_each_dispatch(&mut self) -> Result<bool, EngineError> {
        self.drain()?;
        let Some(timer) = self.timer.as_mut() else {
            return Ok(false);
        };
        // Status staging buffers grow by the timestamps' room.
        self.spare_staging.clear();
        Ok(timer.time_each_dispatch(&self.ctx))
    }

    /// The device time of the batches retired since `time_each_dispatch`,
    /// split between the step and the output dispatches.
    pub fn dispatch_times(&self) -> Option<DispatchTimes> {
        self.timer.as_ref().and_then(|t| t.dispatch_times())
    }

    /// Whether output samples are recorded on the device.
    pub fn records_on_device(&self) -> bool {
        self.recorder.is_some()
    }

    fn kernel_description(&self) -> String {
        let kernel = self.kernel_alone();
        match &self.choice {
            Some(choice) => format!("{kernel}; auto {}", choice.describe()),
            None => kernel,
        }
    }

    /// The kernel and what else of its launch changes its bits or its
    /// speed: the bulk forces by patches, where the lanes merge, (on
    /// hardware, where it is a choice) the junction lanes a round, and the
    /// junction lanes a thread.
    fn kernel_alone(&self) -> String {
        let mut text = self.kernel_shape();
        if self.bond_patches {
            text.push_str(", bulk forces by 2x2 patches of blocks");
        }
        if self.kernel.merges_lanes_through_storage() && self.build.lanes == LaneMerge::Shuffle {
            text.push_str(", junction lanes merged in subgroups where they fit");
        }
        if self.build.workgroup_barriers {
            text.push_str(", phase barriers at workgroup scope");
        }
        if self.build.phase_clocks {
            text.push_str(", phase clocks");
        }
        if self.build.strict_arithmetic {
            text.push_str(", strict arithmetic (NoContraction)");
        }
        let lanes_a_round = self
            .constants
            .iter()
            .find(|(name, _)| *name == "TWO_LANES_A_ROUND")
            .map(|&(_, v)| v);
        let junctions = matches!(
            self.scenes[0].model.law,
            FrictionLaw::Junctions | FrictionLaw::SingleJunction
        );
        let lane_run = self
            .constants
            .iter()
            .find(|(name, _)| *name == "LANE_RUN")
            .map(|&(_, v)| v as u32);
        if !self.ctx.is_software() && junctions && lane_run == Some(1) {
            match lanes_a_round {
                Some(1.0) => text.push_str(", two junction lanes a round"),
                Some(_) => text.push_str(", one junction lane a round"),
                None => {}
            }
        }
        if let Some(run) = lane_run.filter(|&r| junctions && r > 1) {
            text.push_str(&format!(", {run} junction lanes a thread"));
        }
        text
    }

    /// Threads each scene of a workgroup steps with (the persistent
    /// kernel's grouped scenes share its workgroup's).
    fn scene_threads(&self) -> u32 {
        self.persistent_threads / self.group_scenes
    }

    fn kernel_shape(&self) -> String {
        match self.kernel {
            Kernel::OneStep => "one-step kernel, 1 dispatch per step".to_string(),
            Kernel::OneStepLanes => {
                "one-step kernel with junction lanes, 1 dispatch per step".to_string()
            }
            Kernel::Persistent if self.group_scenes > 1 => format!(
                "persistent kernel, 1 dispatch per {} steps, {} threads: {} scenes a workgroup, \
                 {} threads each",
                self.steps_per_dispatch,
                self.persistent_threads,
                self.group_scenes,
                self.scene_threads()
            ),
            Kernel::Persistent => format!(
                "persistent kernel, 1 dispatch per {} steps, {} threads",
                self.steps_per_dispatch, self.persistent_threads
            ),
            Kernel::Resident => {
                let fit = resident_fit::<T>(&self.scenes[0].model, &self.ctx.limits);
                let held = match fit {
                    Ok(f) if f.velocities => {
                        format!("u and v in {} bytes of workgroup memory", f.bytes)
                    }
                    Ok(f) => format!("u in {} bytes of workgroup memory, v in storage", f.bytes),
                    Err(_) => "u and v in workgroup memory".to_string(),
                };
                format!(
                    "resident kernel ({held}), 1 dispatch per {} steps, {} threads",
                    self.steps_per_dispatch, self.persistent_threads
                )
            }
            Kernel::Tiled => {
                let g = self
                    .tiles
                    .as_ref()
                    .expect("the tiled kernel has tiles")
                    .geometry;
                let per_dispatch = match self.chain {
                    Some(c) => format!(
                        "rounds of up to {} steps chained, up to {} rounds per dispatch",
                        g.halo, c.rounds
                    ),
                    None => format!("up to {} steps per dispatch", g.halo),
                };
                format!(
                    "tiled kernel ({} tiles of {} columns, halo {}, {} bytes of workgroup memory \
                     each), {per_dispatch}, {} threads",
                    g.tiles,
                    g.width,
                    g.halo,
                    g.workgroup_bytes::<T>(),
                    self.persistent_threads
                )
            }
        }
    }
}

impl<T: GpuReal> Engine for GpuEngine<T> {
    fn model(&self) -> &Model {
        &self.scenes[0].model
    }

    fn steps_done(&self) -> u64 {
        self.step
    }

    fn advance(&mut self, n: u64) -> Result<(), EngineError> {
        self.advance_steps(n)
    }

    fn snapshot(&mut self) -> Result<Snapshot, EngineError> {
        self.snapshot_of(0)
    }

    fn set_kinematics(
        &mut self,
        step: u64,
        disp: &[[f64; 2]],
        vel: &[[f64; 2]],
    ) -> Result<(), EngineError> {
        crate::engines::assert_driving_phase(&self.scenes[0].model, self.step, step);
        self.set_kinematics_of(0, disp, vel)?;
        self.step = step;
        self.mark_sampled(step);
        Ok(())
    }

    fn set_junctions(&mut self, snap: &Snapshot) -> Result<(), EngineError> {
        self.set_junctions_of(0, snap)
    }

    fn save_state(&mut self) -> Result<EngineState, EngineError> {
        self.save_state_of(0)
    }

    fn load_state(&mut self, state: &EngineState) -> Result<(), EngineError> {
        self.load_state_of(0, state)?;
        self.step = state.step;
        self.mark_sampled(state.step);
        Ok(())
    }

    fn describe(&self) -> String {
        format!(
            "gpu {}, {}, on {}",
            precision_name::<T, Coord<T>>(),
            self.kernel_description(),
            self.ctx.describe()
        )
    }

    fn dispatches(&self) -> Option<u64> {
        Some(self.dispatches)
    }

    fn output_dispatches(&self) -> Option<u64> {
        Some(self.output_dispatches)
    }

    /// The planned samples read back so far, all scenes, and how many of
    /// them the device computed: the one-step kernels skip those their
    /// fast chain finds cannot be due.
    fn device_samples(&self) -> Option<PlannedAndComputed> {
        self.recorder.as_ref().map(|r| r.read_back)
    }

    fn record_samples(&mut self, plan: &SamplePlan) -> Result<bool, EngineError> {
        self.record_samples_of(0, plan)
    }

    fn take_samples(&mut self) -> Vec<Sample> {
        self.take_samples_of(0)
    }

    fn run_ahead(&mut self) {
        self.lead = self.run_ahead_batches;
    }

    fn settle(&mut self) -> Result<(), EngineError> {
        self.drain()
    }
}
