//! The quasi-static path of a slider whose junctions all hold: the force
//! residual of a state (the engines' own force law, in f64), the velocity
//! field w = K⁻¹·ḟ with which the equilibrium follows a steadily moving
//! drive, and Newton's method for the equilibrium at a given step.
//!
//! While the junctions hold and the contact set does not change, every load
//! is linear in time after the normal-load phase (side spring pulled at V,
//! top force ramped at a constant rate, top row moved at V), so the
//! equilibrium moves along u(t) = u(t₀) + w·(t − t₀) up to the bonds'
//! geometric nonlinearity, which Newton's method removes at the ends.

use super::band::BandCholesky;
use super::cg::{self, Preconditioner};
use super::tangent::Tangent;
use crate::engines::kernels::bulk_forces::{bond_consts, bulk_force, Blocks};
use crate::engines::step_params::{step_params, Consts};
use crate::engines::Snapshot;
use crate::model::friction::junctions::{slipping_friction, SlipAtRest};
use crate::model::junction::PINNED;
use crate::model::lattice::{block_flags, FLAG_PRESCRIBED_X};
use crate::model::{Driver, Model};

/// How the linear systems are solved (chosen by measurement: BENCHMARKS.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolverKind {
    /// Banded Cholesky of the tangent, reused as the preconditioner of CG
    /// while junction stiffnesses change, refactorised when CG needs more
    /// than `REFACTOR_AFTER` iterations.
    Direct,
    /// Jacobi-preconditioned CG, warm-started.
    Cg,
}

/// CG iterations with a stale factor beyond which it is refactorised.
const REFACTOR_AFTER: usize = 30;
/// Relative residual of every linear solve.
const LINEAR_TOLERANCE: f64 = 1e-12;

/// Solves tangent systems, keeping a factor across jumps.
pub struct Solver {
    pub kind: SolverKind,
    factor: Option<BandCholesky>,
    pub factorisations: u64,
    pub cg_iterations: u64,
    pub solves: u64,
}

#[derive(Debug, thiserror::Error)]
pub enum QuasiStaticError {
    #[error(
        "fast-forward: the tangent stiffness is not positive definite at degree of freedom \
         {0} (a block without support: all its junctions free and no contact?)"
    )]
    Singular(usize),
    #[error("fast-forward: {what} did not converge (residual {residual:.3e})")]
    NoConvergence { what: &'static str, residual: f64 },
}

impl Solver {
    pub fn new(kind: SolverKind) -> Self {
        Solver {
            kind,
            factor: None,
            factorisations: 0,
            cg_iterations: 0,
            solves: 0,
        }
    }

    /// The factor kept for the next solves (direct solver).
    pub fn factor(&self) -> Option<&BandCholesky> {
        self.factor.as_ref()
    }

    /// Puts back a kept factor and the counters (a resumed run).
    pub fn restore(&mut self, factor: Option<BandCholesky>, factorisations: u64, cg: u64) {
        self.factor = factor;
        self.factorisations = factorisations;
        self.cg_iterations = cg;
    }

    /// Solves K·x = b, x holding a guess.
    pub fn solve(&mut self, k: &Tangent, b: &[f64], x: &mut [f64]) -> Result<(), QuasiStaticError> {
        self.solves += 1;
        match self.kind {
            SolverKind::Cg => {
                let d = k.diagonal();
                let r = cg::solve(
                    k,
                    b,
                    x,
                    &Preconditioner::Jacobi(&d),
                    LINEAR_TOLERANCE,
                    20 * (k.dofs.nx + k.dofs.nz) + 1000,
                );
                self.cg_iterations += r.iterations as u64;
                if !r.converged {
                    return Err(QuasiStaticError::NoConvergence {
                        what: "conjugate gradients",
                        residual: r.relative_residual,
                    });
                }
                Ok(())
            }
            SolverKind::Direct => {
                // CG preconditioned by the factor of an earlier tangent
                // (exact or off by a few junction stiffnesses); refactorise
                // when it stalls.
                if self.factor.is_some() {
                    let guess = x.to_vec();
                    if self.refine(k, b, x).converged {
                        return Ok(());
                    }
                    x.copy_from_slice(&guess);
                }
                let f = k.band().cholesky().map_err(QuasiStaticError::Singular)?;
                self.factorisations += 1;
                self.factor = Some(f);
                let r = self.refine(k, b, x);
                if r.converged {
                    Ok(())
                } else {
                    Err(QuasiStaticError::NoConvergence {
                        what: "the direct solve",
                        residual: r.relative_residual,
                    })
                }
            }
        }
    }

    /// Up to `REFACTOR_AFTER` CG iterations preconditioned by the factor.
    fn refine(&mut self, k: &Tangent, b: &[f64], x: &mut [f64]) -> cg::CgReport {
        let f = self.factor.as_ref().expect("a factor");
        let r = cg::solve(
            k,
            b,
            x,
            &Preconditioner::Factor(f),
            LINEAR_TOLERANCE,
            REFACTOR_AFTER,
        );
        self.cg_iterations += r.iterations as u64;
        r
    }
}

/// Forces on every block at a state (DOF-indexed, 0 on held degrees of
/// freedom): bulk springs, dashpots at velocity `vel`, foundation, loads of
/// step `step`, and the junctions' forces (pinned: their springs; slipping:
/// μd·f_N each against `vel`, or holding a block at rest under the
/// scenario's at-rest rule `hold`).
pub fn residual(
    model: &Model,
    snap: &Snapshot,
    disp: &[[f64; 2]],
    vel: &[[f64; 2]],
    step: u64,
    drive_origin: f64,
    k: &Tangent,
) -> Vec<f64> {
    let c = Consts::<f64>::new(model);
    let bonds = bond_consts(&c);
    let p = step_params(&c, step);
    let flags = block_flags(model);
    let blocks = Blocks {
        disp,
        vel,
        flags: &flags,
    };
    let target = drive_origin + p.drive_offset;
    let d = k.dofs;
    let mut r = vec![0.0; d.len()];
    for i in 0..model.n_blocks() {
        let f = bulk_force(&c, &bonds, &p, target, blocks, i);
        r[d.index(i, 0)] = f[0];
        r[d.index(i, 1)] = f[1];
    }
    let ns = snap.slip_steps_left.len() / model.nx.max(1);
    let hold = model
        .junctions
        .is_some_and(|j| j.at_rest == SlipAtRest::Hold);
    for ix in 0..model.nx {
        let f_n =
            crate::model::laws::foundation_normal(model.k_foundation, disp[ix][1]) / ns as f64;
        let (mut pinned, mut slipping) = (0.0, 0usize);
        for j in ix * ns..(ix + 1) * ns {
            if snap.slip_steps_left[j] == PINNED {
                pinned += -snap.junction_stiffness[j] * (disp[ix][0] - snap.anchor[j]);
            } else {
                slipping += 1;
            }
        }
        // The slipping junctions act as in the junction kernel: a block
        // that moves with the quasi-static path slides on them, n·μd·f_N
        // against its velocity, under either rule (the path is linear in
        // that force); a block at rest is held up to n·μd·f_N under `hold`.
        let other = r[d.index(ix, 0)];
        let capacity = slipping as f64 * model.mu_d * f_n;
        let held = hold && vel[ix][0] == 0.0;
        r[d.index(ix, 0)] +=
            pinned + slipping_friction(held, capacity, -(other + pinned), vel[ix][0]);
    }
    for (v, &h) in r.iter_mut().zip(&k.held) {
        if h {
            *v = 0.0;
        }
    }
    r
}

/// The velocity field (per block) with which the equilibrium follows the
/// drive: K·w = ḟ on the free degrees of freedom, w = V on the prescribed
/// top row.
pub fn drive_response(
    model: &Model,
    k: &Tangent,
    solver: &mut Solver,
) -> Result<Vec<[f64; 2]>, QuasiStaticError> {
    let d = k.dofs;
    let n = d.len();
    let mut rhs = vec![0.0; n];
    let mut held_motion = vec![0.0; n];
    match model.driver {
        Driver::None => {}
        Driver::SideSpring {
            stiffness,
            row,
            velocity,
        } => rhs[d.index(row * model.nx, 0)] = stiffness * velocity,
        Driver::TopForce { rate } => {
            for ix in 0..model.nx {
                rhs[d.index((model.nz - 1) * model.nx + ix, 0)] = rate * model.top_share(ix);
            }
        }
        Driver::TopVelocity { velocity } => {
            for (i, f) in block_flags(model).into_iter().enumerate() {
                if f & FLAG_PRESCRIBED_X != 0 {
                    held_motion[d.index(i, 0)] = velocity;
                }
            }
            let mut push = vec![0.0; n];
            k.apply_unheld(&held_motion, &mut push);
            for (r, p) in rhs.iter_mut().zip(&push) {
                *r = -p;
            }
        }
    }
    for (k, &h) in k.held.iter().enumerate() {
        if h {
            rhs[k] = held_motion[k];
        }
    }
    let mut w = held_motion.clone();
    solver.solve(k, &rhs, &mut w)?;
    Ok(per_block(&d, &w, model.n_blocks()))
}

fn per_block(d: &super::tangent::Dofs, x: &[f64], n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| [x[d.index(i, 0)], x[d.index(i, 1)]])
        .collect()
}

/// Largest force any free block carries at a residual, relative to the
/// force scale of one block under the normal load.
pub fn residual_ratio(model: &Model, r: &[f64]) -> f64 {
    let scale = model.normal_force.max(1e-300) / model.nx as f64;
    r.iter().map(|v| v.abs()).fold(0.0, f64::max) / scale
}

/// Newton iterations on the equilibrium at `step` with velocity field `w`,
/// starting from `disp` (held components must already be where they go).
/// Returns the iterations used.
#[allow(clippy::too_many_arguments)]
pub fn settle(
    model: &Model,
    snap: &Snapshot,
    disp: &mut [[f64; 2]],
    w: &[[f64; 2]],
    step: u64,
    drive_origin: f64,
    k: &Tangent,
    solver: &mut Solver,
    tolerance: f64,
) -> Result<usize, QuasiStaticError> {
    let d = k.dofs;
    let mut delta = vec![0.0; d.len()];
    let mut last = f64::INFINITY;
    for it in 0..20 {
        let r = residual(model, snap, disp, w, step, drive_origin, k);
        let ratio = residual_ratio(model, &r);
        if ratio <= tolerance {
            return Ok(it);
        }
        // Stagnation at round-off: accept once the residual stops falling.
        if it > 2 && ratio > 0.5 * last && ratio < 1e3 * tolerance {
            return Ok(it);
        }
        last = ratio;
        delta.iter_mut().for_each(|v| *v = 0.0);
        solver.solve(k, &r, &mut delta)?;
        for (i, u) in disp.iter_mut().enumerate() {
            u[0] += delta[d.index(i, 0)];
            u[1] += delta[d.index(i, 1)];
        }
    }
    let r = residual(model, snap, disp, w, step, drive_origin, k);
    Err(QuasiStaticError::NoConvergence {
        what: "Newton's method on the equilibrium",
        residual: residual_ratio(model, &r),
    })
}
