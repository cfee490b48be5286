//! The force laws more than one place evaluates, defined once: the engines'
//! kernels (any precision), the energy ledger, the trigger and the output's
//! drive force call these. The WGSL twins are in `shaders/common.wgsl`
//! (`foundation_normal`) and `shaders/bulk_forces.wgsl` (`top_share`, with
//! the shares precomputed here into the uniform block).

use crate::model::real::Real;

/// Normal force the rigid track's foundation (a penalty spring of stiffness
/// `k_foundation` that only pushes) carries under an interface block whose
/// vertical displacement is `uz`.
#[inline]
pub fn foundation_normal<T: Real>(k_foundation: T, uz: T) -> T {
    k_foundation * (-uz).max(T::zero())
}

/// Energy stored in the foundation under a block at `uz`.
pub fn foundation_energy(k_foundation: f64, uz: f64) -> f64 {
    let penetration = (-uz).max(0.0);
    0.5 * k_foundation * penetration * penetration
}

/// Share of a total force applied to the top row that column `ix` of `nx`
/// carries: the edge blocks take half shares (trapezoid rule: the load acts
/// on the top surface, of which an edge block holds half a spacing), so the
/// shares sum to one. A single row (`nz` = 1) is a chain of equal blocks
/// each loaded as a body, as in the 1D models: equal shares 1/nx.
#[inline]
pub fn top_share<T: Real>(nx: usize, nz: usize, ix: usize) -> T {
    if nz == 1 {
        T::one() / T::from_f64(nx as f64)
    } else if nx == 1 {
        T::one()
    } else {
        let full = T::one() / T::from_f64((nx - 1) as f64);
        if ix == 0 || ix == nx - 1 {
            full * T::from_f64(0.5)
        } else {
            full
        }
    }
}

/// Relative line load of column `ix` of `nx` under a linear normal-load
/// profile of slope `slope` = (r − 1)/(r + 1), r the trailing-to-leading
/// ratio: 1 + slope at the trailing edge, 1 − slope at the leading edge.
/// Linear, so its top-share-weighted sum is exactly 1 (the total load is
/// kept).
#[inline]
pub fn normal_profile<T: Real>(slope: T, nx: usize, ix: usize) -> T {
    if nx == 1 {
        T::one()
    } else {
        let x = T::from_f64(ix as f64) / T::from_f64((nx - 1) as f64);
        T::one() + slope * (T::one() - (x + x))
    }
}

/// Stretch of the side-driving spring (m): how far its far end, pulled at
/// `velocity` from `origin` for time `t` (≥ 0), is ahead of the driven
/// block at `u`. Its tension is stiffness × stretch.
pub fn side_spring_stretch(velocity: f64, t: f64, u: f64, origin: f64) -> f64 {
    velocity * t.max(0.0) - (u - origin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn top_shares_sum_to_one_and_edges_take_half() {
        for nx in [1usize, 2, 3, 57] {
            for nz in [1usize, 2, 31] {
                let sum: f64 = (0..nx).map(|ix| top_share::<f64>(nx, nz, ix)).sum();
                assert!((sum - 1.0).abs() < 1e-12, "nx = {nx}, nz = {nz}: {sum}");
            }
        }
        assert_eq!(
            top_share::<f64>(57, 31, 0),
            0.5 * top_share::<f64>(57, 31, 1)
        );
        assert_eq!(top_share::<f64>(57, 1, 0), top_share::<f64>(57, 1, 1));
    }

    #[test]
    fn the_foundation_only_pushes() {
        assert_eq!(foundation_normal(10.0, 0.1), 0.0);
        assert_eq!(foundation_normal(10.0f32, -0.1), 1.0);
        assert_eq!(foundation_energy(10.0, -0.1), 0.05);
    }
}
