//! The loads of one step, a pure function of the model and the integer step
//! count (time is never a running sum). `shaders/common.wgsl::step_params`
//! computes the same in f32 on the GPU.

use crate::model::real::{Coordinate, Real};
use crate::model::{Driver, Model};

/// While driving, the drive target is anchored at every this many steps of
/// driving: a step's target is the anchor's, origin + V·t rounded once to
/// a coordinate, plus i·hi and i·lo (V·dt split, `split_drive_step`) for
/// the i < 4096 steps since (`drive_target`). Every engine computes it so,
/// the GPU kernels in `shaders/common.wgsl` `loads_at`, and the GPU's
/// batches never cross an anchor, so where a run is cut into batches
/// (output samples, snapshots, chunks sized by wall time) changes no bit.
/// At most 4096: i · hi must stay exact.
pub const DRIVE_ANCHOR_STEPS: u64 = 4096;

/// The anchor of `step` (the step itself while preparing).
pub fn drive_anchor<T: Real>(c: &Consts<T>, step: u64) -> u64 {
    if step < c.prep_steps {
        step
    } else {
        c.prep_steps + (step - c.prep_steps) / DRIVE_ANCHOR_STEPS * DRIVE_ANCHOR_STEPS
    }
}

/// V·dt split as hi + lo with hi on 12 significant bits.
pub fn split_drive_step<T: Real>(v_dt: f64) -> (T, T) {
    if v_dt == 0.0 {
        return (T::zero(), T::zero());
    }
    let scale = 2f64.powi(11 - v_dt.abs().log2().floor() as i32);
    let hi = (v_dt * scale).round() / scale;
    (T::from_f64(hi), T::from_f64(v_dt - hi))
}

/// Where the side spring's far end is at `step` (while driving): the
/// anchor's target, origin + V·t in f64 rounded to a coordinate, then
/// i·hi and i·lo added as the kernels add them (`DRIVE_ANCHOR_STEPS`).
/// Within an ulp or two of origin + V·t; what matters is that the CPU
/// engines and the GPU kernels take the same one, so that they can agree
/// bit for bit (session 67: rounding origin + V·t once at every step, the
/// CPU's target parted from the kernels' by an ulp after 320,000 driving
/// steps of Table S1). While preparing the drive is idle: the origin.
pub fn drive_target<T: Real, C: Coordinate<T>>(c: &Consts<T>, origin: C, step: u64) -> C {
    if step < c.prep_steps {
        return origin;
    }
    let anchor = drive_anchor(c, step);
    let i = T::from_f64((step - anchor) as f64);
    drive_target_at_anchor(c, origin, anchor)
        .add(i * c.drive_step_hi)
        .add(i * c.drive_step_lo)
}

/// The drive target at `anchor` (a `drive_anchor`): origin + V·t there,
/// in f64, rounded once to a coordinate (what a GPU batch carries).
pub fn drive_target_at_anchor<T: Real, C: Coordinate<T>>(
    c: &Consts<T>,
    origin: C,
    anchor: u64,
) -> C {
    C::from_f64(origin.as_f64() + step_params(c, anchor).drive_offset)
}

/// Constants of a run in the engine's precision.
#[derive(Debug, Clone, Copy)]
pub struct Consts<T> {
    pub nx: usize,
    pub nz: usize,
    pub spacing: T,
    pub k: T,
    pub k_diag: T,
    pub eta: T,
    pub bond_damping: bool,
    pub k_foundation: T,
    pub mass: T,
    pub inv_mass: T,
    pub dt: T,
    pub mu_s: T,
    pub mu_d: T,
    /// The friction law's constants (`Model::law_constants`).
    pub law: [T; crate::model::friction::LAW_CONSTANTS],
    pub junction_count: usize,
    pub junction_stiffness_normal_load: bool,
    pub junction_stiffness_value: T,
    pub slip_mean_steps: T,
    pub slip_std_steps: T,
    pub seed: u32,
    pub normal_force: T,
    /// Slope of the linear normal-load profile (`laws::normal_profile`).
    pub normal_slope: T,
    pub ramp_steps: u64,
    /// 1/ramp_steps, so the ramp is a product (exact alike on CPU and GPU).
    pub inv_ramp_steps: T,
    pub prep_steps: u64,
    pub relax_eta: T,
    /// Absolute-velocity damping once driving starts (kg/s).
    pub absolute_eta: T,
    /// Prestress totals (ratio × F_N) outside and inside the trigger strip;
    /// column ix takes its top share of one of them (`Model::interface_shear`).
    pub interface_shear_force: T,
    pub strip_shear_force: T,
    pub strip_blocks: usize,
    pub drive_stiffness: T,
    pub drive_velocity: T,
    pub top_force_rate: T,
    pub top_prestress_force: T,
    /// V and dt in f64: the drive position is a coordinate, kept exact (see
    /// `crate::model::real::Coordinate`), whatever the engine computes in.
    pub drive_velocity_exact: f64,
    pub dt_exact: f64,
    /// V·dt split as hi + lo (`split_drive_step`): what every engine adds
    /// a step to the anchor's drive target.
    pub drive_step_hi: T,
    pub drive_step_lo: T,
    /// Quantities held in f32 by the precision study's instrument
    /// (`crate::engines::precision_probe`); 0 in every ordinary run.
    pub f32_probe: u32,
}

impl<T: Real> Consts<T> {
    pub fn new(m: &Model) -> Self {
        let f32_probe = crate::engines::precision_probe::from_environment().unwrap_or(0);
        let c = |v: f64| {
            let held = std::mem::size_of::<T>() == 8
                && f32_probe & crate::engines::precision_probe::CONSTANTS != 0;
            T::from_f64(if held { v as f32 as f64 } else { v })
        };
        let (drive_stiffness, drive_velocity, top_force_rate) = match m.driver {
            Driver::None => (0.0, 0.0, 0.0),
            Driver::SideSpring {
                stiffness,
                velocity,
                ..
            } => (stiffness, velocity, 0.0),
            Driver::TopForce { rate } => (0.0, 0.0, rate),
            Driver::TopVelocity { velocity } => (0.0, velocity, 0.0),
        };
        let j = m.junctions;
        let (drive_step_hi, drive_step_lo) = split_drive_step::<T>(drive_velocity * m.dt);
        Consts {
            nx: m.nx,
            nz: m.nz,
            spacing: c(m.spacing),
            k: c(m.k),
            k_diag: c(m.k_diag),
            eta: c(m.eta),
            bond_damping: m.damping_form == crate::model::scenario::DampingForm::Bond,
            k_foundation: c(m.k_foundation),
            mass: c(m.mass),
            inv_mass: c(1.0 / m.mass),
            dt: c(m.dt),
            mu_s: c(m.mu_s),
            mu_d: c(m.mu_d),
            law: m.law_constants().map(c),
            junction_count: j.map_or(0, |j| j.count),
            junction_stiffness_normal_load: j.is_some_and(|j| {
                j.stiffness == crate::model::scenario::JunctionStiffness::NormalLoad
            }),
            junction_stiffness_value: c(j.map_or(0.0, |j| j.stiffness_value)),
            slip_mean_steps: c(j.map_or(0.0, |j| j.slip_time_mean / m.dt)),
            slip_std_steps: c(j.map_or(0.0, |j| j.slip_time_std / m.dt)),
            seed: m.seed,
            normal_force: c(m.normal_force),
            normal_slope: c(m.normal_slope),
            ramp_steps: m.ramp_steps,
            inv_ramp_steps: c(1.0 / m.ramp_steps.max(1) as f64),
            prep_steps: m.prep_steps,
            relax_eta: c(m.relax_eta),
            absolute_eta: c(m.absolute_eta),
            interface_shear_force: c(m.prestress.map_or(0.0, |p| p.ratio * m.normal_force)),
            strip_shear_force: c(m.prestress.map_or(0.0, |p| p.strip_ratio * m.normal_force)),
            strip_blocks: m.prestress.map_or(0, |p| p.strip_blocks),
            drive_stiffness: c(drive_stiffness),
            drive_velocity: c(drive_velocity),
            top_force_rate: c(top_force_rate),
            top_prestress_force: c(m
                .trigger
                .map_or(0.0, |t| t.shear_prestress * m.normal_force)),
            drive_velocity_exact: drive_velocity,
            dt_exact: m.dt,
            drive_step_hi,
            drive_step_lo,
            f32_probe,
        }
    }

    /// Junction stiffness for a junction attached under normal force `f_n`.
    #[inline]
    pub fn junction_stiffness(&self, f_n: T) -> T {
        if self.junction_stiffness_normal_load {
            (self.junction_stiffness_value * f_n).sqrt()
        } else {
            self.junction_stiffness_value
        }
    }
}

/// Loads of one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepParams<T> {
    pub step: u64,
    /// True in the normal-load phase: junctions cannot break.
    pub preparing: bool,
    /// Total normal load on the top row (N).
    pub normal_total: T,
    /// Total tangential force on the top row (N).
    pub top_tangential_total: T,
    /// Absolute-velocity damping (kg/s): the relaxation's while relaxing,
    /// the scene's absolute viscosity once driving.
    pub absolute_eta: T,
    /// Prestress totals on the interface (0 before driving starts).
    pub interface_shear_total: T,
    pub strip_shear_total: T,
    /// Displacement the side spring's far end has been pulled, V·t (m), in
    /// f64: engines add it to the drive origin as a coordinate.
    pub drive_offset: f64,
    /// Prescribed top-row velocity (m/s).
    pub top_velocity: T,
}

/// The loads at global step `step`.
pub fn step_params<T: Real>(c: &Consts<T>, step: u64) -> StepParams<T> {
    let preparing = step < c.prep_steps;
    let ramp = if c.ramp_steps == 0 || step >= c.ramp_steps {
        T::one()
    } else {
        T::from_f64(step as f64) * c.inv_ramp_steps
    };
    let drive_time = if preparing {
        T::zero()
    } else {
        T::from_f64((step - c.prep_steps) as f64) * c.dt
    };
    StepParams {
        step,
        preparing,
        normal_total: c.normal_force * ramp,
        top_tangential_total: c.top_prestress_force * ramp + c.top_force_rate * drive_time,
        absolute_eta: if !preparing {
            c.absolute_eta
        } else if step >= c.ramp_steps {
            c.relax_eta
        } else {
            T::zero()
        },
        interface_shear_total: if preparing {
            T::zero()
        } else {
            c.interface_shear_force
        },
        strip_shear_total: if preparing {
            T::zero()
        } else {
            c.strip_shear_force
        },
        drive_offset: if preparing {
            0.0
        } else {
            c.drive_velocity_exact * ((step - c.prep_steps) as f64 * c.dt_exact)
        },
        top_velocity: if preparing {
            T::zero()
        } else {
            c.drive_velocity
        },
    }
}
