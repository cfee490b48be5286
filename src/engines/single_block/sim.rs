//! One interface block and its Ns junctions, moved along a prescribed slip
//! history or pulled through a spring; the junctions follow a
//! [`JunctionLaw`]. The friction is the mean junction force (units of
//! f_N/Ns, i.e. a friction coefficient).

use super::law::JunctionLaw;
use crate::model::friction::junctions::{slipping_friction, SlipAtRest};
use crate::model::rng::{draw_key, pcg_hash, unit_from_bits};

/// The junctions of one block.
#[derive(Debug, Clone)]
pub struct Junctions {
    pub law: JunctionLaw,
    seed: u32,
    /// Block position at which each junction is unstretched (pinned).
    anchor: Vec<f64>,
    /// Time each junction broke, NaN while pinned.
    broke_at: Vec<f64>,
    /// Time each slipping junction re-pins.
    repin_at: Vec<f64>,
    ruptures: Vec<u32>,
}

/// Stream of the initial-state draws (distinct from the slip times').
const START_STREAM: u32 = 0x5EED_0B10;

impl Junctions {
    /// `count` junctions pinned at position 0 with zero stretch.
    pub fn pinned(law: JunctionLaw, count: usize, seed: u32) -> Junctions {
        Junctions {
            law,
            seed,
            anchor: vec![0.0; count],
            broke_at: vec![f64::NAN; count],
            repin_at: vec![f64::NAN; count],
            ruptures: vec![0; count],
        }
    }

    /// `count` junctions each at a random point of its steady cycle at
    /// speed `v` (pinned with a uniform stretch with the probability of the
    /// pinned share of the cycle, else part-way through a drawn slip), so
    /// that a steady-sliding average needs no long transient.
    pub fn steady(law: JunctionLaw, count: usize, seed: u32, v: f64) -> Junctions {
        let mut j = Junctions::pinned(law, count, seed);
        let pinned_time = law.break_stretch / v;
        let share = pinned_time / (pinned_time + law.slip_time.mean());
        for i in 0..count {
            let u = |k: u32| -> f64 {
                unit_from_bits(pcg_hash(draw_key(seed ^ START_STREAM, k, i as u32, 0)))
            };
            if u(0) < share {
                j.anchor[i] = -u(1) * law.break_stretch;
            } else {
                let slip = law.slip_time.draw(seed ^ START_STREAM, i as u32, 0);
                let elapsed = u(2) * slip;
                j.broke_at[i] = -elapsed;
                j.repin_at[i] = slip - elapsed;
            }
        }
        j
    }

    pub fn count(&self) -> usize {
        self.anchor.len()
    }

    /// Advances every junction to time `t` with the block at `x` moving at
    /// `v` and returns the friction (mean junction force opposing the
    /// motion, in units of f_N/Ns; positive opposes +x), the slipping
    /// junctions pulling against v (a prescribed motion: nothing to hold).
    pub fn friction(&mut self, t: f64, x: f64, v: f64) -> f64 {
        let f = self.forces(t, x, v);
        f.pinned + f.slipping * crate::model::friction::junctions::velocity_sign(v)
    }

    /// Advances every junction to time `t` with the block at `x` moving at
    /// `v`: the pinned junctions' mean force (positive opposes +x) and the
    /// slipping ones' mean strength (≥ 0), which the caller applies by the
    /// at-rest rule.
    pub fn forces(&mut self, t: f64, x: f64, v: f64) -> JunctionForces {
        let law = self.law;
        let k = law.threshold / law.break_stretch;
        let (mut pinned, mut slipping) = (0.0, 0.0);
        for i in 0..self.count() {
            if !self.broke_at[i].is_nan() && t >= self.repin_at[i] {
                self.anchor[i] = x;
                self.broke_at[i] = f64::NAN;
            }
            if self.broke_at[i].is_nan() {
                let f = k * (x - self.anchor[i]);
                if f.abs() < law.threshold {
                    pinned += f;
                    continue;
                }
                self.ruptures[i] += 1;
                let slip = law.slip_time.draw(self.seed, i as u32, self.ruptures[i]);
                self.broke_at[i] = t;
                self.repin_at[i] = t + slip;
            }
            slipping += law.slip_force.at(t - self.broke_at[i]) + law.drag * v.abs();
        }
        let n = self.count() as f64;
        JunctionForces {
            pinned: pinned / n,
            slipping: slipping / n,
        }
    }

    /// A block pinned at its junctions' threshold: every junction pinned at
    /// anchor 0 with the block at `x`, just past the break stretch.
    pub fn at_threshold(law: JunctionLaw, count: usize, seed: u32) -> (Junctions, f64) {
        (
            Junctions::pinned(law, count, seed),
            law.break_stretch * (1.0 + 1e-9),
        )
    }

    /// Share of the junctions pinned.
    pub fn pinned_fraction(&self) -> f64 {
        self.broke_at.iter().filter(|b| b.is_nan()).count() as f64 / self.count() as f64
    }

    pub fn total_ruptures(&self) -> u64 {
        self.ruptures.iter().map(|&r| r as u64).sum()
    }
}

/// A prescribed slip history: segments of constant acceleration from rest
/// at x = 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// (duration s, acceleration m/s²).
    pub segments: Vec<(f64, f64)>,
}

impl Motion {
    /// Accelerate to `speed` in `accelerate_time`, slide for `steady_time`,
    /// decelerate at `deceleration` to rest, hold for `hold_time`, then
    /// move at `reload_speed` for `reload_time` (an abrupt start, as a
    /// displacement-controlled reloading).
    pub fn stop_and_reload(
        speed: f64,
        accelerate_time: f64,
        steady_time: f64,
        deceleration: f64,
        hold_time: f64,
        reload_speed: f64,
        reload_time: f64,
    ) -> Motion {
        let start = if accelerate_time > 0.0 {
            (accelerate_time, speed / accelerate_time)
        } else {
            (0.0, speed)
        };
        let mut segments = vec![
            start,
            (steady_time, 0.0),
            (speed / deceleration, -deceleration),
            (hold_time, 0.0),
        ];
        if reload_time > 0.0 {
            // A jump to the reload speed: one segment of infinite
            // acceleration is replaced by starting it at that speed.
            segments.push((0.0, reload_speed));
            segments.push((reload_time, 0.0));
        }
        Motion { segments }
    }

    /// Steady sliding at `speed` from t = 0 for `duration`.
    pub fn steady(speed: f64, duration: f64) -> Motion {
        Motion {
            segments: vec![(0.0, speed), (duration, 0.0)],
        }
    }

    pub fn duration(&self) -> f64 {
        self.segments.iter().map(|s| s.0).sum()
    }

    /// (x, v) at time `t`. A zero-duration segment is a velocity jump of
    /// its "acceleration" value.
    pub fn at(&self, t: f64) -> (f64, f64) {
        let (mut x, mut v, mut start) = (0.0, 0.0, 0.0);
        for &(d, a) in &self.segments {
            if d == 0.0 {
                v = a;
                continue;
            }
            let dt = (t - start).clamp(0.0, d);
            let (x1, v1) = (x + v * dt + 0.5 * a * dt * dt, v + a * dt);
            if t < start + d {
                return (x1, v1.max(0.0));
            }
            x = x1;
            v = v1;
            start += d;
        }
        (x, v.max(0.0))
    }
}

/// The junctions' forces on a block at one instant (units of f_N/Ns).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JunctionForces {
    /// Mean force of the pinned junctions (positive opposes +x).
    pub pinned: f64,
    /// Mean strength of the slipping junctions (≥ 0): their force against
    /// the motion, or what holds the block at rest under `hold`.
    pub slipping: f64,
}

/// One output sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub time: f64,
    pub position: f64,
    pub velocity: f64,
    pub friction: f64,
    pub pinned: f64,
}

/// Runs the junctions along `motion` with step `dt`, calling `sample` at
/// every step.
pub fn follow(junctions: &mut Junctions, motion: &Motion, dt: f64, sample: impl FnMut(Sample)) {
    follow_between(junctions, motion, 0.0, motion.duration(), dt, sample)
}

/// `follow` from `start` to `end` only (phases of one history can take
/// different steps).
pub fn follow_between(
    junctions: &mut Junctions,
    motion: &Motion,
    start: f64,
    end: f64,
    dt: f64,
    mut sample: impl FnMut(Sample),
) {
    let steps = ((end - start) / dt).ceil() as u64;
    for n in 0..=steps {
        let t = start + n as f64 * dt;
        let (x, v) = motion.at(t);
        let friction = junctions.friction(t, x, v);
        sample(Sample {
            time: t,
            position: x,
            velocity: v,
            friction,
            pinned: junctions.pinned_fraction(),
        });
    }
}

/// A block pulled through a spring (all per unit normal force): mass
/// (kg/N), spring stiffness (1/m), a dashpot on the block's velocity
/// (kg/(N·s)), the spring's far end at `preload + speed·t` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pull {
    pub mass: f64,
    pub stiffness: f64,
    pub damping: f64,
    pub speed: f64,
    pub preload: f64,
    /// What the slipping junctions do at rest.
    pub at_rest: SlipAtRest,
}

impl Pull {
    /// The dashpot of damping ratio `ratio` on the block and its spring:
    /// ratio·2√(m·K).
    pub fn damping_for(mass: f64, stiffness: f64, ratio: f64) -> f64 {
        ratio * 2.0 * (mass * stiffness).sqrt()
    }
}

/// Runs the pulled block from `x0` at rest for `duration`, symplectic
/// Euler with step `dt`, calling `sample` at every step. The slipping
/// junctions act by the at-rest rule, as in the 2D model
/// (`model::friction::junctions::slipping_friction`): under `hold` they
/// stop the block when their strength allows.
pub fn pull_from(
    junctions: &mut Junctions,
    p: &Pull,
    x0: f64,
    duration: f64,
    dt: f64,
    mut sample: impl FnMut(Sample),
) {
    let (mut x, mut v) = (x0, 0.0);
    let steps = (duration / dt).ceil() as u64;
    let hold = p.at_rest == SlipAtRest::Hold;
    for n in 0..=steps {
        let t = n as f64 * dt;
        let f = junctions.forces(t, x, v);
        let other = p.stiffness * (p.preload + p.speed * t - x) - p.damping * v - f.pinned;
        let slipping = slipping_friction(hold, f.slipping, -other - p.mass * v / dt, v);
        sample(Sample {
            time: t,
            position: x,
            velocity: v,
            friction: f.pinned - slipping,
            pinned: junctions.pinned_fraction(),
        });
        v += dt * (other + slipping) / p.mass;
        x += dt * v;
    }
}
