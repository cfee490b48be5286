//! `--gpu-path auto` on a hardware adapter: every kernel that fits the
//! scene is timed on the scene itself for a few hundred steps, and the
//! fastest steps the run. The choice and its figures are cached per
//! adapter, driver, precision, lattice, compiled terms and kernel sources,
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

use super::context::GpuContext;
use super::options::{GpuOptions, GpuPath};
use super::precision::GpuReal;
use super::shaders::{Kernel, Variant};
use super::GpuEngine;
use crate::engines::{EngineError, EngineState};
use crate::model::scenario::FrictionLaw;
use crate::model::Model;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The persistent kernel steps a lattice with one workgroup: it is timed
/// only up to this many blocks (at 1024×256 it ran 150× slower than the
/// lanes kernel on an H100).
pub const PERSISTENT_MEASURE_MAX_BLOCKS: usize = 16_384;
/// Steps run before timing: the pipeline is compiled and warm.
const WARM_UP_STEPS: u64 = 32;
/// Timed repeats per kernel; the fastest counts (others share the GPU).
const REPEATS: usize = 3;
/// Steps per timed repeat at most, and the wall time one repeat aims at
/// (a large lattice is timed over fewer steps).
const MAX_TIMED_STEPS: u64 = 256;
const TARGET_REPEAT_SECONDS: f64 = 0.05;
/// The most wall time spent stepping the normal-load phase before timing
/// (once for all candidates). A lattice whose load phase takes longer (a
/// large one: more blocks, a shorter time step, more steps) is timed from
/// its initial state, and the choice says so.
pub const PREPARE_BUDGET_SECONDS: f64 = 3.0;
/// Steps timed after the warm-up to estimate the load phase's wall time.
const ESTIMATE_STEPS: u64 = 32;
/// The cache file in the cache directory.
pub const CACHE_FILE: &str = "gpu-kernels.tsv";

/// Threads a workgroup of the single-workgroup kernels (persistent,
/// resident) are timed at when an ensemble is measured: with many scenes,
/// fewer threads a scene let several scenes share a multiprocessor (on an
/// H200, 1024-thread resident scenes ran one per SM, in waves), while one
/// scene alone runs fastest with the most (BENCHMARKS.md, 2026-11-27).
pub const ENSEMBLE_THREADS: [u32; 3] = [256, 512, 1024];

/// A kernel as timed: its threads a workgroup where they were chosen
/// (None: the kernel's default, or `--gpu-threads`). Written
/// `resident/512` (kernel/threads) in figures and in the cache.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Launch {
    pub kernel: Kernel,
    pub threads: Option<u32>,
}

impl Launch {
    pub fn of(kernel: Kernel) -> Launch {
        Launch {
            kernel,
            threads: None,
        }
    }

    /// `one-step-lanes`, `resident/512`.
    pub fn name(self) -> String {
        match self.threads {
            Some(t) => format!("{}/{t}", path_name(self.kernel)),
            None => path_name(self.kernel),
        }
    }

    /// The inverse of `name`.
    pub fn named(name: &str) -> Option<Launch> {
        let (kernel, threads) = match name.split_once('/') {
            Some((k, t)) => (k, Some(t.parse().ok().filter(|&t: &u32| t > 0)?)),
            None => (name, None),
        };
        Some(Launch {
            kernel: kernel_named(kernel)?,
            threads,
        })
    }

    /// `opts` running this launch.
    pub fn options(self, opts: GpuOptions) -> GpuOptions {
        GpuOptions {
            path: GpuPath::of(self.kernel),
            persistent_threads: self.threads.or(opts.persistent_threads),
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
    /// `timed from step 13409 (driving)`; also the cache's field.
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
/// blocks (496) do not say which count wins.
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
                    .map(|&t| Launch {
                        kernel,
                        threads: Some(t),
                    }),
            );
        } else {
            out.push(Launch::of(kernel));
        }
    }
    out
}

/// Wall time per step of `launch` on the scenes `models` (one, or an
/// ensemble stepped in one dispatch), from `start` (one state per scene)
/// or else from their initial state: a warm-up, then the fastest of a few
/// repeats (each an `advance`, which returns when its steps have run on
/// the device).
pub fn time_kernel<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
    launch: Launch,
    start: Option<&[EngineState]>,
) -> Result<f64, EngineError> {
    let opts = launch.options(opts);
    let mut engine = GpuEngine::<T>::build(models, ctx.clone(), opts, models.len() > 1)?;
    if let Some(states) = start {
        engine.start_scenes_from(&states.iter().collect::<Vec<_>>())?;
    }
    let started = Instant::now();
    engine.advance_steps(WARM_UP_STEPS)?;
    let rough = started.elapsed().as_secs_f64() / WARM_UP_STEPS as f64;
    let steps = ((TARGET_REPEAT_SECONDS / rough.max(1e-9)) as u64).clamp(8, MAX_TIMED_STEPS);
    let mut best = f64::INFINITY;
    for _ in 0..REPEATS {
        let t = Instant::now();
        engine.advance_steps(steps)?;
        best = best.min(t.elapsed().as_secs_f64() / steps as f64);
    }
    Ok(best)
}

/// The states the candidates are timed from: the scenes stepped by
/// `launch` to the last step of their normal-load phase, if that takes at
/// most `budget` seconds (estimated from a few steps after a warm-up);
/// else none, and why.
pub fn driving_start<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
    launch: Launch,
    budget: f64,
) -> (Option<Vec<EngineState>>, TimedPhase) {
    let end = models[0].prep_steps.saturating_sub(1);
    if models.iter().any(|m| m.prep_steps != models[0].prep_steps) {
        let why = "the scenes' normal-load phases differ in length".to_string();
        return (None, TimedPhase::NormalLoad { why });
    }
    if end == 0 {
        return (None, TimedPhase::Driving { from_step: 0 });
    }
    let stepped = || -> Result<Result<Vec<EngineState>, String>, EngineError> {
        let mut engine =
            GpuEngine::<T>::build(models, ctx.clone(), launch.options(opts), models.len() > 1)?;
        engine.advance_steps(WARM_UP_STEPS.min(end))?;
        let estimate = ESTIMATE_STEPS.min(end - engine.step);
        let t = Instant::now();
        engine.advance_steps(estimate)?;
        let per_step = t.elapsed().as_secs_f64() / estimate.max(1) as f64;
        let left = end - engine.step;
        let reach = per_step * left as f64;
        if reach > budget {
            return Ok(Err(format!(
                "reaching driving would take {reach:.1} s ({left} steps at {:.1} µs/step on {}), \
                 over the {budget} s budget",
                per_step * 1e6,
                launch.name()
            )));
        }
        engine.advance_steps(left)?;
        (0..models.len())
            .map(|k| engine.save_state_of(k))
            .collect::<Result<Vec<_>, _>>()
            .map(Ok)
    };
    match stepped() {
        Ok(Ok(states)) => (Some(states), TimedPhase::Driving { from_step: end }),
        Ok(Err(why)) => (None, TimedPhase::NormalLoad { why }),
        Err(e) => {
            let why = format!(
                "{} could not step the normal-load phase: {e}",
                launch.name()
            );
            (None, TimedPhase::NormalLoad { why })
        }
    }
}

/// Times every launch (`launches`) on the scenes `models` (one, or an
/// ensemble of one lattice shape) from the start of driving
/// (`driving_start`, within `PREPARE_BUDGET_SECONDS`) and takes the
/// fastest. A launch that cannot be built (a buffer too large, a lattice
/// beyond workgroup memory, a device error) is skipped with its reason; if
/// none can, the first error is returned.
pub fn measure<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
) -> Result<KernelChoice, EngineError> {
    measure_within::<T>(models, ctx, opts, PREPARE_BUDGET_SECONDS)
}

/// `measure` with `budget` seconds to step the normal-load phase.
pub fn measure_within<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
    budget: f64,
) -> Result<KernelChoice, EngineError> {
    let mut timings = Vec::new();
    let mut skipped = Vec::new();
    let mut first_error = None;
    let launches = launches(&models[0], models.len(), opts, &ctx.limits);
    // One-step (always a candidate, first) steps the load phase.
    let (start, phase) = driving_start::<T>(models, ctx, opts, launches[0], budget);
    for launch in launches {
        match time_kernel::<T>(models, ctx, opts, launch, start.as_deref()) {
            Ok(s) => timings.push((launch, s)),
            Err(e) => {
                skipped.push((launch, e.to_string()));
                first_error.get_or_insert(e);
            }
        }
    }
    let Some(&(launch, _)) = timings.iter().min_by(|a, b| a.1.total_cmp(&b.1)) else {
        return Err(first_error.expect("at least one candidate (one-step always is)"));
    };
    Ok(KernelChoice {
        launch,
        timings,
        source: ChoiceSource::Measured,
        skipped,
        scenes: models.len(),
        phase,
    })
}

/// The measured choices of this machine, one line per adapter and lattice:
/// `key <TAB> launch <TAB> launch=seconds,... <TAB> phase` (a launch:
/// `resident`, or `resident/512` with its threads; the phase as
/// `TimedPhase::describe` writes it). A line without its phase (an older
/// build's, timed in the load phase) is measured again.
#[derive(Debug, Clone)]
pub struct ChoiceCache {
    /// None: no cache directory could be found (nothing is kept).
    dir: Option<PathBuf>,
}

impl ChoiceCache {
    /// `$SLIPFRONT_CACHE_DIR`, else `$XDG_CACHE_HOME/slipfront`, else
    /// `~/.cache/slipfront`.
    pub fn default_location() -> ChoiceCache {
        let env = |k: &str| {
            std::env::var_os(k)
                .filter(|v| !v.is_empty())
                .map(PathBuf::from)
        };
        let dir = env("SLIPFRONT_CACHE_DIR")
            .or_else(|| env("XDG_CACHE_HOME").map(|d| d.join("slipfront")))
            .or_else(|| env("HOME").map(|d| d.join(".cache").join("slipfront")));
        ChoiceCache { dir }
    }

    pub fn at(dir: &Path) -> ChoiceCache {
        ChoiceCache {
            dir: Some(dir.to_path_buf()),
        }
    }

    pub fn file(&self) -> Option<PathBuf> {
        self.dir.as_ref().map(|d| d.join(CACHE_FILE))
    }

    fn lines(&self) -> Vec<String> {
        self.file()
            .and_then(|f| std::fs::read_to_string(f).ok())
            .map(|text| text.lines().map(str::to_string).collect())
            .unwrap_or_default()
    }

    /// The choice stored under `key`; a line that does not parse is
    /// ignored (measured again).
    pub fn lookup(&self, key: &str) -> Option<KernelChoice> {
        self.lines().iter().find_map(|line| {
            let mut fields = line.split('\t');
            if fields.next()? != key {
                return None;
            }
            let launch = Launch::named(fields.next()?)?;
            let timings = fields
                .next()?
                .split(',')
                .map(|pair| {
                    let (name, seconds) = pair.split_once('=')?;
                    let seconds: f64 = seconds.parse().ok()?;
                    (seconds.is_finite() && seconds > 0.0)
                        .then_some((Launch::named(name)?, seconds))
                })
                .collect::<Option<Vec<_>>>()?;
            let phase = TimedPhase::described(fields.next()?)?;
            timings
                .iter()
                .any(|(l, _)| *l == launch)
                .then_some(KernelChoice {
                    launch,
                    timings,
                    source: ChoiceSource::Cached,
                    skipped: Vec::new(),
                    scenes: 1,
                    phase,
                })
        })
    }

    /// Stores `choice` under `key`, replacing an older line. The file is
    /// written whole and renamed into place, so a reader never sees half
    /// of it. Failing to write only loses the cache: returns why.
    pub fn store(&self, key: &str, choice: &KernelChoice) -> Result<(), String> {
        let (Some(dir), Some(file)) = (&self.dir, self.file()) else {
            return Err("no cache directory (set SLIPFRONT_CACHE_DIR)".into());
        };
        let mut lines: Vec<String> = self
            .lines()
            .into_iter()
            .filter(|l| l.split('\t').next() != Some(key))
            .collect();
        let figures: Vec<String> = choice
            .timings
            .iter()
            .map(|(l, s)| format!("{}={s:e}", l.name()))
            .collect();
        lines.push(format!(
            "{key}\t{}\t{}\t{}",
            choice.launch.name(),
            figures.join(","),
            choice.phase.describe().replace(['\t', '\n'], " ")
        ));
        let write = || -> std::io::Result<()> {
            std::fs::create_dir_all(dir)?;
            let tmp = dir.join(format!("{CACHE_FILE}.{}.tmp", std::process::id()));
            std::fs::write(&tmp, lines.join("\n") + "\n")?;
            std::fs::rename(&tmp, &file)
        };
        write().map_err(|e| format!("cannot write {}: {e}", file.display()))
    }
}

/// What a measured choice depends on: the adapter and its driver, the
/// precision, the lattice (`lattice_key`), the persistent kernels' threads
/// and the kernels' sources (a new version of slipfront measures again).
pub fn cache_key<T: GpuReal>(model: &Model, ctx: &GpuContext, opts: GpuOptions) -> String {
    scenes_cache_key::<T>(model, 1, ctx, opts)
}

/// The lattice a choice is for: its shape, junction count and compiled
/// terms (scenes alike in these step at the same speed).
pub fn lattice_key(model: &Model) -> String {
    format!(
        "{}x{} | junctions {} | {}",
        model.nx,
        model.nz,
        model.n_junctions(),
        Variant::for_model(model).describe()
    )
}

/// `cache_key` of an ensemble of `scenes` scenes like `model` (one scene:
/// the solo key).
pub fn scenes_cache_key<T: GpuReal>(
    model: &Model,
    scenes: usize,
    ctx: &GpuContext,
    opts: GpuOptions,
) -> String {
    let mut sources = std::collections::hash_map::DefaultHasher::new();
    for kernel in Kernel::ALL {
        kernel.source::<T>().hash(&mut sources);
    }
    let info = &ctx.info;
    let ensemble = if scenes > 1 {
        format!(" | ensemble of {scenes}")
    } else {
        String::new()
    };
    format!(
        "{} | {:?} | {} {} | {} | {}{ensemble} | threads {} | kernels {:016x}",
        info.name,
        info.backend,
        info.driver,
        info.driver_info,
        T::NAME,
        lattice_key(model),
        opts.persistent_threads
            .map_or_else(|| "default".to_string(), |t| t.to_string()),
        sources.finish()
    )
    .replace(['\t', '\n'], " ")
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
