//! Quasi-static fast-forward through the stick phases of a driven run.
//!
//! A side-driven slider spends almost all of its time at rest while the
//! drive loads it; integrating those phases at dt = T/50 is most of a run's
//! cost. When the scene is quiet (every junction pinned, kinetic energy a
//! small fraction of one junction's elastic energy at threshold, held for a
//! minimum time), the slider follows its equilibrium, which moves linearly
//! with the drive: u(t) = u(t₀) + w·(t − t₀) with K·w = ḟ. The first
//! junction to reach μs·f_N on that path is found exactly
//! ([`threshold::first_change`]); the run jumps there less a lead time,
//! sets the equilibrium displacement and the velocity field w, and resumes
//! full dynamics, which then perform the rupture. What the jump drops (the
//! residual ring-down of the quiet phase) is booked as dissipated.
//!
//! Isolated junction ruptures during loading end a jump like any other:
//! dynamics take over until the scene is quiet again (measured and argued
//! in `results/fast_forward.md`).

pub mod band;
pub mod cg;
pub mod equilibrium;
pub mod path;
pub mod tangent;
pub mod threshold;

use crate::engines::Snapshot;
use crate::model::junction::PINNED;
use crate::model::{Driver, Model};
use equilibrium::{QuasiStaticError, Solver, SolverKind};
use path::{Path, PathContext};
use tangent::Tangent;
use threshold::PathEnd;

/// Settings of the fast-forward (scenario `[fast_forward]` with defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FastForwardSettings {
    /// Kinetic energy below which the slider counts as at rest, as a
    /// fraction of the elastic energy of one junction at its threshold.
    pub quiet_energy: f64,
    /// How long (s) the scene must stay quiet before a jump.
    pub quiet_time: f64,
    /// Simulated time (s) left to full dynamics before the predicted
    /// rupture.
    pub lead_time: f64,
    /// Cadence (s) of the quiet checks.
    pub check_interval: f64,
    pub solver: SolverKind,
    /// Factor on the drive response w (1: the computed one). Not a scenario
    /// key: the negative controls of the accuracy tests set it.
    pub response_scale: f64,
    /// Newton's correction of the path's equilibria (true). Without it a
    /// jump lands on the linear prediction u₀ + w·Δt from the quiet state
    /// as it is: the negative control of the accuracy tests.
    pub settle_ends: bool,
    /// Isolated junction ruptures (and the re-pins after them) done on the
    /// quasi-static path (true), or left to full dynamics, each ending a
    /// jump.
    pub quasi_static_ruptures: bool,
    /// Overshoot factor of the cascade check on path events (scenario
    /// `fast_forward.cascade_overshoot`).
    pub cascade_overshoot: f64,
}

impl FastForwardSettings {
    /// The scenario's `[fast_forward]` keys, or their defaults.
    pub fn from_scenario(s: &crate::model::scenario::Scenario) -> Self {
        let f = s.fast_forward.clone().unwrap_or_default();
        FastForwardSettings {
            quiet_energy: f.quiet_energy,
            quiet_time: f.quiet_time,
            lead_time: f.lead_time,
            check_interval: f.check_interval,
            solver: match f.solver {
                crate::model::scenario::FastForwardSolver::Direct => SolverKind::Direct,
                crate::model::scenario::FastForwardSolver::Cg => SolverKind::Cg,
            },
            response_scale: 1.0,
            settle_ends: true,
            quasi_static_ruptures: f.quasi_static_ruptures,
            cascade_overshoot: f.cascade_overshoot,
        }
    }
}

/// One jump, as the `/fast_forward` channel records it.
#[derive(Debug, Clone, PartialEq)]
pub struct JumpRecord {
    pub start_step: u64,
    pub end_step: u64,
    pub start_time: f64,
    pub end_time: f64,
    /// Drive position at both ends: side spring's far end V·t (m), top
    /// force (N), or prescribed top-row displacement (m).
    pub drive_start: f64,
    pub drive_end: f64,
    /// Predicted time of the change that ends the path (s).
    pub predicted_change: f64,
    /// Interface block and junction whose rupture sets the end (None: a
    /// contact change, or nothing before the end of the run).
    pub block: Option<usize>,
    pub junction: Option<usize>,
    /// Isolated junction ruptures and re-pins done on the path.
    pub ruptures: u64,
    pub repins: u64,
    /// Energy (J) of the quiet state's ring-down, dropped by the jump and
    /// booked as dissipated (≥ 0 up to round-off).
    pub dropped_energy: f64,
    /// Work (J) of the drive, top loads and junction forces along the path.
    pub work_in: f64,
    /// Dashpot dissipation (J) along the path (the velocity field w).
    pub damping: f64,
    /// Change of the stored energy (J) along the path: the ledger closes
    /// when it equals work_in − damping.
    pub stored_change: f64,
}

/// Running totals, for the run summary and the metadata.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FastForwardStats {
    pub jumps: u64,
    pub skipped_steps: u64,
    pub skipped_time: f64,
    pub dropped_energy: f64,
    pub factorisations: u64,
    pub cg_iterations: u64,
    pub solver_seconds: f64,
    /// Largest quadratic-path error of any jump (see [`Path::path_error`]).
    pub max_path_error: f64,
    /// Isolated junction ruptures done on quasi-static paths.
    pub path_ruptures: u64,
}

/// The fast-forward's state between two checks (see [`FastForward::state`]).
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct FastForwardState {
    pub quiet_since: Option<u64>,
    pub last_ruptures: Option<u64>,
    pub stats: FastForwardStats,
    /// Stored apart, as binary (`checkpoint::format`).
    #[serde(skip)]
    pub factor: Option<band::BandCholesky>,
}

/// A planned jump: the quasi-static path and its record.
pub struct Jump {
    pub path: Path,
    pub record: JumpRecord,
}

/// Lagrange quadratic through three (step, displacement field) nodes.
pub(crate) fn quadratic(steps: [u64; 3], nodes: [&[[f64; 2]]; 3], step: u64) -> Vec<[f64; 2]> {
    let x = steps.map(|s| s as f64);
    let t = step as f64;
    let l = [
        (t - x[1]) * (t - x[2]) / ((x[0] - x[1]) * (x[0] - x[2])),
        (t - x[0]) * (t - x[2]) / ((x[1] - x[0]) * (x[1] - x[2])),
        (t - x[0]) * (t - x[1]) / ((x[2] - x[0]) * (x[2] - x[1])),
    ];
    (0..nodes[0].len())
        .map(|i| {
            let c =
                |k: usize| l[0] * nodes[0][i][k] + l[1] * nodes[1][i][k] + l[2] * nodes[2][i][k];
            [c(0), c(1)]
        })
        .collect()
}

/// Elastic energy (J) of a mean junction at its threshold: the scale of
/// the quiet criterion.
pub fn junction_energy_scale(model: &Model, snap: &Snapshot) -> f64 {
    let pinned: Vec<f64> = snap
        .slip_steps_left
        .iter()
        .zip(&snap.junction_stiffness)
        .filter(|(s, _)| **s == PINNED)
        .map(|(_, k)| *k)
        .collect();
    if pinned.is_empty() {
        return 0.0;
    }
    let k = pinned.iter().sum::<f64>() / pinned.len() as f64;
    let ns = snap.slip_steps_left.len() as f64 / model.nx as f64;
    let f = crate::model::friction::junctions::break_threshold(
        model.mu_s,
        model.normal_force / (model.nx as f64 * ns),
    );
    0.5 * f * f / k
}

/// With quasi-static ruptures, a block with a smaller pinned fraction is
/// taken to be inside an event, and the scene is not quiet.
pub const MID_EVENT_PINNED: f64 = 0.5;

/// Largest force left on a block at a settled equilibrium, relative to one
/// block's share of the normal load.
pub(crate) const SETTLE_TOLERANCE: f64 = 1e-12;

/// The fast-forward of one run: quiet detector, solver and totals.
pub struct FastForward {
    pub settings: FastForwardSettings,
    quiet_since: Option<u64>,
    /// Rupture count at the last check.
    last_ruptures: Option<u64>,
    solver: Solver,
    pub stats: FastForwardStats,
}

impl FastForward {
    pub fn new(settings: FastForwardSettings) -> Self {
        FastForward {
            settings,
            quiet_since: None,
            last_ruptures: None,
            solver: Solver::new(settings.solver),
            stats: FastForwardStats::default(),
        }
    }

    /// What a checkpoint keeps of the fast-forward: the detector's memory,
    /// the totals and the solver's factor (it preconditions later solves,
    /// so a resumed run needs it to take the same path to the bit).
    pub fn state(&self) -> FastForwardState {
        FastForwardState {
            quiet_since: self.quiet_since,
            last_ruptures: self.last_ruptures,
            stats: self.stats,
            factor: self.solver.factor().cloned(),
        }
    }

    /// Continues from a saved state.
    pub fn restore(&mut self, state: &FastForwardState) {
        self.quiet_since = state.quiet_since;
        self.last_ruptures = state.last_ruptures;
        self.stats = state.stats;
        self.solver.restore(
            state.factor.clone(),
            state.stats.factorisations,
            state.stats.cg_iterations,
        );
    }

    /// Steps between quiet checks.
    pub fn check_steps(&self, model: &Model) -> u64 {
        ((self.settings.check_interval / model.dt).round() as u64).max(1)
    }

    /// Feeds the detector a snapshot of the driving phase; true when every
    /// junction has held for the hold time (the kinetic-energy part of the
    /// criterion needs the quasi-static velocity field: [`Self::plan`]).
    pub fn observe(&mut self, model: &Model, snap: &Snapshot) -> bool {
        // With ruptures on the path, slipping junctions may remain (they
        // slip on at μd·f_N); without, every junction must hold.
        let ruptures = snap.total_ruptures();
        let calm = if self.settings.quasi_static_ruptures {
            // No new rupture, and no block still slipping as part of an
            // event (fewer than half its junctions pinned, the event
            // detector's rule): a slow front breaks a block's junctions
            // less often than the hold time, and the path would stop it.
            self.last_ruptures == Some(ruptures)
                && snap
                    .pinned_fraction(model.nx)
                    .iter()
                    .all(|&p| p >= MID_EVENT_PINNED)
        } else {
            snap.slip_steps_left.iter().all(|&s| s == PINNED)
        } && !snap.slip_steps_left.is_empty();
        self.last_ruptures = Some(ruptures);
        if !calm {
            self.quiet_since = None;
            return false;
        }
        let since = *self.quiet_since.get_or_insert(snap.step);
        (snap.step - since) as f64 * model.dt >= self.settings.quiet_time
    }

    /// Plans the jump from the quiet state `snap` (None when the next
    /// change is too close for a jump to pay). `last_step` bounds the jump
    /// (the end of the run).
    pub fn plan(
        &mut self,
        model: &Model,
        snap: &Snapshot,
        drive_origin: f64,
        last_step: u64,
    ) -> Result<Option<Jump>, QuasiStaticError> {
        let started = std::time::Instant::now();
        let result = self.plan_inner(model, snap, drive_origin, last_step);
        self.stats.solver_seconds += started.elapsed().as_secs_f64();
        self.stats.factorisations = self.solver.factorisations;
        self.stats.cg_iterations = self.solver.cg_iterations;
        // Whatever happens, the next jump waits for a new quiet period.
        self.quiet_since = None;
        result
    }

    fn plan_inner(
        &mut self,
        model: &Model,
        snap: &Snapshot,
        drive_origin: f64,
        last_step: u64,
    ) -> Result<Option<Jump>, QuasiStaticError> {
        let lead = (self.settings.lead_time / model.dt).ceil() as u64;
        let s0 = snap.step;
        if s0 + 2 * lead >= last_step {
            return Ok(None);
        }
        let cx = PathContext {
            model,
            drive_origin,
            lead,
            last_step,
            response_scale: self.settings.response_scale,
            settle_ends: self.settings.settle_ends,
            events: self.settings.quasi_static_ruptures,
            cascade_overshoot: self.settings.cascade_overshoot,
        };
        let k = Tangent::at(model, snap);
        let w = cx.response(&mut self.solver, &k)?;
        // Quiet: the kinetic energy of the departure from the quasi-static
        // motion (v − w; the creep itself grows with the drive speed) is a
        // small fraction of one junction's elastic energy at threshold.
        let ring_down = 0.5
            * model.mass
            * snap
                .vel
                .iter()
                .zip(&w)
                .map(|(v, w)| (v[0] - w[0]).powi(2) + (v[1] - w[1]).powi(2))
                .sum::<f64>();
        if ring_down >= self.settings.quiet_energy * junction_energy_scale(model, snap) {
            return Ok(None);
        }
        let mut start = snap.clone();
        start.disp = cx.settled(&mut self.solver, snap, &k, &w, s0, snap.disp.clone())?;
        start.vel = w.clone();
        start.vel_half = w.clone();
        let Some(path) = path::build(&cx, &mut self.solver, start, k, w)? else {
            return Ok(None);
        };
        let first = &path.segments[0];
        let (block, junction) = match path.stop {
            PathEnd::Rupture { ix, junction } => (Some(ix), Some(junction)),
            PathEnd::Contact { ix } => (Some(ix), None),
            PathEnd::Never => (None, None),
        };
        let record = JumpRecord {
            start_step: s0,
            end_step: path.end_step,
            start_time: model.time_of_step(s0),
            end_time: model.time_of_step(path.end_step),
            drive_start: drive_position(model, &first.base.disp, s0),
            drive_end: drive_position(model, &path.end.disp, path.end_step),
            predicted_change: path.stop_time,
            block,
            junction,
            ruptures: path.ruptures,
            repins: path.repins,
            dropped_energy: 0.0,
            work_in: 0.0,
            damping: 0.0,
            stored_change: 0.0,
        };
        Ok(Some(Jump { path, record }))
    }

    /// Books a completed jump.
    pub fn book(&mut self, model: &Model, record: &JumpRecord, path_error: f64) {
        self.stats.jumps += 1;
        self.stats.path_ruptures += record.ruptures;
        self.stats.max_path_error = self.stats.max_path_error.max(path_error);
        self.stats.skipped_steps += record.end_step - record.start_step;
        self.stats.skipped_time = self.stats.skipped_steps as f64 * model.dt;
        self.stats.dropped_energy += record.dropped_energy;
    }
}

/// Where the drive is at a step: V·t for the side spring, the top force,
/// or the prescribed top row's displacement.
pub fn drive_position(model: &Model, disp: &[[f64; 2]], step: u64) -> f64 {
    let t = model.time_of_step(step).max(0.0);
    match model.driver {
        Driver::None => 0.0,
        Driver::SideSpring { velocity, .. } => velocity * t,
        Driver::TopForce { rate } => rate * t,
        Driver::TopVelocity { .. } => disp[(model.nz - 1) * model.nx][0],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scenario::Scenario;

    /// With quasi-static ruptures the detector waits while a block is
    /// inside an event (fewer than half its junctions pinned) even when no
    /// junction broke since the last check; a few slipping junctions on a
    /// block do not stop it.
    #[test]
    fn a_block_inside_an_event_is_not_quiet() {
        let s = Scenario::default_scene();
        let m = Model::from_scenario(&s, false).unwrap();
        let ns = m.junctions.unwrap().count;
        let settings = FastForwardSettings {
            quasi_static_ruptures: true,
            quiet_time: 0.0,
            ..FastForwardSettings::from_scenario(&s)
        };
        let snap = |slipping: usize| {
            let mut left = vec![PINNED; m.nx * ns];
            left[3 * ns..3 * ns + slipping].fill(100);
            Snapshot {
                slip_steps_left: left,
                ruptures: vec![0; m.nx * ns],
                ..Default::default()
            }
        };
        let quiet_after = |slipping: usize| {
            let mut ff = FastForward::new(settings);
            ff.observe(&m, &snap(slipping));
            ff.observe(&m, &snap(slipping))
        };
        assert!(quiet_after(0));
        assert!(quiet_after(ns / 2));
        assert!(!quiet_after(ns / 2 + 1));
        // Without quasi-static ruptures every junction must hold.
        let mut ff = FastForward::new(FastForwardSettings {
            quasi_static_ruptures: false,
            ..settings
        });
        ff.observe(&m, &snap(1));
        assert!(!ff.observe(&m, &snap(1)));
    }
}
