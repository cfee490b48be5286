//! WGSL sources, composed per kernel (the generated prelude of
//! `layout.rs`, the shared snippets, the scene snippet (one scene, or an
//! ensemble of scenes), the state bindings of the kernel and its entry
//! file), and the variant a scene needs: which kernel runs and its
//! override constants. Every module is generated in either precision
//! (`GpuReal`: mixed f32 or f64) from the same files: only the prelude's
//! type aliases and the coordinate functions differ.

use super::precision::GpuReal;
use crate::model::scenario::{DampingForm, FrictionLaw};
use crate::model::{Driver, Model};

pub const COMMON: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/common.wgsl"));
pub const SCENE_SINGLE: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/scene_single.wgsl"
));
pub const SCENE_ENSEMBLE: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/scene_ensemble.wgsl"
));
pub const RNG: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/rng.wgsl"));
pub const BULK_FORCES: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/bulk_forces.wgsl"
));
pub const JUNCTIONS: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/junctions.wgsl"
));
pub const COULOMB: &str =
    include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/coulomb.wgsl"));
pub const VERLET: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/verlet.wgsl"));
pub const STATE_ONE_STEP: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/state_one_step.wgsl"
));
pub const STATE_PERSISTENT: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/state_persistent.wgsl"
));
pub const STEP_FORCES: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/step_forces.wgsl"
));
pub const ONE_STEP: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/one_step.wgsl"
));
pub const ONE_STEP_LANES: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/one_step_lanes.wgsl"
));
pub const PERSISTENT: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/persistent.wgsl"
));
pub const RECORD: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/record.wgsl"));
pub const RECORD_BUFFERS: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/record_buffers.wgsl"
));
pub const RECORD_COMMON: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/shaders/record_common.wgsl"
));

/// The output kernels' module (`record_small`, `record_sample`,
/// `record_finish`): one
/// scene, no override constants.
pub fn record_source<T: GpuReal>() -> String {
    [
        super::layout::wgsl_prelude::<T>().as_str(),
        T::COORDINATES,
        SCENE_SINGLE,
        RECORD_BUFFERS,
        RECORD_COMMON,
        RECORD,
    ]
    .join("\n")
}

/// Parses and validates the output kernels' module with naga.
pub fn validate_record<T: GpuReal>() -> Result<naga::Module, String> {
    let src = record_source::<T>();
    let module = naga::front::wgsl::parse_str(&src)
        .map_err(|e| format!("record: {}", e.emit_to_string(&src)))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), T::CAPABILITIES)
        .validate(&module)
        .map_err(|e| format!("record: {}", e.emit_to_string(&src)))?;
    for name in ["record_small", "record_sample", "record_finish"] {
        if !module.entry_points.iter().any(|e| e.name == name) {
            return Err(format!("record: entry point {name} missing"));
        }
    }
    Ok(module)
}

/// A compute kernel: its entry point (the CPU twin's name) and source.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kernel {
    /// One step of any lattice per dispatch, ping-pong state buffers, one
    /// thread per block (no barrier: the software adapters' kernel).
    OneStep,
    /// The same with the junction lanes of each interface block in parallel
    /// (a workgroup per interface block).
    OneStepLanes,
    /// Many steps of a small lattice per dispatch, one workgroup.
    Persistent,
}

impl Kernel {
    pub const ALL: [Kernel; 3] = [Kernel::OneStep, Kernel::OneStepLanes, Kernel::Persistent];

    pub fn entry_point(self) -> &'static str {
        match self {
            Kernel::OneStep => "one_step",
            Kernel::OneStepLanes => "one_step_lanes",
            Kernel::Persistent => "persistent_steps",
        }
    }

    /// The full WGSL module of this kernel, for one scene or an ensemble
    /// (many scenes of one lattice shape per dispatch).
    pub fn source<T: GpuReal>(self, ensemble: bool) -> String {
        let (state, entry) = match self {
            Kernel::OneStep => (STATE_ONE_STEP, ONE_STEP),
            Kernel::OneStepLanes => (STATE_ONE_STEP, ONE_STEP_LANES),
            Kernel::Persistent => (STATE_PERSISTENT, PERSISTENT),
        };
        // The persistent kernel records output samples in its loop.
        let (step_forces, record_buffers, record_common) = if self == Kernel::Persistent {
            ("", RECORD_BUFFERS, RECORD_COMMON)
        } else {
            (STEP_FORCES, "", "")
        };
        let prelude = super::layout::wgsl_prelude::<T>();
        [
            prelude.as_str(),
            COMMON,
            if ensemble {
                SCENE_ENSEMBLE
            } else {
                SCENE_SINGLE
            },
            state,
            T::COORDINATES,
            RNG,
            BULK_FORCES,
            JUNCTIONS,
            COULOMB,
            VERLET,
            step_forces,
            record_buffers,
            record_common,
            entry,
        ]
        .join("\n")
    }
}

/// The override constants of a scene: terms it does not use are compiled out.
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    pub constants: Vec<(&'static str, f64)>,
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
        let law = match m.law {
            FrictionLaw::None => 0.0,
            FrictionLaw::Junctions | FrictionLaw::SingleJunction => 1.0,
            FrictionLaw::Coulomb => 2.0,
        };
        Variant {
            constants: vec![
                ("FRICTION_LAW", law),
                ("DAMPING_FORM", damping),
                ("USE_FOUNDATION", flag(m.k_foundation > 0.0)),
                ("USE_TOP_LOADS", flag(top_loads)),
                (
                    "USE_SIDE_SPRING",
                    flag(matches!(m.driver, Driver::SideSpring { .. })),
                ),
                (
                    "USE_RELAXATION",
                    flag(
                        (m.relax_eta > 0.0 && m.prep_steps > m.ramp_steps) || m.absolute_eta > 0.0,
                    ),
                ),
                ("USE_PRESTRESS", flag(m.prestress.is_some())),
            ],
        }
    }

    /// `CONST=value, ...`.
    pub fn describe(&self) -> String {
        self.constants
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(",")
    }
}

/// Parses and validates a kernel's module with naga (no adapter needed).
pub fn validate_kernel<T: GpuReal>(phase: Kernel, ensemble: bool) -> Result<naga::Module, String> {
    let src = phase.source::<T>(ensemble);
    let module = naga::front::wgsl::parse_str(&src)
        .map_err(|e| format!("{}: {}", phase.entry_point(), e.emit_to_string(&src)))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), T::CAPABILITIES)
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

    fn validate_all<T: GpuReal>() {
        for kernel in Kernel::ALL {
            for ensemble in [false, true] {
                validate_kernel::<T>(kernel, ensemble)
                    .unwrap_or_else(|e| panic!("{}: {e}", T::NAME));
            }
        }
        validate_record::<T>().unwrap_or_else(|e| panic!("{}: {e}", T::NAME));
    }

    #[test]
    fn every_shader_parses_and_validates_with_naga() {
        validate_all::<f32>();
    }

    #[test]
    fn every_shader_validates_in_f64_too() {
        validate_all::<f64>();
    }

    /// The f64 kernels need the FLOAT64 capability, so the test above
    /// validates f64 code (the mixed ones validate without it).
    #[test]
    fn f64_kernels_need_the_float64_capability() {
        let one_step = |caps| {
            let src = Kernel::OneStep.source::<f64>(false);
            let module = naga::front::wgsl::parse_str(&src).unwrap();
            naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
                .validate(&module)
                .is_ok()
        };
        assert!(!one_step(naga::valid::Capabilities::empty()));
        assert!(one_step(naga::valid::Capabilities::FLOAT64));
    }
}
