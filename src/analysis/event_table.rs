//! The event table of a run, one row per slip event, as `slipfront info`
//! prints it, `info --events-csv` writes it and the Python package returns
//! it: one definition of each column.

use super::events::{Event, InterfaceSeries, FRONT_WINDOW};

/// One event's row, beside the [`Event`] itself.
#[derive(Debug, Clone)]
pub struct EventRow {
    /// "full" (the whole interface slipped) or "partial".
    pub kind: &'static str,
    /// Where the event started along the interface (m).
    pub origin: f64,
    /// F/F_N when it started.
    pub drive_ratio: f64,
    /// The front's speed profile, classified (`FrontKind`, as text).
    pub front: String,
    /// Slowest and fastest resolved front speed (m/s).
    pub speeds: Option<(f64, f64)>,
    /// The largest lower bound of the windows the samples do not resolve
    /// (the front crossed them between two samples).
    pub bound: Option<f64>,
}

impl EventRow {
    pub fn new(series: &InterfaceSeries, e: &Event, drive_ratio: f64) -> Self {
        let (speeds, bound) = series.resolved_front_speeds(e, FRONT_WINDOW);
        EventRow {
            kind: if e.full { "full" } else { "partial" },
            origin: e.origin(series.spacing),
            drive_ratio,
            front: format!("{:?}", series.front_kind(e, FRONT_WINDOW)),
            speeds: speeds.iter().fold(None, |a, &v| match a {
                None => Some((v, v)),
                Some((lo, hi)) => Some((f64::min(lo, v), f64::max(hi, v))),
            }),
            bound,
        }
    }

    /// "1.2e2..3.4e3", "1.2e2..3.4e3, ≥4.3e3 unresolved" or "≥4.3e3".
    pub fn speed_range(&self) -> String {
        let bound = self.bound.map(|b| format!("≥{b:.3e} unresolved"));
        match (self.speeds, bound) {
            (Some((lo, hi)), Some(b)) => format!("{lo:.3e}..{hi:.3e}, {b}"),
            (Some((lo, hi)), None) => format!("{lo:.3e}..{hi:.3e}"),
            (None, Some(b)) => b,
            (None, None) => "-".into(),
        }
    }
}

/// The events of `series` (ruptures less than `quiet_gap` seconds apart are
/// one event), each with its row; `ratio_at` gives F/F_N at a time.
pub fn event_rows(
    series: &InterfaceSeries,
    quiet_gap: f64,
    ratio_at: impl Fn(f64) -> f64,
) -> Vec<(Event, EventRow)> {
    series
        .events_separated_by(quiet_gap)
        .into_iter()
        .map(|e| {
            let row = EventRow::new(series, &e, ratio_at(e.start));
            (e, row)
        })
        .collect()
}
