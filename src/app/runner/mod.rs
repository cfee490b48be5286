//! Runs a scene to its end: advances the engine between output times,
//! streams snapshots to the output sink, shows progress, and stops cleanly
//! on Ctrl-C or a blow-up.

mod checkpoints;
mod jump;
mod outputs;
mod progress;

pub use jump::{path_work, relaxation_drop};
pub use outputs::{drive_force, drive_origin, global_of, global_sample, sample_plan};
pub use progress::ProgressMode;

use crate::engines::quasistatic::{FastForward, FastForwardSettings, FastForwardStats};
use crate::engines::{advance_to, Engine, EngineError, PlannedAndComputed};
use crate::io::checkpoint::RunnerState;
use crate::io::live::LiveView;
use crate::io::output::{ChunkCompression, ChunkLayout, McapSink};
use crate::model::scenario::Scenario;
use checkpoints::Checkpointer;
use jump::perform_jump;
use outputs::{next_multiple, Outputs};
use progress::Reporter;
use std::path::PathBuf;
use std::sync::atomic::{AtomicI32, Ordering};
use std::sync::Once;
use std::time::Instant;

/// The signal that asked the runs of this process to stop (0: none).
static SIGNAL: AtomicI32 = AtomicI32::new(0);
static HANDLER: Once = Once::new();

/// A SIGINT, SIGTERM or SIGHUP has asked the runs of this process to stop.
pub fn interrupted() -> bool {
    SIGNAL.load(Ordering::SeqCst) != 0
}

/// The signal that stopped the run, if one did (its number; the exit
/// status is 128 + it, as shells report).
pub fn stopping_signal() -> Option<i32> {
    Some(SIGNAL.load(Ordering::SeqCst)).filter(|&s| s != 0)
}

#[cfg(unix)]
extern "C" fn on_signal(signal: libc::c_int) {
    // Only an atomic store: async-signal-safe.
    SIGNAL.store(signal, Ordering::SeqCst);
}

/// For a host that keeps its own signal handling (the Python package,
/// whose Ctrl-C must stay Python's): the runner installs no handlers, and
/// the host stops runs with [`request_stop`].
pub fn leave_signals_to_host() {
    HANDLER.call_once(|| {});
}

/// Asks the runs of this process to stop at their next chunk, as a SIGINT
/// would: each writes its checkpoint and closes its file.
pub fn request_stop() {
    SIGNAL.store(2, Ordering::SeqCst);
}

/// Forgets a stop request, so that the next run of a long-lived host
/// process runs.
pub fn clear_stop() {
    SIGNAL.store(0, Ordering::SeqCst);
}

/// Notes SIGINT, SIGTERM and SIGHUP from now on (see [`interrupted`]), as a
/// run does: for commands that wait before or without a run.
pub fn watch_stop_signals() {
    HANDLER.call_once(catch_stop_signals);
}

/// Stop requests are noted (the run ends at its next chunk, closing its
/// file and writing a checkpoint), not acted on at once.
fn catch_stop_signals() {
    #[cfg(unix)]
    for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
        // SAFETY: the handler only stores to an atomic.
        unsafe {
            libc::signal(
                signal,
                on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t,
            );
        }
    }
    #[cfg(not(unix))]
    let _ = ctrlc::set_handler(|| SIGNAL.store(2, Ordering::SeqCst));
}

/// Steps between progress updates (and interrupt checks) at most.
const MAX_CHUNK: u64 = 20_000;

/// Wall time a chunk of steps should take at most, so that a signal, a due
/// checkpoint and the progress report wait no longer than this on any
/// lattice.
const CHUNK_SECONDS: f64 = 0.25;

/// Called after each chunk of steps with the steps done and the run's total
/// steps: where a host reports progress and checks for its own stop
/// requests.
pub type ChunkHook = std::sync::Arc<dyn Fn(u64, u64) + Send + Sync>;

#[derive(Default)]
pub struct RunOptions {
    pub output: Option<PathBuf>,
    /// How `output`'s chunks are stored (zstd unless it is scratch).
    pub output_compression: ChunkCompression,
    pub progress: ProgressMode,
    /// Fast-forward settings that replace the scenario's (and switch it on
    /// whatever `time.fast_forward` says).
    pub fast_forward: Option<FastForwardSettings>,
    /// Continue a saved run (the engine already holds its state).
    pub start: Option<StartFrom>,
    /// One line per start, resume and branch of the run (metadata and
    /// checkpoints carry it on).
    pub history: Vec<String>,
    pub on_chunk: Option<ChunkHook>,
    /// Streams the records to a live view too (its caller started it, and
    /// closes it).
    pub live: Option<LiveView>,
}

/// The runner's side of a saved run, and the run file whose first
/// `runner.sequence` messages the new output copies.
pub struct StartFrom {
    pub runner: RunnerState,
    pub parent_output: Option<PathBuf>,
}

/// What a finished (or interrupted) run reports.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub backend: String,
    pub steps: u64,
    pub simulated_time: f64,
    pub wall_seconds: f64,
    /// Integrated (not skipped) block-steps per wall second.
    pub block_steps_per_second: f64,
    /// F/F_N; 0 without a normal load (`normal_load` false), where it has
    /// no meaning.
    pub peak_drive_ratio: f64,
    pub final_drive_ratio: f64,
    /// F_N > 0: the drive ratios mean something.
    pub normal_load: bool,
    pub ruptures: u64,
    /// GPU dispatches over the run (GPU engines only): those that stepped
    /// the lattice (recording their samples), and those that only finish
    /// output samples (a batch's record finish).
    pub dispatches: Option<u64>,
    pub output_dispatches: Option<u64>,
    /// Output samples planned on the device and those it computed (the
    /// others its fast chain found could not be due).
    pub device_samples: Option<PlannedAndComputed>,
    /// Quasi-static fast-forward totals (when it was on), over the whole
    /// run (a resumed run's include the part before the resume).
    pub fast_forward: Option<FastForwardStats>,
    /// Steps of this invocation skipped by the fast-forward.
    pub skipped_steps: u64,
    pub interrupted: bool,
    pub output: Option<PathBuf>,
    /// The last checkpoint written (runs with an output file).
    pub checkpoint: Option<PathBuf>,
    /// Peak resident memory of the process (bytes), where the OS tells.
    pub peak_memory: Option<u64>,
}

/// Peak resident set size of this process (Linux: VmHWM).
pub fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "run {}",
            if self.interrupted {
                "INTERRUPTED"
            } else {
                "complete"
            }
        )?;
        writeln!(f, "  backend            {}", self.backend)?;
        writeln!(f, "  steps              {}", self.steps)?;
        writeln!(
            f,
            "  simulated time     {:.6} s after the normal-load phase",
            self.simulated_time
        )?;
        writeln!(f, "  wall time          {:.2} s", self.wall_seconds)?;
        writeln!(
            f,
            "  throughput         {:.3e} block-steps/s",
            self.block_steps_per_second
        )?;
        if self.normal_load {
            writeln!(f, "  peak F/F_N         {:.4}", self.peak_drive_ratio)?;
            writeln!(f, "  final F/F_N        {:.4}", self.final_drive_ratio)?;
        } else {
            writeln!(f, "  F/F_N              none: no normal load (F_N = 0)")?;
        }
        writeln!(f, "  junction ruptures  {}", self.ruptures)?;
        if let Some(d) = self.dispatches {
            write!(
                f,
                "  GPU dispatches     {d} ({:.4} per step)",
                d as f64 / self.steps.max(1) as f64
            )?;
            match self.output_dispatches.filter(|&o| o > 0) {
                Some(o) => writeln!(
                    f,
                    ", and {o} finishing output samples on the device (one a batch)"
                )?,
                None => writeln!(f)?,
            }
        }
        if let Some(s) = self.device_samples.filter(|s| s.planned > 0) {
            writeln!(
                f,
                "  device samples     {s} (the rest could not be due: the fast cadence was off)"
            )?;
        }
        if let Some(ff) = &self.fast_forward {
            writeln!(
                f,
                "  fast-forward       {} jumps skipped {:.6} s ({:.1}% of the steps), \
                 dropped {:.3e} J of ring-down; {} factorisations, {} CG iterations, {:.2} s solving, \
                 path error {:.1e}",
                ff.jumps,
                ff.skipped_time,
                100.0 * self.skipped_steps as f64 / (self.steps.max(1)) as f64,
                ff.dropped_energy,
                ff.factorisations,
                ff.cg_iterations,
                ff.solver_seconds,
                ff.max_path_error
            )?;
        }
        if let Some(b) = self.peak_memory {
            writeln!(f, "  peak memory        {:.1} MiB", b as f64 / 1048576.0)?;
        }
        if let Some(c) = &self.checkpoint {
            writeln!(f, "  checkpoint         {}", c.display())?;
        }
        match (&self.output, self.interrupted) {
            (Some(p), true) => write!(
                f,
                "  output             {}\n  continue with      slipfront run --resume {}",
                p.display(),
                p.display()
            ),
            (Some(p), false) => write!(f, "  output             {}", p.display()),
            (None, _) => write!(f, "  output             none (use -o run.mcap)"),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Engine(#[from] EngineError),
    #[error("output: {0}")]
    Output(#[from] crate::io::output::OutputError),
    #[error("checkpoint: {0}")]
    Checkpoint(String),
}

/// Runs `engine` over its whole scene (from the step it is at). With an
/// output file, checkpoints go beside it (`checkpoint::path_for`) every
/// `output.checkpoint_interval` seconds of wall time, at the end, and when
/// SIGINT or SIGTERM stops the run; the loaded slider, one step before
/// driving starts, goes to `checkpoint::loaded_path_for`.
/// Waits for the steps the engine runs ahead (`Engine::run_ahead`) and
/// writes their samples, so that the output holds every sample up to the
/// engine's step: before a checkpoint, a jump and the end. Samples before
/// a blow-up among those steps are written before its error returns.
fn settle(engine: &mut dyn Engine, outputs: &mut Outputs) -> Result<(), RunError> {
    let settled = engine.settle();
    for sample in &engine.take_samples() {
        outputs.emit_sample(sample)?;
    }
    Ok(settled?)
}

pub fn run_scene(
    engine: &mut dyn Engine,
    scenario: &Scenario,
    opts: &RunOptions,
) -> Result<RunSummary, RunError> {
    HANDLER.call_once(catch_stop_signals);
    let model = engine.model().clone();
    let total = model.total_steps();
    let describe = engine.describe();
    let sink = match (&opts.output, &opts.start) {
        (
            Some(p),
            Some(StartFrom {
                parent_output: Some(parent),
                runner,
            }),
        ) => Some(McapSink::continue_from(
            p,
            parent,
            runner.sequence,
            &model,
            scenario,
            &describe,
            &opts.history,
        )?),
        (Some(p), _) => Some(McapSink::create(
            p,
            &model,
            scenario,
            &describe,
            &opts.history,
            ChunkLayout::of(opts.output_compression),
        )?),
        (None, _) => None,
    };
    let mut outputs = Outputs::new(&model, scenario, sink, opts.live.clone());
    let mut ff = opts
        .fast_forward
        .or_else(|| {
            scenario
                .time
                .fast_forward
                .then(|| FastForwardSettings::from_scenario(scenario))
        })
        .map(FastForward::new);
    if let Some(start) = &opts.start {
        outputs.restore(&start.runner);
        if let (Some(ff), Some(saved)) = (ff.as_mut(), &start.runner.fast_forward) {
            ff.restore(saved);
        }
    }
    let mut checkpoints = opts
        .output
        .as_ref()
        .map(|p| Checkpointer::new(p.clone(), scenario, opts.history.clone()));
    let every_check = ff.as_ref().map_or(0, |f| f.check_steps(&model));
    // The engine records the output samples on the device where it can
    // (then chunks do not stop at output steps and nothing else is read
    // back for them); otherwise each output step is a snapshot.
    let on_device = outputs.sink.is_some() && engine.record_samples(&outputs.plan())?;
    if on_device {
        // The device steps on while the samples it has recorded are written.
        engine.run_ahead();
    }
    let started = Instant::now();
    let mut interrupted = false;
    let start_step = engine.steps_done();
    let start_dispatches = engine.dispatches();
    let start_output_dispatches = engine.output_dispatches();
    let start_skipped = ff.as_ref().map_or(0, |f| f.stats.skipped_steps);
    let mut progress = Reporter::new(opts.progress, &model, start_step);
    // Steps per chunk: grows while chunks are quick, shrinks on big
    // lattices.
    let fixed_chunk = engine.fixed_chunk();
    let mut chunk: u64 = fixed_chunk.unwrap_or(64);
    let result = (|| -> Result<(), RunError> {
        while engine.steps_done() < total {
            let s = engine.steps_done();
            if let Some(c) = checkpoints.as_mut() {
                // The loaded slider, one step before driving starts, is
                // always saved apart: branches with any drive or trigger
                // start there, and a run killed early resumes there.
                if s + 1 == model.prep_steps && s > start_step {
                    let loaded = crate::io::checkpoint::loaded_path_for(&c.output_path);
                    c.write_to(&loaded, engine, &mut outputs, ff.as_ref())?;
                }
                if c.due() {
                    c.write(engine, &mut outputs, ff.as_ref())?;
                }
            }
            if self::interrupted() {
                interrupted = true;
                break;
            }
            let mut target = (s + chunk).min(total);
            for stop in [model.prep_steps.saturating_sub(1), model.prep_steps] {
                if s < stop {
                    target = target.min(stop);
                }
            }
            // Without an output file nothing is read back until the end.
            let out_step = if on_device {
                u64::MAX
            } else {
                outputs.next_due(s)
            };
            let check_step = if s >= model.prep_steps && every_check > 0 {
                next_multiple(s - model.prep_steps, every_check) + model.prep_steps
            } else {
                u64::MAX
            };
            target = target.min(out_step).min(check_step);
            let chunk_started = Instant::now();
            let advanced = advance_to(engine, target);
            let samples = engine.take_samples();
            if advanced.is_ok() && engine.steps_done() == model.prep_steps {
                let snap = engine.snapshot()?;
                if let Some(origin) = drive_origin(&model, &snap) {
                    outputs.origin = origin;
                }
            }
            // What was recorded before a blow-up is written all the same.
            for sample in &samples {
                outputs.emit_sample(sample)?;
            }
            advanced?;
            let s_before = s;
            let s = engine.steps_done();
            // The next chunk from this one's speed (whole chunks only: a
            // cut-short one says little).
            let took = chunk_started.elapsed().as_secs_f64();
            if fixed_chunk.is_none() && s - s_before == chunk {
                let fit = (chunk as f64 * CHUNK_SECONDS / took.max(1e-9)) as u64;
                chunk = fit.clamp(1, MAX_CHUNK).min(chunk.saturating_mul(2));
            }
            progress.update(s, outputs.events());
            if let Some(live) = &outputs.live {
                live.show_time(model.time_of_step(s));
            }
            if let Some(hook) = &opts.on_chunk {
                hook(s, total);
            }
            if s != out_step && s != check_step {
                continue;
            }
            // A jump writes its own samples after the device's so far.
            settle(engine, &mut outputs)?;
            let snap = engine.snapshot()?;
            if s == out_step {
                outputs.emit(&snap)?;
            }
            // The detector sees every check, the last step's too, so that
            // a run extended from its end sees the same checks as one run
            // through; only a jump needs steps left.
            if let Some(ff) = ff.as_mut().filter(|_| s == check_step) {
                if ff.observe(&model, &snap) && s < total {
                    let planned = ff
                        .plan(&model, &snap, outputs.origin, total)
                        .map_err(|e| EngineError::Gpu(e.to_string()))?;
                    if let Some(mut jump) = planned {
                        perform_jump(engine, &mut outputs, ff, &snap, &mut jump)?;
                        if on_device {
                            // The path's samples may have switched the fast cadence.
                            engine.record_samples(&outputs.plan())?;
                        }
                        progress.update(engine.steps_done(), outputs.events());
                    }
                }
            }
        }
        settle(engine, &mut outputs)?;
        if let Some(c) = checkpoints.as_mut() {
            c.write(engine, &mut outputs, ff.as_ref())?;
        }
        Ok(())
    })();
    if let Err(e) = result {
        // Closing is best effort here: the first error is the cause (a
        // full disk fails the close too, with a message that hides it).
        let _ = outputs.finish(ff.as_ref().map(|f| &f.stats));
        progress.abandon();
        return Err(e);
    }
    progress.finish();
    outputs.finish(ff.as_ref().map(|f| &f.stats))?;
    let final_snap = engine.snapshot()?;
    let g = global_sample(&model, &final_snap, outputs.origin);
    let wall = started.elapsed().as_secs_f64();
    let steps = engine.steps_done() - start_step;
    // The fast-forward's totals cover the whole run, resumes included.
    let skipped = ff.as_ref().map_or(0, |f| f.stats.skipped_steps) - start_skipped;
    let integrated = steps - skipped;
    Ok(RunSummary {
        // As it ends: an engine may have settled what it timed as it ran
        // (the CPU engine's thread count); the file keeps the start's.
        backend: engine.describe(),
        steps,
        simulated_time: model.time_of_step(engine.steps_done()).max(0.0),
        wall_seconds: wall,
        block_steps_per_second: integrated as f64 * model.n_blocks() as f64 / wall.max(1e-9),
        peak_drive_ratio: outputs.peak.max(g.drive_ratio),
        final_drive_ratio: if steps > 0 {
            g.drive_ratio
        } else {
            outputs.last
        },
        normal_load: model.normal_force > 0.0,
        ruptures: outputs.ruptures.max(g.ruptures),
        dispatches: engine
            .dispatches()
            .zip(start_dispatches)
            .map(|(end, start)| end - start),
        output_dispatches: engine
            .output_dispatches()
            .zip(start_output_dispatches)
            .map(|(end, start)| end - start),
        device_samples: engine.device_samples(),
        fast_forward: ff.map(|f| f.stats),
        skipped_steps: skipped,
        interrupted,
        output: opts.output.clone(),
        checkpoint: checkpoints.filter(|c| c.written > 0).map(|c| c.path),
        peak_memory: peak_memory(),
    })
}
