//! WGSL sources, composed per phase (common + double-single + rng + phase file), and the
//! variant a scene needs: which pipelines exist and their override constants.

use crate::model::{Driver, Model};
use crate::scenario::{DampingForm, FrictionLaw};

pub const COMMON: &str = include_str!("../../shaders/common.wgsl");
pub const DOUBLE_SINGLE: &str = include_str!("../../shaders/double_single.wgsl");
pub const RNG: &str = include_str!("../../shaders/rng.wgsl");
pub const BULK_FORCES: &str = include_str!("../../shaders/bulk_forces.wgsl");
pub const JUNCTIONS: &str = include_str!("../../shaders/junctions.wgsl");
pub const COULOMB: &str = include_str!("../../shaders/coulomb.wgsl");
pub const VERLET: &str = include_str!("../../shaders/verlet.wgsl");

/// A compute phase: its entry point (the CPU twin's name) and source.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    BulkForces,
    Junctions,
    Coulomb,
    Verlet,
}

impl Phase {
    pub const ALL: [Phase; 4] = [
        Phase::BulkForces,
        Phase::Junctions,
        Phase::Coulomb,
        Phase::Verlet,
    ];

    pub fn entry_point(self) -> &'static str {
        match self {
            Phase::BulkForces => "bulk_forces",
            Phase::Junctions => "junctions",
            Phase::Coulomb => "coulomb",
            Phase::Verlet => "verlet",
        }
    }

    /// The full WGSL module of this phase.
    pub fn source(self) -> String {
        let body = match self {
            Phase::BulkForces => BULK_FORCES,
            Phase::Junctions => JUNCTIONS,
            Phase::Coulomb => COULOMB,
            Phase::Verlet => VERLET,
        };
        let rng = if self == Phase::Junctions { RNG } else { "" };
        format!("{COMMON}\n{DOUBLE_SINGLE}\n{rng}\n{body}")
    }
}

/// The pipelines a scene builds, in dispatch order, with their constants.
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    pub phases: Vec<(Phase, Vec<(&'static str, f64)>)>,
}

impl Variant {
    pub fn for_model(m: &Model) -> Variant {
        let damping = if m.eta == 0.0 || m.n_blocks() == 1 {
            0.0
        } else {
            match m.damping_form {
                DampingForm::Full => 1.0,
                DampingForm::Bond => 2.0,
            }
        };
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        let top_loads = m.normal_force != 0.0
            || m.trigger.is_some()
            || matches!(m.driver, Driver::TopForce { .. });
        let mut phases = vec![(
            Phase::BulkForces,
            vec![
                ("DAMPING_FORM", damping),
                ("USE_FOUNDATION", flag(m.k_foundation > 0.0)),
                ("USE_TOP_LOADS", flag(top_loads)),
                (
                    "USE_SIDE_SPRING",
                    flag(matches!(m.driver, Driver::SideSpring { .. })),
                ),
                (
                    "USE_RELAXATION",
                    flag(m.relax_eta > 0.0 && m.prep_steps > m.ramp_steps),
                ),
            ],
        )];
        match m.law {
            FrictionLaw::Junctions | FrictionLaw::SingleJunction => {
                phases.push((Phase::Junctions, vec![]))
            }
            FrictionLaw::Coulomb => phases.push((Phase::Coulomb, vec![])),
            FrictionLaw::None => {}
        }
        phases.push((
            Phase::Verlet,
            vec![("USE_FRICTION", flag(m.law != FrictionLaw::None))],
        ));
        Variant { phases }
    }

    /// One line per pipeline: `entry(CONST=value, ...)`.
    pub fn describe(&self) -> String {
        self.phases
            .iter()
            .map(|(p, c)| {
                let consts: Vec<String> = c.iter().map(|(k, v)| format!("{k}={v}")).collect();
                format!("{}({})", p.entry_point(), consts.join(","))
            })
            .collect::<Vec<_>>()
            .join(" -> ")
    }
}

/// Parses and validates a phase's module with naga (no adapter needed).
pub fn validate_phase(phase: Phase) -> Result<naga::Module, String> {
    let src = phase.source();
    let module = naga::front::wgsl::parse_str(&src)
        .map_err(|e| format!("{}: {}", phase.entry_point(), e.emit_to_string(&src)))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .map_err(|e| format!("{}: {}", phase.entry_point(), e.emit_to_string(&src)))?;
    if !module
        .entry_points
        .iter()
        .any(|e| e.name == phase.entry_point())
    {
        return Err(format!("{}: entry point missing", phase.entry_point()));
    }
    Ok(module)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shader_parses_and_validates_with_naga() {
        for phase in Phase::ALL {
            validate_phase(phase).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}
