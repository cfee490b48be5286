//! `--gpu-path auto` on a hardware adapter: every kernel that fits the
//! scene is timed on the scene itself, and the fastest steps the run. A
//! launch's figure is what a step costs in a run: the time a long span of
//! steps takes beyond a short one, over the extra steps, which leaves out
//! what each timed advance pays once (`step_timing::marginal_step_seconds`).
//! A run with an output file is timed recording its samples on the
//! device at its cadences (`GpuOptions::samples`): output weighs on the
//! launches unequally (a one-step launch adds record dispatches, a
//! persistent or tiled one reduces each sample in its workgroups).
//! The choice and its figures are cached per
//! adapter, driver, precision, lattice, compiled terms, output cadences
//! and kernel sources,
//! so a second run of the same shape starts at once.
//!
//! The kernels are timed from the end of the scene's normal-load phase,
//! stepped once beforehand and shared by every candidate: a run spends
//! nearly all its steps driving, and there a quiet block keeps its
//! junction sums, while in the load phase every junction is written each
//! step. Timed in the load phase, a kernel whose junction work is its cost
//! would be judged on work it mostly skips.
//!
//! Why measure: the fixed rule picked a kernel 3.3× slower than the best
//! on an H100 for Table S1 (BENCHMARKS.md), and which kernel wins depends
//! on the lattice, the junction count, the precision and the GPU.
//! Software adapters (lavapipe) keep the measured rule of
//! `options::choose_kernel`: there pipelines take seconds to compile, and
//! runs must stay deterministic in CI. `--gpu-path measure` times the
//! kernels anyway, on any adapter, and refreshes the cache.
//!
//! The tiled kernel's tile shape is searched too (a few widths, then a
//! few halos at the fastest width): which shape wins depends on how many
//! multiprocessors the GPU has against the lattice's columns, and no
//! hardware figure fixes a default yet. So is where the junction lanes'
//! sums merge (in subgroups first, or all through storage): the fastest
//! launch that merged in subgroups is timed again with every sum through
//! storage. Both merge the same sums by the same tree (bit for bit but
//! where a driver compiles a rounding tie apart: docs/gpu-kernels.md); no
//! hardware run has timed the subgroup merges yet.
//!
//! `timing` times the launches, `cache` keeps the choices.

mod cache;
mod timing;

pub use cache::{cache_key, lattice_key, scenes_cache_key, ChoiceCache, CACHE_FILE};
pub use timing::{
    chained_halo_search, driving_start, measure, measure_within, search_tile_shapes, time_kernel,
    PREPARE_BUDGET_SECONDS,
};

use super::context::GpuContext;
use super::options::{GpuOptions, GpuPath};
use super::precision::GpuReal;
use super::shaders::Kernel;
use super::tiles::TileShape;
use crate::engines::EngineError;
use crate::model::scenario::FrictionLaw;
use crate::model::Model;

/// The persistent kernel steps a lattice with one workgroup: it is timed
/// only up to this many blocks (at 1024×256 it ran 150× slower than the
/// lanes kernel on an H100).
pub const PERSISTENT_MEASURE_MAX_BLOCKS: usize = 16_384;

/// Threads a workgroup of the single-workgroup kernels (persistent,
/// resident) are timed at when an ensemble is measured: with many scenes,
/// fewer threads a scene let several scenes share a multiprocessor (on an
/// H200, 1024-thread resident scenes ran one per SM, in waves), while one
/// scene alone runs fastest with the most (BENCHMARKS.md, 2026-11-27).
pub const ENSEMBLE_THREADS: [u32; 3] = [256, 512, 1024];

/// Scenes a persistent workgroup is timed with side by side when an
/// ensemble is measured (`GpuOptions::group_scenes`): on NVIDIA a
/// 1024-thread workgroup is held to 64 registers a thread, so two or four
/// scenes share a multiprocessor that one 512- or 256-thread scene with
/// more registers has to itself (on an H200, 256 Table S1 scenes ran in
/// two waves of one scene an SM).
pub const ENSEMBLE_GROUP_SCENES: [u32; 2] = [2, 4];
/// The fewest threads a scene of a group is timed with.
const MIN_SCENE_THREADS: u32 = 64;

/// A kernel as timed: its threads a workgroup where they were chosen
/// (None: the kernel's default, or `--gpu-threads`), for the tiled
/// kernel its tile shape where one was searched (None: the default, or
/// `--gpu-tile`), and whether its junction lanes' sums all went through
/// storage where they would merge in subgroups first, and whether its bulk
/// forces went by patches of blocks. Written `resident/512`,
/// `tiled/1024/16x4`, `resident/1024/lanes-in-storage` or
/// `persistent/1024/bond-patches` (kernel/threads/shape/lanes/patches) in
/// figures and in the cache.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Launch {
    pub kernel: Kernel,
    pub threads: Option<u32>,
    pub tile: Option<TileShape>,
    /// Every lane's sum through storage (`GpuOptions::lane_shuffle`
    /// false): the same sums by the same tree, at another speed.
    /// Only for the kernels that merge lanes through storage.
    pub lanes_in_storage: bool,
    /// Bulk forces by 2×2 patches of blocks (`GpuOptions::bond_patches`):
    /// the same forces to their last bits, another split of the work.
    pub bond_patches: bool,
    /// One junction lane a round (`GpuOptions::two_lanes_a_round` false):
    /// the same bits, fewer registers a thread. Only for the persistent
    /// and resident kernels.
    pub one_lane_a_round: bool,
    /// The tiled kernel's rounds chained in one dispatch
    /// (`GpuOptions::chained_tiles`): the same bits, fewer dispatches.
    pub chained_tiles: bool,
    /// Junction lanes a thread (`GpuOptions::lane_run`) where not the
    /// options': the same bits, fewer instructions a block's lanes. Only
    /// for the persistent, resident and tiled kernels.
    pub lane_run: Option<u32>,
    /// Scenes a persistent workgroup steps side by side
    /// (`GpuOptions::group_scenes`) where not the options': the same bits,
    /// scenes sharing a multiprocessor.
    pub group_scenes: Option<u32>,
}

/// The name's part (after the threads) for `Launch::group_scenes`, after
/// its count.
const SCENES: &str = "-scenes";
/// The name's last part for `Launch::lanes_in_storage`.
const LANES_IN_STORAGE: &str = "lanes-in-storage";
/// The name's last part for `Launch::bond_patches`.
const BOND_PATCHES: &str = "bond-patches";
/// The name's last part for `Launch::one_lane_a_round`.
const ONE_LANE_A_ROUND: &str = "one-lane-a-round";
/// The name's part (after the tile shape) for `Launch::chained_tiles`.
const CHAINED: &str = "chained";
/// The name's last part for `Launch::lane_run`, before its count.
const LANE_RUN: &str = "lane-run-";

impl Launch {
    pub fn of(kernel: Kernel) -> Launch {
        Launch {
            kernel,
            threads: None,
            tile: None,
            lanes_in_storage: false,
            bond_patches: false,
            one_lane_a_round: false,
            chained_tiles: false,
            lane_run: None,
            group_scenes: None,
        }
    }

    /// `kernel` at `threads` threads a workgroup.
    pub fn with_threads(kernel: Kernel, threads: u32) -> Launch {
        Launch {
            threads: Some(threads),
            ..Launch::of(kernel)
        }
    }

    /// This launch with tiles of `shape`.
    pub fn with_tile(self, shape: TileShape) -> Launch {
        Launch {
            tile: Some(shape),
            ..self
        }
    }

    /// This launch with every lane's sum through storage.
    pub fn with_lanes_in_storage(self) -> Launch {
        Launch {
            lanes_in_storage: true,
            ..self
        }
    }

    /// This launch with the bulk forces by patches.
    pub fn with_bond_patches(self) -> Launch {
        Launch {
            bond_patches: true,
            ..self
        }
    }

    /// This launch with one junction lane a round.
    pub fn with_one_lane_a_round(self) -> Launch {
        Launch {
            one_lane_a_round: true,
            ..self
        }
    }

    /// This launch with `run` junction lanes a thread.
    pub fn with_lane_run(self, run: u32) -> Launch {
        Launch {
            lane_run: Some(run),
            ..self
        }
    }

    /// Whether the launch's kernel steps lane runs (the persistent,
    /// resident and tiled kernels).
    pub fn has_lane_runs(self) -> bool {
        self.kernel.is_persistent() || self.kernel == Kernel::Tiled
    }

    /// This launch with `scenes` scenes a workgroup.
    pub fn with_group_scenes(self, scenes: u32) -> Launch {
        Launch {
            group_scenes: Some(scenes),
            ..self
        }
    }

    /// This launch with the tiled kernel's rounds chained.
    pub fn with_chained_tiles(self) -> Launch {
        Launch {
            chained_tiles: true,
            ..self
        }
    }

    /// `one-step-lanes`, `resident/512`, `tiled/1024/16x4`, `tiled/256/8x4/chained`,
    /// `resident/1024/lanes-in-storage`, `persistent/1024/bond-patches`,
    /// `resident/256/bond-patches/one-lane-a-round`, `resident/1024/lane-run-4`,
    /// `persistent/1024/2-scenes`.
    pub fn name(self) -> String {
        let mut name = path_name(self.kernel);
        if let Some(t) = self.threads {
            name += &format!("/{t}");
        }
        if let Some(g) = self.group_scenes {
            name += &format!("/{g}{SCENES}");
        }
        if let Some(shape) = self.tile {
            name += &format!("/{}", shape.name());
        }
        if self.chained_tiles {
            name += &format!("/{CHAINED}");
        }
        if self.lanes_in_storage {
            name += &format!("/{LANES_IN_STORAGE}");
        }
        if self.bond_patches {
            name += &format!("/{BOND_PATCHES}");
        }
        if self.one_lane_a_round {
            name += &format!("/{ONE_LANE_A_ROUND}");
        }
        if let Some(run) = self.lane_run {
            name += &format!("/{LANE_RUN}{run}");
        }
        name
    }

    /// The inverse of `name`: the parts in its order, each at most once.
    pub fn named(name: &str) -> Option<Launch> {
        let mut parts = name.split('/');
        let mut launch = Launch::of(kernel_named(parts.next()?)?);
        let mut rest = parts.peekable();
        if let Some(t) = rest.next_if(|p| {
            p.starts_with(|c: char| c.is_ascii_digit()) && !p.contains('x') && !p.ends_with(SCENES)
        }) {
            launch.threads = Some(t.parse().ok().filter(|&t: &u32| t > 0)?);
        }
        if let Some(g) = rest.next_if(|p| p.ends_with(SCENES)) {
            let g = g[..g.len() - SCENES.len()].parse().ok();
            let allowed = super::options::GROUP_SCENES_ALLOWED;
            if launch.kernel != Kernel::Persistent {
                return None;
            }
            launch.group_scenes = Some(g.filter(|g| allowed.contains(g))?);
        }
        if let Some(shape) = rest.next_if(|p| {
            ![CHAINED, LANES_IN_STORAGE, BOND_PATCHES, ONE_LANE_A_ROUND].contains(p)
                && !p.starts_with(LANE_RUN)
        }) {
            if launch.kernel != Kernel::Tiled {
                return None;
            }
            launch.tile = Some(TileShape::parse(shape).ok()?);
        }
        if rest.next_if(|p| *p == CHAINED).is_some() {
            if launch.kernel != Kernel::Tiled {
                return None;
            }
            launch.chained_tiles = true;
        }
        if rest.next_if(|p| *p == LANES_IN_STORAGE).is_some() {
            if !launch.kernel.merges_lanes_through_storage() {
                return None;
            }
            launch.lanes_in_storage = true;
        }
        if rest.next_if(|p| *p == BOND_PATCHES).is_some() {
            launch.bond_patches = true;
        }
        if rest.next_if(|p| *p == ONE_LANE_A_ROUND).is_some() {
            if !launch.kernel.is_persistent() {
                return None;
            }
            launch.one_lane_a_round = true;
        }
        if let Some(run) = rest.next_if(|p| p.starts_with(LANE_RUN)) {
            if !launch.has_lane_runs() {
                return None;
            }
            let run = run[LANE_RUN.len()..].parse().ok();
            launch.lane_run = Some(run.filter(|r| super::options::LANE_RUNS.contains(r))?);
        }
        rest.next().is_none().then_some(launch)
    }

    /// `opts` running this launch.
    pub fn options(self, opts: GpuOptions) -> GpuOptions {
        GpuOptions {
            path: GpuPath::of(self.kernel),
            persistent_threads: self.threads.or(opts.persistent_threads),
            tile: self.tile.or(opts.tile),
            lane_shuffle: opts.lane_shuffle && !self.lanes_in_storage,
            bond_patches: opts.bond_patches || self.bond_patches,
            two_lanes_a_round: opts.two_lanes_a_round && !self.one_lane_a_round,
            lane_run: self.lane_run.unwrap_or(opts.lane_run),
            // Only the tiled kernel has rounds to chain.
            chained_tiles: (opts.chained_tiles || self.chained_tiles)
                && self.kernel == Kernel::Tiled,
            // Only the persistent kernel steps scenes side by side.
            group_scenes: match self.kernel {
                Kernel::Persistent => self.group_scenes.unwrap_or(opts.group_scenes),
                _ => 1,
            },
            ..opts
        }
    }
}

/// Where a choice came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChoiceSource {
    /// Timed now on this scene.
    Measured,
    /// Timed earlier on this adapter for this lattice (the cache).
    Cached,
}

/// Where the candidates were timed.
#[derive(Debug, Clone, PartialEq)]
pub enum TimedPhase {
    /// From the state at `from_step`, the last step of the normal-load
    /// phase: the timed steps are the first of driving.
    Driving { from_step: u64 },
    /// From the initial state, in the normal-load phase, and why.
    NormalLoad { why: String },
}

impl TimedPhase {
    /// `timed in driving from step 13409`; also the cache's field.
    pub fn describe(&self) -> String {
        match self {
            TimedPhase::Driving { from_step } => format!("timed in driving from step {from_step}"),
            TimedPhase::NormalLoad { why } => format!("timed in the normal-load phase: {why}"),
        }
    }

    /// The inverse of `describe`.
    pub fn described(text: &str) -> Option<TimedPhase> {
        if let Some(step) = text.strip_prefix("timed in driving from step ") {
            return Some(TimedPhase::Driving {
                from_step: step.parse().ok()?,
            });
        }
        let why = text.strip_prefix("timed in the normal-load phase: ")?;
        Some(TimedPhase::NormalLoad {
            why: why.to_string(),
        })
    }
}

/// The kernel that steps a run, and the figures behind it.
#[derive(Debug, Clone, PartialEq)]
pub struct KernelChoice {
    pub launch: Launch,
    /// Each launch timed, with its wall time per step in seconds.
    pub timings: Vec<(Launch, f64)>,
    pub source: ChoiceSource,
    /// Candidates that could not be timed, and why.
    pub skipped: Vec<(Launch, String)>,
    /// Scenes stepped together while timed (1: a solo run's choice).
    pub scenes: usize,
    /// The state the launches were timed from.
    pub phase: TimedPhase,
    /// Where the launches were timed recording the run's output samples
    /// on the device (`GpuOptions::samples`): the fewest samples a launch
    /// recorded (0: none fell in its timed steps, as in the normal-load
    /// phase). None: timed without output.
    pub recorded: Option<u64>,
}

impl KernelChoice {
    /// `chose one-step-lanes: one-step 45.1, one-step-lanes 8.7,
    /// persistent 29.0 µs/step, measured now on this scene`.
    pub fn describe(&self) -> String {
        let figures: Vec<String> = self
            .timings
            .iter()
            .map(|(l, s)| format!("{} {:.1}", l.name(), s * 1e6))
            .collect();
        let source = match (self.source, self.scenes) {
            (ChoiceSource::Measured, 1) => "measured now on this scene".to_string(),
            (ChoiceSource::Measured, n) => format!("measured now on an ensemble of {n} scenes"),
            (ChoiceSource::Cached, 1) => {
                "measured earlier on this adapter for this lattice".to_string()
            }
            (ChoiceSource::Cached, n) => {
                format!("measured earlier on this adapter for ensembles of {n} of this lattice")
            }
        };
        let unit = if self.scenes > 1 {
            "µs per step of the ensemble"
        } else {
            "µs/step"
        };
        let mut text = format!(
            "chose {}: {} {unit}, {source}, {}",
            self.launch.name(),
            figures.join(", "),
            self.phase.describe()
        );
        text += &match self.recorded {
            None => String::new(),
            Some(0) => ", with the run's output cadences but no sample in the timed steps".into(),
            Some(n) => {
                format!(", recording the run's output on the device ({n} samples or more a launch)")
            }
        };
        for (l, why) in &self.skipped {
            text += &format!("; {} not timed: {why}", l.name());
        }
        text
    }

    /// The kernel chosen.
    pub fn kernel(&self) -> Kernel {
        self.launch.kernel
    }
}

/// The `--gpu-path` value of `kernel`.
pub fn path_name(kernel: Kernel) -> String {
    GpuPath::of(kernel).name()
}

fn kernel_named(name: &str) -> Option<Kernel> {
    Kernel::ALL.into_iter().find(|k| path_name(*k) == name)
}

/// The kernels worth timing on `model`: the lanes kernel only where
/// junctions give it lanes, the persistent and tiled kernels only on small
/// lattices (the tiled one without a per-block friction law).
pub fn candidates(model: &Model) -> Vec<Kernel> {
    let junctions = matches!(
        model.law,
        FrictionLaw::Junctions | FrictionLaw::SingleJunction
    ) && model.junctions.is_some_and(|j| j.count > 1);
    Kernel::ALL
        .into_iter()
        .filter(|k| match k {
            Kernel::OneStep => true,
            Kernel::OneStepLanes => junctions,
            // The resident kernel is refused at build where the lattice
            // does not fit workgroup memory (skipped with that reason).
            Kernel::Persistent | Kernel::Resident => {
                model.n_blocks() <= PERSISTENT_MEASURE_MAX_BLOCKS
            }
            // Refused at build too where its tile does not fit.
            Kernel::Tiled => {
                !model.law.is_per_block() && model.n_blocks() <= PERSISTENT_MEASURE_MAX_BLOCKS
            }
        })
        .collect()
}

/// The launches to time on `scenes` scenes like `model`: every candidate
/// kernel, and for an ensemble the single-workgroup kernels at each of
/// `ENSEMBLE_THREADS` the adapter allows, unless `--gpu-threads` fixed
/// them. A scene alone takes each kernel's default threads (on an H200 the
/// most threads were fastest alone, and every variant costs a compile),
/// but the tiled kernel is timed at each of them too: not yet measured on
/// hardware, a tile's lanes (1,024 at Table S1's defaults) against its
/// blocks (496) do not say which count wins. An ensemble also times the
/// persistent kernel with `ENSEMBLE_GROUP_SCENES` scenes side by side in
/// its largest workgroup (where there are that many scenes), unless the
/// options fix the threads or the scenes a workgroup.
pub fn launches(
    model: &Model,
    scenes: usize,
    opts: GpuOptions,
    limits: &wgpu::Limits,
) -> Vec<Launch> {
    let most = limits
        .max_compute_invocations_per_workgroup
        .min(limits.max_compute_workgroup_size_x);
    let mut out = Vec::new();
    for kernel in candidates(model) {
        let varied = kernel == Kernel::Tiled || (kernel.is_persistent() && scenes > 1);
        if varied && opts.persistent_threads.is_none() {
            out.extend(
                ENSEMBLE_THREADS
                    .iter()
                    .filter(|&&t| t <= most)
                    .map(|&t| Launch::with_threads(kernel, t)),
            );
        } else {
            out.push(Launch::of(kernel));
        }
        let grouped = kernel == Kernel::Persistent
            && opts.persistent_threads.is_none()
            && opts.group_scenes == 1;
        let largest = ENSEMBLE_THREADS
            .iter()
            .copied()
            .filter(|&t| t <= most)
            .max();
        if let Some(threads) = largest.filter(|_| grouped) {
            out.extend(
                ENSEMBLE_GROUP_SCENES
                    .iter()
                    .filter(|&&g| g as usize <= scenes && threads / g >= MIN_SCENE_THREADS)
                    .map(|&g| Launch::with_threads(kernel, threads).with_group_scenes(g)),
            );
        }
    }
    out
}

/// The options a solo run is built with, and the measured choice behind
/// them: `auto` on a hardware adapter takes the cached choice or measures
/// and caches one; `measure` always measures (and caches); any other path
/// (and `auto` on a software adapter, by the rule) is kept as it is.
pub fn resolve<T: GpuReal>(
    model: &Model,
    ctx: &GpuContext,
    opts: GpuOptions,
    cache: &ChoiceCache,
) -> Result<(GpuOptions, Option<KernelChoice>), EngineError> {
    resolve_scenes::<T>(model, 1, ctx, opts, cache)
}

/// `resolve` for `scenes` scenes like `model` stepped as one ensemble: the
/// candidates are timed on such an ensemble (a sweep's kernel: which
/// kernel fills the GPU best depends on how many scenes share it).
pub fn resolve_scenes<T: GpuReal>(
    model: &Model,
    scenes: usize,
    ctx: &GpuContext,
    opts: GpuOptions,
    cache: &ChoiceCache,
) -> Result<(GpuOptions, Option<KernelChoice>), EngineError> {
    let use_cache = match opts.path {
        GpuPath::Auto if !ctx.is_software() => true,
        GpuPath::Measure => false,
        _ => return Ok((opts, None)),
    };
    let key = scenes_cache_key::<T>(model, scenes, ctx, opts);
    let cached = if use_cache { cache.lookup(&key) } else { None };
    let choice = match cached {
        Some(c) => KernelChoice { scenes, ..c },
        None => {
            let c = measure::<T>(&vec![model.clone(); scenes.max(1)], ctx, opts)?;
            // A cache that cannot be written costs only the next run's
            // measurement.
            let _ = cache.store(&key, &c);
            c
        }
    };
    Ok((choice.launch.options(opts), Some(choice)))
}
