//! Counter-based junction RNG. The draw for junction `j` of interface block
//! `i` at its `n`-th rupture is a pure function of `(seed, i, j, n)`, so the
//! CPU and GPU engines draw the same slip times in any execution order.
//! `shaders/rng.wgsl` holds the same functions, line for line.

use num_traits::Float;

/// PCG-RXS-M-XS 32-bit output hash (Jarzynski & Olano, JCGT 2020).
#[inline]
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The 32-bit key of one draw.
#[inline]
pub fn draw_key(seed: u32, block: u32, junction: u32, count: u32) -> u32 {
    pcg_hash(count ^ pcg_hash(junction ^ pcg_hash(block ^ pcg_hash(seed))))
}

/// Uniform in (0, 1]: 24 bits, exact in f32 and f64 alike.
#[inline]
pub fn unit_from_bits<T: Float>(bits: u32) -> T {
    let scale = T::from(1.0 / 16_777_216.0).unwrap();
    (T::from((bits >> 8) as f64).unwrap() + T::one()) * scale
}

/// Two uniforms in (0, 1] for a draw.
#[inline]
pub fn uniform_pair<T: Float>(seed: u32, block: u32, junction: u32, count: u32) -> (T, T) {
    let a = pcg_hash(draw_key(seed, block, junction, count));
    let b = pcg_hash(a);
    (unit_from_bits(a), unit_from_bits(b))
}

/// Standard normal deviate by Box–Muller.
#[inline]
pub fn standard_normal<T: Float>(seed: u32, block: u32, junction: u32, count: u32) -> T {
    let (u1, u2): (T, T) = uniform_pair(seed, block, junction, count);
    let two = T::from(2.0).unwrap();
    let two_pi = T::from(std::f64::consts::TAU).unwrap();
    (-two * u1.ln()).sqrt() * (two_pi * u2).cos()
}

/// Slip duration in whole steps for a rupture: t_R ~ N(mean, std) truncated
/// at 0, at least one step. `mean_steps`, `std_steps` are ⟨t_R⟩/dt and σ_R/dt.
#[inline]
pub fn slip_steps<T: Float>(
    seed: u32,
    block: u32,
    junction: u32,
    count: u32,
    mean_steps: T,
    std_steps: T,
) -> u32 {
    let z: T = standard_normal(seed, block, junction, count);
    let steps = (mean_steps + std_steps * z).max(T::zero()).round();
    steps.to_u32().unwrap_or(u32::MAX).max(1)
}

/// Stream of the trigger's initial junction forces, apart from the rupture draws.
pub const TRIGGER_STREAM: u32 = 0x9E37_79B9;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_counter_same_draw_and_neighbours_differ() {
        let a: f64 = standard_normal(7, 3, 11, 5);
        let b: f64 = standard_normal(7, 3, 11, 5);
        assert_eq!(a.to_bits(), b.to_bits());
        let others = [
            standard_normal::<f64>(8, 3, 11, 5),
            standard_normal::<f64>(7, 4, 11, 5),
            standard_normal::<f64>(7, 3, 12, 5),
            standard_normal::<f64>(7, 3, 11, 6),
        ];
        for o in others {
            assert_ne!(a.to_bits(), o.to_bits());
        }
    }

    #[test]
    fn uniforms_are_in_unit_interval_and_exact_across_precisions() {
        for c in 0..10_000u32 {
            let (a, b): (f64, f64) = uniform_pair(1, c, c / 7, c % 13);
            let (af, bf): (f32, f32) = uniform_pair(1, c, c / 7, c % 13);
            assert!(a > 0.0 && a <= 1.0 && b > 0.0 && b <= 1.0);
            assert_eq!(a, af as f64);
            assert_eq!(b, bf as f64);
        }
    }
}
