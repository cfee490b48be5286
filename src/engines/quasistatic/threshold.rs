//! When the quasi-static path ends: along u(τ) = u₀ + w·τ every pinned
//! junction's force −k_j·(u_x − a_j) and its block's break threshold
//! μs·k_f·(−u_z)/Ns are linear in τ, so the first junction to reach its
//! threshold (and the first block to lose or gain contact with the track,
//! which changes the stiffness) is found exactly.

use crate::engines::Snapshot;
use crate::model::friction::junctions::break_threshold;
use crate::model::junction::PINNED;
use crate::model::Model;

/// What ends a quasi-static path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PathEnd {
    /// Junction `junction` of interface block `ix` reaches μs·f_N.
    Rupture { ix: usize, junction: usize },
    /// Interface block `ix` leaves (or reaches) the track.
    Contact { ix: usize },
    /// Nothing changes on this path (no drive, or moving away from every
    /// threshold).
    Never,
}

/// The first change along the path from `disp` with velocity `w`:
/// (time from the start of the path, s; what happens). `disp` is the
/// equilibrium at the start, whose junctions are all below threshold.
pub fn first_change(
    model: &Model,
    snap: &Snapshot,
    disp: &[[f64; 2]],
    w: &[[f64; 2]],
) -> (f64, PathEnd) {
    let mut best = (f64::INFINITY, PathEnd::Never);
    let ns = snap.slip_steps_left.len() / model.nx.max(1);
    // The law's break threshold per metre of indentation (f_N = k_f·d/Ns).
    let per_junction = break_threshold(model.mu_s, model.k_foundation / ns.max(1) as f64);
    for ix in 0..model.nx {
        let (ux, uz) = (disp[ix][0], disp[ix][1]);
        let (wx, wz) = (w[ix][0], w[ix][1]);
        // Contact: u_z crosses 0.
        if (uz < 0.0 && wz > 0.0) || (uz > 0.0 && wz < 0.0) {
            let tau = -uz / wz;
            if tau < best.0 {
                best = (tau, PathEnd::Contact { ix });
            }
        }
        if uz >= 0.0 {
            continue;
        }
        // threshold(τ) = θ₀ + θ'·τ with θ = μs·k_f·(−u_z)/Ns.
        let (theta0, theta1) = (-per_junction * uz, -per_junction * wz);
        for j in ix * ns..(ix + 1) * ns {
            if snap.slip_steps_left[j] != PINNED {
                continue;
            }
            let kj = snap.junction_stiffness[j];
            let (f0, f1) = (-kj * (ux - snap.anchor[j]), -kj * wx);
            // Either sign of the force: ±f(τ) − θ(τ) = 0 with g(0) < 0.
            for s in [1.0, -1.0] {
                let g0 = s * f0 - theta0;
                let g1 = s * f1 - theta1;
                if g1 > 0.0 {
                    let tau = (-g0 / g1).max(0.0);
                    if tau < best.0 {
                        best = (
                            tau,
                            PathEnd::Rupture {
                                ix,
                                junction: j - ix * ns,
                            },
                        );
                    }
                }
            }
        }
    }
    best
}

/// Smallest margin of the pinned junctions below their threshold at a
/// state, as a fraction of the threshold (negative: one is past it).
pub fn threshold_margin(model: &Model, snap: &Snapshot, disp: &[[f64; 2]]) -> f64 {
    let ns = snap.slip_steps_left.len() / model.nx.max(1);
    // The law's break threshold per metre of indentation (f_N = k_f·d/Ns).
    let per_junction = break_threshold(model.mu_s, model.k_foundation / ns.max(1) as f64);
    let mut margin = f64::INFINITY;
    for (ix, u) in disp.iter().enumerate().take(model.nx) {
        let theta = per_junction * (-u[1]).max(0.0);
        for j in ix * ns..(ix + 1) * ns {
            if snap.slip_steps_left[j] != PINNED {
                continue;
            }
            let f = snap.junction_stiffness[j] * (u[0] - snap.anchor[j]);
            let m = if theta > 0.0 {
                (theta - f.abs()) / theta
            } else if f == 0.0 {
                0.0
            } else {
                -1.0
            };
            margin = margin.min(m);
        }
    }
    margin
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scenario::Scenario;

    /// One interface block loaded at a known rate reaches its threshold at
    /// the time the linear law gives.
    #[test]
    fn the_crossing_of_a_linearly_loaded_junction_is_exact() {
        let m = Model::from_scenario(&Scenario::default_scene(), false).unwrap();
        let ns = m.junctions.unwrap().count;
        let n = m.n_blocks();
        let snap = Snapshot {
            slip_steps_left: vec![PINNED; m.nx * ns],
            junction_stiffness: vec![1.0e5; m.nx * ns],
            anchor: vec![0.0; m.nx * ns],
            ..Default::default()
        };
        let uz = -1.0e-6;
        let mut disp = vec![[0.0, uz]; n];
        let w = vec![[0.0; 2]; n];
        let mut w1 = w.clone();
        w1[3] = [2.0e-4, 0.0];
        disp[3][0] = 1.0e-7;
        let (tau, end) = first_change(&m, &snap, &disp, &w1);
        // k_j·(1e-7 + 2e-4·τ) = μs·k_f·1e-6/Ns.
        let theta = m.mu_s * m.k_foundation * 1.0e-6 / ns as f64;
        let expect = (theta / 1.0e5 - 1.0e-7) / 2.0e-4;
        assert!((tau - expect).abs() < 1e-12 * expect, "{tau} vs {expect}");
        assert!(matches!(end, PathEnd::Rupture { ix: 3, .. }));
        // No motion: no end. Motion away from the track: a contact change.
        assert_eq!(first_change(&m, &snap, &disp, &w).1, PathEnd::Never);
        let mut w2 = w.clone();
        w2[5] = [0.0, 1.0e-3];
        let (tau, end) = first_change(&m, &snap, &disp, &w2);
        assert_eq!(end, PathEnd::Contact { ix: 5 });
        assert!((tau - 1.0e-3).abs() < 1e-15);
        let margin = threshold_margin(&m, &snap, &disp);
        assert!((margin - (1.0 - 1.0e5 * 1.0e-7 / theta)).abs() < 1e-12);
    }
}
