//! The step kernel a scene compiles on an adapter, decided from what the
//! adapter is (its limits, software or not, subgroups) without a device:
//! the kernel, its threads and tiles, its override constants and its
//! module's build. The engine builds what `plan` decides; the driver
//! statistics (`driver_stats`) compile the same kernels on another device.

use super::batch_sizes::*;
use super::buffers::{Shape, PHASE_CLOCK_BYTES};
use super::compile::{KernelBuild, KernelSource, ShaderChecks};
use super::context::GpuContext;
use super::layout::{self, WORKGROUP};
use super::options::*;
use super::phase_clocks::PHASE_CLOCK_WORDS;
use super::precision::GpuReal;
use super::shaders::{Kernel, LaneMerge, Variant};
use super::tiles;
use crate::engines::EngineError;
use crate::model::scenario::FrictionLaw;
use crate::model::Model;

/// The kernel an engine steps with, as built: its workgroup's threads and
/// the tiled kernel's geometry resolved (`kernel_choice::Launch` is what
/// a choice asks for).
#[derive(Debug, Clone, Copy)]
pub struct StepKernel {
    pub kernel: Kernel,
    /// Threads of a workgroup: `group_scenes` scenes' of the persistent
    /// kernel.
    pub threads: u32,
    /// Scenes a persistent workgroup steps (`GpuOptions::group_scenes`; 1
    /// for every other kernel).
    pub group_scenes: u32,
    pub geometry: Option<tiles::TileGeometry>,
    /// Bulk forces by 2×2 patches (`GpuOptions::bond_patches`, on a kernel
    /// that has them).
    pub bond_patches: bool,
    /// The tiled kernel's rounds chained in one dispatch
    /// (`GpuOptions::chained_tiles`).
    pub chain: Option<tiles::TileChain>,
    /// The resident kernel's v in workgroup memory beside u (where both
    /// fit: `options::resident_fit`), else in storage.
    pub resident_velocities: bool,
}

impl StepKernel {
    /// Threads each scene of a workgroup steps with.
    pub fn scene_threads(&self) -> u32 {
        self.threads / self.group_scenes
    }

    /// The override constants of the kernel's pipeline: the scene's terms
    /// (`variant`), then what the kernel's layout needs; `shape`: the
    /// lattice's (the resident kernel's workgroup arrays).
    pub fn constants<T: GpuReal>(
        &self,
        variant: &Variant,
        opts: GpuOptions,
        shape: Shape,
        software: bool,
    ) -> Vec<(&'static str, f64)> {
        let mut constants = variant.constants.clone();
        constants.push(("KEEP_JUNCTION_SUMS", opts.keep_junction_sums as u8 as f64));
        constants.push((
            "COUNT_SUMMED_BLOCKS",
            opts.count_summed_junction_blocks as u8 as f64,
        ));
        if self.kernel.is_persistent() {
            constants.push(("PERSISTENT_THREADS", self.threads as f64));
            constants.push(("SCENE_THREADS", self.scene_threads() as f64));
            constants.push(("GROUP_SCENES", self.group_scenes as f64));
            // Each scene reduces its samples in its own share of the slots.
            constants.push(("REDUCTION_GROUPS", self.group_scenes as f64));
            // llvmpipe counts the iterations of every inlined loop against
            // its limit: one junction lane a round there.
            let two_lanes = !software && opts.two_lanes_a_round;
            constants.push(("TWO_LANES_A_ROUND", two_lanes as u8 as f64));
            // A lane run's next lane loaded ahead where two lanes a round
            // would be (`shaders/junctions.wgsl` lane_run), software
            // adapters included: it adds no loop pass for llvmpipe to count.
            let ahead = opts.two_lanes_a_round;
            constants.push(("LANE_RUN_AHEAD", ahead as u8 as f64));
            // llvmpipe's loop budget, checked at each dispatch's end; on
            // hardware (no budget) the probe would only cost registers.
            constants.push(("LOOP_PROBE", software as u8 as f64));
        }
        if self.kernel.is_persistent() || self.geometry.is_some() {
            constants.push(("LANE_RUN", opts.lane_run as f64));
        }
        if self.kernel.has_phase_barriers() {
            let words = match opts.phase_clocks {
                true => PHASE_CLOCK_WORDS,
                false => 1,
            };
            constants.push(("PHASE_CLOCKS", opts.phase_clocks as u8 as f64));
            constants.push(("PHASE_SUM_WORDS", words as f64));
        }
        constants.push(("BOND_PATCHES", self.bond_patches as u8 as f64));
        if self.kernel == Kernel::Resident {
            constants.push(("RESIDENT_BLOCKS", shape.blocks as f64));
            let velocities = self.resident_velocities;
            constants.push(("RESIDENT_VELOCITIES", velocities as u8 as f64));
            let vel_blocks = if velocities { shape.blocks } else { 1 };
            constants.push(("RESIDENT_VEL_BLOCKS", vel_blocks as f64));
        }
        // Their workgroup memory holds the state: fewer slots for the
        // samples they record.
        if matches!(self.kernel, Kernel::Resident | Kernel::Tiled) {
            constants.push((
                "REDUCTION_WIDTH",
                workgroup_state_reduction_width::<T>() as f64,
            ));
        }
        // The one-step kernels reduce samples in their recording variant
        // only (`step_recording_constants`): no slots in the others, whose
        // workgroup memory would hold them unused (drivers allocate every
        // workgroup variable a module's entry point names, used or not).
        if !self.kernel.is_persistent() && self.geometry.is_none() {
            constants.push(("REDUCTION_WIDTH", 1.0));
            // Their neighbours are in storage and their state copies one
            // array: every neighbour's loads in flight together
            // (`bulk_forces.wgsl`).
            constants.push(("NEIGHBOURS_WITHOUT_BRANCHES", 1.0));
        }
        // The kernels whose steps end at a workgroup barrier, so that their
        // lanes and updates can read their block's junction block from
        // workgroup memory (shaders/noted_blocks.wgsl): a note per
        // interface block of the resident kernel's lattice, or of the tiled
        // kernel's tile.
        let noted_blocks = match (self.kernel, self.geometry) {
            (Kernel::Resident, _) => Some(shape.nx),
            (_, Some(g)) => Some(g.span as usize),
            _ => None,
        };
        if let Some(blocks) = noted_blocks {
            constants.push((
                "NOTED_JUNCTION_BLOCKS",
                opts.noted_junction_blocks as u8 as f64,
            ));
            let notes = layout::noted_blocks(blocks, shape.junctions);
            constants.push(("NOTED_BLOCKS", notes as f64));
        }
        if let Some(g) = self.geometry {
            constants.push(("TILE_WIDTH", g.width as f64));
            constants.push(("TILE_HALO", g.halo as f64));
            constants.push(("TILE_BLOCKS", g.blocks as f64));
            constants.push(("TILE_THREADS", self.threads as f64));
            constants.push(("PUBLISHED_HALO_SUMS", opts.published_halo_sums as u8 as f64));
        }
        if let Some(chain) = self.chain {
            constants.push(("TILE_CHAINED", 1.0));
            constants.push(("CHAIN_POLLS", chain.polls as f64));
            constants.push(("CHAIN_POLL_PAUSE", chain.pause as u8 as f64));
        }
        constants
    }

    /// Workgroups of a step dispatch in x and y (z: the scenes): a tile
    /// each for the tiled kernel; else a workgroup per interface block's
    /// junctions (one-step-lanes) and one per `WORKGROUP` blocks (one-step
    /// with patches: per `WORKGROUP` threads of the interface row's blocks
    /// and the 2×2 patches above it).
    pub fn groups(&self, model: &Model) -> (u32, u32) {
        if let Some(g) = self.geometry {
            return (g.tiles, 1);
        }
        groups_for(self.workgroups(model))
    }

    /// The workgroups of a one-step dispatch of one scene that hold blocks
    /// (`groups` may pad them to fit its two dimensions); each keeps a
    /// partial of a sample (`shaders/record_step.wgsl`).
    pub fn workgroups(&self, model: &Model) -> u32 {
        let junction_groups = match (self.kernel, model.law) {
            (Kernel::OneStepLanes, FrictionLaw::Junctions | FrictionLaw::SingleJunction) => {
                model.nx as u32
            }
            _ => 0,
        };
        if self.bond_patches {
            // The items of step_patches.wgsl: the interface row a thread a
            // block, then the patches; with junction workgroups, from the
            // run of WORKGROUP items that holds item nx (one_step_lanes.wgsl).
            let items = patch_items(model.nx as u32, model.nz as u32);
            let first = if junction_groups > 0 {
                model.nx as u32 / WORKGROUP * WORKGROUP
            } else {
                0
            };
            return junction_groups + (items - first).div_ceil(WORKGROUP);
        }
        // With junction workgroups, the others start at the first block of
        // the workgroup-sized run that holds block nx (one_step_lanes.wgsl).
        let first_plain = if junction_groups > 0 {
            model.nx as u32 / WORKGROUP * WORKGROUP
        } else {
            0
        };
        junction_groups + (model.n_blocks() as u32 - first_plain).div_ceil(WORKGROUP)
    }
}

/// What decides which step kernel an adapter compiles, short of the
/// device itself: its limits (workgroup memory and threads), whether it
/// is a software adapter, and whether it has subgroup operations.
#[derive(Debug, Clone)]
pub struct AdapterTraits {
    pub limits: wgpu::Limits,
    pub software: bool,
    pub subgroups: bool,
    /// `@coherent` storage buffers (the chained tiled kernel's halos).
    pub coherent_storage: bool,
    /// Immediates with room for the step offset (`KernelBuild::step_immediate`).
    pub immediates: bool,
    /// The engine writes the device's SPIR-V itself where a kernel's build
    /// asks (`KernelBuild::workgroup_barriers`, `strict_arithmetic`).
    pub own_spirv: bool,
    /// The kernels may read the multiprocessor's clock
    /// (`GpuContext::has_shader_clock`, `KernelBuild::phase_clocks`).
    pub shader_clock: bool,
}

impl AdapterTraits {
    pub fn of(ctx: &GpuContext) -> AdapterTraits {
        AdapterTraits {
            limits: ctx.limits.clone(),
            software: ctx.is_software(),
            subgroups: ctx.has_subgroups(),
            coherent_storage: ctx.has_coherent_storage(),
            immediates: ctx.has_immediates(),
            own_spirv: ctx.has_own_spirv(),
            shader_clock: ctx.has_shader_clock(),
        }
    }

    /// A hardware adapter with every feature the engine asks for, 1024
    /// threads and 64 KB of workgroup memory a workgroup: the unit tests'
    /// plans, made without a device.
    #[cfg(test)]
    pub(crate) fn test_hardware() -> AdapterTraits {
        AdapterTraits {
            limits: wgpu::Limits {
                max_compute_workgroup_storage_size: 65536,
                max_compute_invocations_per_workgroup: 1024,
                max_compute_workgroup_size_x: 1024,
                ..wgpu::Limits::default()
            },
            software: false,
            subgroups: true,
            coherent_storage: true,
            immediates: true,
            own_spirv: true,
            shader_clock: true,
        }
    }

    /// How junction lanes merge where `wanted` asks for shuffles: in
    /// subgroups only where the adapter has them.
    pub fn lane_merge(&self, wanted: bool) -> LaneMerge {
        if wanted && self.subgroups {
            LaneMerge::Shuffle
        } else {
            LaneMerge::Storage
        }
    }
}

/// The step kernel of a scene as an adapter compiles it (`plan`).
pub struct KernelPlan {
    pub step_kernel: StepKernel,
    pub variant: Variant,
    pub constants: Vec<(&'static str, f64)>,
    pub build: KernelBuild,
}

/// The sources of `kernel`'s pipelines compiled with `build` and
/// `constants`: its steps, and the tiled kernel's halo gather (`tiled`).
pub fn kernel_sources<T: GpuReal>(
    kernel: Kernel,
    build: KernelBuild,
    tiled: bool,
    constants: &[(&'static str, f64)],
) -> Vec<KernelSource> {
    let gather = kernel.gather_entry_point().filter(|_| tiled);
    std::iter::once(kernel.entry_point())
        .chain(gather)
        .map(|entry| KernelSource::of::<T>(kernel, build, entry, constants))
        .collect()
}

/// How a kernel holds a scene in workgroup memory (`kernel_fit`).
struct KernelFit {
    geometry: Option<tiles::TileGeometry>,
    resident_velocities: bool,
}

/// Fails where `kernel` cannot hold `model` on this adapter (the
/// resident kernel's lattice, the tiled kernel's tile in workgroup
/// memory); the tiled kernel's geometry, and whether the resident
/// kernel's v fits beside u.
fn kernel_fit<T: GpuReal>(
    model: &Model,
    adapter: &AdapterTraits,
    opts: GpuOptions,
    kernel: Kernel,
    threads: u32,
) -> Result<KernelFit, EngineError> {
    // Every kernel but the resident one: v is where it always is.
    let tiles_only = |geometry| KernelFit {
        geometry,
        resident_velocities: true,
    };
    match kernel {
        Kernel::Resident => {
            let fit = resident_fit::<T>(model, &adapter.limits).map_err(EngineError::Gpu)?;
            Ok(KernelFit {
                geometry: None,
                resident_velocities: fit.velocities,
            })
        }
        Kernel::Tiled => {
            let shape = opts.tile.unwrap_or(tiles::TileShape::DEFAULT);
            let g = tiles::TileGeometry::new(model, shape).map_err(EngineError::Gpu)?;
            tiles::tiled_fit::<T>(model, &g, &adapter.limits).map_err(EngineError::Gpu)?;
            if adapter.software {
                tiles::software_fit(model, &g, threads, opts.lane_run).map_err(EngineError::Gpu)?;
            }
            Ok(tiles_only(Some(g)))
        }
        _ => Ok(tiles_only(None)),
    }
}

/// The chain of the tiled kernel's rounds on this adapter: it needs
/// `@coherent` storage for the halos its tiles publish within a dispatch.
fn chain_fit(
    model: &Model,
    adapter: &AdapterTraits,
    geometry: &tiles::TileGeometry,
    threads: u32,
    lane_run: u32,
) -> Result<tiles::TileChain, EngineError> {
    if !adapter.coherent_storage {
        return Err(EngineError::Gpu(
            "chained tiles read their neighbours' halos within a dispatch, from @coherent \
             storage buffers, which this adapter does not offer: use the tiled kernel unchained"
                .into(),
        ));
    }
    tiles::TileChain::new(model, geometry, threads, lane_run, adapter.software)
        .map_err(EngineError::Gpu)
}

/// The step kernel `model` compiles with `opts` on an adapter like
/// `adapter`, decided without a device: the kernel, its threads and
/// tiles, its override constants and its module's build. `opts.path`
/// names the kernel (`auto`'s measurement is resolved before this).
pub fn plan<T: GpuReal>(
    model: &Model,
    opts: GpuOptions,
    adapter: &AdapterTraits,
) -> Result<KernelPlan, EngineError> {
    if !LANE_RUNS.contains(&opts.lane_run) {
        return Err(EngineError::Gpu(format!(
            "GPU option lane_run = {}: must be one of {LANE_RUNS:?}",
            opts.lane_run
        )));
    }
    let kernel = choose_kernel(opts.path, adapter.software);
    if opts.phase_clocks {
        phase_clocks_allowed(opts.path, kernel, adapter)?;
    }
    let threads = persistent_threads(
        kernel,
        opts.persistent_threads,
        &adapter.limits,
        adapter.software,
    );
    let group_scenes = group_scenes(opts, kernel, threads)?;
    // The phases' sums take workgroup memory beside the state.
    let mut fit = adapter.clone();
    if opts.phase_clocks {
        let room = &mut fit.limits.max_compute_workgroup_storage_size;
        *room = room.saturating_sub(PHASE_CLOCK_BYTES as u32);
    }
    let KernelFit {
        geometry,
        resident_velocities,
    } = kernel_fit::<T>(model, &fit, opts, kernel, threads)?;
    // Asked for with a kernel named that has no rounds to chain: refused
    // (auto and measure leave the other kernels unchained).
    if opts.chained_tiles
        && kernel != Kernel::Tiled
        && !matches!(opts.path, GpuPath::Auto | GpuPath::Measure)
    {
        return Err(EngineError::Gpu(format!(
            "--gpu-chained-tiles chains the tiled kernel's rounds, and --gpu-path {} has none: \
             use --gpu-path tiled, auto or measure, or leave the flag out",
            super::kernel_choice::path_name(kernel)
        )));
    }
    let chain = match geometry.filter(|_| opts.chained_tiles) {
        Some(g) => Some(chain_fit(model, adapter, &g, threads, opts.lane_run)?),
        None => None,
    };
    let variant = Variant::for_model(model);
    let step_kernel = StepKernel {
        kernel,
        threads,
        group_scenes,
        geometry,
        bond_patches: opts.bond_patches,
        chain,
        resident_velocities,
    };
    let constants = step_kernel.constants::<T>(&variant, opts, Shape::of(model), adapter.software);
    // One module (and one compiled pipeline) for the one-step kernels.
    let build = KernelBuild {
        lanes: adapter.lane_merge(opts.lane_shuffle && kernel.merges_lanes_through_storage()),
        checks: ShaderChecks::of(opts.shader_checks),
        chained_tiles: chain.is_some(),
        step_immediate: adapter.immediates && opts.step_immediates,
        workgroup_barriers: adapter.own_spirv
            && opts.workgroup_barriers
            && kernel.has_phase_barriers(),
        phase_clocks: opts.phase_clocks,
        strict_arithmetic: adapter.own_spirv && opts.arithmetic.strict::<T>(),
    };
    Ok(KernelPlan {
        step_kernel,
        variant,
        constants,
        build,
    })
}

/// Fails unless `kernel` on `adapter` can time its phases
/// (`GpuOptions::phase_clocks`): a kernel named, with phases, on a device
/// that takes the engine's own SPIR-V and lets it read the clock.
fn phase_clocks_allowed(
    path: GpuPath,
    kernel: Kernel,
    adapter: &AdapterTraits,
) -> Result<(), EngineError> {
    // A profile names what it profiles: auto's pick is timed unclocked.
    if matches!(path, GpuPath::Auto | GpuPath::Measure) {
        return Err(EngineError::Gpu(format!(
            "GPU option phase_clocks times a launch named: --gpu-path {} chooses one by \
             timing; use persistent, resident or tiled",
            path.name()
        )));
    }
    if !kernel.has_phase_barriers() {
        return Err(EngineError::Gpu(format!(
            "GPU option phase_clocks: --gpu-path {} steps once a dispatch and has no phases to \
             time: use persistent, resident or tiled",
            super::kernel_choice::path_name(kernel)
        )));
    }
    if !adapter.shader_clock {
        return Err(EngineError::Gpu(
            "GPU option phase_clocks: the adapter does not let the engine read the \
             multiprocessor's clock (it needs Vulkan 1.3 with VK_KHR_shader_clock's \
             shaderSubgroupClock, and the engine's own SPIR-V accepted)"
                .into(),
        ));
    }
    Ok(())
}

/// Scenes a workgroup of `kernel` steps at `threads` threads: the option
/// for the persistent kernel, where it divides the threads; 1 for the
/// others, and an error where the option names one of them (`auto` and
/// `measure` leave the others at one scene a workgroup).
fn group_scenes(opts: GpuOptions, kernel: Kernel, threads: u32) -> Result<u32, EngineError> {
    let asked = opts.group_scenes;
    if !GROUP_SCENES_ALLOWED.contains(&asked) {
        return Err(EngineError::Gpu(format!(
            "GPU option group_scenes = {asked}: must be one of {GROUP_SCENES_ALLOWED:?}"
        )));
    }
    if kernel != Kernel::Persistent {
        if asked > 1 && !matches!(opts.path, GpuPath::Auto | GpuPath::Measure) {
            return Err(EngineError::Gpu(format!(
                "--gpu-group-scenes {asked} puts scenes side by side in the persistent kernel's \
                 workgroup, and --gpu-path {} has none: use --gpu-path persistent, or leave the \
                 flag out",
                super::kernel_choice::path_name(kernel)
            )));
        }
        return Ok(1);
    }
    if !threads.is_multiple_of(asked) {
        return Err(EngineError::Gpu(format!(
            "--gpu-group-scenes {asked}: the workgroup's {threads} threads (--gpu-threads, within \
             the adapter's limit) must split evenly among its {asked} scenes"
        )));
    }
    Ok(asked)
}

/// The override constants of the one-step kernels' recording variant
/// (`shaders/record_step.wgsl`) from their step kernel's `constants`:
/// `STEP_RECORDS`, and a slot a thread to reduce a sample across the
/// workgroup in (as many as workgroup memory's 16 KB hold).
pub fn step_recording_constants<T: GpuReal>(
    constants: &[(&'static str, f64)],
) -> Vec<(&'static str, f64)> {
    let mut recording: Vec<(&'static str, f64)> = constants
        .iter()
        .filter(|(name, _)| *name != "REDUCTION_WIDTH")
        .copied()
        .collect();
    recording.push(("STEP_RECORDS", 1.0));
    let width = WORKGROUP.min(layout::reduction_slots::<T>());
    recording.push(("REDUCTION_WIDTH", width as f64));
    recording
}

/// Workgroups (x, y) of a dispatch of `workgroups` of them (at least one),
/// within the 65,535 a dimension every adapter allows.
pub fn groups_for(workgroups: u32) -> (u32, u32) {
    let groups = workgroups.max(1);
    let x = groups.min(65_535);
    (x, groups.div_ceil(x))
}

/// Threads of the one-step kernels by patches on a lattice `nx` × `nz`
/// (`shaders/patch_items.wgsl`): the interface row a block each, then the
/// 2×2 patches of the rows above, ⌈nx/2⌉ a row.
fn patch_items(nx: u32, nz: u32) -> u32 {
    nx + nx.div_ceil(2) * (nz - 1).div_ceil(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first block (column, row) of the one-step kernels' patch item
    /// `t` ≥ nx on a lattice `nx` wide (`shaders/patch_items.wgsl`, the
    /// same name); its row is nz or more past the last patch.
    fn patch_item_origin(t: u32, nx: u32) -> (u32, u32) {
        let columns = nx.div_ceil(2);
        let p = t - nx;
        (2 * (p % columns), 1 + 2 * (p / columns))
    }

    /// The item that holds block `i` (`shaders/patch_items.wgsl`, the same
    /// name): the block itself, or with `patches` its interface item or
    /// its patch's. The recording steps find the driven block's and the
    /// top row's workgroups by it (`shaders/record_step.wgsl`).
    fn item_of_block(i: u32, nx: u32, patches: bool) -> u32 {
        if !patches || i < nx {
            return i;
        }
        let columns = nx.div_ceil(2);
        nx + ((i / nx - 1) / 2) * columns + (i % nx) / 2
    }

    /// Every block of odd and even lattices lies in exactly one of the
    /// `patch_items` items (patch_item_origin), and none is empty: each
    /// block's part of a sample is summed once. item_of_block names that
    /// item, and the top row's blocks lie in the items from its first
    /// block's item on (a recording step's test of a workgroup's range).
    #[test]
    fn patch_items_hold_each_block_once() {
        for (nx, nz) in [(57, 31), (256, 128), (15, 8), (130, 1), (3, 2)] {
            let top_first = item_of_block(nx * (nz - 1), nx, true);
            let mut seen = vec![0u32; (nx * nz) as usize];
            for t in 0..patch_items(nx, nz) {
                let blocks: Vec<(u32, u32)> = if t < nx {
                    vec![(t, 0)]
                } else {
                    let (x0, z0) = patch_item_origin(t, nx);
                    [(0, 0), (1, 0), (0, 1), (1, 1)]
                        .iter()
                        .map(|&(dx, dz)| (x0 + dx, z0 + dz))
                        .filter(|&(x, z)| x < nx && z < nz)
                        .collect()
                };
                assert!(!blocks.is_empty(), "{nx}×{nz}: item {t} is empty");
                for (x, z) in blocks {
                    let i = z * nx + x;
                    seen[i as usize] += 1;
                    assert_eq!(item_of_block(i, nx, true), t, "{nx}×{nz}: block {i}");
                    assert_eq!(item_of_block(i, nx, false), i);
                    if z == nz - 1 {
                        assert!(t >= top_first, "{nx}×{nz}: top block {i} in item {t}");
                    }
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{nx}×{nz}: {seen:?}");
        }
    }

    /// Bytes of workgroup memory the entry point of `source` names, after
    /// its override constants: what a driver allocates a workgroup (naga's
    /// layout of each workgroup variable the entry point uses).
    fn declared_workgroup_bytes(source: &KernelSource) -> u64 {
        let (module, info) = source.module().expect("the kernel validates");
        let (module, info) = source
            .with_constants(&module, &info)
            .expect("its constants apply");
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).expect("the types lay out");
        let entry = module
            .entry_points
            .iter()
            .position(|e| e.name == source.entry)
            .expect("the entry point is there");
        let used = info.get_entry_point(entry);
        module
            .global_variables
            .iter()
            .filter(|(h, v)| v.space == naga::AddressSpace::WorkGroup && !used[*h].is_empty())
            .map(|(_, v)| layouter[v.ty].size as u64)
            .sum()
    }

    /// The workgroup memory the resident and tiled kernels are fitted by
    /// (`resident_fit`, `TileGeometry::workgroup_bytes`) is what their
    /// modules declare, after the override constants the plan sets: never
    /// less (a driver would refuse a launch the engine thought fits), and
    /// at most 64 bytes more (a fit that counts an array the
    /// module no longer holds would refuse launches that fit). Table S1
    /// and a small lattice, both precisions, junctions and (resident)
    /// Coulomb friction, tiles of several shapes, chained or not.
    #[test]
    fn the_workgroup_memory_fitted_is_what_the_kernels_declare() {
        use crate::model::scenario::{built_in, Scenario};
        let adapter = AdapterTraits::test_hardware();
        let model = |name: &str, set: &[&str]| {
            let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
            let s = Scenario::parse(built_in(name).unwrap(), name, &set).unwrap();
            Model::from_scenario(&s, false).unwrap()
        };
        let scenes = [
            ("Table S1", model("tromborg2014_precursors", &[]), true),
            (
                "Table S1, Coulomb",
                model("tromborg2014_precursors", &["friction.law=\"coulomb\""]),
                false,
            ),
            ("small", model("small_stick_slip", &[]), true),
        ];
        fn check<T: GpuReal>(name: &str, m: &Model, tiled: bool, adapter: &AdapterTraits) {
            let mut launches = vec![(GpuPath::Resident, None, false)];
            if tiled {
                for (width, halo) in [(8, 4), (4, 2), (16, 1)] {
                    let shape = Some(tiles::TileShape { width, halo });
                    launches.push((GpuPath::Tiled, shape, false));
                    launches.push((GpuPath::Tiled, shape, true));
                }
            }
            for (path, tile, chained_tiles) in launches {
                let opts = GpuOptions {
                    path,
                    tile,
                    chained_tiles,
                    ..GpuOptions::default()
                };
                let plan = plan::<T>(m, opts, adapter).unwrap();
                let fitted = match plan.step_kernel.geometry {
                    Some(g) => g.workgroup_bytes::<T>(),
                    None => resident_fit::<T>(m, &adapter.limits).unwrap().bytes,
                };
                let k = plan.step_kernel.kernel;
                let source = &kernel_sources::<T>(k, plan.build, false, &plan.constants)[0];
                let declared = declared_workgroup_bytes(source);
                let what = format!(
                    "{name}, {}, {path:?} {tile:?} chained {chained_tiles}: fitted {fitted} bytes, \
                     declared {declared}",
                    T::NAME
                );
                assert!(declared <= fitted, "{what}");
                assert!(fitted - declared <= 64, "{what}");
            }
        }
        for (name, m, tiled) in &scenes {
            check::<f32>(name, m, *tiled, &adapter);
            check::<f64>(name, m, *tiled, &adapter);
        }
    }
}
