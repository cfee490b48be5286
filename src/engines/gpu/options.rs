//! The choices of the GPU engine: which kernel steps a scene, with how many
//! threads and steps per dispatch (the fixed batch sizes: `batch_sizes`).

use super::batch_sizes::{
    workgroup_state_reduction_width, PERSISTENT_BATCH, WORKGROUP_STATE_REDUCTION_WIDTH,
};
use super::layout;
use super::loop_budget;
use super::precision::{Coord, GpuReal};
use super::shaders::Kernel;
use super::tiles::TileShape;
use crate::engines::SamplePlan;
use crate::model::scenario::FrictionLaw;
use crate::model::Model;

/// Batches an `advance` may leave running by default when its caller
/// writes output meanwhile (`Engine::run_ahead`, `GpuOptions::run_ahead`):
/// the device keeps stepping while the runner handles the samples read
/// back so far, instead of idling for it. Four one-step batches are 4096
/// steps; a lockstep chunk is eight. Warmed up and weighed per step, it
/// pays on the H200 (BENCHMARKS.md, session 16): output cost 1.33× against
/// 1.44× at 57×31, 1.58× against 1.79× at 1024×512.
pub const RUN_AHEAD_BATCHES: usize = 4;
/// The most batches a run may ask to run ahead (`--gpu-run-ahead`): each
/// holds its staging buffers until it is retired, and its samples wait.
pub const MAX_RUN_AHEAD_BATCHES: usize = 64;

/// `batches` as a run-ahead count (`--gpu-run-ahead`, Python's
/// `gpu_run_ahead`): 0 to `MAX_RUN_AHEAD_BATCHES`, else why not.
pub fn run_ahead_batches(batches: i64) -> Result<usize, String> {
    match usize::try_from(batches) {
        Ok(n) if n <= MAX_RUN_AHEAD_BATCHES => Ok(n),
        _ => Err(format!(
            "{batches} is not a count of batches from 0 to {MAX_RUN_AHEAD_BATCHES}"
        )),
    }
}

/// Threads of the persistent kernel's workgroup by default.
pub const PERSISTENT_THREADS: u32 = 256;
/// Threads of the resident kernel's workgroup by default on hardware
/// (fewer where the adapter allows fewer): with its state on chip, the
/// workgroup is the whole engine, so it takes the largest that WGSL
/// hardware offers.
pub const RESIDENT_THREADS: u32 = 1024;
/// ... and on software adapters, the persistent kernel's: llvmpipe runs a
/// workgroup's invocations as coroutines on one core, switching them at
/// every barrier (small_stick_slip, 0.01 s: 1.0 s with 64 threads, 1.7 s
/// with 256, 6.8 s with 1024); the loop budget
/// (`persistent_steps_per_dispatch`) holds at any count.
pub const RESIDENT_THREADS_SOFTWARE: u32 = PERSISTENT_THREADS;
/// The resident kernel's own workgroup words (its step span, its member
/// scenes' stop and sample flags and steps run, four of each as the
/// persistent kernel's grouped scenes have, and the lane shuffles' levels:
/// 68 bytes), rounded up.
const RESIDENT_OWN_BYTES: u64 = 96;

/// Which kernel steps the lattice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum GpuPath {
    /// Hardware: the fastest kernel on this scene, timed at start-up and
    /// cached per adapter and lattice (`kernel_choice`). Software adapters:
    /// one step per dispatch, one thread per block (the measured rule).
    Auto,
    /// Time every kernel that fits on this scene now, on any adapter, take
    /// the fastest and refresh the cache.
    Measure,
    /// One dispatch per step, one thread per block.
    OneStep,
    /// One dispatch per step, a workgroup per interface block's junctions.
    OneStepLanes,
    /// One workgroup, many steps per dispatch (any lattice: slow for large ones).
    Persistent,
    /// The persistent kernel with the lattice held in workgroup memory for
    /// the whole dispatch (lattices that fit the adapter's workgroup memory:
    /// Table S1 needs 46 KB in mixed f32; in f64 u and v take 62 KB, so
    /// where the adapter offers less, u alone, 34 KB, with v in storage).
    Resident,
    /// Temporal blocking: a workgroup per column tile steps its tile and a
    /// halo of 4 columns for up to 4 steps per dispatch (small lattices
    /// with junction friction or none).
    Tiled,
}

/// Where the output samples of a run with an output file are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum GpuOutput {
    /// On the device, by the step kernels in their steps
    /// (`shaders/record_common.wgsl`): only the channels due are read
    /// back, asynchronously with the batches; an ensemble records all its
    /// scenes together (in the run's precision, mixed f32 or f64).
    #[default]
    Device,
    /// A whole-state snapshot read back at every output step (the
    /// reference the device records are tested against).
    Host,
}

#[derive(Debug, Clone, Copy)]
pub struct GpuOptions {
    pub path: GpuPath,
    pub output: GpuOutput,
    /// Threads of the persistent and resident kernels' workgroup; None:
    /// the kernel's default (`PERSISTENT_THREADS`, `RESIDENT_THREADS`).
    pub persistent_threads: Option<u32>,
    /// Steps per persistent dispatch instead of the adapter's safe default.
    pub steps_per_dispatch: Option<u64>,
    /// The tiled kernel's tiles: columns each owns and halo columns each
    /// side, the most steps a dispatch runs (None: `TileShape::DEFAULT`,
    /// and `auto` searches a few; `--gpu-tile`).
    pub tile: Option<TileShape>,
    /// Batches an `advance` may leave running once its runner lets it run
    /// ahead (`Engine::run_ahead`); 0: every advance waits for its steps.
    pub run_ahead: usize,
    /// Keep an interface block's junction sums while none of its junctions
    /// can change, and skip its junctions then (`junction_cache`): the same
    /// bits either way. false sums every junction every step (a check).
    pub keep_junction_sums: bool,
    /// Merge runs of a block's junction lanes in subgroups before their
    /// sums cross threads through storage (persistent, resident and tiled
    /// kernels, adapters with subgroup operations; `shaders::LaneMerge`):
    /// the same tree, so the same sums. false: every lane's sum through
    /// storage (a check, and the comparison in benchmarks).
    pub lane_shuffle: bool,
    /// Let wgpu add its run-time checks to the kernels (an index clamp at
    /// every fixed-size array access, an iteration counter in every loop;
    /// `compile::ShaderChecks`): the same bits, more instructions.
    /// false (the default): the kernels as written (`--gpu-shader-checks`).
    pub shader_checks: bool,
    /// The kernels compute the bulk forces by 2×2 patches of blocks, a
    /// thread each, every bond inside a patch once (`bulk_patch.wgsl`; the
    /// one-step kernels' interface row keeps a thread per block): 26 bonds' work a patch where a thread per
    /// block does 32, on a quarter of the threads. The same arithmetic; the
    /// forces agree to their last bits, not always to the bit (lavapipe's
    /// mixed f32: `tests/gpu_bond_patches.rs`). false (the default): a thread
    /// per block; `auto` on hardware times both (`--gpu-bond-patches`
    /// fixes it on).
    pub bond_patches: bool,
    /// The resident and tiled kernels' junction lanes, and a block's
    /// update, read the block's junction block (its u_x, reference, normal
    /// force and whether it keeps its sums) from a note made once per block
    /// and step by the thread that updates it (`shaders/noted_blocks.wgsl`),
    /// not from a `junction_block` call per lane and two per update: the
    /// same values, so the same bits. false: a call each, as before
    /// session 33 (the comparison in benchmarks).
    pub noted_junction_blocks: bool,
    /// The persistent and resident kernels step two junction lanes a round
    /// on hardware, both lanes' first junctions loaded before either is
    /// stepped: half the chains of storage round trips on a thread's path,
    /// for more registers a thread (on AMD's compiler 8–16 more in f64,
    /// none in mixed f32: BENCHMARKS.md, session 36), which can leave an
    /// SM room for fewer of an ensemble's scenes. false: one lane a round, as
    /// software adapters always run (`TWO_LANES_A_ROUND`). The same
    /// operations on the same values: the same bits
    /// (`tests/gpu_engine.rs`, resident with one against persistent with
    /// two, on hardware). `auto` on hardware times its fastest persistent
    /// launch both ways.
    pub two_lanes_a_round: bool,
    /// Consecutive junction lanes a thread steps in the persistent,
    /// resident and tiled kernels (`LANE_RUNS`; `LANE_RUN` in
    /// `shaders/junctions.wgsl`): the thread works out its block's
    /// junction state once for the run, not once a lane, and merges the
    /// run's lane sums itself as the lane tree's lowest levels, so fewer
    /// levels are left to subgroup shuffles or storage. On AMD's compiler
    /// (Table S1) a block's lane work is about a quarter to a third fewer
    /// instructions at 4 (BENCHMARKS.md, session 57), for more registers a
    /// thread. The same lanes merged by the same tree: the same bits. 1:
    /// a lane a thread, as before. `auto` on hardware times its fastest
    /// launch of these kernels at 4 too.
    pub lane_run: u32,
    /// The tiled kernel runs the rounds of a batch (its dispatches of up
    /// to a halo's steps) in one dispatch, each tile waiting for the
    /// tiles in its halo to finish a round before it reads their edges
    /// (`tiled.wgsl`, `tiles::TileChain`): the same rounds, so the same
    /// bits, in one dispatch where there were many. It needs a scene's
    /// tiles on the GPU at once; a tile that waits past its polls stops
    /// the run with an error rather than hang. false (the default): a
    /// dispatch a round; `auto` on hardware times its fastest tiled
    /// launch both ways (`--gpu-chained-tiles` fixes it on).
    pub chained_tiles: bool,
    /// The output cadences of the run this engine steps, where it records
    /// its samples on the device (a run with an output file): `auto`
    /// times each launch recording at them, the records dropped. Every
    /// multiple of the fast cadence is a planned sample, whether the
    /// interface turns out fast or not (the device decides at each
    /// sample): at Table S1's defaults every 4 or 5 steps. There a
    /// one-step launch adds the record dispatches; a persistent one
    /// reduces the sample across its workgroup, and a tiled one (chained
    /// or not) across each tile's, with a dispatch a batch that adds the
    /// tiles' partials. So output weighs on the launches unequally. None:
    /// timed without output.
    pub samples: Option<SamplePlan>,
    /// The storage arrays as ranges of a few buffers (`arena`): wgpu's
    /// host cost of encoding a dispatch grows with the distinct buffers it
    /// binds, and the one-step kernels encode a dispatch a step. The same
    /// arrays and kernels, so the same bits. false: a buffer per array, as
    /// before session 55 (the comparison in benchmarks).
    pub pack_arrays: bool,
    /// Each dispatch's step offset passed as an immediate where the
    /// adapter has them (`KernelBuild::step_immediate`): setting 4 bytes
    /// costs the host less than rebinding group 1 with a dynamic offset,
    /// at every dispatch of a one-step launch. The same kernels read the
    /// same value, so the same bits. false: the dynamic offset (the
    /// comparison in benchmarks, and adapters without immediates).
    pub step_immediates: bool,
    /// The tiled kernel publishes its edge blocks' kept junction sums with
    /// their junctions, and a tile starts its halo blocks from them
    /// (`PUBLISHED_HALO_SUMS` in `shaders/junction_tiled.wgsl`): a quiet
    /// halo block keeps its sums from a round's first step, where it
    /// summed its junctions then (a whole lane phase a round in every
    /// tile). Kept or made anew, sums of the same junctions have the same
    /// bits. false: each round's halo sums made anew, as before session 60
    /// (the comparison in benchmarks).
    pub published_halo_sums: bool,
    /// The kernels count the interface block-steps whose junctions they
    /// summed (`GpuStatus::summed_junction_blocks`,
    /// `GpuEngine::summed_junction_blocks`): an atomic each, so off (and
    /// compiled out) unless a test or benchmark asks.
    pub count_summed_junction_blocks: bool,
    /// Scenes the persistent kernel steps side by side in one workgroup,
    /// each on `persistent_threads / group_scenes` threads (1, 2 or 4:
    /// `GROUP_SCENES_ALLOWED`; `shaders/persistent.wgsl`). On NVIDIA a
    /// 1024-thread workgroup is held to 64 registers a thread, so two
    /// 512-thread scenes share a multiprocessor where a 512-thread
    /// workgroup of its own takes more registers and runs alone. Each
    /// scene's steps are the same arithmetic, so the same bits.
    pub group_scenes: u32,
    /// The storage barriers between a step's phases in the persistent,
    /// resident and tiled kernels with workgroup memory scope, where the
    /// engine may write the device's SPIR-V itself (Vulkan 1.3 and
    /// PASSTHROUGH_SHADERS: `KernelBuild::workgroup_barriers`,
    /// `shaders/barriers.wgsl`). naga writes WGSL's `storageBarrier` with
    /// device scope, which on hardware may drain a multiprocessor's stores
    /// to L2 and drop its cached storage at every phase of every step,
    /// though only the workgroup's own threads read what it orders. The
    /// same values in the same order, so the same bits. false: naga's
    /// device scope (the comparison in benchmarks).
    pub workgroup_barriers: bool,
    /// The persistent, resident and tiled kernels read their
    /// multiprocessor's cycle counter at the barriers between phases, and
    /// sum each phase's cycles per scene (`GpuEngine::phase_cycles`,
    /// `shaders/phase_clocks.wgsl`): where a step's time goes on the
    /// device. Needs the engine's own SPIR-V and VK_KHR_shader_clock
    /// (`GpuContext::has_shader_clock`); an engine asked for it elsewhere,
    /// on a one-step kernel (no phases) or on `auto` (a profile names
    /// its launch), is refused. Off by default:
    /// the marks cost thread 0 a few shared-memory words a phase.
    pub phase_clocks: bool,
    /// How the kernels' floating-point arithmetic is compiled: strict
    /// (NoContraction throughout) or as wgpu writes it, per precision
    /// (`Arithmetic`; `--gpu-arithmetic`).
    pub arithmetic: Arithmetic,
}

/// How the kernels' floating-point arithmetic is compiled
/// (`GpuOptions::arithmetic`). Strict: every floating-point operation
/// NoContraction, where the engine may write the device's SPIR-V itself
/// (`KernelBuild::strict_arithmetic`, `spirv::forbid_contraction`): no
/// driver may fuse a product into an add or regroup a sum, so each kernel
/// computes its CPU twin's operations as written. On a device that rounds
/// division and square roots as IEEE does (llvmpipe), every kernel is then
/// its twin bit for bit: mixed f32 `CpuEngine<f32>` (session 67), f64 the
/// CPU reference `CpuEngine<f64>` itself (session 68). What it costs
/// differs by precision (AMD's compiler, Table S1): in mixed f32 it also
/// compiles out the guards wgpu's modules need in the compensated sums
/// (`shaders/double_single.wgsl`), 2.5-5 % fewer instructions; f64 has no
/// guards, and there the fused multiply-adds come apart, 4-7 % more
/// instructions and 12-18 % more of ACO's estimated latency. NVIDIA's
/// figures are `gpu_table` section 12's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Arithmetic {
    /// Each precision's leaner build: strict in mixed f32, wgpu's in f64
    /// (the default).
    Leaner,
    /// Strict in both precisions: the CPU twin's operations, where a GPU
    /// run must give the CPU reference's numbers.
    Strict,
    /// wgpu's modules in both: mixed f32 with its fusion guards, f64 as
    /// naga writes it (the driver may fuse).
    Wgpu,
}

impl Arithmetic {
    /// Whether precision `T`'s kernels are asked to be strict (they are
    /// where the engine writes the device's SPIR-V).
    pub fn strict<T: GpuReal>(self) -> bool {
        match self {
            Arithmetic::Leaner => T::FUSION_GUARDS,
            Arithmetic::Strict => true,
            Arithmetic::Wgpu => false,
        }
    }

    /// The `--gpu-arithmetic` value (as the command line spells it).
    pub fn name(self) -> String {
        clap::ValueEnum::to_possible_value(&self)
            .map_or_else(|| format!("{self:?}"), |v| v.get_name().to_string())
    }
}

/// Scenes a persistent workgroup may step (`GpuOptions::group_scenes`).
pub const GROUP_SCENES_ALLOWED: [u32; 3] = [1, 2, 4];

impl Default for GpuOptions {
    fn default() -> Self {
        GpuOptions {
            path: GpuPath::Auto,
            output: GpuOutput::Device,
            persistent_threads: None,
            steps_per_dispatch: None,
            tile: None,
            run_ahead: RUN_AHEAD_BATCHES,
            keep_junction_sums: true,
            lane_shuffle: true,
            shader_checks: false,
            bond_patches: false,
            noted_junction_blocks: true,
            two_lanes_a_round: true,
            lane_run: 1,
            chained_tiles: false,
            samples: None,
            pack_arrays: true,
            step_immediates: true,
            published_halo_sums: true,
            count_summed_junction_blocks: false,
            group_scenes: 1,
            workgroup_barriers: true,
            phase_clocks: false,
            arithmetic: Arithmetic::Leaner,
        }
    }
}

/// Steps per dispatch of the persistent kernel. Hardware runs a whole batch
/// in one dispatch. llvmpipe (lavapipe) silently ends a shader's loops after
/// 65535 iterations per invocation in all, so there a dispatch runs at most
/// half that many loop iterations, counted here per step for the busiest
/// invocation: its blocks (8 bonds each) in both phases, its junction
/// lanes (each with its junctions), one lane sum, the step loop and its
/// interface blocks' per-block friction law (`Law::block_loop_iterations`);
/// the resident kernel adds its samples' folding rounds to each step and
/// its loading and writing back to each dispatch. Measured on lavapipe
/// (29 × 16 and 36 × 30, f32 and f64, 8 to 256 threads), a dispatch runs
/// 2.2 to 6.8 times this many steps before llvmpipe cuts it; a dispatch
/// cut anyway is caught (`persistent.wgsl` `loop_budget_left`) and is an
/// error, never a silent partial step.
pub fn persistent_steps_per_dispatch(
    model: &Model,
    kernel: Kernel,
    threads: u32,
    lane_run: u32,
    software: bool,
) -> u64 {
    if !software {
        return PERSISTENT_BATCH;
    }
    let t = threads as usize;
    let (lanes, ns) = match (model.law, model.junctions) {
        (FrictionLaw::Junctions | FrictionLaw::SingleJunction, Some(j)) => {
            (crate::model::junction::JUNCTION_LANES.min(j.count), j.count)
        }
        _ => (0, 0),
    };
    let blocks = model.n_blocks().div_ceil(t);
    let friction = model.nx.div_ceil(t) * model.law.declaration().block_loop_iterations;
    let lane_loops = loop_budget::lane_loop_iterations(model.nx, lanes, ns, t, lane_run);
    let mut per_step = 3 + blocks * 10 + lane_loops + lanes + friction;
    let mut budget = loop_budget::SOFTWARE_LOOP_BUDGET;
    if kernel == Kernel::Resident {
        let slots = WORKGROUP_STATE_REDUCTION_WIDTH as usize;
        per_step += t.div_ceil(slots) + slots.ilog2() as usize;
        budget -= 2 * blocks;
    }
    (budget as u64 / per_step as u64).clamp(1, PERSISTENT_BATCH)
}

/// The lane runs a thread may step (`GpuOptions::lane_run`): powers of two
/// up to the lane tree's eight-leaf subtrees.
pub const LANE_RUNS: [u32; 4] = [1, 2, 4, 8];

/// The lane run `gpu_table` section 8 times beside a lane a thread (the
/// run `fitting_lane_run` gives Table S1 on the resident kernel's 1024
/// threads).
pub const LANE_RUN_TIMED: u32 = 4;

/// The lane run `auto` times beside a lane a thread on hardware: the
/// shortest that gives every thread of a junction phase at most one run,
/// where `blocks` interface blocks of `lanes` lanes each step at once on
/// `threads` threads. A thread's lanes are a chain (each lane's loads, its
/// junctions, its merge), so the longest chain is then as short as the
/// threads allow, and a longer run would only lengthen it; a shorter one
/// leaves some threads two runs, as long a chain with more runs' overhead.
/// 1 where a lane a thread already fits, at most the longest run.
pub fn fitting_lane_run(blocks: u32, lanes: u32, threads: u32) -> u32 {
    let longest = LANE_RUNS[LANE_RUNS.len() - 1];
    LANE_RUNS
        .into_iter()
        .find(|&run| blocks.saturating_mul(lanes.div_ceil(run)) <= threads)
        .unwrap_or(longest)
}

/// `--gpu-lane-run`: one of `LANE_RUNS`, else an error naming the value and
/// the allowed ones.
pub fn lane_run(text: &str) -> Result<u32, String> {
    text.parse()
        .ok()
        .filter(|n| LANE_RUNS.contains(n))
        .ok_or_else(|| format!("lane run `{text}`: must be one of {LANE_RUNS:?}"))
}

/// `--gpu-group-scenes`: one of `GROUP_SCENES_ALLOWED`, else an error
/// naming the value and the allowed ones.
pub fn group_scenes(text: &str) -> Result<u32, String> {
    text.parse()
        .ok()
        .filter(|n| GROUP_SCENES_ALLOWED.contains(n))
        .ok_or_else(|| {
            format!("`{text}` scenes a workgroup: must be one of {GROUP_SCENES_ALLOWED:?}")
        })
}

/// Threads of `kernel`'s workgroup: the option, else the kernel's default,
/// within the adapter's limits.
pub fn persistent_threads(
    kernel: Kernel,
    asked: Option<u32>,
    limits: &wgpu::Limits,
    software: bool,
) -> u32 {
    let default = match kernel {
        Kernel::Resident if software => RESIDENT_THREADS_SOFTWARE,
        Kernel::Resident => RESIDENT_THREADS,
        _ => PERSISTENT_THREADS,
    };
    asked
        .unwrap_or(default)
        .min(limits.max_compute_invocations_per_workgroup)
        .min(limits.max_compute_workgroup_size_x)
        .max(1)
}

/// How the resident kernel holds a lattice in workgroup memory
/// (`resident_fit`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ResidentFit {
    /// Bytes of workgroup memory it takes.
    pub bytes: u64,
    /// v in workgroup memory beside u; else v stays in storage, where the
    /// persistent kernel keeps it (`RESIDENT_VELOCITIES`).
    pub velocities: bool,
}

/// How the resident kernel holds `model` in precision `T`: u and v where
/// both fit the adapter's workgroup memory, else u alone. Beside them: the
/// sample reduction's slots and its own words. f64 Table S1 needs 62 KB
/// for both, and NVIDIA's Vulkan driver offers 48 KB; u alone takes 34 KB.
/// An error naming the sizes where not even u fits.
pub fn resident_fit<T: GpuReal>(
    model: &Model,
    limits: &wgpu::Limits,
) -> Result<ResidentFit, String> {
    let disp = std::mem::size_of::<[Coord<T>; 2]>();
    let vel = std::mem::size_of::<[T; 2]>();
    let slots = workgroup_state_reduction_width::<T>() as usize;
    let others = (slots * std::mem::size_of::<layout::GpuSampleSums<T>>()) as u64
        + layout::noted_blocks_bytes::<T>(layout::noted_blocks(model.nx, model.n_junctions()))
        + RESIDENT_OWN_BYTES;
    let both = (model.n_blocks() * (disp + vel)) as u64 + others;
    let disp_only = (model.n_blocks() * disp) as u64 + others;
    let allowed = limits.max_compute_workgroup_storage_size as u64;
    if both <= allowed {
        return Ok(ResidentFit {
            bytes: both,
            velocities: true,
        });
    }
    if disp_only <= allowed {
        return Ok(ResidentFit {
            bytes: disp_only,
            velocities: false,
        });
    }
    Err(format!(
        "the resident kernel holds the lattice in workgroup memory: {} blocks in {} need \
         {disp_only} bytes for their displacements alone ({both} with their velocities), the \
         adapter allows {allowed}: use --gpu-path one-step-lanes or persistent",
        model.n_blocks(),
        T::NAME
    ))
}

impl GpuPath {
    /// Every path that names a kernel, in `Kernel::ALL`'s order (what the
    /// GPU tests run each comparison on).
    pub const KERNELS: [GpuPath; 5] = [
        GpuPath::OneStep,
        GpuPath::OneStepLanes,
        GpuPath::Persistent,
        GpuPath::Resident,
        GpuPath::Tiled,
    ];

    /// The path that names `kernel`.
    pub fn of(kernel: Kernel) -> GpuPath {
        match kernel {
            Kernel::OneStep => GpuPath::OneStep,
            Kernel::OneStepLanes => GpuPath::OneStepLanes,
            Kernel::Persistent => GpuPath::Persistent,
            Kernel::Resident => GpuPath::Resident,
            Kernel::Tiled => GpuPath::Tiled,
        }
    }

    /// The `--gpu-path` value (as the command line spells it).
    pub fn name(self) -> String {
        clap::ValueEnum::to_possible_value(&self)
            .map_or_else(|| format!("{self:?}"), |v| v.get_name().to_string())
    }
}

/// `path` with `auto` and `measure` replaced by the kernel the rule takes
/// (`choose_kernel`): what a sweep runs, alone and in ensembles alike,
/// where it does not measure (`app::sweeps::kernels`).
pub fn without_measuring(path: GpuPath, software: bool) -> GpuPath {
    GpuPath::of(choose_kernel(path, software))
}

/// The kernel for `path` without measuring: what an engine built with
/// `auto` runs where nothing measured (software adapters; a solo run on
/// hardware measures first, `kernel_choice::resolve`, and a sweep once per
/// lattice shape, `kernel_choice::resolve_scenes`).
pub fn choose_kernel(path: GpuPath, software: bool) -> Kernel {
    match path {
        GpuPath::OneStep => Kernel::OneStep,
        GpuPath::OneStepLanes => Kernel::OneStepLanes,
        GpuPath::Persistent => Kernel::Persistent,
        GpuPath::Resident => Kernel::Resident,
        GpuPath::Tiled => Kernel::Tiled,
        // Measured on lavapipe (BENCHMARKS.md): barriers cost more than
        // dispatches there, so neither the lanes nor the persistent kernel
        // pays.
        GpuPath::Auto | GpuPath::Measure if software => Kernel::OneStep,
        // Measured on an H100 and an H200 (BENCHMARKS.md): the lanes kernel
        // is the fastest at every size measured, Table S1 included (11.5
        // against 36 µs per step for the persistent kernel on the H200), and
        // it makes its output samples on the device.
        GpuPath::Auto | GpuPath::Measure => Kernel::OneStepLanes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scenario::{Scenario, DEFAULT_SCENARIO};

    /// The tests' list of kernel paths is every kernel, once, in order.
    #[test]
    fn the_kernel_paths_are_every_kernel() {
        assert_eq!(GpuPath::KERNELS, Kernel::ALL.map(GpuPath::of));
    }

    #[test]
    fn auto_takes_the_barrier_free_kernel_on_software_adapters_and_lanes_on_hardware() {
        assert_eq!(choose_kernel(GpuPath::Auto, true), Kernel::OneStep);
        assert_eq!(choose_kernel(GpuPath::Auto, false), Kernel::OneStepLanes);
        assert_eq!(choose_kernel(GpuPath::Persistent, true), Kernel::Persistent);
        assert_eq!(choose_kernel(GpuPath::OneStep, false), Kernel::OneStep);
    }

    /// On llvmpipe a persistent dispatch of Table S1 stays well inside the
    /// 65535 loop iterations per invocation (measured: a 29 × 16 scene ran
    /// 517 steps per dispatch at most with 256 threads, the bound gives 295).
    #[test]
    fn software_dispatches_stay_within_half_the_loop_limit() {
        let s = Scenario::parse(DEFAULT_SCENARIO, "test", &[]).unwrap();
        let m = Model::from_scenario(&s, false).unwrap();
        let k = persistent_steps_per_dispatch(&m, Kernel::Persistent, 256, 1, true);
        assert_eq!(k, 180);
        assert_eq!(
            persistent_steps_per_dispatch(&m, Kernel::Persistent, 256, 1, false),
            PERSISTENT_BATCH
        );
        // The resident kernel's sample folding and state copies count too.
        let resident = persistent_steps_per_dispatch(&m, Kernel::Resident, 256, 1, true);
        assert!(resident < k && resident > k / 2, "{resident}");
        // A lane run's passes a lane count too: fewer steps a dispatch.
        let runs = persistent_steps_per_dispatch(&m, Kernel::Persistent, 256, 4, true);
        assert!(runs < k && runs > k / 2, "{runs}");
    }

    /// `--gpu-lane-run` takes the powers of two up to 8 and names the
    /// allowed values otherwise.
    #[test]
    fn lane_runs_are_powers_of_two_up_to_eight() {
        for n in LANE_RUNS {
            assert_eq!(lane_run(&n.to_string()), Ok(n));
        }
        for bad in ["0", "3", "16", "-1", "four"] {
            let e = lane_run(bad).unwrap_err();
            assert!(e.contains(bad) && e.contains("[1, 2, 4, 8]"), "{e}");
        }
    }
}
