//! Validation cases: measured against expected, each with its tolerance.
//! Run by `slipfront verify` on any backend and by the integration tests.

mod coulomb_block;
mod elastic;
mod junction_drag;
pub mod rate_state;
mod rng_stats;
mod waves;

pub use coulomb_block::{coulomb_ensemble_error, coulomb_exact_position, CoulombExact};
pub use junction_drag::renewal_friction_coefficient;
pub use waves::measure_wave_speed;

use crate::engines::{Engine, EngineError};
use crate::model::scenario::Scenario;
use crate::model::Model;
use serde::Serialize;

/// How a case compares its measurement.
#[derive(Debug, Clone, Copy, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Comparison {
    /// |measured − expected| ≤ tolerance.
    Within,
    /// measured ≤ expected (a bound).
    AtMost,
}

/// One validation result.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct CaseResult {
    pub name: String,
    pub measured: f64,
    pub expected: f64,
    /// Allowed |measured − expected| (absolute, in `unit`).
    pub tolerance: f64,
    pub unit: String,
    pub comparison: Comparison,
    pub pass: bool,
}

impl CaseResult {
    pub fn new(name: &str, measured: f64, expected: f64, tolerance: f64, unit: &str) -> Self {
        CaseResult {
            name: name.to_string(),
            measured,
            expected,
            tolerance,
            unit: unit.to_string(),
            comparison: Comparison::Within,
            pass: measured.is_finite() && (measured - expected).abs() <= tolerance,
        }
    }

    /// A case that passes when `measured <= bound`.
    pub fn at_most(name: &str, measured: f64, bound: f64, unit: &str) -> Self {
        CaseResult {
            name: name.to_string(),
            measured,
            expected: bound,
            tolerance: 0.0,
            unit: unit.to_string(),
            comparison: Comparison::AtMost,
            pass: measured.is_finite() && measured <= bound,
        }
    }
}

impl CaseResult {
    /// "≤ 1.000e0" or "2.000e3 ± 1.000e1": what the measurement must meet.
    pub fn requirement(&self) -> String {
        match self.comparison {
            Comparison::AtMost => format!("≤ {:.4e}", self.expected),
            Comparison::Within => format!("{:.4e} ± {:.2e}", self.expected, self.tolerance),
        }
    }
}

/// One line per failed case: name, measured, expected and tolerance.
pub fn failures(results: &[CaseResult]) -> Vec<String> {
    results
        .iter()
        .filter(|r| !r.pass)
        .map(|r| format!("{}: {} vs {}", r.name, r.measured, r.requirement()))
        .collect()
}

/// Builds an engine for a model (the backend under test).
pub type EngineFactory<'a> = &'a dyn Fn(&Model) -> Result<Box<dyn Engine>, EngineError>;

/// Errors of the verification harness itself.
#[derive(Debug, thiserror::Error)]
pub enum VerifyError {
    #[error(transparent)]
    Engine(#[from] EngineError),
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
}

type CaseGroup = fn(EngineFactory<'_>) -> Result<Vec<CaseResult>, VerifyError>;

/// The groups of cases, in order, by name.
const GROUPS: [(&str, CaseGroup); 6] = [
    ("wave speeds", waves::wave_speed_cases),
    ("elastic constants", elastic::elastic_constant_cases),
    ("coulomb block", coulomb_block::coulomb_block_cases),
    ("junction drag", junction_drag::junction_drag_cases),
    ("rate and state", rate_state::rate_state_cases),
    ("rng", rng_stats::rng_cases),
];

/// Every validation case, in order.
pub fn run_all(factory: EngineFactory<'_>) -> Result<Vec<CaseResult>, VerifyError> {
    run_all_reporting(factory, &mut |_, _| {})
}

/// Every validation case; `done(group, seconds)` is called after each group.
pub fn run_all_reporting(
    factory: EngineFactory<'_>,
    done: &mut dyn FnMut(&str, f64),
) -> Result<Vec<CaseResult>, VerifyError> {
    let mut out = Vec::new();
    for (name, group) in GROUPS {
        let start = std::time::Instant::now();
        out.extend(group(factory)?);
        done(name, start.elapsed().as_secs_f64());
    }
    Ok(out)
}

/// Overrides that shrink the Table S1 scene to 29 × 16 blocks (same
/// spacing) with short loading phases: the small side-driven scene of the
/// GPU cross-checks, the stability tests and the time-step study.
pub const SMALL_SCENE: [&str; 6] = [
    "geometry.nx=29",
    "geometry.nz=16",
    "geometry.length=0.07",
    "geometry.height=0.0375",
    "loading.normal.ramp_time=2e-4",
    "loading.normal.relax_time=3e-4",
];

/// Overrides that make the small scene blow up within a few hundred steps:
/// junctions 10⁴× too stiff for the time step (a run must be forced past
/// the stability check), driven fast (the GPU blow-up tests).
pub const STIFF_JUNCTIONS_BLOW_UP: [&str; 3] = [
    "loading.drive.velocity=0.4",
    "friction.junctions.stiffness_coefficient=39.2e17",
    "time.end=1e-3",
];

/// Overrides for a stick-slip window in the small scene: a fast drive and
/// short slip times, so junctions break, re-pin and break again within a
/// few thousand steps of driving (the GPU, stability and sweep-engine
/// cross-checks).
pub const STICK_SLIP_WINDOW: [&str; 3] = [
    "loading.drive.velocity=0.4",
    "friction.junctions.slip_time_mean=2e-4",
    "friction.junctions.slip_time_std=2e-5",
];

/// The small side-driven scene with `extra` overrides after SMALL_SCENE.
pub fn small_scene(extra: &[&str]) -> Result<Scenario, crate::model::scenario::ScenarioError> {
    let set: Vec<String> = SMALL_SCENE
        .iter()
        .chain(extra)
        .map(|s| s.to_string())
        .collect();
    Scenario::parse(
        crate::model::scenario::DEFAULT_SCENARIO,
        "small scene",
        &set,
    )
}

/// `scenarios/triggered_front.toml`, built in.
pub const TRIGGERED_FRONT: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/triggered_front.toml"
));

/// The small lattice (SMALL_SCENE) with the triggered front and the output
/// tests' cadences (interface rows every 20 µs, every 1 µs while the
/// interface slips, bulk fields every 50 µs): the interface slips within
/// the first 0.3 ms of driving, so the fast cadence switches on and off.
/// `extra` overrides after these.
pub fn small_triggered_scene(
    extra: &[&str],
) -> Result<Scenario, crate::model::scenario::ScenarioError> {
    let set: Vec<String> = SMALL_SCENE
        .iter()
        .chain(&[
            "output.interface_interval=2e-5",
            "output.fast_interval=1e-6",
            "output.bulk_interval=5e-5",
        ])
        .chain(extra)
        .map(|s| s.to_string())
        .collect();
    Scenario::parse(TRIGGERED_FRONT, "triggered_front.toml", &set)
}

/// The Table S1 scene stripped of loads, friction and damping: the base of
/// the verification scenes, which then set what they test.
pub fn bare_scene(name: &str) -> Scenario {
    use crate::model::scenario::{DriveMode, EdgeConstraint, FrictionLaw};
    let mut s = Scenario::default_scene();
    s.name = name.to_string();
    s.damping.ratio = 0.0;
    s.foundation.stiffness_ratio = 0.0;
    s.friction.law = FrictionLaw::None;
    s.friction.junctions = None;
    s.loading.normal.force = 0.0;
    s.loading.normal.ramp_time = 0.0;
    s.loading.normal.relax_time = 0.0;
    s.loading.drive = crate::model::scenario::Drive {
        mode: DriveMode::None,
        stiffness: None,
        height: None,
        velocity: None,
        force_rate: None,
    };
    s.boundary.top = EdgeConstraint::Free;
    s.boundary.bottom = EdgeConstraint::Free;
    s
}

/// One 2.5 mm block on its foundation (k_f = k/2), pressed by
/// `normal_force` over a ramp and a critically damped relaxation (10 and
/// 40 times √(m/k_f): the times scale with the block), then pulled from
/// its side, at its own height, by a spring of `stiffness` at `velocity`:
/// the single-block scene of the friction-law cases. `friction` sets the
/// law (and anything else of the scene) first.
pub fn spring_block(
    name: &str,
    normal_force: f64,
    stiffness: f64,
    velocity: f64,
    friction: impl FnOnce(&mut Scenario),
) -> Result<Scenario, VerifyError> {
    use crate::model::scenario::{Drive, DriveMode};
    let mut s = bare_scene(name);
    s.geometry.nx = 1;
    s.geometry.nz = 1;
    s.geometry.length = 2.5e-3;
    s.geometry.height = 2.5e-3;
    s.foundation.stiffness_ratio = 0.5;
    friction(&mut s);
    let probe = scene_model(&s)?;
    let foundation_time = (probe.mass / probe.k_foundation).sqrt();
    s.loading.normal.force = normal_force;
    s.loading.normal.ramp_time = 10.0 * foundation_time;
    s.loading.normal.relax_time = 40.0 * foundation_time;
    // Critical damping of the block on its foundation: √(k_f/k) of 2√(km).
    s.loading.normal.relax_damping_ratio = 0.5f64.sqrt();
    s.loading.drive = Drive {
        mode: DriveMode::SideSpring,
        stiffness: Some(stiffness),
        height: Some(0.0),
        velocity: Some(velocity),
        force_rate: None,
    };
    Ok(s)
}

/// Model of a verification scene (validated like a user's scenario).
pub fn scene_model(s: &Scenario) -> Result<Model, VerifyError> {
    let text = s.to_toml();
    let problems = crate::model::scenario::validate(s, &text, &[]);
    if !problems.is_empty() {
        return Err(VerifyError::Model(crate::model::ModelError::Invalid(
            problems.join("; "),
        )));
    }
    Ok(Model::from_scenario(s, false)?)
}
