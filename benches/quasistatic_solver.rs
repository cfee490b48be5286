//! The fast-forward's linear solver, measured: banded Cholesky (factor,
//! solve, and CG preconditioned by a stale factor after one interface
//! block's junction stiffness changes) against Jacobi-preconditioned CG,
//! on the drive response K·w = ḟ of a loaded slider.
//! `cargo bench --bench quasistatic_solver [-- NXxNZ ...]` (default 57x31).
//!
//! The state is the start of the normal-load phase with every junction
//! pinned at its normal-load stiffness and the interface in contact: the
//! stiffness pattern of a quiet phase (the solver's cost does not depend on
//! the loads).

use slipfront::engines::cpu::CpuEngine;
use slipfront::engines::quasistatic::cg::{self, Preconditioner};
use slipfront::engines::quasistatic::equilibrium::{drive_response, Solver, SolverKind};
use slipfront::engines::quasistatic::tangent::Tangent;
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{Engine, Model};
use std::time::Instant;

fn model(nx: usize, nz: usize) -> Model {
    // Keep Table S1's spacing (2.5 mm): the lattice grows with the slider.
    let spacing = 0.140 / 56.0;
    let set = [
        format!("geometry.nx={nx}"),
        format!("geometry.nz={nz}"),
        format!("geometry.length={}", spacing * (nx - 1) as f64),
        format!("geometry.height={}", spacing * (nz - 1) as f64),
    ];
    let s = Scenario::parse(DEFAULT_SCENARIO, "solver bench", &set).unwrap();
    Model::from_scenario(&s, false).unwrap()
}

fn main() {
    let sizes: Vec<(usize, usize)> = std::env::args()
        .skip(1)
        .filter_map(|a| {
            let (x, z) = a.split_once('x')?;
            Some((x.parse().ok()?, z.parse().ok()?))
        })
        .collect();
    let sizes = if sizes.is_empty() {
        vec![(57, 31)]
    } else {
        sizes
    };
    println!("| lattice | DOFs | half band | factor (s) | factor (MiB) | direct solve (s) | stale-factor CG: its, s | Jacobi CG: its, s |");
    println!("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for (nx, nz) in sizes {
        let m = model(nx, nz);
        let e = CpuEngine::<f64>::new(&m, 1).unwrap();
        let mut snap = {
            let mut e = e;
            e.snapshot().unwrap()
        };
        let j = m.junctions.unwrap();
        let f_n = m.normal_force / (m.nx * j.count) as f64;
        let k_j = (j.stiffness_value * f_n).sqrt();
        snap.junction_stiffness.iter_mut().for_each(|k| *k = k_j);
        for ix in 0..m.nx {
            snap.disp[ix][1] = -f_n * j.count as f64 / m.k_foundation;
        }
        let k = Tangent::at(&m, &snap);
        let t = Instant::now();
        let band = k.band();
        let factor = band.cholesky().expect("positive definite");
        let t_factor = t.elapsed().as_secs_f64();
        let mut direct = Solver::new(SolverKind::Direct);
        let t = Instant::now();
        let w = drive_response(&m, &k, &mut direct).unwrap();
        let t_direct = t.elapsed().as_secs_f64() - 0.0;
        // One junction's stiffness changes: CG with the stale factor.
        let mut k2 = k.clone();
        k2.add_support_x(m.nx / 2, -k_j);
        let n = k.dofs.len();
        let mut rhs = vec![0.0; n];
        let mut x = vec![0.0; n];
        let mut scratch = Vec::new();
        let wflat: Vec<f64> = {
            let mut v = vec![0.0; n];
            for (i, w) in w.iter().enumerate() {
                v[k.dofs.index(i, 0)] = w[0];
                v[k.dofs.index(i, 1)] = w[1];
            }
            v
        };
        k.apply(&wflat, &mut rhs, &mut scratch);
        let t = Instant::now();
        let stale = cg::solve(
            &k2,
            &rhs,
            &mut x,
            &Preconditioner::Factor(&factor),
            1e-12,
            1000,
        );
        let t_stale = t.elapsed().as_secs_f64();
        let diag = k.diagonal();
        let mut y = vec![0.0; n];
        let t = Instant::now();
        let jacobi = cg::solve(
            &k,
            &rhs,
            &mut y,
            &Preconditioner::Jacobi(&diag),
            1e-12,
            200_000,
        );
        let t_jacobi = t.elapsed().as_secs_f64();
        println!(
            "| {nx}×{nz} | {n} | {} | {t_factor:.3} | {:.0} | {t_direct:.3} | {}, {t_stale:.4} | {}{}, {t_jacobi:.3} |",
            k.dofs.half_bandwidth(),
            factor.bytes() as f64 / 1048576.0,
            stale.iterations,
            jacobi.iterations,
            if jacobi.converged { "" } else { " (not converged)" },
        );
    }
}
