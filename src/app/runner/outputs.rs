//! The output side of a run: what each record holds (the global series
//! of a snapshot, the drive force), the cadences, and the sink.

use super::RunError;
use crate::engines::quasistatic::FastForwardStats;
use crate::engines::step_params::{step_params, Consts};
use crate::engines::{record_sample, Sample, SamplePlan, Snapshot};
use crate::io::checkpoint::RunnerState;
use crate::io::live::LiveView;
use crate::io::output::records::{Record, RecordBuilder};
use crate::io::output::{GlobalSample, McapSink};
use crate::model::scenario::Scenario;
use crate::model::{Driver, Model};

/// Tangential force (N) the scene's driver applies at a sample's instant:
/// the side spring's tension; the programmed top force (ramp plus any
/// trigger prestress); for a prescribed top-row velocity, the constraint
/// reaction that gives the row its prescribed velocity over the next step;
/// 0 without a driver. Friction is reported apart.
pub fn drive_force(model: &Model, sample: &Sample, origin: f64) -> f64 {
    match model.driver {
        Driver::SideSpring {
            stiffness,
            velocity,
            ..
        } => {
            stiffness
                * crate::model::laws::side_spring_stretch(
                    velocity,
                    sample.time,
                    sample.sums.driven_ux,
                    origin,
                )
        }
        Driver::TopForce { .. } => {
            step_params(&Consts::<f64>::new(model), sample.step).top_tangential_total
        }
        Driver::TopVelocity { .. } => sample.sums.top_reaction,
        Driver::None => 0.0,
    }
}

/// The side spring's far-end origin (m) from the snapshot at the start of
/// driving: the driven block's x displacement then (the reported drive
/// force is the spring's stretch from there). None for other drivers.
pub fn drive_origin(model: &Model, snap: &Snapshot) -> Option<f64> {
    match model.driver {
        Driver::SideSpring { row, .. } => Some(snap.disp[row * model.nx][0]),
        _ => None,
    }
}

/// The global series of a sample.
pub fn global_of(model: &Model, sample: &Sample, origin: f64) -> GlobalSample {
    let force = drive_force(model, sample, origin);
    let sums = &sample.sums;
    GlobalSample {
        time: sample.time,
        step: sample.step,
        drive_force: force,
        // Without a normal load F/F_N has no meaning: 0, documented
        // (README, /global), and the run summary says so.
        drive_ratio: if model.normal_force > 0.0 {
            force / model.normal_force
        } else {
            0.0
        },
        friction_force: sums.friction,
        pinned_fraction: sums.pinned_fraction,
        kinetic_energy: sums.kinetic_energy,
        ruptures: sums.ruptures,
    }
}

/// The global series of one snapshot.
pub fn global_sample(model: &Model, snap: &Snapshot, origin: f64) -> GlobalSample {
    global_of(model, &record_sample(model, snap, false, false), origin)
}

pub(super) fn interval_steps(model: &Model, interval: f64) -> u64 {
    if interval > 0.0 {
        ((interval / model.dt).round() as u64).max(1)
    } else {
        0
    }
}

pub(super) fn next_multiple(step: u64, every: u64) -> u64 {
    step.checked_div(every)
        .map_or(u64::MAX, |n| (n + 1) * every)
}

/// The output cadences `scenario` gives a run of `model`, in steps, with
/// the fast cadence off (as at the start of driving).
pub fn sample_plan(model: &Model, scenario: &Scenario) -> SamplePlan {
    let o = &scenario.output;
    SamplePlan {
        prep_steps: model.prep_steps,
        every_global: interval_steps(model, o.global_interval),
        every_interface: interval_steps(model, o.interface_interval),
        every_bulk: interval_steps(model, o.bulk_interval),
        every_fast: interval_steps(model, o.fast_interval),
        fast_slip_speed: o.fast_slip_speed,
        fast: false,
    }
}

/// The output side of a run: cadences, the sinks (the run file, the live
/// view), and what the summary reports (peak and last F/F_N, ruptures).
pub(super) struct Outputs {
    model: Model,
    pub sink: Option<McapSink>,
    /// Records go to the live view too; without a run file, samples are
    /// taken only while a viewer subscribes.
    pub live: Option<LiveView>,
    records: RecordBuilder,
    every_global: u64,
    every_interface: u64,
    every_bulk: u64,
    /// Interface output speeds up to `fast_interval` while any interface
    /// block slips faster than `fast_slip_speed` (decided at each sample).
    every_fast: u64,
    fast_slip_speed: f64,
    fast: bool,
    pub origin: f64,
    pub peak: f64,
    pub last: f64,
    pub ruptures: u64,
    /// Slip events seen in the output samples so far, and the time of the
    /// last sample with a ruptured block (for the progress report).
    events: u64,
    last_slip: Option<f64>,
}

impl Outputs {
    pub fn new(
        model: &Model,
        scenario: &Scenario,
        sink: Option<McapSink>,
        live: Option<LiveView>,
    ) -> Self {
        let plan = sample_plan(model, scenario);
        Outputs {
            model: model.clone(),
            sink,
            live,
            records: RecordBuilder::default(),
            every_global: plan.every_global,
            every_interface: plan.every_interface,
            every_bulk: plan.every_bulk,
            every_fast: plan.every_fast,
            fast_slip_speed: plan.fast_slip_speed,
            fast: plan.fast,
            origin: 0.0,
            peak: 0.0,
            last: 0.0,
            ruptures: 0,
            events: 0,
            last_slip: None,
        }
    }

    /// The first step after `s` at which some channel is due (u64::MAX:
    /// none, or nothing is written).
    pub fn next_due(&self, s: u64) -> u64 {
        let prep = self.model.prep_steps;
        if s < prep || !self.recording() {
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

    /// Records are wanted now: there is a run file, or a viewer.
    fn recording(&self) -> bool {
        self.sink.is_some() || self.live.as_ref().is_some_and(LiveView::wanted)
    }

    /// The cadences as the engines' sample plan, with the fast cadence's
    /// current state.
    pub fn plan(&self) -> SamplePlan {
        SamplePlan {
            prep_steps: self.model.prep_steps,
            every_global: self.every_global,
            every_interface: self.every_interface,
            every_bulk: self.every_bulk,
            every_fast: self.every_fast,
            fast_slip_speed: self.fast_slip_speed,
            fast: self.fast,
        }
    }

    /// Writes the channels due at the snapshot's step.
    pub fn emit(&mut self, snap: &Snapshot) -> Result<(), RunError> {
        let due = self.plan().due(snap.step);
        let interface = due.interface || (self.fast && due.fast);
        let sample = record_sample(&self.model, snap, interface, due.bulk);
        self.emit_sample(&sample)
    }

    /// Writes a sample (its channels are those due at its step) and
    /// updates the fast cadence, the event count and the summary from it.
    pub fn emit_sample(&mut self, sample: &Sample) -> Result<(), RunError> {
        let model = &self.model;
        let due = self.plan().due(sample.step);
        let g = global_of(model, sample, self.origin);
        self.peak = self.peak.max(g.drive_ratio);
        self.last = g.drive_ratio;
        self.ruptures = g.ruptures;
        self.fast = self.every_fast > 0 && sample.sums.max_slip_speed > self.fast_slip_speed;
        if sample.sums.min_pinned_fraction < crate::analysis::events::RUPTURED_BELOW {
            let gap = crate::analysis::events::DEFAULT_QUIET_GAP;
            if self.last_slip.is_none_or(|t| sample.time - t >= gap) {
                self.events += 1;
            }
            self.last_slip = Some(sample.time);
        }
        if due.global {
            self.send(RecordBuilder::global(&g))?;
        }
        if let Some(row) = &sample.interface {
            let record = self
                .records
                .interface(&self.model, sample.step, sample.time, row);
            self.send(record)?;
        }
        if let Some(field) = &sample.bulk {
            let record = RecordBuilder::bulk(&self.model, sample.step, sample.time, field);
            self.send(record)?;
        }
        Ok(())
    }

    /// Writes a record to the run file and the live view, encoded once.
    pub fn send(&mut self, record: Record) -> Result<(), RunError> {
        let bytes = record.encode();
        if let Some(live) = &self.live {
            live.publish(&record, &bytes);
        }
        if let Some(sink) = self.sink.as_mut() {
            sink.write(record.topic(), record.time(), bytes)?;
        }
        Ok(())
    }

    /// Slip events so far (as `info` counts them, from the samples
    /// written); None without an output file.
    pub fn events(&self) -> Option<u64> {
        self.sink.as_ref().map(|_| self.events)
    }

    /// The runner state's output part (the fast-forward's is added by the
    /// caller).
    pub fn save(&self) -> RunnerState {
        let sequence = self.sink.as_ref().map_or(0, McapSink::sequence);
        let slip_origin = self.records.slip_origin();
        RunnerState {
            origin: self.origin,
            fast: self.fast,
            peak: self.peak,
            last: self.last,
            ruptures: self.ruptures,
            sequence,
            slip_origin,
            fast_forward: None,
            events: self.events,
            last_slip: self.last_slip,
        }
    }

    /// Continues from a saved state.
    pub fn restore(&mut self, r: &RunnerState) {
        self.origin = r.origin;
        self.fast = r.fast;
        self.peak = r.peak;
        self.last = r.last;
        self.ruptures = r.ruptures;
        self.events = r.events;
        self.last_slip = r.last_slip;
        self.records = RecordBuilder::restored(r.slip_origin.clone());
        if let Some(sink) = self.sink.as_mut() {
            sink.restore(r.sequence);
        }
    }

    pub fn finish(&mut self, fast_forward: Option<&FastForwardStats>) -> Result<(), RunError> {
        if let Some(sink) = self.sink.take() {
            sink.finish(fast_forward)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plan the GPU's launches are timed recording at is the one the
    /// run samples at from the start of driving; another scenario's
    /// cadences give another plan.
    #[test]
    fn the_timed_plan_is_the_runs_own() {
        let scenario = Scenario::default_scene();
        let model = Model::from_scenario(&scenario, false).unwrap();
        let plan = sample_plan(&model, &scenario);
        assert_eq!(plan, Outputs::new(&model, &scenario, None, None).plan());
        assert!(!plan.fast);
        assert!(plan.every_global > 0 && plan.every_fast > 0);
        assert!(plan.every_fast < plan.every_global);
        let mut slower = scenario.clone();
        slower.output.fast_interval *= 2.0;
        assert_ne!(sample_plan(&model, &slower), plan);
    }
}
