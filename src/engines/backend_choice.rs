//! `--backend auto` on a hardware GPU: the GPU engine (its kernel as
//! `--gpu-path` chose it; `auto` measures the kernels) against the CPU
//! engine (its threads as `--threads` asks; `0` times them), each timed on
//! the scene itself, from the same state (the last step of its
//! normal-load phase where the GPU reaches it within the kernel choice's
//! budget), by the same procedure (`step_timing`: what a step costs in a
//! run, without output). The faster steps the run.
//!
//! Why measure: a hardware GPU is not always the faster. A consumer GPU
//! runs f64 at 1/32 to 1/64 of its f32 rate and an integrated one has few
//! cores, while the thesis's lattice is small (57 × 31 blocks), which a
//! CPU's cache holds. Even on the H100 (2026-11-25, issue 32) the kernel
//! `auto` then picked stepped Table S1 in 29 µs, the pace of one core of
//! its host: which engine is faster is a measurement, not a rule.
//!
//! The choice and its figures are printed, and cached per adapter and
//! driver, precision, lattice, GPU launch and options, kernel sources
//! (`kernel_choice::cache_key`), the CPU's cores, the threads asked and
//! slipfront's version, beside the kernel choices (`CACHE_FILE`): a
//! second run of the same shape starts at once.

use crate::engines::gpu::context::GpuContext;
use crate::engines::gpu::kernel_choice::{
    self, ChoiceCache, ChoiceSource, Launch, TimedPhase, PREPARE_BUDGET_SECONDS,
};
use crate::engines::gpu::precision::GpuReal;
use crate::engines::gpu::{GpuEngine, GpuOptions};
use crate::engines::step_timing::{step_seconds, WARM_UP_STEPS};
use crate::engines::{cpu::SweepEngine, Engine, EngineError, EngineState};
use crate::model::Model;
use std::time::Instant;

/// The cache file, in the kernel choices' directory.
pub const CACHE_FILE: &str = "backend-choices.tsv";

/// The most wall time the CPU engine's own trial of thread counts may
/// take before it is timed (a trial of a handful of counts takes well
/// under a second).
const THREAD_TRIAL_SECONDS: f64 = 10.0;

/// A CPU whose first step takes longer than this, and more than
/// `SLOW_STEP_RATIO` times the GPU's step, is not timed further: that
/// step is its figure (a large lattice, whose timing would take seconds
/// to lose). Below it a first step pays one-off costs (a thread trial's
/// first pool) that the figure must not.
const SLOW_STEP_SECONDS: f64 = 5e-3;
const SLOW_STEP_RATIO: f64 = 4.0;

/// What `auto` on a hardware GPU found.
#[derive(Debug, Clone, PartialEq)]
pub enum AutoChoice {
    /// Both engines timed (or their cached figures).
    Timed(BackendChoice),
    /// The CPU engine was not built: its state would need more than half
    /// the memory available (`needed` and `available` bytes).
    CpuWouldNotFit { needed: u64, available: u64 },
    /// The timing failed (why): the GPU runs, as before there was a
    /// comparison, and the run itself reports what fails.
    NotCompared(String),
}

impl AutoChoice {
    pub fn cpu_is_faster(&self) -> bool {
        matches!(self, AutoChoice::Timed(c) if c.cpu_is_faster())
    }

    pub fn timed(&self) -> Option<&BackendChoice> {
        match self {
            AutoChoice::Timed(c) => Some(c),
            AutoChoice::CpuWouldNotFit { .. } | AutoChoice::NotCompared(_) => None,
        }
    }

    pub fn describe(&self) -> String {
        use crate::engines::memory::human;
        match self {
            AutoChoice::Timed(c) => c.describe(),
            AutoChoice::CpuWouldNotFit { needed, available } => format!(
                "the CPU engine would need {} of the {} available, so it is not timed: \
                 the GPU steps the run",
                human(*needed),
                human(*available)
            ),
            AutoChoice::NotCompared(why) => {
                format!("the GPU and the CPU could not be timed ({why}): the GPU steps the run")
            }
        }
    }
}

/// Whether a CPU engine of `needed` bytes may be built to be timed: at
/// most half the memory available (unknown: yes).
pub fn cpu_fits(needed: u64, available: Option<u64>) -> Result<(), AutoChoice> {
    match available {
        Some(available) if needed > available / 2 => {
            Err(AutoChoice::CpuWouldNotFit { needed, available })
        }
        _ => Ok(()),
    }
}

/// The engine `auto` runs on, and the figures behind it.
#[derive(Debug, Clone, PartialEq)]
pub struct BackendChoice {
    /// The GPU's launch as timed (`Launch::name`).
    pub gpu_launch: String,
    /// The GPU engine's wall seconds a step.
    pub gpu_seconds: f64,
    /// The CPU engine's threads as timed (after its own trial, where it
    /// makes one).
    pub cpu_threads: usize,
    /// The CPU engine's wall seconds a step.
    pub cpu_seconds: f64,
    /// The state both were timed from.
    pub phase: TimedPhase,
    pub source: ChoiceSource,
}

impl BackendChoice {
    /// The CPU steps the run only where it is faster: at a tie the GPU,
    /// which frees the CPU.
    pub fn cpu_is_faster(&self) -> bool {
        self.cpu_seconds < self.gpu_seconds
    }

    /// `the GPU (LAUNCH) G µs a step against the CPU (N thread(s)) C µs,
    /// timed in driving from step S, measured now: the GPU steps the run`
    /// (the winner first).
    pub fn describe(&self) -> String {
        let source = match self.source {
            ChoiceSource::Measured => "measured now",
            ChoiceSource::Cached => "measured earlier on this machine",
        };
        let gpu = (
            "the GPU",
            format!(" ({})", self.gpu_launch),
            self.gpu_seconds,
        );
        let cpu = (
            "the CPU",
            format!(" ({} thread(s))", self.cpu_threads),
            self.cpu_seconds,
        );
        let (winner, other) = if self.cpu_is_faster() {
            (cpu, gpu)
        } else {
            (gpu, cpu)
        };
        format!(
            "{}{} {:.1} µs a step against {}{} {:.1} µs, {}, {source}: {} steps the run",
            winner.0,
            winner.1,
            winner.2 * 1e6,
            other.0,
            other.1,
            other.2 * 1e6,
            self.phase.describe(),
            winner.0
        )
    }

    /// The cache line's fields: `launch <TAB> seconds <TAB> threads <TAB>
    /// seconds <TAB> phase`.
    fn fields(&self) -> String {
        format!(
            "{}\t{:e}\t{}\t{:e}\t{}",
            self.gpu_launch,
            self.gpu_seconds,
            self.cpu_threads,
            self.cpu_seconds,
            self.phase.describe().replace(['\t', '\n'], " ")
        )
    }

    /// The inverse of `fields` (None: not a choice, measured again).
    fn parsed(fields: &str) -> Option<BackendChoice> {
        let mut f = fields.split('\t');
        let gpu_launch = f.next()?.to_string();
        let gpu_seconds: f64 = f.next()?.parse().ok()?;
        let cpu_threads: usize = f.next()?.parse().ok()?;
        let cpu_seconds: f64 = f.next()?.parse().ok()?;
        let phase = TimedPhase::described(f.next()?)?;
        let positive = |s: f64| s.is_finite() && s > 0.0;
        (f.next().is_none() && positive(gpu_seconds) && positive(cpu_seconds) && cpu_threads > 0)
            .then_some(BackendChoice {
                gpu_launch,
                gpu_seconds,
                cpu_threads,
                cpu_seconds,
                phase,
                source: ChoiceSource::Cached,
            })
    }
}

/// The launch `engine` steps with: `auto`'s measured one, else its
/// kernel (with the options it was built with, which `Launch::options`
/// keeps).
pub fn launch_of<T: GpuReal>(engine: &GpuEngine<T>) -> Launch {
    engine
        .kernel_choice()
        .map_or_else(|| Launch::of(engine.kernel()), |c| c.launch)
}

/// What a choice depends on (the module's header): the kernel choice's
/// key without output cadences, the launch, the CPU's cores, the threads
/// asked and slipfront's version.
pub fn cache_key<T: GpuReal>(
    model: &Model,
    ctx: &GpuContext,
    opts: GpuOptions,
    launch: Launch,
    threads: usize,
) -> String {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!(
        "{} | launch {} | cpu: {cores} cores, --threads {threads}, slipfront {}",
        kernel_choice::cache_key::<T>(
            model,
            ctx,
            GpuOptions {
                samples: None,
                ..opts
            }
        ),
        launch.name(),
        env!("CARGO_PKG_VERSION")
    )
}

/// The cached choice for `engine` (built with `opts`) against the CPU
/// engine at `threads`, or one measured now and cached.
pub fn resolve<T: GpuReal>(
    model: &Model,
    ctx: &GpuContext,
    opts: GpuOptions,
    engine: &GpuEngine<T>,
    threads: usize,
    cache: &ChoiceCache,
) -> Result<BackendChoice, EngineError> {
    let launch = launch_of(engine);
    let key = cache_key::<T>(model, ctx, opts, launch, threads);
    if let Some(c) = cache
        .lookup_line(CACHE_FILE, &key)
        .and_then(|f| BackendChoice::parsed(&f))
    {
        return Ok(c);
    }
    let choice = measure::<T>(model, ctx, opts, launch, threads)?;
    // A cache that cannot be written costs only the next run's timing.
    let _ = cache.store_line(CACHE_FILE, &key, &choice.fields());
    Ok(choice)
}

/// Times `launch` and the CPU engine at `threads` on `model`, from the
/// last step of its normal-load phase where the GPU reaches it within
/// `PREPARE_BUDGET_SECONDS` (else from the initial state), without output.
pub fn measure<T: GpuReal>(
    model: &Model,
    ctx: &GpuContext,
    opts: GpuOptions,
    launch: Launch,
    threads: usize,
) -> Result<BackendChoice, EngineError> {
    let opts = GpuOptions {
        samples: None,
        ..opts
    };
    let models = std::slice::from_ref(model);
    let (start, phase) =
        kernel_choice::driving_start::<T>(models, ctx, opts, launch, PREPARE_BUDGET_SECONDS);
    let gpu_seconds = kernel_choice::time_kernel::<T>(models, ctx, opts, launch, start.as_deref())?;
    let state = start.as_ref().map(|s| &s[0]);
    let mut cpu = SweepEngine::<T>::new(model, threads)?;
    let cpu_seconds = cpu_step_seconds(&mut cpu, state, SLOW_STEP_RATIO * gpu_seconds)?;
    Ok(BackendChoice {
        gpu_launch: launch.name(),
        gpu_seconds,
        cpu_threads: cpu.threads(),
        cpu_seconds,
        phase,
        source: ChoiceSource::Measured,
    })
}

/// What a step of `engine` costs in a run, from `start` (else from where
/// it is): its own trial of thread counts first (the steps it takes at the
/// start of a loading phase; its figure is the count it then keeps), then
/// `step_timing::step_seconds` (no clocks to raise). A first step longer
/// than `SLOW_STEP_SECONDS` and than `give_up_above` seconds is the
/// figure.
pub fn cpu_step_seconds<T: GpuReal>(
    engine: &mut SweepEngine<T>,
    start: Option<&EngineState>,
    give_up_above: f64,
) -> Result<f64, EngineError> {
    if let Some(state) = start {
        engine.load_state(state)?;
    }
    let t = Instant::now();
    engine.advance(1)?;
    let first = t.elapsed().as_secs_f64();
    if first > SLOW_STEP_SECONDS && first > give_up_above {
        return Ok(first);
    }
    let t = Instant::now();
    engine.advance(WARM_UP_STEPS)?;
    let mut rough = t.elapsed().as_secs_f64() / WARM_UP_STEPS as f64;
    let trial = Instant::now();
    while engine.timing_threads() && trial.elapsed().as_secs_f64() < THREAD_TRIAL_SECONDS {
        let t = Instant::now();
        engine.advance(WARM_UP_STEPS)?;
        rough = t.elapsed().as_secs_f64() / WARM_UP_STEPS as f64;
    }
    step_seconds(
        |n| {
            let t = Instant::now();
            engine.advance(n)?;
            Ok(t.elapsed().as_secs_f64())
        },
        rough,
        u64::MAX,
        0.0,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn choice(gpu_seconds: f64, cpu_seconds: f64) -> BackendChoice {
        BackendChoice {
            gpu_launch: "one-step-lanes".into(),
            gpu_seconds,
            cpu_threads: 2,
            cpu_seconds,
            phase: TimedPhase::Driving { from_step: 13408 },
            source: ChoiceSource::Measured,
        }
    }

    /// The faster engine wins, whichever it is; a tie goes to the GPU; the
    /// line names the winner and both figures, the winner's first.
    #[test]
    fn the_faster_engine_steps_the_run_and_the_line_says_why() {
        let gpu = choice(5.9e-6, 21.3e-6);
        assert!(!gpu.cpu_is_faster());
        assert_eq!(
            gpu.describe(),
            "the GPU (one-step-lanes) 5.9 µs a step against the CPU (2 thread(s)) 21.3 µs, \
             timed in driving from step 13408, measured now: the GPU steps the run"
        );
        let cpu = choice(120.4e-6, 35.9e-6);
        assert!(cpu.cpu_is_faster());
        assert_eq!(
            cpu.describe(),
            "the CPU (2 thread(s)) 35.9 µs a step against the GPU (one-step-lanes) 120.4 µs, \
             timed in driving from step 13408, measured now: the CPU steps the run"
        );
        assert!(!choice(10e-6, 10e-6).cpu_is_faster(), "a tie: the GPU");
    }

    /// The CPU engine is built to be timed only where its state takes at
    /// most half the memory available; the GPU then runs, and says why.
    #[test]
    fn a_cpu_engine_that_would_not_fit_is_not_timed() {
        assert!(cpu_fits(4 << 30, Some(8 << 30)).is_ok());
        assert!(cpu_fits(4 << 30, None).is_ok());
        let too_large = cpu_fits((4 << 30) + 1, Some(8 << 30)).unwrap_err();
        assert!(!too_large.cpu_is_faster());
        assert!(too_large.timed().is_none());
        assert_eq!(
            too_large.describe(),
            "the CPU engine would need 4.0 GiB of the 8.0 GiB available, so it is not timed: \
             the GPU steps the run"
        );
    }

    /// A comparison that failed leaves the GPU, and says why.
    #[test]
    fn a_failed_comparison_leaves_the_gpu() {
        let failed = AutoChoice::NotCompared("GPU: device lost".into());
        assert!(!failed.cpu_is_faster());
        assert!(failed.timed().is_none());
        assert_eq!(
            failed.describe(),
            "the GPU and the CPU could not be timed (GPU: device lost): the GPU steps the run"
        );
    }

    /// A stored choice reads back as cached with its figures; a line with
    /// a missing, extra or non-positive field is no choice.
    #[test]
    fn a_choice_reads_back_from_its_cache_fields() {
        let measured = choice(120.4e-6, 35.9e-6);
        let back = BackendChoice::parsed(&measured.fields()).unwrap();
        assert_eq!(
            back,
            BackendChoice {
                source: ChoiceSource::Cached,
                ..measured.clone()
            }
        );
        let load = BackendChoice {
            phase: TimedPhase::NormalLoad {
                why: "reaching driving would take 9 s".into(),
            },
            ..measured.clone()
        };
        assert_eq!(
            BackendChoice::parsed(&load.fields()).unwrap().phase,
            load.phase
        );
        let fields = measured.fields();
        let mut parts: Vec<&str> = fields.split('\t').collect();
        assert!(BackendChoice::parsed(&parts[..4].join("\t")).is_none());
        assert!(BackendChoice::parsed(&(fields.clone() + "\textra")).is_none());
        parts[1] = "0";
        assert!(BackendChoice::parsed(&parts.join("\t")).is_none());
        parts[1] = "1e-5";
        parts[2] = "0";
        assert!(BackendChoice::parsed(&parts.join("\t")).is_none());
    }
}
