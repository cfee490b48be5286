//! Branching: which scenario keys may differ from the saved run's, and the
//! driver's continuity across a changed drive.

use super::RunnerState;
use crate::engines::step_params::{step_params, Consts};
use crate::engines::EngineState;
use crate::model::scenario::{DriveMode, Scenario};
use crate::model::{Driver, Model};
use std::collections::BTreeMap;

/// Keys that change nothing of the saved state's meaning.
const FREE: &[&str] = &[
    "name",
    "output.",
    "fast_forward.",
    "time.end",
    "time.seed",
    "time.fast_forward",
    "friction.static_coefficient",
    "friction.dynamic_coefficient",
    "friction.junctions.slip_time_",
    "friction.junctions.stiffness",
    "friction.junctions.stiffness_coefficient",
    "friction.junctions.constant_stiffness",
    "loading.drive.",
];

/// Keys that nothing before the start of driving reads (junctions cannot
/// break, the drive is off, the trigger's strips and spread act when
/// driving starts): scenes that differ only in these have the same
/// normal-load phase, bit for bit. Not the junction stiffness (pinned
/// junctions follow it while the load is applied) nor the trigger's
/// prestress (it loads the top row from the start).
const LOADING_FREE: &[&str] = &[
    "name",
    "output.",
    "fast_forward.",
    "time.end",
    "time.seed",
    "time.fast_forward",
    "friction.static_coefficient",
    "friction.dynamic_coefficient",
    "friction.junctions.slip_time_",
    "loading.drive.",
    "loading.trigger.force_width",
    "loading.trigger.strip_length",
    "loading.trigger.strip_prestress",
];

fn listed(key: &str, list: &[&str]) -> bool {
    list.iter()
        .any(|f| key == *f || (f.ends_with(['.', '_']) && key.starts_with(f)))
}

/// `a` and `b` have the same normal-load phase: a state saved one step
/// before `a` starts driving continues as `b` exactly as `b` itself would
/// (what lets a sweep load the slider once for many points).
pub fn same_loading(a: &Scenario, b: &Scenario) -> bool {
    changed_keys(a, b)
        .iter()
        .all(|(key, _, _)| listed(key, LOADING_FREE))
}

/// Every leaf of a scenario as `dotted.key → value`.
fn leaves(s: &Scenario) -> BTreeMap<String, String> {
    fn walk(prefix: &str, v: &toml::Value, out: &mut BTreeMap<String, String>) {
        match v {
            toml::Value::Table(t) => {
                for (k, v) in t {
                    let key = if prefix.is_empty() {
                        k.clone()
                    } else {
                        format!("{prefix}.{k}")
                    };
                    walk(&key, v, out);
                }
            }
            other => {
                out.insert(prefix.to_string(), other.to_string());
            }
        }
    }
    let mut out = BTreeMap::new();
    let value = toml::Value::try_from(s).expect("a scenario is a TOML table");
    walk("", &value, &mut out);
    out
}

/// The keys whose values differ, as "key: old → new".
pub fn changed_keys(parent: &Scenario, child: &Scenario) -> Vec<(String, String, String)> {
    let (a, b) = (leaves(parent), leaves(child));
    let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
    let absent = || "(absent)".to_string();
    keys.into_iter()
        .filter(|k| a.get(*k) != b.get(*k))
        .map(|k| {
            (
                k.clone(),
                a.get(k).cloned().unwrap_or_else(absent),
                b.get(k).cloned().unwrap_or_else(absent),
            )
        })
        .collect()
}

/// Checks that `child` may continue from a state of `parent` at `step`;
/// returns the changed keys ("key = old → new"), or every refusal, each
/// naming its key and why.
pub fn check(
    parent: &Scenario,
    parent_model: &Model,
    child: &Scenario,
    child_model: &Model,
    step: u64,
) -> Result<Vec<String>, Vec<String>> {
    let prep = parent_model.prep_steps;
    let driving = step >= prep;
    let t = parent_model.time_of_step(step).max(0.0);
    let mut refusals = Vec::new();
    let mut changed = Vec::new();
    for (key, old, new) in changed_keys(parent, child) {
        changed.push(format!("{key} = {old} → {new}"));
        let free = listed(&key, FREE);
        if key == "loading.trigger.shear_prestress" {
            let value = |s: &Scenario| {
                s.loading
                    .trigger
                    .as_ref()
                    .map_or(0.0, |t| t.shear_prestress)
            };
            if value(parent) != value(child) && step > 0 {
                refusals.push(format!(
                    "{key} = {old} → {new}: the prestress also sets the top row's tangential \
                     force during the normal-load phase, so the saved state depends on it"
                ));
            }
        } else if key.starts_with("loading.trigger.") {
            if driving {
                refusals.push(format!(
                    "{key} = {old} → {new}: the trigger acts when driving starts (step {prep}), \
                     and this state is at step {step}, after it; branch from a checkpoint \
                     taken during the normal-load phase"
                ));
            }
        } else if !free {
            refusals.push(format!(
                "{key} = {old} → {new}: fixed by the saved state (the lattice, material, \
                 damping, normal load, boundaries and time step cannot change under it)"
            ));
        }
    }
    let top_force = child.loading.drive.mode == DriveMode::TopForce;
    let force_changes = parent.loading.drive.mode != DriveMode::TopForce
        || parent.loading.drive.force_rate != child.loading.drive.force_rate;
    if top_force && force_changes && step > prep {
        refusals.push(format!(
            "loading.drive.force_rate: the top force is the rate times the time since \
             driving started, so a new rate at t = {t:.6e} s would make it jump; branch from \
             the checkpoint at the start of driving (a run with --t-end 0)"
        ));
    }
    if child_model.total_steps() < step {
        refusals.push(format!(
            "time.end = {:e} s is before the saved state (t = {t:.6e} s)",
            child.time.end
        ));
    }
    if refusals.is_empty() {
        Ok(changed)
    } else {
        Err(refusals)
    }
}

/// Keeps the side spring continuous across a branch that changes the
/// drive: with the same spring and a new velocity, its far end goes on from
/// where it is (the origin moves by (V_old − V_new)·t); a spring that was
/// not there before starts unstretched. Nothing changes before driving
/// starts (the origin is set then) or when the drive is unchanged.
pub fn rebase_drive(
    parent: &Model,
    child: &Model,
    state: &mut EngineState,
    runner: &mut RunnerState,
) {
    if state.step < child.prep_steps || parent.driver == child.driver {
        return;
    }
    let Driver::SideSpring { row, .. } = child.driver else {
        return;
    };
    let offset = |m: &Model| step_params(&Consts::<f64>::new(m), state.step).drive_offset;
    let origin = match parent.driver {
        Driver::SideSpring { row: r, .. } if r == row => {
            state.drive_origin_value() + offset(parent) - offset(child)
        }
        _ => {
            let u = state.disp[row * child.nx][0];
            u[0] + u[1] - offset(child)
        }
    };
    state.drive_origin = [origin, 0.0];
    runner.origin = origin;
}
