//! The precursor sequence of a side-driven run: the partial events before
//! the first full sliding event, their rupture lengths against the driving
//! force, and whether the lengths grow with the force (the published
//! signature, Rubinstein et al. 2007; Trømborg et al. 2011, 2014).

use crate::analysis::events::Event;

/// One precursor: the driving ratio F/F_N at its start, its length and
/// where it started (m from the trailing edge).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Precursor {
    pub drive_ratio: f64,
    pub length: f64,
    pub origin: f64,
}

impl Precursor {
    /// Started at the trailing edge (within two blocks of it), where the
    /// driving spring loads the interface; others start inside, at an
    /// earlier arrest point.
    pub fn at_trailing_edge(&self, spacing: f64) -> bool {
        self.origin <= 2.0 * spacing
    }
}

/// The precursors of a run and the load of the first full event.
#[derive(Debug, Clone, PartialEq)]
pub struct PrecursorSequence {
    pub precursors: Vec<Precursor>,
    /// F/F_N at the start of the first full sliding event (None if none).
    pub first_full_ratio: Option<f64>,
}

impl PrecursorSequence {
    /// Splits `events` at the first full event; `ratio` gives F/F_N at the
    /// start of an event.
    pub fn from_events(events: &[Event], spacing: f64, ratio: impl Fn(&Event) -> f64) -> Self {
        let first_full = events.iter().position(|e| e.full);
        let before = &events[..first_full.unwrap_or(events.len())];
        PrecursorSequence {
            precursors: before
                .iter()
                .map(|e| Precursor {
                    drive_ratio: ratio(e),
                    length: e.rupture_length,
                    origin: e.origin(spacing),
                })
                .collect(),
            first_full_ratio: first_full.map(|k| ratio(&events[k])),
        }
    }

    /// Precursors that ruptured more than one block (`spacing` apart):
    /// a lone edge block slipping under the driving spring is creep at the
    /// loading point, not an arrested front.
    pub fn extended(&self, spacing: f64) -> Vec<Precursor> {
        self.precursors
            .iter()
            .copied()
            .filter(|p| p.length > 1.5 * spacing)
            .collect()
    }

    /// Extended precursors that started at the trailing edge: the
    /// published sequence.
    pub fn from_trailing_edge(&self, spacing: f64) -> Vec<Precursor> {
        self.extended(spacing)
            .into_iter()
            .filter(|p| p.at_trailing_edge(spacing))
            .collect()
    }

    /// Spearman rank correlation of length with F/F_N over `precursors`:
    /// +1 when every precursor is longer than the ones before it at lower
    /// load. None with fewer than three precursors.
    pub fn growth(precursors: &[Precursor]) -> Option<f64> {
        if precursors.len() < 3 {
            return None;
        }
        let load = ranks(&precursors.iter().map(|p| p.drive_ratio).collect::<Vec<_>>());
        let length = ranks(&precursors.iter().map(|p| p.length).collect::<Vec<_>>());
        Some(pearson(&load, &length))
    }
}

/// Ranks 1..n, ties sharing their mean rank.
fn ranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut rank = vec![0.0; values.len()];
    let mut i = 0;
    while i < order.len() {
        let mut j = i;
        while j + 1 < order.len() && values[order[j + 1]] == values[order[i]] {
            j += 1;
        }
        let mean = (i + j) as f64 / 2.0 + 1.0;
        for &k in &order[i..=j] {
            rank[k] = mean;
        }
        i = j + 1;
    }
    rank
}

fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    if va == 0.0 || vb == 0.0 {
        return 0.0;
    }
    cov / (va * vb).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn event(length: f64, full: bool, start: f64) -> Event {
        Event {
            first: 0,
            last: 0,
            start,
            end: start,
            full,
            rupture_length: length,
            slip: 0.0,
            rupture_time: vec![Some(start), None],
        }
    }

    /// F/F_N grows with time in these synthetic runs: ratio = start.
    fn sequence(lengths: &[f64]) -> PrecursorSequence {
        let mut events: Vec<Event> = lengths
            .iter()
            .enumerate()
            .map(|(k, &l)| event(l, false, 0.1 + 0.01 * k as f64))
            .collect();
        events.push(event(0.14, true, 0.3));
        events.push(event(0.01, false, 0.31));
        PrecursorSequence::from_events(&events, 0.0025, |e| e.start)
    }

    #[test]
    fn growing_precursors_correlate_fully() {
        let s = sequence(&[0.01, 0.02, 0.04, 0.07]);
        assert_eq!(
            s.precursors.len(),
            4,
            "the partial event after the full one is not a precursor"
        );
        assert_eq!(s.first_full_ratio, Some(0.3));
        let r = PrecursorSequence::growth(&s.precursors).unwrap();
        assert!((r - 1.0).abs() < 1e-12, "{r}");
    }

    /// Negative control: shrinking or unordered lengths must not read as growth.
    #[test]
    fn shrinking_or_unordered_precursors_do_not() {
        let r = PrecursorSequence::growth(&sequence(&[0.07, 0.04, 0.02, 0.01]).precursors).unwrap();
        assert!((r + 1.0).abs() < 1e-12, "{r}");
        let r = PrecursorSequence::growth(&sequence(&[0.04, 0.01, 0.07, 0.02]).precursors).unwrap();
        assert!(r.abs() < 0.5, "{r}");
        assert_eq!(
            PrecursorSequence::growth(&sequence(&[0.01, 0.02]).precursors),
            None
        );
    }

    #[test]
    fn single_block_creep_is_not_an_extended_precursor() {
        let s = sequence(&[0.0025, 0.01, 0.0025, 0.03]);
        let ext = s.extended(0.0025);
        assert_eq!(ext.len(), 2);
        assert_eq!(ext[1].length, 0.03);
    }

    #[test]
    fn precursors_from_inside_are_told_apart() {
        let mut events: Vec<Event> = [0.01, 0.03, 0.02]
            .iter()
            .enumerate()
            .map(|(k, &l)| event(l, false, 0.1 + 0.01 * k as f64))
            .collect();
        // The third starts at block 10, not at the trailing edge.
        events[2].rupture_time = vec![None; 12];
        events[2].rupture_time[10] = Some(0.12);
        let s = PrecursorSequence::from_events(&events, 0.0025, |e| e.start);
        assert_eq!(s.precursors[2].origin, 0.025);
        assert_eq!(s.extended(0.0025).len(), 3);
        assert_eq!(s.from_trailing_edge(0.0025).len(), 2);
    }

    #[test]
    fn a_run_without_full_event_keeps_all_its_partial_events() {
        let events = vec![event(0.01, false, 0.1), event(0.02, false, 0.2)];
        let s = PrecursorSequence::from_events(&events, 0.0025, |e| e.start);
        assert_eq!(s.precursors.len(), 2);
        assert_eq!(s.first_full_ratio, None);
    }
}
