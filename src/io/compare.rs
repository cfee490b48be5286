//! Comparing two engine states field by field (the GPU against the CPU
//! reference): the maximum error of each field relative to its scale.

use crate::engines::Snapshot;

/// Maximum |a − b| of one field, and the field's scale (max |a|).
#[derive(Debug, Clone, PartialEq)]
pub struct FieldError {
    pub field: &'static str,
    pub max_error: f64,
    pub scale: f64,
}

impl FieldError {
    /// Error relative to the field's scale (0 when both are zero).
    pub fn relative(&self) -> f64 {
        if self.scale > 0.0 {
            self.max_error / self.scale
        } else {
            self.max_error
        }
    }
}

fn field(name: &'static str, a: &[f64], b: &[f64]) -> FieldError {
    let max_error = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let scale = a.iter().map(|x| x.abs()).fold(0.0, f64::max);
    FieldError {
        field: name,
        max_error: if a.len() == b.len() {
            max_error
        } else {
            f64::INFINITY
        },
        scale,
    }
}

/// Per-field errors of `b` against the reference `a`.
pub fn compare_snapshots(a: &Snapshot, b: &Snapshot) -> Vec<FieldError> {
    let comp = |s: &Snapshot, k: usize, v: bool| -> Vec<f64> {
        let src = if v { &s.vel } else { &s.disp };
        src.iter().map(|x| x[k]).collect()
    };
    let as_f64 = |v: &[u32]| v.iter().map(|&x| x as f64).collect::<Vec<_>>();
    vec![
        field("ux", &comp(a, 0, false), &comp(b, 0, false)),
        field("uz", &comp(a, 1, false), &comp(b, 1, false)),
        field("vx", &comp(a, 0, true), &comp(b, 0, true)),
        field("vz", &comp(a, 1, true), &comp(b, 1, true)),
        field("friction", &a.friction, &b.friction),
        field("normal", &a.normal, &b.normal),
        field("anchor", &a.anchor, &b.anchor),
        field(
            "junction_stiffness",
            &a.junction_stiffness,
            &b.junction_stiffness,
        ),
        field("ruptures", &as_f64(&a.ruptures), &as_f64(&b.ruptures)),
        field("law_state", &a.law_state, &b.law_state),
    ]
}

/// Fields whose relative error exceeds `tolerance`; velocity errors under
/// `velocity_floor` (m/s) pass whatever their scale.
pub fn fields_over(errors: &[FieldError], tolerance: f64, velocity_floor: f64) -> Vec<String> {
    errors
        .iter()
        .filter(|e| {
            let floor = e.field.starts_with('v') && e.max_error <= velocity_floor;
            !(e.relative() <= tolerance || floor)
        })
        .map(|e| format!("{}: {:.3e} of {:.3e}", e.field, e.max_error, e.scale))
        .collect()
}

/// What a long side-driven run is about, for comparing precisions and
/// engines: the precursors before the first full event (lengths and F/F_N)
/// and the time and F/F_N of the first full event.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOutcome {
    /// (rupture length in m, F/F_N at its start, start time in s) of each
    /// precursor.
    pub precursors: Vec<(f64, f64, f64)>,
    /// (start time in s, F/F_N) of the first full event.
    pub first_full: Option<(f64, f64)>,
}

impl RunOutcome {
    /// The outcome recorded in a run file (events as `info` finds them).
    pub fn from_run(run: &crate::io::output::reader::RunFile, quiet_gap: f64) -> RunOutcome {
        let events = run.interface_series().events_separated_by(quiet_gap);
        let first = events.iter().position(|e| e.full);
        let before = &events[..first.unwrap_or(events.len())];
        RunOutcome {
            precursors: before
                .iter()
                .map(|e| (e.rupture_length, run.drive_ratio_at(e.start), e.start))
                .collect(),
            first_full: first.map(|k| (events[k].start, run.drive_ratio_at(events[k].start))),
        }
    }

    /// One line: "30.0 mm, 50.0 mm; first full event at t = … s, F/F_N …".
    pub fn describe(&self) -> String {
        let lengths: Vec<String> = self
            .precursors
            .iter()
            .map(|p| format!("{:.1} mm", p.0 * 1e3))
            .collect();
        let full = match self.first_full {
            Some((t, r)) => format!("first full event at t = {t:.6} s, F/F_N {r:.5}"),
            None => "no full event".into(),
        };
        format!("precursors [{}]; {full}", lengths.join(", "))
    }
}

/// Where `other` departs from `reference`: a different precursor count or
/// precursor lengths, a precursor or the first full event more than
/// `rel_tol` (relative) away in start time or F/F_N. Empty when they agree.
pub fn outcome_mismatch(reference: &RunOutcome, other: &RunOutcome, rel_tol: f64) -> Vec<String> {
    let mut out = Vec::new();
    let lengths = |o: &RunOutcome| o.precursors.iter().map(|p| p.0).collect::<Vec<_>>();
    // Rupture lengths are whole numbers of blocks: equal, or a block apart.
    let same_lengths = lengths(reference)
        .iter()
        .zip(lengths(other))
        .all(|(a, b)| (a - b).abs() <= 1e-9 * a.abs().max(1e-3));
    if reference.precursors.len() != other.precursors.len() || !same_lengths {
        out.push(format!(
            "precursors differ: {:?} m against {:?} m",
            lengths(reference),
            lengths(other)
        ));
    }
    if out.is_empty() {
        for (k, (a, b)) in reference
            .precursors
            .iter()
            .zip(&other.precursors)
            .enumerate()
        {
            if (a.2 - b.2).abs() > rel_tol * a.2.abs() || (a.1 - b.1).abs() > rel_tol * a.1.abs() {
                out.push(format!(
                    "precursor {k} at t = {} s, F/F_N {} against t = {} s, F/F_N {}",
                    b.2, b.1, a.2, a.1
                ));
            }
        }
    }
    match (reference.first_full, other.first_full) {
        (Some((ta, ra)), Some((tb, rb))) => {
            if (ta - tb).abs() > rel_tol * ta.abs() {
                out.push(format!("first full event at t = {tb} s against {ta} s"));
            }
            if (ra - rb).abs() > rel_tol * ra.abs() {
                out.push(format!("first full event at F/F_N {rb} against {ra}"));
            }
        }
        (None, None) => {}
        (a, b) => out.push(format!("first full event {b:?} against {a:?}")),
    }
    out
}

/// Per-field errors of run file `b` against the reference `a`, channel by
/// channel (each field over all its samples, relative to its scale), or the
/// first place their records differ in count or step.
pub fn compare_run_files(
    a: &crate::io::output::reader::RunFile,
    b: &crate::io::output::reader::RunFile,
) -> Result<Vec<FieldError>, String> {
    let steps = |name: &str, x: Vec<u64>, y: Vec<u64>| -> Result<(), String> {
        if x.len() != y.len() {
            return Err(format!("{name}: {} records against {}", y.len(), x.len()));
        }
        match x.iter().zip(&y).position(|(p, q)| p != q) {
            Some(k) => Err(format!(
                "{name}: record {k} is at step {} against {}",
                y[k], x[k]
            )),
            None => Ok(()),
        }
    };
    steps(
        "/global",
        a.global.iter().map(|g| g.step).collect(),
        b.global.iter().map(|g| g.step).collect(),
    )?;
    steps(
        "/interface",
        a.interface.iter().map(|r| r.step).collect(),
        b.interface.iter().map(|r| r.step).collect(),
    )?;
    steps(
        "/bulk",
        a.bulk.iter().map(|r| r.step).collect(),
        b.bulk.iter().map(|r| r.step).collect(),
    )?;
    let series = |run: &crate::io::output::reader::RunFile,
                  f: &dyn Fn(&crate::io::output::messages::Global) -> f64| {
        run.global.iter().map(f).collect::<Vec<f64>>()
    };
    let rows = |run: &crate::io::output::reader::RunFile,
                f: &dyn Fn(&crate::io::output::messages::Interface) -> &Vec<f64>| {
        run.interface
            .iter()
            .flat_map(|r| f(r).clone())
            .collect::<Vec<f64>>()
    };
    let bulk = |run: &crate::io::output::reader::RunFile,
                f: &dyn Fn(&crate::io::output::messages::Bulk) -> &Vec<f32>| {
        run.bulk
            .iter()
            .flat_map(|r| f(r).iter().map(|&x| x as f64))
            .collect::<Vec<f64>>()
    };
    Ok(vec![
        field(
            "global.drive_force",
            &series(a, &|g| g.drive_force),
            &series(b, &|g| g.drive_force),
        ),
        field(
            "global.friction_force",
            &series(a, &|g| g.friction_force),
            &series(b, &|g| g.friction_force),
        ),
        field(
            "global.pinned_fraction",
            &series(a, &|g| g.pinned_fraction),
            &series(b, &|g| g.pinned_fraction),
        ),
        field(
            "global.kinetic_energy",
            &series(a, &|g| g.kinetic_energy),
            &series(b, &|g| g.kinetic_energy),
        ),
        field(
            "global.ruptures",
            &series(a, &|g| g.ruptures as f64),
            &series(b, &|g| g.ruptures as f64),
        ),
        field(
            "interface.shear_stress",
            &rows(a, &|r| &r.shear_stress),
            &rows(b, &|r| &r.shear_stress),
        ),
        field(
            "interface.normal_stress",
            &rows(a, &|r| &r.normal_stress),
            &rows(b, &|r| &r.normal_stress),
        ),
        field(
            "interface.pinned_fraction",
            &rows(a, &|r| &r.pinned_fraction),
            &rows(b, &|r| &r.pinned_fraction),
        ),
        field(
            "interface.slip",
            &rows(a, &|r| &r.slip),
            &rows(b, &|r| &r.slip),
        ),
        field(
            "interface.slip_speed",
            &rows(a, &|r| &r.slip_speed),
            &rows(b, &|r| &r.slip_speed),
        ),
        field("bulk.ux", &bulk(a, &|r| &r.ux), &bulk(b, &|r| &r.ux)),
        field("bulk.uz", &bulk(a, &|r| &r.uz), &bulk(b, &|r| &r.uz)),
        field("bulk.vx", &bulk(a, &|r| &r.vx), &bulk(b, &|r| &r.vx)),
        field("bulk.vz", &bulk(a, &|r| &r.vz), &bulk(b, &|r| &r.vz)),
    ])
}
