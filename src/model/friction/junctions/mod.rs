//! The micro-junction laws (`junctions`, and `single_junction`: one
//! junction per block): their scenario table `[friction.junctions]` and its
//! validation, the parameters the engines use (`JunctionModel`), and the
//! break threshold every path computes the same way (the kernels' twin and
//! the quasi-static fast-forward).
//!
//! Each interface block holds Ns junctions, each pinned (a spring to its
//! anchor, breaking at μs·f_N with f_N = p/Ns) or slipping (μd·f_N against
//! the motion for a drawn slip time), computed in parallel lanes: their
//! state is the junction arrays every engine keeps (anchors, stiffnesses,
//! slip countdowns, rupture counts), and their step is the lane kernel
//! `shaders/junctions.wgsl` with its CPU twin
//! `src/engines/kernels/junctions.rs`, which the engines call directly
//! (lane-parallel, unlike a per-block law's one call per block).

use super::{FrictionLaw, Law, TableChecks};
use crate::model::real::Real;
use serde::{Deserialize, Serialize};

/// `junctions`: Ns micro-junctions per interface block.
pub const LAW: Law = Law {
    name: "junctions",
    kernel: 1,
    kernel_constant: "LAW_JUNCTIONS",
    block_state_words: 0,
    block_shader: None,
    block_loop_iterations: 0,
};

/// `single_junction`: the junction kernel with one junction per block.
pub const SINGLE_JUNCTION_LAW: Law = Law {
    name: "single_junction",
    ..LAW
};

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum JunctionStiffness {
    /// k_j = √(coefficient · f_N) at attachment.
    NormalLoad,
    /// k_j = constant_stiffness.
    Constant,
    /// k_j = stiffness_ratio · k, the interface/bulk stiffness ratio of the
    /// 1D front literature.
    BulkRatio,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Junctions {
    /// Ns, junctions per interface block.
    pub count: u32,
    pub stiffness: JunctionStiffness,
    /// N/m², for `normal_load` stiffness (placeholder 39.2e9).
    pub stiffness_coefficient: f64,
    /// N/m, for `constant` stiffness.
    pub constant_stiffness: f64,
    /// k_j / k, for `bulk_ratio` stiffness.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness_ratio: Option<f64>,
    /// ⟨t_R⟩ (s).
    pub slip_time_mean: f64,
    /// σ_R (s).
    pub slip_time_std: f64,
    /// What the slipping junctions of a block do when it is at rest
    /// (`SlipAtRest`; `hold` unless the scenario says otherwise).
    #[serde(default)]
    pub at_rest: SlipAtRest,
}

/// The force of a block's slipping junctions, μd·f_N each, when the block
/// is at rest or about to reverse.
///
/// The thesis writes it −μd·f_N·sign(v). That force vanishes only at v
/// exactly 0, so a block that should stay at rest is kicked by ±μd·f_N
/// every step and drifts at a speed set by dt (the dt-convergence study in
/// `results/slow_slip_dt.md` measures it). `hold` treats the slipping
/// junctions as the Coulomb law treats a stuck block: together they supply
/// any force up to n_slipping·μd·f_N that stops the block this step, and
/// push with that bound against the motion otherwise. While the block
/// moves on, both rules give the same force.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SlipAtRest {
    /// Up to n_slipping·μd·f_N of friction that brings the block to rest.
    #[default]
    Hold,
    /// −n_slipping·μd·f_N·sign(v): the thesis's rule, kept to compare.
    Sign,
}

impl SlipAtRest {
    /// Its code in the run constants (`c.law0`; `JUNCTION_HOLD` in WGSL).
    pub fn code(self) -> f64 {
        match self {
            SlipAtRest::Hold => JUNCTION_HOLD,
            SlipAtRest::Sign => 0.0,
        }
    }
}

/// `c.law0` of the junction laws when slipping junctions hold a block at
/// rest (`SlipAtRest::Hold`).
pub const JUNCTION_HOLD: f64 = 1.0;

/// The junction laws' constants: the at-rest rule's code.
pub fn constants(j: &Junctions) -> [f64; 1] {
    [j.at_rest.code()]
}

/// The friction of a block's slipping junctions, `capacity` =
/// n_slipping·μd·f_N: under `hold`, the force `stop` that brings the block
/// to rest, bounded by ±capacity; under `sign`, −capacity·sign(v). The
/// kernels' twin (`engines::kernels::junctions::junction_friction`) and
/// the quasi-static residual both call this.
#[inline]
pub fn slipping_friction<T: Real>(hold: bool, capacity: T, stop: T, velocity: T) -> T {
    if hold {
        stop.max(-capacity).min(capacity)
    } else {
        -capacity * velocity_sign(velocity)
    }
}

/// Sign of a block velocity, 0 when it is exactly zero.
#[inline]
pub fn velocity_sign<T: Real>(v: T) -> T {
    if v > T::zero() {
        T::one()
    } else if v < T::zero() {
        -T::one()
    } else {
        T::zero()
    }
}

/// Junction parameters resolved from the scenario.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JunctionModel {
    /// Ns per interface block.
    pub count: usize,
    pub stiffness: JunctionStiffness,
    /// N/m² for normal-load stiffness, N/m for constant.
    pub stiffness_value: f64,
    pub slip_time_mean: f64,
    pub slip_time_std: f64,
    pub at_rest: SlipAtRest,
}

impl JunctionModel {
    /// The parameters of a `[friction.junctions]` table on a lattice of
    /// bond stiffness `k` (N/m).
    pub fn from_table(j: &Junctions, k: f64) -> JunctionModel {
        JunctionModel {
            count: j.count as usize,
            // The engines know two kinds: a bulk ratio is a constant.
            stiffness: match j.stiffness {
                JunctionStiffness::BulkRatio => JunctionStiffness::Constant,
                other => other,
            },
            stiffness_value: match j.stiffness {
                JunctionStiffness::NormalLoad => j.stiffness_coefficient,
                JunctionStiffness::Constant => j.constant_stiffness,
                JunctionStiffness::BulkRatio => j.stiffness_ratio.unwrap_or(0.0) * k,
            },
            slip_time_mean: j.slip_time_mean,
            slip_time_std: j.slip_time_std,
            at_rest: j.at_rest,
        }
    }
}

/// The force at which a pinned junction breaks: μs·f_N, f_N its share of
/// the block's normal force. The kernels' twin (`junction_block`) and the
/// quasi-static path's thresholds both call this.
#[inline]
pub fn break_threshold<T: Real>(mu_s: T, f_n: T) -> T {
    mu_s * f_n
}

/// The table's problems for `law` (a junction law needs it, and a
/// single-junction law has exactly one junction).
pub fn validate(law: FrictionLaw, junctions: Option<&Junctions>, c: &mut dyn TableChecks) {
    match (law, junctions) {
        (FrictionLaw::Junctions | FrictionLaw::SingleJunction, None) => c.problem(format!(
            "missing table [friction.junctions], required by friction.law = \"{}\"",
            law.name()
        )),
        (FrictionLaw::Junctions | FrictionLaw::SingleJunction, Some(j)) => {
            if law == FrictionLaw::SingleJunction && j.count != 1 {
                let line = c.line("friction.junctions.count");
                c.problem(format!(
                    "friction.junctions.count = {} but friction.law = \"single_junction\" needs \
                     exactly 1 (allowed: 1){line}",
                    j.count
                ));
            } else {
                // f_N / Ns is formed in f32 on the GPU: every count up to
                // 2^24 is exact there.
                c.range_u("friction.junctions.count", j.count, 1, 1 << 24);
            }
            match j.stiffness {
                JunctionStiffness::NormalLoad => c.positive(
                    "friction.junctions.stiffness_coefficient",
                    j.stiffness_coefficient,
                ),
                JunctionStiffness::Constant => c.positive(
                    "friction.junctions.constant_stiffness",
                    j.constant_stiffness,
                ),
                JunctionStiffness::BulkRatio => match j.stiffness_ratio {
                    Some(r) => c.positive("friction.junctions.stiffness_ratio", r),
                    None => c.problem(
                        "missing key friction.junctions.stiffness_ratio, required by \
                         friction.junctions.stiffness = \"bulk_ratio\""
                            .into(),
                    ),
                },
            }
            if j.stiffness != JunctionStiffness::BulkRatio {
                if let Some(r) = j.stiffness_ratio {
                    let line = c.line("friction.junctions.stiffness_ratio");
                    c.problem(format!(
                        "friction.junctions.stiffness_ratio = {r} is used only with \
                         friction.junctions.stiffness = \"bulk_ratio\"{line}"
                    ));
                }
            }
            // Bounded above by the 32-bit slip countdown, in Model.
            c.at_least("friction.junctions.slip_time_mean", j.slip_time_mean, 0.0);
            c.at_least("friction.junctions.slip_time_std", j.slip_time_std, 0.0);
        }
        _ => {}
    }
}
