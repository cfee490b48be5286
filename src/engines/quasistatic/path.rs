//! The quasi-static path of a jump, through isolated junction events.
//!
//! Between events the equilibrium moves with the drive (quadratic through
//! settled equilibria, see [`Segment`]). A junction that reaches μs·f_N
//! breaks, slips at μd·f_N for its drawn slip time (the same counter-based
//! draw as the junction kernel) and re-pins with zero stretch at the
//! stiffness of its normal force then, as in full dynamics; the slider
//! settles to the new equilibrium at the event's step. An event whose
//! release could set off a neighbour (a pinned junction whose margin below
//! threshold after the event is smaller than the force the event added to
//! it, the bound on a step load's dynamic overshoot) ends the path a lead
//! time before it, so that full dynamics perform it.

use super::equilibrium::{drive_response, settle, QuasiStaticError, Solver};
use super::tangent::Tangent;
use super::threshold::{first_change, threshold_margin, PathEnd};
use super::{quadratic, SETTLE_TOLERANCE};
use crate::engines::step_params::Consts;
use crate::engines::Snapshot;
use crate::model::friction::junctions::break_threshold;
use crate::model::junction::PINNED;
use crate::model::Model;

/// One stretch of a jump with fixed junction arrays.
#[derive(Debug, Clone)]
pub struct Segment {
    /// Junction arrays of the stretch; `disp` is its settled start.
    pub base: Snapshot,
    pub start_step: u64,
    pub end_step: u64,
    pub mid_disp: Vec<[f64; 2]>,
    /// Settled at `end_step` with this stretch's arrays (before the event
    /// that ends it).
    pub end_disp: Vec<[f64; 2]>,
    /// The quasi-static velocity field.
    pub w: Vec<[f64; 2]>,
}

impl Segment {
    pub fn mid_step(&self) -> u64 {
        self.start_step + (self.end_step - self.start_step) / 2
    }

    /// The equilibrium at a step of the stretch: the quadratic through the
    /// settled start, middle and end (the path bends with the bonds'
    /// geometric nonlinearity; a straight line is off by ~3e-4 of the load
    /// change in the middle).
    pub fn disp_at(&self, step: u64) -> Vec<[f64; 2]> {
        quadratic(
            [self.start_step, self.mid_step(), self.end_step],
            [&self.base.disp, &self.mid_disp, &self.end_disp],
            step,
        )
    }
}

/// What a path does and where it ends.
#[derive(Debug, Clone)]
pub struct Path {
    pub segments: Vec<Segment>,
    /// The state the engine resumes from: arrays, settled displacement.
    pub end: Snapshot,
    pub end_w: Vec<[f64; 2]>,
    pub end_step: u64,
    /// What stopped the path (the first change full dynamics must do).
    pub stop: PathEnd,
    /// Predicted time of that change (s, run time).
    pub stop_time: f64,
    pub ruptures: u64,
    pub repins: u64,
    /// Largest distance of a stretch's quadratic from settled equilibria
    /// at its quarter points, relative to the stretch's largest motion.
    pub path_error: f64,
}

/// Inputs fixed over a path.
pub struct PathContext<'a> {
    pub model: &'a Model,
    pub drive_origin: f64,
    pub lead: u64,
    pub last_step: u64,
    pub response_scale: f64,
    pub settle_ends: bool,
    /// Isolated junction ruptures and re-pins handled on the path (else the
    /// path ends before the first rupture).
    pub events: bool,
    /// An event stays on the path only if every pinned junction's margin
    /// after it exceeds this many times the force it added.
    pub cascade_overshoot: f64,
}

impl PathContext<'_> {
    pub(crate) fn settled(
        &self,
        solver: &mut Solver,
        arrays: &Snapshot,
        k: &Tangent,
        w: &[[f64; 2]],
        step: u64,
        guess: Vec<[f64; 2]>,
    ) -> Result<Vec<[f64; 2]>, QuasiStaticError> {
        let mut d = guess;
        if self.settle_ends {
            settle(
                self.model,
                arrays,
                &mut d,
                w,
                step,
                self.drive_origin,
                k,
                solver,
                SETTLE_TOLERANCE,
            )?;
        }
        Ok(d)
    }

    pub(crate) fn response(
        &self,
        solver: &mut Solver,
        k: &Tangent,
    ) -> Result<Vec<[f64; 2]>, QuasiStaticError> {
        let mut w = drive_response(self.model, k, solver)?;
        for v in &mut w {
            *v = v.map(|x| x * self.response_scale);
        }
        Ok(w)
    }

    fn advance(&self, disp: &[[f64; 2]], w: &[[f64; 2]], steps: u64) -> Vec<[f64; 2]> {
        let t = steps as f64 * self.model.dt;
        disp.iter()
            .zip(w)
            .map(|(u, w)| [u[0] + w[0] * t, u[1] + w[1] * t])
            .collect()
    }
}

/// A junction event on the path.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Event {
    Rupture { ix: usize, junction: usize },
    Repin { ix: usize, junction: usize },
}

/// The first re-pin: (step, block, junction) of the slipping junction whose
/// countdown ends first (a junction with `left` steps to go re-pins at the
/// force pass of step `now + left`).
fn next_repin(snap: &Snapshot, nx: usize, now: u64) -> Option<(u64, usize, usize)> {
    let ns = snap.slip_steps_left.len() / nx.max(1);
    snap.slip_steps_left
        .iter()
        .enumerate()
        .filter(|(_, &s)| s != PINNED)
        .map(|(j, &s)| (now + s as u64, j / ns, j % ns))
        .min()
}

/// Force of pinned junction `j` on its block at u_x.
fn junction_force(snap: &Snapshot, j: usize, ux: f64) -> f64 {
    -snap.junction_stiffness[j] * (ux - snap.anchor[j])
}

/// Builds the path from the quiet state `start` (its junction arrays,
/// displacement already settled at `start.step`, velocity field `w`).
pub fn build(
    cx: &PathContext<'_>,
    solver: &mut Solver,
    start: Snapshot,
    k: Tangent,
    w: Vec<[f64; 2]>,
) -> Result<Option<Path>, QuasiStaticError> {
    let model = cx.model;
    let consts = Consts::<f64>::new(model);
    let ns = start.slip_steps_left.len() / model.nx.max(1);
    // The law's break threshold per metre of indentation (f_N = k_f·d/Ns).
    let per_junction = break_threshold(model.mu_s, model.k_foundation / ns.max(1) as f64);
    let (mut base, mut k, mut w) = (start, k, w);
    let mut now = base.step;
    let mut segments: Vec<Segment> = Vec::new();
    let (mut ruptures, mut repins) = (0u64, 0u64);
    let mut path_error = 0.0f64;
    // Closes a stretch [from, to] of `base`: settles its middle and end and
    // measures the quadratic at the quarter points.
    let close = |solver: &mut Solver,
                 base: &Snapshot,
                 k: &Tangent,
                 w: &[[f64; 2]],
                 to: u64,
                 path_error: &mut f64|
     -> Result<Segment, QuasiStaticError> {
        let from = base.step;
        let end_disp = cx.settled(solver, base, k, w, to, cx.advance(&base.disp, w, to - from))?;
        let mid = from + (to - from) / 2;
        let mid_disp = cx.settled(
            solver,
            base,
            k,
            w,
            mid,
            cx.advance(&base.disp, w, mid - from),
        )?;
        let seg = Segment {
            base: base.clone(),
            start_step: from,
            end_step: to,
            mid_disp,
            end_disp,
            w: w.to_vec(),
        };
        let scale = base
            .disp
            .iter()
            .zip(&seg.end_disp)
            .map(|(a, b)| (b[0] - a[0]).abs().max((b[1] - a[1]).abs()))
            .fold(0.0, f64::max)
            .max(1e-300);
        for q in [from + (to - from) / 4, from + 3 * (to - from) / 4] {
            if q == from || q == mid || q == to {
                continue;
            }
            let guess = seg.disp_at(q);
            let settled = cx.settled(solver, base, k, w, q, guess.clone())?;
            for (a, b) in guess.iter().zip(&settled) {
                *path_error = path_error.max((a[0] - b[0]).abs().max((a[1] - b[1]).abs()) / scale);
            }
        }
        Ok(seg)
    };
    let time = |step: u64| model.time_of_step(step);
    let (stop, stop_time) = loop {
        let (tau, change) = first_change(model, &base, &base.disp, &w);
        let change_step = if tau.is_finite() {
            now.saturating_add((tau / model.dt).floor() as u64 + 1)
        } else {
            u64::MAX
        };
        let repin = if cx.events {
            next_repin(&base, model.nx, now)
        } else {
            None
        };
        let repin_step = repin.map_or(u64::MAX, |r| r.0);
        let event_step = change_step.min(repin_step);
        let event = match change {
            _ if repin_step <= change_step => {
                repin.map(|(_, ix, junction)| Event::Repin { ix, junction })
            }
            PathEnd::Rupture { ix, junction } if cx.events => Some(Event::Rupture { ix, junction }),
            _ => None,
        };
        // Ends the path a lead time before `step` (or at the end of the
        // run), backing off while the bonds' nonlinearity has moved a
        // crossing before the target.
        let finish = |solver: &mut Solver,
                      base: &mut Snapshot,
                      now: &mut u64,
                      step: u64,
                      segments: &mut Vec<Segment>,
                      path_error: &mut f64|
         -> Result<(), QuasiStaticError> {
            let mut target = if step > cx.last_step {
                cx.last_step
            } else {
                step.saturating_sub(cx.lead)
            };
            while target > *now {
                let seg = close(solver, base, &k, &w, target, path_error)?;
                if threshold_margin(model, base, &seg.end_disp) > 0.0 {
                    base.disp = seg.end_disp.clone();
                    base.step = target;
                    segments.push(seg);
                    *now = target;
                    break;
                }
                target = *now + (target - *now) / 2;
            }
            Ok(())
        };
        let Some(event) = event.filter(|_| event_step <= cx.last_step) else {
            let stop_time = time(now) + tau;
            finish(
                solver,
                &mut base,
                &mut now,
                event_step,
                &mut segments,
                &mut path_error,
            )?;
            break (change, stop_time);
        };
        let as_stop = match event {
            Event::Rupture { ix, junction } => PathEnd::Rupture { ix, junction },
            Event::Repin { ix, .. } => PathEnd::Contact { ix },
        };
        // The stretch up to the event, with the arrays before it (none when
        // the event is at the current step: two at once).
        let seg = if event_step > now {
            Some(close(solver, &base, &k, &w, event_step, &mut path_error)?)
        } else {
            None
        };
        let before = seg
            .as_ref()
            .map_or(base.disp.clone(), |s| s.end_disp.clone());
        let mut next = base.clone();
        next.step = event_step;
        next.disp = before.clone();
        let applied = match event {
            Event::Rupture { ix, junction } => {
                let j = ix * ns + junction;
                // Only this junction may be past its threshold at the event.
                let over = |jj: usize| {
                    let th = per_junction * (-before[jj / ns][1]).max(0.0);
                    next.slip_steps_left[jj] == PINNED
                        && junction_force(&next, jj, before[jj / ns][0]).abs() > th
                };
                let alone =
                    over(j) && (0..next.slip_steps_left.len()).all(|jj| jj == j || !over(jj));
                if alone {
                    let count = next.ruptures[j].wrapping_add(1);
                    next.ruptures[j] = count;
                    let n = crate::model::rng::slip_steps(
                        consts.seed,
                        ix as u32,
                        junction as u32,
                        count,
                        consts.slip_mean_steps,
                        consts.slip_std_steps,
                    );
                    next.slip_steps_left[j] = n.min(PINNED - 1);
                }
                alone
            }
            Event::Repin { ix, junction } => {
                let j = ix * ns + junction;
                let f_n = crate::model::laws::foundation_normal(model.k_foundation, before[ix][1])
                    / ns as f64;
                if f_n > 0.0 {
                    next.anchor[j] = before[ix][0];
                    next.junction_stiffness[j] = consts.junction_stiffness(f_n);
                    next.slip_steps_left[j] = PINNED;
                }
                f_n > 0.0
            }
        };
        let (ex, ej) = match event {
            Event::Rupture { ix, junction } | Event::Repin { ix, junction } => (ix, junction),
        };
        // Every other slipping junction's countdown advances to the event.
        for (jj, s) in next.slip_steps_left.iter_mut().enumerate() {
            if *s != PINNED && jj != ex * ns + ej {
                *s -= (event_step - now) as u32;
            }
        }
        let mut after = None;
        if applied {
            let k_next = Tangent::at(model, &next);
            let w_next = cx.response(solver, &k_next)?;
            let settled =
                cx.settled(solver, &next, &k_next, &w_next, event_step, before.clone())?;
            // Could the event set off a neighbour? Each pinned junction's
            // margin after it must exceed the force it added times the
            // assumed overshoot (one damped oscillator's step response
            // overshoots by at most its static change: factor 1).
            let safe = (0..next.slip_steps_left.len()).all(|jj| {
                if next.slip_steps_left[jj] != PINNED {
                    return true;
                }
                let b = jj / ns;
                let f_before = junction_force(&next, jj, before[b][0]);
                let f_after = junction_force(&next, jj, settled[b][0]);
                let th = per_junction * (-settled[b][1]).max(0.0);
                th - f_after.abs() > cx.cascade_overshoot * (f_after - f_before).abs()
            });
            if safe {
                after = Some((settled, k_next, w_next));
            }
        }
        let Some((settled, k_next, w_next)) = after else {
            // Full dynamics do this event: end a lead time before it.
            finish(
                solver,
                &mut base,
                &mut now,
                event_step,
                &mut segments,
                &mut path_error,
            )?;
            break (as_stop, time(event_step));
        };
        match event {
            Event::Rupture { .. } => ruptures += 1,
            Event::Repin { .. } => repins += 1,
        }
        segments.extend(seg);
        next.disp = settled;
        base = next;
        k = k_next;
        w = w_next;
        now = event_step;
    };
    if segments.is_empty() {
        return Ok(None);
    }
    let end_step = now;
    base.step = end_step;
    base.vel = w.clone();
    base.vel_half = w.clone();
    Ok(Some(Path {
        segments,
        end: base,
        end_w: w,
        end_step,
        stop,
        stop_time,
        ruptures,
        repins,
        path_error,
    }))
}
