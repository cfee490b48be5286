//! Dieterich–Ruina rate-and-state friction, one law per interface block:
//! its scenario table `[friction.rate_state]`, validation, constants and
//! state. The CPU twin of `shaders/laws/rate_state.wgsl` is `twin.rs`.
//!
//! μ(V, θ) = a·asinh(V/(2V0)·e^(ψ/a)), ψ = μ0 + b·ln(V0·θ/Dc): the
//! regularised form (Rice & Ben-Zion; Lapusta et al. 2000), equal to
//! μ0 + a·ln(V/V0) + b·ln(V0·θ/Dc) to within e^(−2ψ/a) once V ≫ V0·e^(−ψ/a),
//! and finite (0) at rest. The state θ (s) evolves by the aging law
//! dθ/dt = 1 − Vθ/Dc or the slip law dθ/dt = −(Vθ/Dc)·ln(Vθ/Dc); at steady
//! state θ = Dc/V and μ_ss = μ0 + (a − b)·ln(V/V0).

mod twin;

pub use twin::{
    evolve_state, friction_coefficient, rate_state, solve_friction_level, state_increment,
};

use super::{Law, TableChecks};
use serde::{Deserialize, Serialize};

pub const LAW: Law = Law {
    name: "rate_state",
    kernel: 3,
    kernel_constant: "LAW_RATE_STATE",
    block_state_words: 1,
    block_shader: Some((
        "rate_state",
        include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/shaders/laws/rate_state.wgsl"
        )),
        "rate_state",
    )),
    // The solve's iterations (at most twin::MAX_ITERATIONS, a few in
    // practice) with the f64 exp's and ln's scaling loops inside.
    block_loop_iterations: 10 * twin::MAX_ITERATIONS as usize,
};

/// How θ evolves.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum StateEvolution {
    /// dθ/dt = 1 − Vθ/Dc (Dieterich): contacts heal at rest.
    Aging,
    /// dθ/dt = −(Vθ/Dc)·ln(Vθ/Dc) (Ruina): no healing at rest.
    Slip,
}

/// `[friction.rate_state]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RateStateTable {
    /// a, the direct effect.
    pub direct_effect: f64,
    /// b, the evolution effect (a − b < 0: velocity weakening).
    pub evolution_effect: f64,
    /// μ0, the friction coefficient of steady sliding at V0.
    pub reference_coefficient: f64,
    /// V0 (m/s).
    pub reference_velocity: f64,
    /// Dc (m), the slip over which θ renews.
    pub characteristic_slip: f64,
    pub state_evolution: StateEvolution,
    /// θ of every block at t = 0 (s); steady sliding at V has θ = Dc/V.
    pub initial_state: f64,
    /// A block slides (its `slide` direction is set, and the stick → slip
    /// transition counts as a rupture) while |V| is at least this (m/s);
    /// default 1e-3.
    #[serde(default = "RateStateTable::default_slip_velocity")]
    pub slip_velocity: f64,
}

/// Number of constants (`constants`), in this order.
pub const CONSTANTS: usize = 7;
/// `state_evolution` as a constant.
pub const AGING: f64 = 0.0;
pub const SLIP: f64 = 1.0;

impl RateStateTable {
    fn default_slip_velocity() -> f64 {
        1e-3
    }

    /// (a, b, μ0, V0, Dc, evolution, slip velocity).
    pub fn constants(&self) -> [f64; CONSTANTS] {
        [
            self.direct_effect,
            self.evolution_effect,
            self.reference_coefficient,
            self.reference_velocity,
            self.characteristic_slip,
            match self.state_evolution {
                StateEvolution::Aging => AGING,
                StateEvolution::Slip => SLIP,
            },
            self.slip_velocity,
        ]
    }

    /// θ per block at t = 0.
    pub fn initial_state(&self) -> Vec<f64> {
        vec![self.initial_state]
    }

    pub fn validate(&self, c: &mut dyn TableChecks) {
        let mut check = |key: &str, v: f64, lo: f64, hi: f64, open_lo: bool| {
            let ok = v.is_finite() && (if open_lo { v > lo } else { v >= lo }) && v <= hi;
            if !ok {
                let lo_sign = if open_lo { "<" } else { "<=" };
                let line = c.line(&format!("friction.rate_state.{key}"));
                c.problem(format!(
                    "friction.rate_state.{key} = {v} is out of range (allowed: {lo} {lo_sign} \
                     {key} <= {hi}){line}"
                ));
            }
        };
        check("direct_effect", self.direct_effect, 0.0, 1.0, true);
        check("evolution_effect", self.evolution_effect, 0.0, 1.0, false);
        check(
            "reference_coefficient",
            self.reference_coefficient,
            0.0,
            10.0,
            false,
        );
        check(
            "reference_velocity",
            self.reference_velocity,
            0.0,
            1e3,
            true,
        );
        check(
            "characteristic_slip",
            self.characteristic_slip,
            0.0,
            1.0,
            true,
        );
        check("initial_state", self.initial_state, 0.0, 1e12, true);
        check("slip_velocity", self.slip_velocity, 0.0, 1e3, true);
    }

    /// Steady-state friction μ_ss(V) = μ0 + (a − b)·ln(V/V0).
    pub fn steady_state_coefficient(&self, velocity: f64) -> f64 {
        self.reference_coefficient
            + (self.direct_effect - self.evolution_effect)
                * (velocity / self.reference_velocity).ln()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    pub fn table() -> RateStateTable {
        RateStateTable {
            direct_effect: 0.01,
            evolution_effect: 0.015,
            reference_coefficient: 0.6,
            reference_velocity: 1e-6,
            characteristic_slip: 1e-5,
            state_evolution: StateEvolution::Aging,
            initial_state: 10.0,
            slip_velocity: 1e-3,
        }
    }

    struct Problems(Vec<String>);

    impl TableChecks for Problems {
        fn line(&self, _: &str) -> String {
            String::new()
        }
        fn problem(&mut self, text: String) {
            self.0.push(text);
        }
        fn positive(&mut self, _: &str, _: f64) {}
        fn at_least(&mut self, _: &str, _: f64, _: f64) {}
        fn range_u(&mut self, _: &str, _: u32, _: u32, _: u32) {}
    }

    #[test]
    fn out_of_range_keys_are_named_with_their_range() {
        let mut t = table();
        t.direct_effect = 0.0;
        t.characteristic_slip = -1.0;
        let mut problems = Problems(Vec::new());
        t.validate(&mut problems);
        let problems = problems.0;
        assert_eq!(problems.len(), 2, "{problems:?}");
        assert!(problems[0].contains("friction.rate_state.direct_effect = 0"));
        assert!(problems[0].contains("allowed: 0 < direct_effect <= 1"));
        assert!(problems[1].contains("characteristic_slip = -1"));
        let mut none = Problems(Vec::new());
        table().validate(&mut none);
        assert!(none.0.is_empty(), "{:?}", none.0);
    }
}
