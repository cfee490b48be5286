//! Runs a scene to its end: advances the engine between output times,
//! streams snapshots to the output sink, shows progress, and stops cleanly
//! on Ctrl-C or a blow-up.

use crate::cpu::CpuEngine;
use crate::engine::{advance_to, Engine, EngineError, Snapshot};
use crate::model::{Driver, Model};
use crate::output::{GlobalSample, McapSink};
use crate::quasistatic::{FastForward, FastForwardSettings, FastForwardStats, Jump};
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
    /// Fast-forward settings that replace the scenario's (and switch it on
    /// whatever `time.fast_forward` says).
    pub fast_forward: Option<FastForwardSettings>,
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
    pub peak_drive_ratio: f64,
    pub final_drive_ratio: f64,
    pub ruptures: u64,
    /// GPU dispatches over the run (GPU engines only).
    pub dispatches: Option<u64>,
    /// Quasi-static fast-forward totals (when it was on).
    pub fast_forward: Option<FastForwardStats>,
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
        if let Some(ff) = &self.fast_forward {
            writeln!(
                f,
                "  fast-forward       {} jumps skipped {:.6} s ({:.1}% of the steps), \
                 dropped {:.3e} J of ring-down; {} factorisations, {} CG iterations, {:.2} s solving, \
                 path error {:.1e}",
                ff.jumps,
                ff.skipped_time,
                100.0 * ff.skipped_steps as f64 / (self.steps.max(1)) as f64,
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

/// The output side of a run: cadences, the sink, and what the summary
/// reports (peak and last F/F_N, ruptures).
struct Outputs {
    model: Model,
    sink: Option<McapSink>,
    every_global: u64,
    every_interface: u64,
    every_bulk: u64,
    /// Interface output speeds up to `fast_interval` while any interface
    /// block slips faster than `fast_slip_speed` (decided at each sample).
    every_fast: u64,
    fast_slip_speed: f64,
    fast: bool,
    origin: f64,
    peak: f64,
    last: f64,
    ruptures: u64,
}

impl Outputs {
    fn new(model: &Model, scenario: &Scenario, sink: Option<McapSink>) -> Self {
        let o = &scenario.output;
        Outputs {
            model: model.clone(),
            sink,
            every_global: interval_steps(model, o.global_interval),
            every_interface: interval_steps(model, o.interface_interval),
            every_bulk: interval_steps(model, o.bulk_interval),
            every_fast: interval_steps(model, o.fast_interval),
            fast_slip_speed: o.fast_slip_speed,
            fast: false,
            origin: 0.0,
            peak: 0.0,
            last: 0.0,
            ruptures: 0,
        }
    }

    /// The first step after `s` at which some channel is due (u64::MAX:
    /// none, or nothing is written).
    fn next_due(&self, s: u64) -> u64 {
        let prep = self.model.prep_steps;
        if s < prep || self.sink.is_none() {
            return u64::MAX;
        }
        let d = s - prep;
        next_multiple(d, self.every_global)
            .min(next_multiple(d, self.every_interface))
            .min(next_multiple(d, self.every_bulk))
            .min(if self.fast {
                next_multiple(d, self.every_fast)
            } else {
                u64::MAX
            })
            .saturating_add(prep)
    }

    /// Writes the channels due at the snapshot's step.
    fn emit(&mut self, snap: &Snapshot) -> Result<(), RunError> {
        let model = &self.model;
        let d = snap.step - model.prep_steps;
        let g = global_sample(model, snap, self.origin);
        self.peak = self.peak.max(g.drive_ratio);
        self.last = g.drive_ratio;
        self.ruptures = g.ruptures;
        let max_slip_speed = (0..model.nx)
            .map(|ix| snap.vel[ix][0].abs())
            .fold(0.0, f64::max);
        self.fast = self.every_fast > 0 && max_slip_speed > self.fast_slip_speed;
        if let Some(sink) = self.sink.as_mut() {
            if self.every_global > 0 && d.is_multiple_of(self.every_global) {
                sink.write_global(&g)?;
            }
            let fast_due = self.fast && self.every_fast > 0 && d.is_multiple_of(self.every_fast);
            if fast_due || (self.every_interface > 0 && d.is_multiple_of(self.every_interface)) {
                sink.write_interface(model, snap)?;
            }
            if self.every_bulk > 0 && d.is_multiple_of(self.every_bulk) {
                sink.write_bulk(model, snap)?;
            }
        }
        Ok(())
    }

    fn finish(&mut self, fast_forward: Option<&FastForwardStats>) -> Result<(), RunError> {
        if let Some(sink) = self.sink.take() {
            sink.finish(fast_forward)?;
        }
        Ok(())
    }
}

/// Performs a planned quasi-static jump: writes the output samples due on
/// the path (exact: the path is the equilibrium), books the energy, records
/// it, and moves the engine to the jump's end.
fn perform_jump(
    engine: &mut dyn Engine,
    outputs: &mut Outputs,
    ff: &mut FastForward,
    dynamic: &Snapshot,
    jump: &mut Jump,
) -> Result<(), RunError> {
    let model = engine.model().clone();
    let origin = outputs.origin;
    let path = &jump.path;
    let s1 = path.end_step;
    // One evaluator per stretch (its junction arrays), and one for the end.
    let mut evaluators = path
        .segments
        .iter()
        .map(|seg| CpuEngine::<f64>::with_junctions(&model, &seg.base, origin))
        .collect::<Result<Vec<_>, _>>()?;
    let mut end_evaluator = CpuEngine::<f64>::with_junctions(&model, &path.end, origin)?;
    let eval = |e: &mut CpuEngine<f64>, step: u64, disp: &[[f64; 2]], w: &[[f64; 2]]| {
        e.set_kinematics(step, disp, w)?;
        e.snapshot()
    };
    let end = eval(&mut end_evaluator, s1, &path.end.disp, &path.end_w)?;
    let mut s = jump.record.start_step;
    loop {
        s = outputs.next_due(s);
        if s > s1 || s == u64::MAX {
            break;
        }
        let snap = if s == s1 {
            end.clone()
        } else {
            let k = path
                .segments
                .iter()
                .position(|seg| seg.start_step <= s && s < seg.end_step)
                .expect("the stretches cover the jump");
            let seg = &path.segments[k];
            eval(&mut evaluators[k], s, &seg.disp_at(s), &seg.w)?
        };
        outputs.emit(&snap)?;
    }
    // The energy: relaxations (the quiet state's ring-down, and the
    // slider's settling after each junction event) are dropped and booked
    // as dissipated; along each stretch, work in and dashpot loss.
    let mut record = jump.record.clone();
    let mut before = dynamic.clone();
    for (k, seg) in path.segments.iter().enumerate() {
        let e = &mut evaluators[k];
        let start = eval(e, seg.start_step, &seg.base.disp, &seg.w)?;
        // The relaxation's force law: the stretch's junction arrays, and
        // slipping junctions pulling against the quasi-static velocity.
        let before_new_law = eval(e, seg.start_step, &before.disp, &seg.w)?;
        record.dropped_energy += relaxation_drop(&model, &before, &before_new_law, &start, origin);
        let end_of_stretch = eval(e, seg.end_step, &seg.end_disp, &seg.w)?;
        let (work_in, damping) = path_work(&model, &start, &end_of_stretch, origin);
        record.work_in += work_in;
        record.damping += damping;
        record.stored_change += crate::energy::stored_energy(&model, &end_of_stretch, origin)
            .total()
            - crate::energy::stored_energy(&model, &start, origin).total();
        before = end_of_stretch;
    }
    if before.step == s1 && before.disp != end.disp {
        // The path ended at an event: its settling is dropped too.
        let before_new_law = eval(&mut end_evaluator, s1, &before.disp, &path.end_w)?;
        record.dropped_energy += relaxation_drop(&model, &before, &before_new_law, &end, origin);
    }
    jump.record = record;
    if let Some(sink) = outputs.sink.as_mut() {
        sink.write_fast_forward(&jump.record)?;
    }
    engine.set_junctions(&path.end)?;
    engine.set_kinematics(s1, &path.end.disp, &path.end_w)?;
    ff.book(&model, &jump.record, path.path_error);
    Ok(())
}

/// Energy (J) a relaxation at fixed time drops: from `before` to the
/// equilibrium `after` under the junction law after it (`before_new_law`:
/// that law's forces at `before`'s displacement). Stored energy lost, plus
/// the work the junction forces (linear in u_x along the relaxation) and
/// the top loads (constant) do; the side spring's far end does not move.
pub fn relaxation_drop(
    model: &Model,
    before: &Snapshot,
    before_new_law: &Snapshot,
    after: &Snapshot,
    origin: f64,
) -> f64 {
    use crate::energy::stored_energy;
    let mut work = 0.0;
    for ix in 0..model.nx {
        let du = after.disp[ix][0] - before.disp[ix][0];
        work += 0.5 * (before_new_law.friction[ix] + after.friction[ix]) * du;
    }
    let loads = step_params(&Consts::<f64>::new(model), before.step);
    for ix in 0..model.nx {
        let i = (model.nz - 1) * model.nx + ix;
        let share = model.top_share(ix);
        work += share
            * (loads.top_tangential_total * (after.disp[i][0] - before.disp[i][0])
                - loads.normal_total * (after.disp[i][1] - before.disp[i][1]));
    }
    stored_energy(model, before, origin).total() - stored_energy(model, after, origin).total()
        + work
}

/// Work in and dashpot loss (J) along a stretch of the quasi-static path
/// (trapezoid rule: exact for its linear forces and constant velocities).
pub fn path_work(model: &Model, start: &Snapshot, end: &Snapshot, origin: f64) -> (f64, f64) {
    use crate::energy::step_power;
    let (pa, pb) = (
        step_power(model, start, start, origin),
        step_power(model, end, end, origin),
    );
    let span = end.time - start.time;
    let work_in = 0.5
        * span
        * (pa.drive + pa.top_loads + pa.friction + pb.drive + pb.top_loads + pb.friction);
    (work_in, 0.5 * span * (pa.damping + pb.damping))
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
    let sink = match &opts.output {
        Some(p) => Some(McapSink::create(p, &model, scenario, &engine.describe())?),
        None => None,
    };
    let mut outputs = Outputs::new(&model, scenario, sink);
    let mut ff = opts
        .fast_forward
        .or_else(|| {
            scenario
                .time
                .fast_forward
                .then(|| FastForwardSettings::from_scenario(scenario))
        })
        .map(FastForward::new);
    let every_check = ff.as_ref().map_or(0, |f| f.check_steps(&model));
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
    let mut interrupted = false;
    let start_step = engine.steps_done();
    let start_dispatches = engine.dispatches();
    let result = (|| -> Result<(), RunError> {
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
            let out_step = outputs.next_due(s);
            let check_step = if s >= model.prep_steps && every_check > 0 {
                next_multiple(s - model.prep_steps, every_check) + model.prep_steps
            } else {
                u64::MAX
            };
            target = target.min(out_step).min(check_step);
            advance_to(engine, target)?;
            let s = engine.steps_done();
            bar.set_position(s - start_step);
            bar.set_message(format!("{:.6} s", model.time_of_step(s)));
            if s == model.prep_steps {
                let snap = engine.snapshot()?;
                if let Driver::SideSpring { row, .. } = model.driver {
                    outputs.origin = snap.disp[row * model.nx][0];
                }
            }
            if s != out_step && s != check_step {
                continue;
            }
            let snap = engine.snapshot()?;
            if s == out_step {
                outputs.emit(&snap)?;
            }
            if let Some(ff) = ff.as_mut().filter(|_| s == check_step && s < total) {
                if ff.observe(&model, &snap) {
                    let planned = ff
                        .plan(&model, &snap, outputs.origin, total)
                        .map_err(|e| EngineError::Gpu(e.to_string()))?;
                    if let Some(mut jump) = planned {
                        perform_jump(engine, &mut outputs, ff, &snap, &mut jump)?;
                        bar.set_position(engine.steps_done() - start_step);
                    }
                }
            }
        }
        Ok(())
    })();
    if let Err(e) = result {
        outputs.finish(ff.as_ref().map(|f| &f.stats))?;
        bar.abandon();
        return Err(e);
    }
    bar.finish_and_clear();
    outputs.finish(ff.as_ref().map(|f| &f.stats))?;
    let final_snap = engine.snapshot()?;
    let g = global_sample(&model, &final_snap, outputs.origin);
    let wall = started.elapsed().as_secs_f64();
    let steps = engine.steps_done() - start_step;
    let integrated = steps - ff.as_ref().map_or(0, |f| f.stats.skipped_steps);
    Ok(RunSummary {
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
        ruptures: outputs.ruptures.max(g.ruptures),
        dispatches: engine
            .dispatches()
            .zip(start_dispatches)
            .map(|(end, start)| end - start),
        fast_forward: ff.map(|f| f.stats),
        interrupted,
        output: opts.output.clone(),
        peak_memory: peak_memory(),
    })
}
