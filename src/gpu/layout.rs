//! Host-side mirrors of the uniform structs in `shaders/common.wgsl`.

use crate::real::{Coordinate, DoubleSingle};
use crate::step_params::{Consts, StepParams};
use bytemuck::{Pod, Zeroable};

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuConsts {
    pub nx: u32,
    pub nz: u32,
    pub junction_count: u32,
    pub seed: u32,
    pub spacing: f32,
    pub k: f32,
    pub eta: f32,
    pub k_foundation: f32,
    pub mass: f32,
    pub inv_mass: f32,
    pub dt: f32,
    pub mu_s: f32,
    pub mu_d: f32,
    pub junction_stiffness_value: f32,
    pub slip_mean_steps: f32,
    pub slip_std_steps: f32,
    pub drive_stiffness: f32,
    pub speed_limit: f32,
    pub top_share_full: f32,
    pub top_share_edge: f32,
    pub stiffness_normal_load: u32,
    pub n_blocks: u32,
    /// 1.0, read at run time: guards the double-single sums against
    /// reassociation (shaders/double_single.wgsl).
    pub one: f32,
    pub _pad: u32,
}

impl GpuConsts {
    pub fn new(c: &Consts<f32>, speed_limit: f32) -> Self {
        use crate::cpu::bulk_forces::top_share;
        GpuConsts {
            nx: c.nx as u32,
            nz: c.nz as u32,
            junction_count: c.junction_count as u32,
            seed: c.seed,
            spacing: c.spacing,
            k: c.k,
            eta: c.eta,
            k_foundation: c.k_foundation,
            mass: c.mass,
            inv_mass: c.inv_mass,
            dt: c.dt,
            mu_s: c.mu_s,
            mu_d: c.mu_d,
            junction_stiffness_value: c.junction_stiffness_value,
            slip_mean_steps: c.slip_mean_steps,
            slip_std_steps: c.slip_std_steps,
            drive_stiffness: c.drive_stiffness,
            speed_limit,
            // Column 1 is interior whenever a full share is used (nx > 2).
            top_share_full: top_share(c, 1),
            top_share_edge: top_share(c, 0),
            stiffness_normal_load: c.junction_stiffness_normal_load as u32,
            n_blocks: (c.nx * c.nz) as u32,
            one: 1.0,
            _pad: 0,
        }
    }
}

/// One step's loads, at a 256-byte stride in a dynamically offset storage buffer.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuStep {
    pub preparing: u32,
    pub normal_total: f32,
    pub top_tangential_total: f32,
    pub relax_eta: f32,
    pub top_velocity: f32,
    pub drive_target: DoubleSingle,
    pub _pad: u32,
}

impl GpuStep {
    /// The loads of `p`, with the drive target origin + V·t formed in f64
    /// and split into a double-single pair, as the CPU engine does.
    pub fn new(p: &StepParams<f32>, drive_origin: DoubleSingle) -> Self {
        GpuStep {
            preparing: p.preparing as u32,
            normal_total: p.normal_total,
            top_tangential_total: p.top_tangential_total,
            relax_eta: p.relax_eta,
            top_velocity: p.top_velocity,
            drive_target: DoubleSingle::from_f64(drive_origin.as_f64() + p.drive_offset),
            _pad: 0,
        }
    }
}

/// A junction's spring as the WGSL `JunctionSpring` (anchor hi, anchor lo,
/// stiffness): the bytes of the CPU twin's `JunctionSpring<DoubleSingle, f32>`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GpuJunctionSpring {
    pub anchor: DoubleSingle,
    pub stiffness: f32,
}

impl From<GpuJunctionSpring> for crate::cpu::JunctionSpring<DoubleSingle, f32> {
    fn from(s: GpuJunctionSpring) -> Self {
        crate::cpu::JunctionSpring {
            anchor: s.anchor,
            stiffness: s.stiffness,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::{Scenario, DEFAULT_SCENARIO};
    use crate::step_params::step_params;

    /// After 1e8 steps (22 s of driving) the drive target the GPU gets is
    /// still origin + V·t to f64 round-off (a plain f32 would be ~1e-10 m
    /// off, a whole creep step), and no field of the loads depends on a
    /// 32-bit step count.
    #[test]
    fn loads_after_1e8_steps_keep_the_drive_position_exact() {
        let s = Scenario::parse(DEFAULT_SCENARIO, "test", &[]).unwrap();
        let m = crate::Model::from_scenario(&s, false).unwrap();
        let c = Consts::<f32>::new(&m);
        let origin = DoubleSingle::from_f64(1.234_567e-5);
        for step in [m.prep_steps + 100_000_000, m.prep_steps + (1 << 32) + 7] {
            let loads = GpuStep::new(&step_params(&c, step), origin);
            let t = m.time_of_step(step);
            let exact = origin.as_f64() + 4.0e-4 * t;
            let got = loads.drive_target.as_f64();
            assert!((got - exact).abs() <= exact * 1e-13, "{got} vs {exact}");
            assert!(((exact as f32) as f64 - exact).abs() > 1e-12);
        }
    }
}
