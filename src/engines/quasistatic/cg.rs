//! Preconditioned conjugate gradients on the tangent operator, warm-started
//! from a guess. The preconditioner is either the diagonal (Jacobi) or a
//! banded Cholesky factor of an earlier tangent: after a junction attaches
//! or breaks the factor is off by a few diagonal entries, and CG converges
//! in a handful of iterations instead of a refactorisation.

use super::band::BandCholesky;
use super::tangent::Tangent;

pub enum Preconditioner<'a> {
    Jacobi(&'a [f64]),
    Factor(&'a BandCholesky),
}

impl Preconditioner<'_> {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        match self {
            Preconditioner::Jacobi(d) => {
                for ((z, r), d) in z.iter_mut().zip(r).zip(d.iter()) {
                    *z = r / d;
                }
            }
            Preconditioner::Factor(f) => {
                z.copy_from_slice(r);
                f.solve(z);
            }
        }
    }
}

/// Outcome of one solve.
#[derive(Debug, Clone, Copy)]
pub struct CgReport {
    pub iterations: usize,
    /// Final ‖r‖/‖b‖.
    pub relative_residual: f64,
    pub converged: bool,
}

/// Solves K·x = b to ‖b − K·x‖ ≤ tol·‖b‖, x holding the initial guess.
pub fn solve(
    k: &Tangent,
    b: &[f64],
    x: &mut [f64],
    pre: &Preconditioner<'_>,
    tol: f64,
    max_iterations: usize,
) -> CgReport {
    let n = b.len();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let norm_b = dot(b, b).sqrt();
    if norm_b == 0.0 {
        x.iter_mut().for_each(|v| *v = 0.0);
        return CgReport {
            iterations: 0,
            relative_residual: 0.0,
            converged: true,
        };
    }
    let mut scratch = Vec::with_capacity(n);
    let mut r = vec![0.0; n];
    k.apply(x, &mut r, &mut scratch);
    for (r, b) in r.iter_mut().zip(b) {
        *r = b - *r;
    }
    let mut z = vec![0.0; n];
    pre.apply(&r, &mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut q = vec![0.0; n];
    let mut rel = dot(&r, &r).sqrt() / norm_b;
    let mut it = 0;
    while rel > tol && it < max_iterations {
        k.apply(&p, &mut q, &mut scratch);
        let alpha = rz / dot(&p, &q);
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * q[i];
        }
        pre.apply(&r, &mut z);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
        rel = dot(&r, &r).sqrt() / norm_b;
        it += 1;
    }
    CgReport {
        iterations: it,
        relative_residual: rel,
        converged: rel <= tol,
    }
}
