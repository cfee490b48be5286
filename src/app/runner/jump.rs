//! A quasi-static jump carried out: the output records on its path, its
//! energy ledger, and the engine moved to its end.

use super::outputs::Outputs;
use super::RunError;
use crate::engines::cpu::fast::SweepEngine;
use crate::engines::quasistatic::{FastForward, Jump};
use crate::engines::step_params::{step_params, Consts};
use crate::engines::{Engine, Snapshot};
use crate::io::output::records::RecordBuilder;
use crate::model::Model;

/// Performs a planned quasi-static jump: writes the output samples due on
/// the path (exact: the path is the equilibrium), books the energy, records
/// it, and moves the engine to the jump's end.
pub(super) fn perform_jump(
    engine: &mut dyn Engine,
    outputs: &mut Outputs,
    ff: &mut FastForward,
    dynamic: &Snapshot,
    jump: &mut Jump,
) -> Result<(), RunError> {
    let model = engine.model().clone();
    let origin = outputs.origin;
    let path = &jump.path;
    let s1 = path.end_step;
    // One evaluator per stretch (its junction arrays), and one for the end:
    // the sweep engine's force pass, the reference's bits at a fraction of
    // its cost (the reference's took 60% of a fast-forwarded run).
    let mut evaluators = path
        .segments
        .iter()
        .map(|seg| SweepEngine::<f64>::with_junctions(&model, &seg.base, origin))
        .collect::<Result<Vec<_>, _>>()?;
    let mut end_evaluator = SweepEngine::<f64>::with_junctions(&model, &path.end, origin)?;
    let eval = |e: &mut SweepEngine<f64>, step: u64, disp: &[[f64; 2]], w: &[[f64; 2]]| {
        e.set_kinematics(step, disp, w)?;
        e.snapshot()
    };
    let end = eval(&mut end_evaluator, s1, &path.end.disp, &path.end_w)?;
    let mut s = jump.record.start_step;
    loop {
        s = outputs.next_due(s);
        if s > s1 || s == u64::MAX {
            break;
        }
        let snap = if s == s1 {
            end.clone()
        } else {
            let k = path
                .segments
                .iter()
                .position(|seg| seg.start_step <= s && s < seg.end_step)
                .expect("the stretches cover the jump");
            let seg = &path.segments[k];
            eval(&mut evaluators[k], s, &seg.disp_at(s), &seg.w)?
        };
        outputs.emit(&snap)?;
    }
    // The energy: relaxations (the quiet state's ring-down, and the
    // slider's settling after each junction event) are dropped and booked
    // as dissipated; along each stretch, work in and dashpot loss.
    let mut record = jump.record.clone();
    let mut before = dynamic.clone();
    for (k, seg) in path.segments.iter().enumerate() {
        let e = &mut evaluators[k];
        let start = eval(e, seg.start_step, &seg.base.disp, &seg.w)?;
        // The relaxation's force law: the stretch's junction arrays, and
        // slipping junctions pulling against the quasi-static velocity.
        let before_new_law = eval(e, seg.start_step, &before.disp, &seg.w)?;
        record.dropped_energy += relaxation_drop(&model, &before, &before_new_law, &start, origin);
        let end_of_stretch = eval(e, seg.end_step, &seg.end_disp, &seg.w)?;
        let (work_in, damping) = path_work(&model, &start, &end_of_stretch, origin);
        record.work_in += work_in;
        record.damping += damping;
        record.stored_change +=
            crate::analysis::energy::stored_energy(&model, &end_of_stretch, origin).total()
                - crate::analysis::energy::stored_energy(&model, &start, origin).total();
        before = end_of_stretch;
    }
    if before.step == s1 && before.disp != end.disp {
        // The path ended at an event: its settling is dropped too.
        let before_new_law = eval(&mut end_evaluator, s1, &before.disp, &path.end_w)?;
        record.dropped_energy += relaxation_drop(&model, &before, &before_new_law, &end, origin);
    }
    jump.record = record;
    outputs.send(RecordBuilder::fast_forward(&jump.record))?;
    engine.set_junctions(&path.end)?;
    engine.set_kinematics(s1, &path.end.disp, &path.end_w)?;
    ff.book(&model, &jump.record, path.path_error);
    Ok(())
}

/// Energy (J) a relaxation at fixed time drops: from `before` to the
/// equilibrium `after` under the junction law after it (`before_new_law`:
/// that law's forces at `before`'s displacement). Stored energy lost, plus
/// the work the junction forces (linear in u_x along the relaxation) and
/// the top loads (constant) do; the side spring's far end does not move.
pub fn relaxation_drop(
    model: &Model,
    before: &Snapshot,
    before_new_law: &Snapshot,
    after: &Snapshot,
    origin: f64,
) -> f64 {
    use crate::analysis::energy::stored_energy;
    let mut work = 0.0;
    for ix in 0..model.nx {
        let du = after.disp[ix][0] - before.disp[ix][0];
        work += 0.5 * (before_new_law.friction[ix] + after.friction[ix]) * du;
    }
    let loads = step_params(&Consts::<f64>::new(model), before.step);
    for ix in 0..model.nx {
        let i = (model.nz - 1) * model.nx + ix;
        let share = model.top_share(ix);
        work += share * loads.top_tangential_total * (after.disp[i][0] - before.disp[i][0])
            - model.normal_share(ix) * loads.normal_total * (after.disp[i][1] - before.disp[i][1]);
    }
    stored_energy(model, before, origin).total() - stored_energy(model, after, origin).total()
        + work
}

/// Work in and dashpot loss (J) along a stretch of the quasi-static path
/// (trapezoid rule: exact for its linear forces and constant velocities).
pub fn path_work(model: &Model, start: &Snapshot, end: &Snapshot, origin: f64) -> (f64, f64) {
    use crate::analysis::energy::step_power;
    let (pa, pb) = (
        step_power(model, start, start, origin),
        step_power(model, end, end, origin),
    );
    let span = end.time - start.time;
    let work_in = 0.5
        * span
        * (pa.drive + pa.top_loads + pa.friction + pb.drive + pb.top_loads + pb.friction);
    (work_in, 0.5 * span * (pa.damping + pb.damping))
}
