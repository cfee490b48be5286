//! The single interface block of Publication 2 (Thøgersen et al., PRE 89,
//! 052401 (2014)): one block and its Ns junctions under a prescribed slip
//! history or pulled through a spring, with a family of junction laws and
//! their analytic steady-state friction μ(v). A model of its own: it
//! shares the junction idea of the 2D model, not its engines.

pub mod law;
pub mod sim;

use crate::model::friction::junctions::SlipAtRest;
use law::JunctionLaw;
use serde::{Deserialize, Serialize};
use sim::{Junctions, Motion, Sample};
use std::path::Path;

/// `scenarios/thogersen2014_single_block.toml`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SingleBlockScene {
    pub name: String,
    /// Ns.
    pub junctions: u32,
    pub seed: u32,
    pub law: JunctionLaw,
    pub motion: MotionSpec,
    /// Time step (s).
    pub dt: f64,
    /// Output cadence (s).
    pub output_interval: f64,
}

/// How the block moves.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum MotionSpec {
    /// Accelerate, slide, decelerate, hold, reload (all prescribed).
    Prescribed {
        speed: f64,
        accelerate_time: f64,
        steady_time: f64,
        deceleration: f64,
        hold_time: f64,
        reload_speed: f64,
        reload_time: f64,
    },
    /// Pulled through a spring (per unit normal force) moved at `speed`,
    /// from rest with every junction pinned unstretched.
    Spring {
        mass_per_normal_force: f64,
        stiffness_per_normal_force: f64,
        speed: f64,
        duration: f64,
        /// A dashpot on the block of this ratio of critical damping on its
        /// spring (0 when absent).
        #[serde(default)]
        damping_ratio: f64,
        /// What the slipping junctions do while the block is at rest, as in
        /// the 2D model (`hold` when absent).
        #[serde(default)]
        at_rest: SlipAtRest,
    },
}

pub const SCENARIO: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/thogersen2014_single_block.toml"
));

impl SingleBlockScene {
    pub fn parse(text: &str, name: &str) -> anyhow::Result<SingleBlockScene> {
        let lattice = toml::from_str::<toml::Table>(text).is_ok_and(|t| t.contains_key("geometry"));
        anyhow::ensure!(
            !lattice,
            "{name} is a lattice scene (it has [geometry]); run it with `slipfront run {name}`"
        );
        let s: SingleBlockScene = toml::from_str(text)
            .map_err(|e| anyhow::anyhow!("invalid single-block scenario {name}: {e}"))?;
        let problems = s.problems();
        anyhow::ensure!(
            problems.is_empty(),
            "invalid single-block scenario {name}:\n  - {}",
            problems.join("\n  - ")
        );
        Ok(s)
    }

    pub fn load(path: &Path) -> anyhow::Result<SingleBlockScene> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| anyhow::anyhow!("cannot read scenario file `{}`: {e}", path.display()))?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Range problems, each naming the key, the value and the range.
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        let mut positive = |key: &str, v: f64| {
            if !(v.is_finite() && v > 0.0) {
                p.push(format!(
                    "{key} = {v} is out of range (allowed: a finite value > 0)"
                ));
            }
        };
        positive("law.threshold", self.law.threshold);
        positive("law.break_stretch", self.law.break_stretch);
        positive("dt", self.dt);
        positive("output_interval", self.output_interval);
        match self.law.slip_time {
            law::SlipTime::Fixed { time } => positive("law.slip_time.time", time),
            law::SlipTime::Gaussian { mean, .. } => positive("law.slip_time.mean", mean),
            law::SlipTime::Exponential { mean } => positive("law.slip_time.mean", mean),
        }
        match self.law.slip_force {
            law::SlipForce::Constant { .. } => {}
            law::SlipForce::Relaxing { time, .. } | law::SlipForce::Ramp { time, .. } => {
                positive("law.slip_force.time", time)
            }
        }
        match self.motion {
            MotionSpec::Prescribed {
                speed,
                deceleration,
                ..
            } => {
                positive("motion.speed", speed);
                positive("motion.deceleration", deceleration);
            }
            MotionSpec::Spring {
                mass_per_normal_force,
                stiffness_per_normal_force,
                speed,
                duration,
                ..
            } => {
                positive("motion.mass_per_normal_force", mass_per_normal_force);
                positive(
                    "motion.stiffness_per_normal_force",
                    stiffness_per_normal_force,
                );
                positive("motion.speed", speed);
                positive("motion.duration", duration);
            }
        }
        if let MotionSpec::Spring { damping_ratio, .. } = self.motion {
            if !(damping_ratio.is_finite() && damping_ratio >= 0.0) {
                p.push(format!(
                    "motion.damping_ratio = {damping_ratio} is out of range (allowed: a finite \
                     value >= 0)"
                ));
            }
        }
        if !(1..=1 << 22).contains(&self.junctions) {
            p.push(format!(
                "junctions = {} is out of range (allowed: 1 to {})",
                self.junctions,
                1 << 22
            ));
        }
        if !(self.law.drag.is_finite() && self.law.drag >= 0.0) {
            p.push(format!(
                "law.drag = {} is out of range (allowed: a finite value >= 0)",
                self.law.drag
            ));
        }
        // A block pulled through a spring is integrated explicitly
        // (symplectic Euler): stable while dt·ω < 2, ω² the spring's and
        // the pinned junctions' stiffness over the mass (all per unit
        // normal force), as the lattice scenes check their dt.
        if let MotionSpec::Spring {
            mass_per_normal_force: mass,
            stiffness_per_normal_force: spring,
            ..
        } = self.motion
        {
            let stiffness = spring + self.law.threshold / self.law.break_stretch;
            let limit = 2.0 * (mass / stiffness).sqrt();
            if limit.is_finite() && self.dt > limit {
                p.push(format!(
                    "dt = {:e} s is above the stability limit {limit:.4e} s of the block on its \
                     spring and pinned junctions (2/ω, ω² = (motion.stiffness_per_normal_force \
                     + law.threshold / law.break_stretch) / motion.mass_per_normal_force) \
                     (allowed: dt <= {limit:.4e} s)",
                    self.dt
                ));
            }
        }
        p
    }

    /// Runs the scene; `sample` gets every `output_interval`.
    pub fn run(&self, mut sample: impl FnMut(Sample)) {
        let mut j = Junctions::pinned(self.law, self.junctions as usize, self.seed);
        let every = (self.output_interval / self.dt).round().max(1.0) as u64;
        let mut n = 0u64;
        let mut thin = |s: Sample| {
            if n.is_multiple_of(every) {
                sample(s);
            }
            n += 1;
        };
        match self.motion {
            MotionSpec::Prescribed {
                speed,
                accelerate_time,
                steady_time,
                deceleration,
                hold_time,
                reload_speed,
                reload_time,
            } => {
                let m = Motion::stop_and_reload(
                    speed,
                    accelerate_time,
                    steady_time,
                    deceleration,
                    hold_time,
                    reload_speed,
                    reload_time,
                );
                sim::follow(&mut j, &m, self.dt, &mut thin);
            }
            MotionSpec::Spring {
                mass_per_normal_force: mass,
                stiffness_per_normal_force: stiffness,
                speed,
                duration,
                damping_ratio,
                at_rest,
            } => {
                let pull = sim::Pull {
                    mass,
                    stiffness,
                    damping: sim::Pull::damping_for(mass, stiffness, damping_ratio),
                    speed,
                    preload: 0.0,
                    at_rest,
                };
                sim::pull_from(&mut j, &pull, 0.0, duration, self.dt, &mut thin)
            }
        }
    }
}

/// Time step that resolves a steady cycle at speed `v`: 1/500 of the
/// cycle and 1/50 of a slip-force time scale.
pub fn steady_dt(law: &JunctionLaw, v: f64) -> f64 {
    let cycle = law.break_stretch / v + law.slip_time.mean();
    let scale = match law.slip_force {
        law::SlipForce::Constant { .. } => f64::INFINITY,
        law::SlipForce::Relaxing { time, .. } | law::SlipForce::Ramp { time, .. } => time,
    };
    (cycle / 500.0).min(scale / 50.0)
}

/// Simulated steady friction at speed `v`: `count` junctions started in
/// their steady cycle, averaged over `cycles` cycles after 3 to settle.
pub fn simulated_steady_friction(
    law: &JunctionLaw,
    v: f64,
    count: usize,
    cycles: f64,
    seed: u32,
) -> f64 {
    let cycle = law.break_stretch / v + law.slip_time.mean();
    let dt = steady_dt(law, v);
    let settle = 3.0 * cycle;
    let mut j = Junctions::steady(*law, count, seed, v);
    let motion = Motion::steady(v, settle + cycles * cycle);
    let (mut sum, mut n) = (0.0, 0u64);
    sim::follow(&mut j, &motion, dt, |s| {
        if s.time >= settle {
            sum += s.friction;
            n += 1;
        }
    });
    sum / n as f64
}

/// The static threshold of the next loading: the peak friction while
/// reloading at `reload_speed` after sliding at `speed` and stopping at
/// `deceleration`, then holding until every junction has re-pinned.
pub fn next_static_threshold(
    law: &JunctionLaw,
    count: usize,
    seed: u32,
    speed: f64,
    deceleration: f64,
    reload_speed: f64,
) -> f64 {
    let slip_max = law.slip_time.expect(|t| t) * 3.0 + 1e-12;
    let cycle = law.break_stretch / speed + law.slip_time.mean();
    let reload_time = 3.0 * law.break_stretch / reload_speed;
    let steady = 5.0 * cycle;
    let stopping = speed / deceleration;
    let motion = Motion::stop_and_reload(
        speed,
        0.0,
        steady,
        deceleration,
        slip_max,
        reload_speed,
        reload_time,
    );
    let mut j = Junctions::steady(*law, count, seed, speed);
    let base = steady_dt(law, speed);
    let stop = steady + stopping + slip_max;
    let mut peak = f64::NEG_INFINITY;
    // Each phase at the step it needs: the stop resolved in 200 steps, the
    // reload in 2000 per break stretch.
    let phases = [
        (0.0, steady, base),
        (steady, steady + stopping, base.min(stopping / 200.0)),
        (steady + stopping, stop, base),
        (
            stop,
            motion.duration(),
            law.break_stretch / reload_speed / 2000.0,
        ),
    ];
    for (k, (a, b, dt)) in phases.into_iter().enumerate() {
        sim::follow_between(&mut j, &motion, a, b, dt, |s| {
            if k == 3 {
                peak = peak.max(s.friction);
            }
        });
    }
    peak
}
