//! Scenario files: the TOML description of one simulation.
//!
//! Every key is required unless it belongs to a mode the scene does not use
//! (those live in optional sub-tables). Unknown keys are refused by serde;
//! ranges are checked by [`validate`], which names the key, the value, the
//! allowed range and the line of the file.

mod built_in;
mod overrides;
mod validate;

pub use built_in::{built_in, BUILT_IN};
pub use overrides::apply_override;
pub use validate::validate;

pub use crate::model::friction::junctions::{JunctionStiffness, Junctions};
pub use crate::model::friction::rate_state::{RateStateTable, StateEvolution};
pub use crate::model::friction::FrictionLaw;
use crate::model::friction::LawTables;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The Table S1 side-driven stick-slip scene, run when no scenario is given.
pub const DEFAULT_SCENARIO: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/tromborg2014_stick_slip.toml"
));
/// Name shown for the built-in default.
pub const DEFAULT_SCENARIO_NAME: &str = "scenarios/tromborg2014_stick_slip.toml (built in)";

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    pub name: String,
    pub geometry: Geometry,
    pub material: Material,
    pub damping: Damping,
    pub foundation: Foundation,
    pub friction: Friction,
    pub loading: Loading,
    pub boundary: Boundary,
    pub time: Time,
    pub output: Output,
    /// Optional initial displacement pulse (wave tests).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pulse: Option<Pulse>,
    /// Optional: where along the track the slider starts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<Start>,
    /// Thresholds of the quasi-static fast-forward (`time.fast_forward`);
    /// defaults when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fast_forward: Option<FastForward>,
}

/// `[fast_forward]`: when a scene counts as quiet and how close to the
/// next rupture a jump lands. Every key has a default.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FastForward {
    /// Kinetic energy below which the slider is at rest, as a fraction of
    /// the elastic energy of one junction at its threshold.
    #[serde(default = "FastForward::default_quiet_energy")]
    pub quiet_energy: f64,
    /// Time (s) the scene must stay quiet before a jump.
    #[serde(default = "FastForward::default_quiet_time")]
    pub quiet_time: f64,
    /// Simulated time (s) left to full dynamics before the predicted
    /// rupture.
    #[serde(default = "FastForward::default_lead_time")]
    pub lead_time: f64,
    /// Cadence (s) of the quiet checks.
    #[serde(default = "FastForward::default_check_interval")]
    pub check_interval: f64,
    /// Linear solver: "direct" (banded Cholesky, reused as the CG
    /// preconditioner) or "cg" (Jacobi-preconditioned CG).
    #[serde(default = "FastForward::default_solver")]
    pub solver: FastForwardSolver,
    /// Isolated junction ruptures during loading (and the re-pins after
    /// them) on the quasi-static path (true), or left to full dynamics
    /// (false, the default: the quasi-static events miss the slow events
    /// after a large one, results/fast_forward.md).
    #[serde(default = "FastForward::default_quasi_static_ruptures")]
    pub quasi_static_ruptures: bool,
    /// With quasi-static ruptures: the dynamic overshoot assumed of an
    /// event's load on the other pinned junctions, in units of its static
    /// change. An event is left to full dynamics unless every pinned
    /// junction's margin below threshold after it exceeds this many times
    /// the force it added (1: the bound of one damped oscillator under a
    /// step load, which peaks at twice its static change).
    #[serde(default = "FastForward::default_cascade_overshoot")]
    pub cascade_overshoot: f64,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FastForwardSolver {
    Direct,
    Cg,
}

impl FastForward {
    fn default_quiet_energy() -> f64 {
        1.0e-3
    }
    fn default_quiet_time() -> f64 {
        1.0e-4
    }
    fn default_lead_time() -> f64 {
        1.0e-4
    }
    fn default_check_interval() -> f64 {
        2.0e-5
    }
    fn default_solver() -> FastForwardSolver {
        FastForwardSolver::Direct
    }
    fn default_quasi_static_ruptures() -> bool {
        false
    }
    fn default_cascade_overshoot() -> f64 {
        1.0
    }
}

impl Default for FastForward {
    fn default() -> Self {
        FastForward {
            quiet_energy: Self::default_quiet_energy(),
            quiet_time: Self::default_quiet_time(),
            lead_time: Self::default_lead_time(),
            check_interval: Self::default_check_interval(),
            solver: Self::default_solver(),
            quasi_static_ruptures: Self::default_quasi_static_ruptures(),
            cascade_overshoot: Self::default_cascade_overshoot(),
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Geometry {
    /// Slider length L along x (m).
    pub length: f64,
    /// Slider height H along z (m).
    pub height: f64,
    /// Out-of-plane width B (m).
    pub width: f64,
    /// Blocks along x.
    pub nx: u32,
    /// Blocks along z (row 0 is the interface).
    pub nz: u32,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Density ρ (kg/m³).
    pub density: f64,
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum DampingForm {
    /// F = η (v_j − v_i), the full relative velocity.
    Full,
    /// F = η ((v_j − v_i)·n) n, projected on the bond.
    Bond,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Damping {
    /// η = ratio · √(k m); Table S1 uses √0.1.
    pub ratio: f64,
    pub form: DampingForm,
    /// A dashpot on every block's absolute velocity (against the track),
    /// η_abs = absolute_ratio · √(k m), acting once driving starts: the
    /// "absolute viscosity" of the 1D front literature. 0 (default): none.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub absolute_ratio: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Foundation {
    /// k_f / k; Table S1 uses 0.5.
    pub stiffness_ratio: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Friction {
    pub law: FrictionLaw,
    /// μs, the static (junction rupture) threshold.
    pub static_coefficient: f64,
    /// μd, the slipping friction level.
    pub dynamic_coefficient: f64,
    /// Required for `junctions` and `single_junction`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub junctions: Option<Junctions>,
    /// Required for `rate_state`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rate_state: Option<RateStateTable>,
}

impl Friction {
    /// The laws' own tables.
    pub fn law_tables(&self) -> LawTables {
        LawTables {
            junctions: self.junctions.clone(),
            rate_state: self.rate_state.clone(),
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Loading {
    pub normal: NormalLoad,
    pub drive: Drive,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trigger: Option<Trigger>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prestress: Option<Prestress>,
}

/// `[loading.prestress]`: a uniform shear prestress applied as a tangential
/// force on every interface block from the start of driving, balanced by
/// friction, in the dimensionless form of the 1D front literature:
/// τ̄ = (τ − μd p)/((μs − μd) p). The first `trigger_blocks` blocks from the
/// trailing edge carry `trigger_tau_bar` (> 1: they break at once).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Prestress {
    pub tau_bar: f64,
    pub trigger_tau_bar: f64,
    pub trigger_blocks: u32,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct NormalLoad {
    /// F_N (N), spread over the top row.
    pub force: f64,
    /// Line load at the trailing edge over that at the leading edge, the
    /// profile linear between them and the total `force`; 1 (default):
    /// uniform.
    #[serde(
        default = "NormalLoad::default_trailing_to_leading",
        skip_serializing_if = "NormalLoad::is_uniform"
    )]
    pub trailing_to_leading: f64,
    /// Ramp duration (s) before driving starts; junctions cannot break.
    pub ramp_time: f64,
    /// Damped relaxation after the ramp (s).
    pub relax_time: f64,
    /// Extra damping on absolute velocity during relaxation, as a fraction of
    /// 2√(k m) (the critical damping of one block on one spring).
    pub relax_damping_ratio: f64,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum DriveMode {
    /// Spring K on the trailing-edge column at height h, pulled at V.
    SideSpring,
    /// Uniform tangential force on the top row growing at `force_rate`.
    TopForce,
    /// Top row moved at constant velocity V.
    TopVelocity,
    /// No tangential driving.
    None,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Drive {
    pub mode: DriveMode,
    /// K (N/m), side_spring.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// h (m) above the interface, side_spring.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<f64>,
    /// V (m/s), side_spring and top_velocity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<f64>,
    /// dF/dt (N/s) of the total top force, top_force.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_rate: Option<f64>,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Trigger {
    /// τ/p, the initial junction force over its normal force, on average.
    pub shear_prestress: f64,
    /// Full width of the uniform distribution of junction force ratios.
    pub force_width: f64,
    /// Length (m) of the trailing-edge strip pushed over threshold at t = 0.
    pub strip_length: f64,
    /// τ/p in the trigger strip at t = 0 (above μs breaks it at once).
    pub strip_prestress: f64,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum EdgeConstraint {
    Free,
    /// u_x = 0 on the row.
    FixX,
    /// u_z = 0 on the row.
    FixZ,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Boundary {
    pub top: EdgeConstraint,
    pub bottom: EdgeConstraint,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Time {
    /// Time step in seconds; give this or `dt_fraction`, not both.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    /// Time step as a fraction of T = 2π√(m/k).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt_fraction: Option<f64>,
    /// Simulated time after the normal-load phase (s).
    pub end: f64,
    /// Seed of the counter-based junction RNG.
    pub seed: u32,
    /// Skip the stick phases on the quasi-static path (`[fast_forward]`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub fast_forward: bool,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Global series cadence (s); 0 disables.
    pub global_interval: f64,
    /// Interface fields cadence (s); 0 disables.
    pub interface_interval: f64,
    /// Bulk snapshots cadence (s); 0 disables.
    pub bulk_interval: f64,
    /// Interface cadence while the interface slips (s); 0 disables.
    pub fast_interval: f64,
    /// Slip speed (m/s) above which the fast cadence applies.
    pub fast_slip_speed: f64,
    /// Wall time (s) between checkpoints beside the output file; 0 keeps
    /// only those at the start of driving, at the end and on a signal.
    #[serde(default = "Output::default_checkpoint_interval")]
    pub checkpoint_interval: f64,
}

impl NormalLoad {
    fn default_trailing_to_leading() -> f64 {
        1.0
    }
    fn is_uniform(r: &f64) -> bool {
        *r == 1.0
    }
}

impl Output {
    fn default_checkpoint_interval() -> f64 {
        600.0
    }
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Component {
    X,
    Z,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Pulse {
    /// Displacement component carried by the pulse.
    pub component: Component,
    /// Centre along x (m).
    pub center: f64,
    /// Gaussian standard deviation (m).
    pub width: f64,
    /// Peak displacement (m).
    pub amplitude: f64,
}

/// `[start]`: where along the track the slider starts, as if it had
/// already slid that far. The track is uniform, so the physics does not
/// depend on it; the rounding of stored displacements does (one f32 ulp of
/// 1 cm is 0.9 nm): a short run at a late run's position shows what f32
/// displacements do to a long run.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Start {
    /// Displacement along x of every block, junction anchor and the drive's
    /// far end at t = 0 (m).
    pub position: f64,
}

/// A scenario error: every problem found, each naming key, value, range and line.
#[derive(Debug, thiserror::Error)]
#[error("invalid scenario {source_name}:\n  - {}", .problems.join("\n  - "))]
pub struct ScenarioError {
    pub source_name: String,
    pub problems: Vec<String>,
}

/// The largest scenario file read (bytes); the shipped ones are ~3 KB.
pub const MAX_SCENARIO_BYTES: u64 = 1 << 20;

impl Scenario {
    /// The built-in default scene.
    pub fn default_scene() -> Scenario {
        Scenario::parse(DEFAULT_SCENARIO, DEFAULT_SCENARIO_NAME, &[])
            .expect("built-in scenario is valid")
    }

    /// Reads a scenario file, applies `--set` overrides and validates it.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Scenario, ScenarioError> {
        let name = path.display().to_string();
        let fail = |why: String| ScenarioError {
            source_name: name.clone(),
            problems: vec![format!("cannot read scenario file `{name}`: {why}")],
        };
        // A regular file of bounded size, checked before reading: not a
        // device (/dev/zero) or a multi-gigabyte file.
        let meta = std::fs::metadata(path).map_err(|e| fail(e.to_string()))?;
        if !meta.is_file() {
            return Err(fail("not a regular file".into()));
        }
        if meta.len() > MAX_SCENARIO_BYTES {
            return Err(fail(format!(
                "{} bytes, more than a scenario can be ({MAX_SCENARIO_BYTES} bytes)",
                meta.len()
            )));
        }
        let mut text = String::new();
        use std::io::Read;
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_SCENARIO_BYTES + 1).read_to_string(&mut text))
            .map_err(|e| fail(e.to_string()))?;
        Scenario::parse(&text, &name, overrides)
    }

    /// Parses TOML text, applies `key.path=value` overrides and validates.
    pub fn parse(
        text: &str,
        source_name: &str,
        overrides: &[String],
    ) -> Result<Scenario, ScenarioError> {
        let fail = |problems: Vec<String>| ScenarioError {
            source_name: source_name.to_string(),
            problems,
        };
        if looks_like_single_block(text) {
            return Err(fail(vec![format!(
                "this is a single-block scene (it has [law] and [motion], no [geometry]); \
                 run it with `slipfront single-block {source_name}`"
            )]));
        }
        let scenario: Scenario = if overrides.is_empty() {
            toml::from_str(text).map_err(|e| fail(vec![describe_toml_error(&e)]))?
        } else {
            let mut table: toml::Table = toml::from_str(text)
                .map_err(|e: toml::de::Error| fail(vec![describe_toml_error(&e)]))?;
            for item in overrides {
                apply_override(&mut table, item).map_err(|p| fail(vec![p]))?;
                // time.dt and time.dt_fraction are alternatives: setting one drops the other.
                let key = item.split_once('=').map_or("", |(k, _)| k.trim());
                let other = match key {
                    "time.dt" => Some("dt_fraction"),
                    "time.dt_fraction" => Some("dt"),
                    _ => None,
                };
                if let (Some(other), Some(toml::Value::Table(t))) = (other, table.get_mut("time")) {
                    t.remove(other);
                }
            }
            Scenario::deserialize(table).map_err(|e| {
                fail(vec![format!(
                    "{} (after --set {})",
                    e.message(),
                    overrides.join(", --set ")
                )])
            })?
        };
        let overridden: Vec<&str> = overrides
            .iter()
            .map(|o| o.split_once('=').map_or(o.as_str(), |(k, _)| k).trim())
            .collect();
        let problems = validate(&scenario, text, &overridden);
        if problems.is_empty() {
            Ok(scenario)
        } else {
            Err(fail(problems))
        }
    }

    /// TOML text of this scenario (the canonical form stored with outputs).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("scenario serialises")
    }
}

/// True for a single-block scene file (`slipfront single-block`): top-level
/// `[law]` and `[motion]` tables and no `[geometry]`.
pub fn looks_like_single_block(text: &str) -> bool {
    toml::from_str::<toml::Table>(text).is_ok_and(|t| {
        t.get("law").is_some_and(toml::Value::is_table)
            && t.get("motion").is_some_and(toml::Value::is_table)
            && !t.contains_key("geometry")
    })
}

fn describe_toml_error(e: &toml::de::Error) -> String {
    // toml's Display already carries "line N, column M" and a snippet; a
    // snippet of a very long line is cut, so an error stays readable.
    const WIDTH: usize = 160;
    e.to_string()
        .trim_end()
        .lines()
        .map(|l| {
            if l.chars().count() > WIDTH {
                format!("{}…", l.chars().take(WIDTH).collect::<String>())
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n    ")
}
