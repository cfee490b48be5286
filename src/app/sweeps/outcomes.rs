//! What a sweep records of each run: the event analysis of its output
//! (first full event, precursors, events, fronts, slip; the first event;
//! the median speed of the slow front windows, below `SLOW_FRONT`, and of
//! the slip behind their tips; the first front's class), as table fields.

use crate::analysis::events::{FrontKind, DEFAULT_QUIET_GAP};
use crate::analysis::precursors::PrecursorSequence;
use crate::analysis::stats::Quartiles;
use crate::io::output::reader::RunFile;

/// Blocks per front-speed window (as `info`).
const FRONT_WINDOW: usize = 3;

/// The outcome fields of a finished run, in `table::OUTCOMES` order after
/// status and message, up to and without peak_drive_ratio, steps, wall_s.
pub fn analyse(run: &RunFile) -> Vec<String> {
    let series = run.interface_series();
    let events = series.events_separated_by(DEFAULT_QUIET_GAP);
    let ratio_at = |t: f64| run.drive_ratio_at(t);
    let precursors = PrecursorSequence::from_events(&events, series.spacing, |e| ratio_at(e.start));
    let first_full = events.iter().find(|e| e.full);
    let mut speeds = Vec::new();
    let mut kinds = [0usize; 4];
    // (front speed, slip speed behind the tip) on the slow windows.
    let mut slow = Vec::new();
    for e in &events {
        speeds.extend(series.resolved_front_speeds(e, FRONT_WINDOW).0);
        slow.extend(series.slow_windows(e, FRONT_WINDOW));
        kinds[match series.front_kind(e, FRONT_WINDOW) {
            FrontKind::Fast => 0,
            FrontKind::Slow => 1,
            FrontKind::FastSlow => 2,
            FrontKind::FastSlowFast => 3,
        }] += 1;
    }
    let number = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:e}"));
    let lengths: Vec<String> = precursors
        .precursors
        .iter()
        .map(|p| format!("{:e}", p.length))
        .collect();
    let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
    let slips: Vec<f64> = events.iter().map(|e| e.slip).collect();
    let mut out = vec![
        number(first_full.map(|e| e.start)),
        number(first_full.map(|e| ratio_at(e.start))),
        events.len().to_string(),
        events.iter().filter(|e| e.full).count().to_string(),
        precursors.precursors.len().to_string(),
        lengths.join(";"),
        number(
            precursors
                .precursors
                .iter()
                .map(|p| p.length)
                .reduce(f64::max),
        ),
        number(events.iter().map(|e| e.rupture_length).reduce(f64::max)),
        number(mean(&speeds)),
        number(speeds.iter().copied().reduce(f64::max)),
    ];
    out.extend(kinds.iter().map(|k| k.to_string()));
    out.push(number(mean(&slips)));
    let first = events.first();
    out.push(number(first.map(|e| e.start)));
    out.push(number(first.map(|e| e.rupture_length)));
    let median = |v: Vec<f64>| Quartiles::of(&v).map(|q| q.median);
    out.push(number(median(slow.iter().map(|p| p.0).collect())));
    out.push(number(median(slow.iter().map(|p| p.1).collect())));
    out.push(first.map_or(String::new(), |e| {
        series.front_class(e, FRONT_WINDOW).name().to_string()
    }));
    out
}
