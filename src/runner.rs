//! Runs a scene to its end: advances the engine between output times,
//! streams snapshots to the output sink, shows progress, and stops cleanly
//! on Ctrl-C or a blow-up.

use crate::engine::{advance_to, Engine, EngineError, Snapshot};
use crate::model::{Driver, Model};
use crate::output::{GlobalSample, McapSink};
use crate::scenario::Scenario;
use crate::step_params::{step_params, Consts};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Once;
use std::time::Instant;

static INTERRUPTED: AtomicBool = AtomicBool::new(false);
static HANDLER: Once = Once::new();

/// Steps between progress updates (and interrupt checks) at most.
const MAX_CHUNK: u64 = 20_000;

pub struct RunOptions {
    pub output: Option<PathBuf>,
    pub progress: bool,
}

/// What a finished (or interrupted) run reports.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub backend: String,
    pub steps: u64,
    pub simulated_time: f64,
    pub wall_seconds: f64,
    pub block_steps_per_second: f64,
    pub peak_drive_ratio: f64,
    pub final_drive_ratio: f64,
    pub ruptures: u64,
    /// GPU dispatches over the run (GPU engines only).
    pub dispatches: Option<u64>,
    pub interrupted: bool,
    pub output: Option<PathBuf>,
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
        writeln!(f, "  peak F/F_N         {:.4}", self.peak_drive_ratio)?;
        writeln!(f, "  final F/F_N        {:.4}", self.final_drive_ratio)?;
        writeln!(f, "  junction ruptures  {}", self.ruptures)?;
        if let Some(d) = self.dispatches {
            writeln!(
                f,
                "  GPU dispatches     {d} ({:.4} per step)",
                d as f64 / self.steps.max(1) as f64
            )?;
        }
        if let Some(b) = self.peak_memory {
            writeln!(f, "  peak memory        {:.1} MiB", b as f64 / 1048576.0)?;
        }
        match &self.output {
            Some(p) => write!(f, "  output             {}", p.display()),
            None => write!(f, "  output             none (use -o run.mcap)"),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Engine(#[from] EngineError),
    #[error("output: {0}")]
    Output(#[from] crate::output::OutputError),
}

/// Tangential force (N) the scene's driver applies at the snapshot's
/// instant: the side spring's tension; the programmed top force (ramp plus
/// any trigger prestress); for a prescribed top-row velocity, the
/// constraint reaction that gives the row its prescribed velocity over the
/// next step; 0 without a driver. Friction is reported apart.
pub fn drive_force(model: &Model, snap: &Snapshot, origin: f64) -> f64 {
    let loads = || step_params(&Consts::<f64>::new(model), snap.step);
    match model.driver {
        Driver::SideSpring {
            stiffness,
            row,
            velocity,
        } => {
            let u = snap.disp[row * model.nx][0];
            stiffness * crate::laws::side_spring_stretch(velocity, snap.time, u, origin)
        }
        Driver::TopForce { .. } => loads().top_tangential_total,
        Driver::TopVelocity { .. } => {
            let v_next = loads().top_velocity;
            let top = (model.nz - 1) * model.nx;
            (top..top + model.nx)
                .map(|i| {
                    let friction = snap.friction.get(i).copied().unwrap_or(0.0);
                    model.mass * (v_next - snap.vel_half[i][0]) / model.dt
                        - snap.force[i][0]
                        - friction
                })
                .sum()
        }
        Driver::None => 0.0,
    }
}

/// The global series of one snapshot.
pub fn global_sample(model: &Model, snap: &Snapshot, origin: f64) -> GlobalSample {
    let force = drive_force(model, snap, origin);
    let pinned = snap.pinned_fraction(model.nx);
    GlobalSample {
        time: snap.time,
        step: snap.step,
        drive_force: force,
        drive_ratio: if model.normal_force > 0.0 {
            force / model.normal_force
        } else {
            0.0
        },
        friction_force: snap.total_friction(),
        pinned_fraction: pinned.iter().sum::<f64>() / pinned.len().max(1) as f64,
        kinetic_energy: snap.kinetic_energy(model.mass),
        ruptures: snap.total_ruptures(),
    }
}

fn interval_steps(model: &Model, interval: f64) -> u64 {
    if interval > 0.0 {
        ((interval / model.dt).round() as u64).max(1)
    } else {
        0
    }
}

fn next_multiple(step: u64, every: u64) -> u64 {
    step.checked_div(every)
        .map_or(u64::MAX, |n| (n + 1) * every)
}

/// Runs `engine` over its whole scene.
pub fn run_scene(
    engine: &mut dyn Engine,
    scenario: &Scenario,
    opts: &RunOptions,
) -> Result<RunSummary, RunError> {
    HANDLER.call_once(|| {
        let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
    });
    let model = engine.model().clone();
    let total = model.total_steps();
    let mut sink = match &opts.output {
        Some(p) => Some(McapSink::create(p, &model, scenario, &engine.describe())?),
        None => None,
    };
    let every_global = interval_steps(&model, scenario.output.global_interval);
    let every_interface = interval_steps(&model, scenario.output.interface_interval);
    let every_bulk = interval_steps(&model, scenario.output.bulk_interval);
    // Interface output speeds up to `fast_interval` while any interface block
    // slips faster than `fast_slip_speed` (decided at each read-back).
    let every_fast = interval_steps(&model, scenario.output.fast_interval);
    let mut fast = false;
    let bar = if opts.progress {
        let b = ProgressBar::new(total);
        b.set_style(
            ProgressStyle::with_template("{bar:30} t = {msg} | {per_sec} | ETA {eta}")
                .expect("valid template"),
        );
        b
    } else {
        ProgressBar::hidden()
    };
    let started = Instant::now();
    let mut origin = 0.0;
    let (mut peak, mut last) = (0.0f64, 0.0f64);
    let mut ruptures = 0;
    let mut interrupted = false;
    let start_step = engine.steps_done();
    let start_dispatches = engine.dispatches();
    while engine.steps_done() < total {
        if INTERRUPTED.load(Ordering::SeqCst) {
            interrupted = true;
            break;
        }
        let s = engine.steps_done();
        let mut target = (s + MAX_CHUNK).min(total);
        if s < model.prep_steps {
            target = target.min(model.prep_steps);
        }
        // Without an output file nothing is read back until the end.
        let out_step = if s >= model.prep_steps && sink.is_some() {
            next_multiple(s - model.prep_steps, every_global)
                .min(next_multiple(s - model.prep_steps, every_interface))
                .min(next_multiple(s - model.prep_steps, every_bulk))
                .min(if fast {
                    next_multiple(s - model.prep_steps, every_fast)
                } else {
                    u64::MAX
                })
                .saturating_add(model.prep_steps)
        } else {
            u64::MAX
        };
        target = target.min(out_step);
        if let Err(e) = advance_to(engine, target) {
            if let Some(sink) = sink.take() {
                sink.finish()?;
            }
            bar.abandon();
            return Err(e.into());
        }
        let s = engine.steps_done();
        bar.set_position(s - start_step);
        bar.set_message(format!("{:.6} s", model.time_of_step(s)));
        if s == model.prep_steps {
            let snap = engine.snapshot()?;
            if let Driver::SideSpring { row, .. } = model.driver {
                origin = snap.disp[row * model.nx][0];
            }
        }
        if s == out_step {
            let snap = engine.snapshot()?;
            let d = s - model.prep_steps;
            let g = global_sample(&model, &snap, origin);
            peak = peak.max(g.drive_ratio);
            last = g.drive_ratio;
            ruptures = g.ruptures;
            let max_slip_speed = (0..model.nx)
                .map(|ix| snap.vel[ix][0].abs())
                .fold(0.0, f64::max);
            fast = every_fast > 0 && max_slip_speed > scenario.output.fast_slip_speed;
            if let Some(sink) = sink.as_mut() {
                if every_global > 0 && d.is_multiple_of(every_global) {
                    sink.write_global(&g)?;
                }
                let fast_due = fast && every_fast > 0 && d.is_multiple_of(every_fast);
                if fast_due || (every_interface > 0 && d.is_multiple_of(every_interface)) {
                    sink.write_interface(&model, &snap)?;
                }
                if every_bulk > 0 && d.is_multiple_of(every_bulk) {
                    sink.write_bulk(&model, &snap)?;
                }
            }
        }
    }
    bar.finish_and_clear();
    if let Some(sink) = sink {
        sink.finish()?;
    }
    let final_snap = engine.snapshot()?;
    let g = global_sample(&model, &final_snap, origin);
    let wall = started.elapsed().as_secs_f64();
    let steps = engine.steps_done() - start_step;
    Ok(RunSummary {
        backend: engine.describe(),
        steps,
        simulated_time: model.time_of_step(engine.steps_done()).max(0.0),
        wall_seconds: wall,
        block_steps_per_second: steps as f64 * model.n_blocks() as f64 / wall.max(1e-9),
        peak_drive_ratio: peak.max(g.drive_ratio),
        final_drive_ratio: if steps > 0 { g.drive_ratio } else { last },
        ruptures: ruptures.max(g.ruptures),
        dispatches: engine
            .dispatches()
            .zip(start_dispatches)
            .map(|(end, start)| end - start),
        interrupted,
        output: opts.output.clone(),
        peak_memory: peak_memory(),
    })
}
