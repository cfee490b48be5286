//! The slider's tangent stiffness at a state: the bond springs linearised
//! about their current geometry, the foundation under blocks in contact,
//! the pinned junctions and the side spring; constrained and prescribed
//! degrees of freedom held. Kept as per-bond 2×2 blocks (a matrix-free
//! operator for conjugate gradients) and assembled into a band matrix for
//! the direct solver.

use super::band::BandMatrix;
use crate::engines::Snapshot;
use crate::model::junction::PINNED;
use crate::model::lattice::{
    block_flags, for_each_bond, FLAG_FIX_X, FLAG_FIX_Z, FLAG_PRESCRIBED_X,
};
use crate::model::{Driver, Model};

/// Numbering of the 2·n degrees of freedom: the shorter lattice side runs
/// fastest, so that the matrix band is as narrow as the lattice allows.
#[derive(Debug, Clone, Copy)]
pub struct Dofs {
    pub nx: usize,
    pub nz: usize,
    z_fastest: bool,
}

impl Dofs {
    pub fn new(nx: usize, nz: usize) -> Self {
        Dofs {
            nx,
            nz,
            z_fastest: nz <= nx,
        }
    }

    pub fn len(&self) -> usize {
        2 * self.nx * self.nz
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of component `c` (0: x, 1: z) of block `i = iz·nx + ix`.
    #[inline]
    pub fn index(&self, i: usize, c: usize) -> usize {
        let (ix, iz) = (i % self.nx, i / self.nx);
        let k = if self.z_fastest { ix * self.nz + iz } else { i };
        2 * k + c
    }

    /// Largest |index difference| between coupled degrees of freedom.
    pub fn half_bandwidth(&self) -> usize {
        2 * (self.nx.min(self.nz) + 1) + 1
    }
}

/// Tangent stiffness K: force change −K·δu for a displacement change δu.
#[derive(Debug, Clone)]
pub struct Tangent {
    pub dofs: Dofs,
    /// (i, j, 2×2 block) per bond, each bond once.
    bonds: Vec<(usize, usize, [[f64; 2]; 2])>,
    /// Stiffness of the block's own supports (foundation, junctions, side
    /// spring) on its x and z components.
    supports: Vec<[f64; 2]>,
    /// Held degrees of freedom (fixed, or prescribed motion), by DOF index.
    pub held: Vec<bool>,
}

/// Stiffness 2×2 of a central spring of stiffness `k` and rest length
/// `rest` whose current vector is `r`: k·n nᵀ along the bond plus the
/// geometric term (tension/length)·(I − n nᵀ).
pub fn bond_tangent(k: f64, rest: f64, r: [f64; 2]) -> [[f64; 2]; 2] {
    let len = (r[0] * r[0] + r[1] * r[1]).sqrt();
    let n = [r[0] / len, r[1] / len];
    let geometric = k * (len - rest) / len;
    let mut m = [[0.0; 2]; 2];
    for a in 0..2 {
        for b in 0..2 {
            let nn = n[a] * n[b];
            m[a][b] = k * nn + geometric * ((a == b) as u8 as f64 - nn);
        }
    }
    m
}

impl Tangent {
    /// The tangent at `snap`'s displacements, with its pinned junctions.
    pub fn at(model: &Model, snap: &Snapshot) -> Self {
        let (nx, nz) = (model.nx, model.nz);
        let dofs = Dofs::new(nx, nz);
        let mut bonds = Vec::with_capacity(4 * nx * nz);
        for_each_bond(model, |i, j, r0, rest, k| {
            let r = [
                r0[0] + snap.disp[j][0] - snap.disp[i][0],
                r0[1] + snap.disp[j][1] - snap.disp[i][1],
            ];
            bonds.push((i, j, bond_tangent(k, rest, r)));
        });
        let mut supports = vec![[0.0; 2]; nx * nz];
        let ns = snap.slip_steps_left.len() / nx.max(1);
        for (ix, support) in supports.iter_mut().enumerate().take(nx) {
            if snap.disp[ix][1] < 0.0 {
                support[1] += model.k_foundation;
            }
            if ns > 0 {
                support[0] += (ix * ns..(ix + 1) * ns)
                    .filter(|&j| snap.slip_steps_left[j] == PINNED)
                    .map(|j| snap.junction_stiffness[j])
                    .sum::<f64>();
            }
        }
        if let Driver::SideSpring { stiffness, row, .. } = model.driver {
            supports[row * nx][0] += stiffness;
        }
        let mut held = vec![false; dofs.len()];
        for (i, f) in block_flags(model).into_iter().enumerate() {
            if f & (FLAG_FIX_X | FLAG_PRESCRIBED_X) != 0 {
                held[dofs.index(i, 0)] = true;
            }
            if f & FLAG_FIX_Z != 0 {
                held[dofs.index(i, 1)] = true;
            }
        }
        Tangent {
            dofs,
            bonds,
            supports,
            held,
        }
    }

    /// Adds `k` to the x support of interface block `ix` (a junction's
    /// stiffness attached or removed).
    pub fn add_support_x(&mut self, ix: usize, k: f64) {
        self.supports[ix][0] += k;
    }

    /// y = K·x over all degrees of freedom, held ones included (the force
    /// that a motion of held ones causes on free ones).
    pub fn apply_unheld(&self, x: &[f64], y: &mut [f64]) {
        let d = self.dofs;
        y.iter_mut().for_each(|v| *v = 0.0);
        for &(i, j, m) in &self.bonds {
            let (i0, j0) = (d.index(i, 0), d.index(j, 0));
            let diff = [x[i0] - x[j0], x[i0 + 1] - x[j0 + 1]];
            for a in 0..2 {
                let f = m[a][0] * diff[0] + m[a][1] * diff[1];
                y[i0 + a] += f;
                y[j0 + a] -= f;
            }
        }
        for (i, s) in self.supports.iter().enumerate() {
            let i0 = d.index(i, 0);
            y[i0] += s[0] * x[i0];
            y[i0 + 1] += s[1] * x[i0 + 1];
        }
    }

    /// y = K·x on the free degrees of freedom, identity on the held ones:
    /// the operator the solvers invert.
    pub fn apply(&self, x: &[f64], y: &mut [f64], scratch: &mut Vec<f64>) {
        scratch.clear();
        scratch.extend(
            x.iter()
                .zip(&self.held)
                .map(|(&v, &h)| if h { 0.0 } else { v }),
        );
        self.apply_unheld(scratch, y);
        for (k, &h) in self.held.iter().enumerate() {
            if h {
                y[k] = x[k];
            }
        }
    }

    /// Diagonal of the operator `apply` (Jacobi preconditioner).
    pub fn diagonal(&self) -> Vec<f64> {
        let d = self.dofs;
        let mut diag = vec![0.0; d.len()];
        for &(i, j, m) in &self.bonds {
            for (b, k) in [(i, 0), (i, 1), (j, 0), (j, 1)] {
                diag[d.index(b, k)] += m[k][k];
            }
        }
        for (i, s) in self.supports.iter().enumerate() {
            diag[d.index(i, 0)] += s[0];
            diag[d.index(i, 1)] += s[1];
        }
        for (k, &h) in self.held.iter().enumerate() {
            if h {
                diag[k] = 1.0;
            }
        }
        diag
    }

    /// The operator `apply` as a band matrix.
    pub fn band(&self) -> BandMatrix {
        let d = self.dofs;
        let mut a = BandMatrix::zeros(d.len(), d.half_bandwidth());
        for &(i, j, m) in &self.bonds {
            for (p, row) in m.iter().enumerate() {
                for (q, &v) in row.iter().enumerate() {
                    let (ip, iq) = (d.index(i, p), d.index(i, q));
                    let (jp, jq) = (d.index(j, p), d.index(j, q));
                    // Each unordered pair once: the band stores A[r][c] for r ≥ c.
                    if p <= q {
                        a.add(ip, iq, v);
                        a.add(jp, jq, v);
                    }
                    a.add(ip, jq, -v);
                }
            }
        }
        for (i, s) in self.supports.iter().enumerate() {
            a.add(d.index(i, 0), d.index(i, 0), s[0]);
            a.add(d.index(i, 1), d.index(i, 1), s[1]);
        }
        for (k, &h) in self.held.iter().enumerate() {
            if h {
                a.constrain(k);
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::lattice::STENCIL;
    use crate::model::scenario::Scenario;

    fn table_s1() -> (Model, Snapshot) {
        let s = Scenario::default_scene();
        let m = Model::from_scenario(&s, false).unwrap();
        let mut e = crate::engines::cpu::CpuEngine::<f64>::new(&m, 1).unwrap();
        let snap = crate::Engine::snapshot(&mut e).unwrap();
        (m, snap)
    }

    /// The band matrix and the matrix-free operator are the same operator.
    #[test]
    fn band_and_operator_agree() {
        let (m, snap) = table_s1();
        let k = Tangent::at(&m, &snap);
        let n = k.dofs.len();
        let x: Vec<f64> = (0..n).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
        let (mut y1, mut y2, mut s) = (vec![0.0; n], vec![0.0; n], Vec::new());
        k.apply(&x, &mut y1, &mut s);
        k.band().mul(&x, &mut y2);
        let scale = y1.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let err = y1
            .iter()
            .zip(&y2)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err <= 1e-12 * scale, "{err} of {scale}");
        let diag = k.diagonal();
        let band = k.band();
        assert!((0..n).all(|i| (diag[i] - band.get(i, i)).abs() <= 1e-9 * diag[i].abs()));
    }

    /// Every coupled pair lies inside the half bandwidth, whichever side of
    /// the lattice is shorter.
    #[test]
    fn numbering_keeps_neighbours_in_the_band() {
        for (nx, nz) in [(57, 31), (5, 40), (8, 8)] {
            let d = Dofs::new(nx, nz);
            let b = d.half_bandwidth();
            for iz in 0..nz {
                for ix in 0..nx {
                    let i = iz * nx + ix;
                    for s in STENCIL {
                        let (jx, jz) = (ix as i64 + s.dx as i64, iz as i64 + s.dz as i64);
                        if jx < 0 || jz < 0 || jx >= nx as i64 || jz >= nz as i64 {
                            continue;
                        }
                        let j = jz as usize * nx + jx as usize;
                        for (p, q) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                            assert!(d.index(i, p).abs_diff(d.index(j, q)) <= b);
                        }
                    }
                }
            }
        }
    }

    /// The tangent of a bond is the derivative of its force: a finite
    /// difference of the exact central-spring force agrees.
    #[test]
    fn bond_tangent_is_the_derivative_of_the_spring_force() {
        let (k, rest) = (3.0e7, 2.5e-3);
        let force = |r: [f64; 2]| {
            let len = (r[0] * r[0] + r[1] * r[1]).sqrt();
            let s = k * (len - rest);
            [s * r[0] / len, s * r[1] / len]
        };
        let r = [2.5e-3 + 3e-6, -4e-6];
        let t = bond_tangent(k, rest, r);
        let h = 1e-10;
        for b in 0..2 {
            let mut rp = r;
            rp[b] += h;
            let mut rm = r;
            rm[b] -= h;
            let (fp, fm) = (force(rp), force(rm));
            for a in 0..2 {
                let fd = (fp[a] - fm[a]) / (2.0 * h);
                assert!(
                    (fd - t[a][b]).abs() < 1e-5 * k,
                    "{a}{b}: {fd} vs {}",
                    t[a][b]
                );
            }
        }
    }
}
