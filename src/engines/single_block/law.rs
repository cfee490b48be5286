//! The junction-law family of Publication 2 (Thøgersen et al., PRE 89,
//! 052401 (2014)): a junction is either pinned, its force set by its
//! stretch (k_j × stretch, breaking at the threshold f_s), or slipping, its
//! force set by the time since it broke, for a slip time drawn from a
//! distribution; then it re-pins with zero stretch. Forces are per
//! junction, in units of f_N/Ns (so a force of 0.4 is μ = 0.4).

use crate::model::rng::{draw_key, pcg_hash, standard_normal, unit_from_bits};
use serde::{Deserialize, Serialize};

/// The force of a slipping junction against the time τ since it broke.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(tag = "form", rename_all = "snake_case", deny_unknown_fields)]
pub enum SlipForce {
    /// μd for the whole slip (the law of the 2D model).
    Constant { level: f64 },
    /// from + (to − from)·e^(−τ/time): relaxes between two levels.
    Relaxing { from: f64, to: f64, time: f64 },
    /// from + (to − from)·min(τ/time, 1): a linear ramp, then flat.
    Ramp { from: f64, to: f64, time: f64 },
}

impl SlipForce {
    /// Force τ after rupture (units of f_N/Ns).
    pub fn at(&self, tau: f64) -> f64 {
        match *self {
            SlipForce::Constant { level } => level,
            SlipForce::Relaxing { from, to, time } => to + (from - to) * (-tau / time).exp(),
            SlipForce::Ramp { from, to, time } => from + (to - from) * (tau / time).min(1.0),
        }
    }

    /// ∫₀^T of the force, exactly.
    pub fn integral(&self, t: f64) -> f64 {
        match *self {
            SlipForce::Constant { level } => level * t,
            SlipForce::Relaxing { from, to, time } => {
                to * t + (from - to) * time * -(-t / time).exp_m1()
            }
            SlipForce::Ramp { from, to, time } => {
                let r = t.min(time);
                from * t + (to - from) * (r * r / (2.0 * time) + (t - r))
            }
        }
    }
}

/// The distribution of slip times (s).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(tag = "distribution", rename_all = "snake_case", deny_unknown_fields)]
pub enum SlipTime {
    Fixed {
        time: f64,
    },
    /// Normal, negative draws clipped to zero (as the 2D model).
    Gaussian {
        mean: f64,
        std: f64,
    },
    Exponential {
        mean: f64,
    },
}

impl SlipTime {
    /// The slip time of junction `j`'s `count`-th rupture.
    pub fn draw(&self, seed: u32, j: u32, count: u32) -> f64 {
        match *self {
            SlipTime::Fixed { time } => time,
            SlipTime::Gaussian { mean, std } => {
                (mean + std * standard_normal::<f64>(seed, 0, j, count)).max(0.0)
            }
            SlipTime::Exponential { mean } => {
                let u: f64 = unit_from_bits(pcg_hash(draw_key(seed, 1, j, count)));
                // u in [0, 1): 1 − u in (0, 1], so the log is finite.
                -mean * (1.0 - u).ln()
            }
        }
    }

    /// E[g(T)] for the distribution, by quadrature where there is no
    /// closed form (Gauss–Legendre on ±8σ for the Gaussian, clipped at 0;
    /// Laguerre-like substitution for the exponential).
    pub fn expect(&self, g: impl Fn(f64) -> f64) -> f64 {
        match *self {
            SlipTime::Fixed { time } => g(time),
            SlipTime::Gaussian { mean, std } => {
                if std == 0.0 {
                    return g(mean.max(0.0));
                }
                let lo = (mean - 8.0 * std).max(0.0);
                let hi = (mean + 8.0 * std).max(lo);
                let density = |t: f64| {
                    (-0.5 * ((t - mean) / std).powi(2)).exp()
                        / (std * (2.0 * std::f64::consts::PI).sqrt())
                };
                // Draws below zero are clipped to a zero slip time.
                let below = 0.5 * erfc_approx(mean / (std * std::f64::consts::SQRT_2));
                below * g(0.0) + integrate(|t| g(t) * density(t), lo, hi, 4000)
            }
            SlipTime::Exponential { mean } => {
                // t = −mean·ln(1 − u), u uniform on [0, 1).
                integrate(|u| g(-mean * (1.0 - u).ln()), 0.0, 1.0 - 1e-12, 20000)
            }
        }
    }

    pub fn mean(&self) -> f64 {
        self.expect(|t| t)
    }
}

/// Composite Simpson's rule with `n` (even) intervals.
fn integrate(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    if b <= a {
        return 0.0;
    }
    let n = n + n % 2;
    let h = (b - a) / n as f64;
    let mut s = f(a) + f(b);
    for i in 1..n {
        s += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// erfc(x), Numerical Recipes' Chebyshev fit (relative error < 1.2e-7).
fn erfc_approx(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// One junction law: threshold, stiffness, slipping force, slip times and
/// a drag on the slipping junctions proportional to the sliding speed.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct JunctionLaw {
    /// Break threshold f_s (units of f_N/Ns): μs.
    pub threshold: f64,
    /// Stretch (m) at which a junction pinned with zero stretch reaches the
    /// threshold: k_j = threshold / break_stretch.
    pub break_stretch: f64,
    pub slip_force: SlipForce,
    pub slip_time: SlipTime,
    /// Extra force on a slipping junction per unit sliding speed (units of
    /// f_N/Ns per m/s); 0 for the purely time-controlled laws.
    #[serde(default)]
    pub drag: f64,
}

impl JunctionLaw {
    /// Steady-state friction coefficient at constant sliding speed `v`,
    /// by the renewal argument: every junction repeats the cycle "pinned
    /// from zero stretch until the threshold (time t_a = s_b/v, mean force
    /// f_s/2), then slipping for a drawn time", independently of the
    /// others; the time average of the force over many cycles is the
    /// expected force-time integral of one cycle over its expected length.
    pub fn steady_friction(&self, v: f64) -> f64 {
        let pinned_time = self.break_stretch / v;
        let slip_mean = self.slip_time.mean();
        let slipping =
            self.slip_time.expect(|t| self.slip_force.integral(t)) + self.drag * v * slip_mean;
        (0.5 * self.threshold * pinned_time + slipping) / (pinned_time + slip_mean)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slip_force_integrals_match_quadrature() {
        let forms = [
            SlipForce::Constant { level: 0.17 },
            SlipForce::Relaxing {
                from: 0.4,
                to: 0.1,
                time: 1e-3,
            },
            SlipForce::Ramp {
                from: 0.0,
                to: 0.3,
                time: 2e-3,
            },
        ];
        for f in forms {
            for t in [0.0, 5e-4, 3e-3] {
                let q = integrate(|s| f.at(s), 0.0, t, 2000);
                assert!((f.integral(t) - q).abs() < 1e-9, "{f:?} {t}");
            }
        }
    }

    #[test]
    fn slip_time_expectations_match_their_closed_forms_and_draws() {
        let g = SlipTime::Gaussian {
            mean: 2e-3,
            std: 2e-4,
        };
        assert!((g.mean() - 2e-3).abs() < 1e-9);
        let e = SlipTime::Exponential { mean: 1e-3 };
        assert!((e.mean() - 1e-3).abs() < 1e-6, "{}", e.mean());
        // E[e^(−T/τ)] = 1/(1 + mean/τ) for the exponential.
        let m = e.expect(|t| (-t / 5e-4).exp());
        assert!((m - 1.0 / 3.0).abs() < 1e-4, "{m}");
        // Sample means of the draws.
        for d in [g, e] {
            let n = 20000;
            let mean = (0..n).map(|j| d.draw(7, j, 1)).sum::<f64>() / n as f64;
            assert!((mean - d.mean()).abs() < 0.03 * d.mean(), "{d:?}: {mean}");
        }
    }

    #[test]
    fn steady_friction_runs_between_half_the_threshold_and_the_mean_slipping_force() {
        let law = JunctionLaw {
            threshold: 0.4,
            break_stretch: 1e-6,
            slip_force: SlipForce::Constant { level: 0.17 },
            slip_time: SlipTime::Fixed { time: 1e-3 },
            drag: 0.0,
        };
        assert!((law.steady_friction(1e-9) - 0.2).abs() < 1e-3);
        assert!((law.steady_friction(1e3) - 0.17).abs() < 1e-3);
    }
}
