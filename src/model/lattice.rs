//! Lattice geometry built once per run: block flags (constraints, rows that
//! take loads) and the 8-neighbour stencil. Shared by both engines; the GPU
//! uploads the same flags and bakes the stencil into `shaders/bulk_forces.wgsl`.

use crate::model::scenario::EdgeConstraint;
use crate::model::{Driver, Model};

/// u_x is held (velocity zeroed).
pub const FLAG_FIX_X: u32 = 1;
/// u_z is held.
pub const FLAG_FIX_Z: u32 = 2;
/// Top row: normal and top tangential loads.
pub const FLAG_TOP: u32 = 4;
/// Interface row: foundation and friction.
pub const FLAG_INTERFACE: u32 = 8;
/// The block the side spring pulls.
pub const FLAG_DRIVEN: u32 = 16;
/// u_x moved at the prescribed top velocity.
pub const FLAG_PRESCRIBED_X: u32 = 32;

/// One direction of the 8-neighbour stencil.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bond {
    pub dx: i32,
    pub dz: i32,
    /// 1 for nearest neighbours, ½ for diagonals (times k).
    pub stiffness_factor: f64,
    /// Rest length in units of l (1 or √2).
    pub length_factor: f64,
}

/// The stencil, in the order both engines sum it (fixed, for reproducibility).
pub const STENCIL: [Bond; 8] = {
    const D: f64 = std::f64::consts::SQRT_2;
    [
        Bond {
            dx: 1,
            dz: 0,
            stiffness_factor: 1.0,
            length_factor: 1.0,
        },
        Bond {
            dx: -1,
            dz: 0,
            stiffness_factor: 1.0,
            length_factor: 1.0,
        },
        Bond {
            dx: 0,
            dz: 1,
            stiffness_factor: 1.0,
            length_factor: 1.0,
        },
        Bond {
            dx: 0,
            dz: -1,
            stiffness_factor: 1.0,
            length_factor: 1.0,
        },
        Bond {
            dx: 1,
            dz: 1,
            stiffness_factor: 0.5,
            length_factor: D,
        },
        Bond {
            dx: -1,
            dz: 1,
            stiffness_factor: 0.5,
            length_factor: D,
        },
        Bond {
            dx: 1,
            dz: -1,
            stiffness_factor: 0.5,
            length_factor: D,
        },
        Bond {
            dx: -1,
            dz: -1,
            stiffness_factor: 0.5,
            length_factor: D,
        },
    ]
};

/// Bonds counted once: the stencil directions pointing "forward".
pub fn forward_bonds() -> impl Iterator<Item = &'static Bond> {
    STENCIL
        .iter()
        .filter(|b| b.dz > 0 || (b.dz == 0 && b.dx > 0))
}

/// Visits every bond once with (i, j, rest length, stiffness).
pub fn for_each_bond(m: &Model, mut f: impl FnMut(usize, usize, [f64; 2], f64, f64)) {
    for iz in 0..m.nz as i64 {
        for ix in 0..m.nx as i64 {
            for b in forward_bonds() {
                let (jx, jz) = (ix + b.dx as i64, iz + b.dz as i64);
                if jx < 0 || jx >= m.nx as i64 || jz >= m.nz as i64 {
                    continue;
                }
                let i = (iz * m.nx as i64 + ix) as usize;
                let j = (jz * m.nx as i64 + jx) as usize;
                let r0 = [b.dx as f64 * m.spacing, b.dz as f64 * m.spacing];
                f(
                    i,
                    j,
                    r0,
                    b.length_factor * m.spacing,
                    b.stiffness_factor * m.k,
                );
            }
        }
    }
}

/// Per-block flags, index `iz * nx + ix`.
pub fn block_flags(model: &Model) -> Vec<u32> {
    let (nx, nz) = (model.nx, model.nz);
    let mut flags = vec![0u32; nx * nz];
    let constraint = |c: EdgeConstraint| match c {
        EdgeConstraint::Free => 0,
        EdgeConstraint::FixX => FLAG_FIX_X,
        EdgeConstraint::FixZ => FLAG_FIX_Z,
    };
    for ix in 0..nx {
        flags[ix] |= FLAG_INTERFACE | constraint(model.bottom);
        let top = (nz - 1) * nx + ix;
        flags[top] |= FLAG_TOP | constraint(model.top);
        if matches!(model.driver, Driver::TopVelocity { .. }) {
            flags[top] |= FLAG_PRESCRIBED_X;
        }
    }
    if let Driver::SideSpring { row, .. } = model.driver {
        flags[row * nx] |= FLAG_DRIVEN;
    }
    flags
}

/// Initial displacements: the start position along x (zero by default),
/// plus the Gaussian pulse of a wave test, uniform in z so that the wave
/// is plane.
pub fn initial_displacement(model: &Model) -> Vec<[f64; 2]> {
    let mut u = vec![[model.start_position, 0.0]; model.n_blocks()];
    if let Some(p) = model.pulse {
        for iz in 0..model.nz {
            for ix in 0..model.nx {
                let x = ix as f64 * model.spacing;
                let g = p.amplitude * (-0.5 * ((x - p.center) / p.width).powi(2)).exp();
                let c = match p.component {
                    crate::model::scenario::Component::X => 0,
                    crate::model::scenario::Component::Z => 1,
                };
                u[iz * model.nx + ix][c] += g;
            }
        }
    }
    u
}

/// Initial junction anchors, index ix·Ns + j: every junction pinned where
/// its interface block starts (a junction pinned at rest carries no force).
pub fn initial_anchors(model: &Model) -> Vec<f64> {
    let u = initial_displacement(model);
    let per_block = model.junctions.map_or(0, |j| j.count);
    (0..model.n_junctions())
        .map(|k| u[k / per_block][0])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scenario::Scenario;

    #[test]
    fn table_s1_flags() {
        let m = Model::from_scenario(&Scenario::default_scene(), false).unwrap();
        let f = block_flags(&m);
        assert_eq!(f.iter().filter(|&&x| x & FLAG_INTERFACE != 0).count(), 57);
        assert_eq!(f.iter().filter(|&&x| x & FLAG_TOP != 0).count(), 57);
        assert_eq!(f[2 * 57] & FLAG_DRIVEN, FLAG_DRIVEN);
        assert_eq!(f.iter().filter(|&&x| x & FLAG_DRIVEN != 0).count(), 1);
    }

    #[test]
    fn stencil_is_symmetric() {
        for b in STENCIL {
            assert!(STENCIL.iter().any(|o| o.dx == -b.dx
                && o.dz == -b.dz
                && o.stiffness_factor == b.stiffness_factor));
        }
    }
}
