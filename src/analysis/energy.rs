//! Energy bookkeeping: the energy stored in a state and the power flowing
//! in and out of it, so that a run can be checked against
//! work in = change of stored energy + dissipation.
//!
//! The system is the slider plus its driving spring. Stored: kinetic energy,
//! bulk springs, foundation, side spring. Power in: the puller of the side
//! spring, the normal and tangential top loads and the interface prestress, the friction forces (all
//! junction forces, pinned or slipping, taken as external). Dissipated: the
//! dashpots and the absolute damping (relaxation, or absolute viscosity).

use crate::engines::Snapshot;
use crate::model::lattice::for_each_bond;
use crate::model::scenario::DampingForm;
use crate::model::{Driver, Model};

/// Energy stored in a state (J).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StoredEnergy {
    pub kinetic: f64,
    pub springs: f64,
    pub foundation: f64,
    pub drive_spring: f64,
}

impl StoredEnergy {
    pub fn total(&self) -> f64 {
        self.kinetic + self.springs + self.foundation + self.drive_spring
    }
}

/// Stored energy of a state; `drive_origin` is u_x of the driven block when
/// driving started.
pub fn stored_energy(m: &Model, s: &Snapshot, drive_origin: f64) -> StoredEnergy {
    let mut e = StoredEnergy {
        kinetic: s.kinetic_energy_half(m.mass),
        ..Default::default()
    };
    for_each_bond(m, |i, j, r0, rest, k| {
        let du = [s.disp[j][0] - s.disp[i][0], s.disp[j][1] - s.disp[i][1]];
        let r = [r0[0] + du[0], r0[1] + du[1]];
        let stretch = (r[0] * r[0] + r[1] * r[1]).sqrt() - rest;
        e.springs += 0.5 * k * stretch * stretch;
    });
    for ix in 0..m.nx {
        e.foundation += crate::model::laws::foundation_energy(m.k_foundation, s.disp[ix][1]);
    }
    if let Driver::SideSpring {
        stiffness,
        row,
        velocity,
    } = m.driver
    {
        let u = s.disp[row * m.nx][0];
        let stretch = crate::model::laws::side_spring_stretch(velocity, s.time, u, drive_origin);
        e.drive_spring = 0.5 * stiffness * stretch * stretch;
    }
    e
}

/// Power terms (W) at one step, from the state before and after it:
/// forces from `before` (positions and loads of step n), velocities averaged
/// over the step (the leapfrog's exact kinetic-energy identity).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Power {
    pub drive: f64,
    pub top_loads: f64,
    pub friction: f64,
    /// Dissipated by dashpots and relaxation damping (≥ 0).
    pub damping: f64,
}

pub fn step_power(m: &Model, before: &Snapshot, after: &Snapshot, drive_origin: f64) -> Power {
    let vbar = |i: usize| {
        [
            0.5 * (before.vel_half[i][0] + after.vel_half[i][0]),
            0.5 * (before.vel_half[i][1] + after.vel_half[i][1]),
        ]
    };
    let mut p = Power::default();
    if let Driver::SideSpring {
        stiffness,
        row,
        velocity,
    } = m.driver
    {
        if before.time >= 0.0 {
            // The puller moves the spring's far end at V.
            let stretch = velocity * before.time - (before.disp[row * m.nx][0] - drive_origin);
            p.drive = stiffness * stretch * velocity;
        }
    }
    let ramp = if m.ramp_steps == 0 || before.step >= m.ramp_steps {
        1.0
    } else {
        before.step as f64 / m.ramp_steps as f64
    };
    let top_tangential = m
        .trigger
        .map_or(0.0, |t| t.shear_prestress * m.normal_force)
        * ramp
        + match m.driver {
            Driver::TopForce { rate } => rate * before.time.max(0.0),
            _ => 0.0,
        };
    for ix in 0..m.nx {
        let i = (m.nz - 1) * m.nx + ix;
        let share = m.top_share(ix);
        let v = vbar(i);
        let normal_share = m.normal_share(ix);
        p.top_loads += -m.normal_force * ramp * normal_share * v[1] + top_tangential * share * v[0];
    }
    if before.step >= m.prep_steps {
        // The interface prestress is a load on the interface blocks.
        for ix in 0..m.nx {
            p.top_loads += m.interface_shear(ix) * vbar(ix)[0];
        }
    }
    for ix in 0..m.nx {
        // Friction of step n is in the snapshot after it.
        // The friction of the step before → after was evaluated at `before`.
        p.friction += before.friction.get(ix).copied().unwrap_or(0.0) * vbar(ix)[0];
    }
    for_each_bond(m, |i, j, r0, _, _| {
        let (vi, vj) = (vbar(i), vbar(j));
        let dv = [vj[0] - vi[0], vj[1] - vi[1]];
        p.damping += match m.damping_form {
            DampingForm::Full => m.eta * (dv[0] * dv[0] + dv[1] * dv[1]),
            DampingForm::Bond => {
                let du = [
                    before.disp[j][0] - before.disp[i][0],
                    before.disp[j][1] - before.disp[i][1],
                ];
                let r = [r0[0] + du[0], r0[1] + du[1]];
                let len = (r[0] * r[0] + r[1] * r[1]).sqrt();
                let along = (dv[0] * r[0] + dv[1] * r[1]) / len;
                m.eta * along * along
            }
        };
    });
    let absolute_eta = if before.step >= m.prep_steps {
        m.absolute_eta
    } else if before.step >= m.ramp_steps {
        m.relax_eta
    } else {
        0.0
    };
    if absolute_eta > 0.0 {
        for i in 0..m.n_blocks() {
            let v = vbar(i);
            p.damping += absolute_eta * (v[0] * v[0] + v[1] * v[1]);
        }
    }
    p
}
