//! Two perturbation ensembles compared outcome by outcome (`slipfront
//! compare A B`). The scenes are chaotic, so two engines or precisions are
//! judged by whether their ensembles' outcome distributions differ, not by
//! run-to-run agreement: KS and Anderson–Darling on continuous outcomes,
//! an exact 2×k test on counts and on the occupancy of each outcome's
//! modes (with "none", e.g. no full event, as a mode of its own).
//!
//! Every test is reported with its own p-value, without a correction for
//! the number of tests; `bonferroni_min_p` gives the corrected smallest.
//! Pooled precursor lengths are several per run and not independent, so
//! their p-values are indicative.

use super::modes::{mode_of, split_at_gaps};
use super::outcome_rows::{read_ensemble, Ensemble, RunOutcomes};
use crate::analysis::stats::{
    anderson_darling_ksample, exact_2xk, ks_two_sample, spearman, Quartiles, TableTest, TestResult,
};
use std::collections::BTreeMap;
use std::path::Path;

/// Significance level by default.
pub const DEFAULT_ALPHA: f64 = 0.01;

/// One side of a continuous outcome: the summary of its values and the
/// runs that have none.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Side {
    /// Left out of the JSON: the tables hold them.
    #[serde(skip)]
    pub values: Vec<f64>,
    pub summary: Option<Quartiles>,
    /// Runs without a value (`missing_label` says why).
    pub missing: usize,
    /// Spearman's ρ of the value against the run's perturbation (runs of a
    /// `perturb` sweep with one value each). Near ±1 the outcome still
    /// moves smoothly with the perturbation: chaos has not scrambled it, so
    /// the ensemble samples the engine's response to the perturbation, not
    /// the scene's spread, and two ensembles can differ by tiny shifts.
    pub follows_perturbation: Option<f64>,
}

/// |ρ| from which an outcome counts as following the perturbation.
pub const FOLLOWS_PERTURBATION: f64 = 0.8;

/// A mode of the pooled sample (or the runs without a value) and how many
/// values of each side fall in it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Mode {
    pub label: String,
    /// Its range; None for the runs without a value.
    pub range: Option<(f64, f64)>,
    pub a: u64,
    pub b: u64,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct ContinuousOutcome {
    pub name: &'static str,
    /// What a run without a value means ("no full event"); None where
    /// every run contributes values or none (pooled lengths).
    pub missing_label: Option<&'static str>,
    pub a: Side,
    pub b: Side,
    /// None when a side has no value.
    pub ks: Option<TestResult>,
    pub ad: Option<TestResult>,
    pub modes: Vec<Mode>,
    /// Exact test on the 2×modes table.
    pub modes_test: Option<TableTest>,
}

/// A count outcome: how many runs of each side have each value.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CountOutcome {
    pub name: &'static str,
    /// (value, runs of A, runs of B), by value.
    pub histogram: Vec<(u64, u64, u64)>,
    pub a: Option<Quartiles>,
    pub b: Option<Quartiles>,
    /// Exact test on the 2×values table.
    pub test: Option<TableTest>,
}

/// The comparison of two ensembles.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Comparison {
    pub label_a: String,
    pub label_b: String,
    pub runs_a: usize,
    pub runs_b: usize,
    /// Rows left out of each table, by status.
    pub dropped_a: BTreeMap<String, usize>,
    pub dropped_b: BTreeMap<String, usize>,
    pub continuous: Vec<ContinuousOutcome>,
    pub counts: Vec<CountOutcome>,
}

/// One test's p-value, named.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PValue {
    pub outcome: &'static str,
    /// `ks`, `ad`, `modes` or `exact`.
    pub test: &'static str,
    pub p: f64,
}

impl Comparison {
    /// Every test's p-value, in report order.
    pub fn p_values(&self) -> Vec<PValue> {
        let mut out = Vec::new();
        for c in &self.continuous {
            let tests = [
                ("ks", c.ks.map(|t| t.p)),
                ("ad", c.ad.map(|t| t.p)),
                ("modes", c.modes_test.map(|t| t.p)),
            ];
            for (test, p) in tests {
                if let Some(p) = p {
                    out.push(PValue {
                        outcome: c.name,
                        test,
                        p,
                    });
                }
            }
        }
        for c in &self.counts {
            if let Some(p) = c.test.map(|t| t.p) {
                out.push(PValue {
                    outcome: c.name,
                    test: "exact",
                    p,
                });
            }
        }
        out
    }

    /// The p-values of the outcomes chaos has mixed: every count outcome,
    /// and each continuous outcome that follows the perturbation on
    /// neither side (|ρ| < `FOLLOWS_PERTURBATION`, or no perturbation
    /// column). Those are the tests that ask whether two ensembles are
    /// draws from one distribution.
    pub fn mixed_p_values(&self) -> Vec<PValue> {
        let follows = |s: &Side| {
            s.follows_perturbation
                .is_some_and(|r| r.abs() >= FOLLOWS_PERTURBATION)
        };
        let smooth: Vec<&str> = self
            .continuous
            .iter()
            .filter(|c| follows(&c.a) || follows(&c.b))
            .map(|c| c.name)
            .collect();
        self.p_values()
            .into_iter()
            .filter(|v| !smooth.contains(&v.outcome))
            .collect()
    }

    /// The smallest p-value (the first of equals); None when no test ran.
    pub fn min_p(&self) -> Option<PValue> {
        self.p_values()
            .into_iter()
            .reduce(|best, v| if v.p < best.p { v } else { best })
    }

    /// The tests with p < alpha.
    pub fn differing(&self, alpha: f64) -> Vec<PValue> {
        self.p_values()
            .into_iter()
            .filter(|v| v.p < alpha)
            .collect()
    }

    /// Whether some outcome differs at p < alpha.
    pub fn differs(&self, alpha: f64) -> bool {
        !self.differing(alpha).is_empty()
    }
}

/// A continuous outcome: its name, what a missing value means, and the
/// values one run gives (None: missing).
struct ContinuousSpec {
    name: &'static str,
    missing_label: Option<&'static str>,
    values: fn(&RunOutcomes) -> Vec<Option<f64>>,
    /// A column later tables added (`outcome_rows::OPTIONAL`).
    later: bool,
}

const CONTINUOUS: [ContinuousSpec; 9] = [
    ContinuousSpec {
        name: "first_full_time_s",
        missing_label: Some("no full event"),
        values: |r| vec![r.first_full_time_s],
        later: false,
    },
    ContinuousSpec {
        name: "first_full_drive_ratio",
        missing_label: Some("no full event"),
        values: |r| vec![r.first_full_drive_ratio],
        later: false,
    },
    ContinuousSpec {
        name: "precursor_lengths_m",
        missing_label: None,
        values: |r| r.precursor_lengths_m.iter().map(|&v| Some(v)).collect(),
        later: false,
    },
    ContinuousSpec {
        name: "precursor_max_length_m",
        missing_label: Some("no precursor"),
        values: |r| vec![r.precursor_max_length_m],
        later: false,
    },
    ContinuousSpec {
        name: "mean_slip_m",
        missing_label: Some("no event"),
        values: |r| vec![r.mean_slip_m],
        later: false,
    },
    ContinuousSpec {
        name: "first_event_time_s",
        missing_label: Some("no event"),
        values: |r| vec![r.first_event_time_s],
        later: true,
    },
    ContinuousSpec {
        name: "first_event_length_m",
        missing_label: Some("no event"),
        values: |r| vec![r.first_event_length_m],
        later: true,
    },
    ContinuousSpec {
        name: "slow_front_speed_m_per_s",
        missing_label: Some("no slow front"),
        values: |r| vec![r.slow_front_speed_m_per_s],
        later: true,
    },
    ContinuousSpec {
        name: "slow_slip_speed_m_per_s",
        missing_label: Some("no slow front"),
        values: |r| vec![r.slow_slip_speed_m_per_s],
        later: true,
    },
];

/// A count outcome of a run.
type Count = fn(&RunOutcomes) -> u64;

const COUNTS: [(&str, Count); 3] = [
    ("precursors", |r| r.precursors),
    ("events", |r| r.events),
    ("full_events", |r| r.full_events),
];

/// Compares the sweep tables at `a` and `b` (sweep folders or CSV files),
/// labelled by their paths.
pub fn compare_tables(a: &Path, b: &Path) -> Result<Comparison, String> {
    let (ea, eb) = (read_ensemble(a)?, read_ensemble(b)?);
    Ok(compare_ensembles(
        &ea,
        &eb,
        &a.display().to_string(),
        &b.display().to_string(),
    ))
}

/// Compares two ensembles read from tables (with their dropped rows).
pub fn compare_ensembles(a: &Ensemble, b: &Ensemble, label_a: &str, label_b: &str) -> Comparison {
    Comparison {
        dropped_a: a.dropped.clone(),
        dropped_b: b.dropped.clone(),
        ..compare_outcomes(&a.runs, &b.runs, label_a, label_b)
    }
}

/// Compares two sets of runs' outcomes held in memory.
pub fn compare_outcomes(
    a: &[RunOutcomes],
    b: &[RunOutcomes],
    label_a: &str,
    label_b: &str,
) -> Comparison {
    Comparison {
        label_a: label_a.to_string(),
        label_b: label_b.to_string(),
        runs_a: a.len(),
        runs_b: b.len(),
        dropped_a: BTreeMap::new(),
        dropped_b: BTreeMap::new(),
        // A later column no run on either side has (older tables lack
        // it, or no slow front anywhere) is left out.
        continuous: CONTINUOUS
            .iter()
            .map(|s| (s.later, continuous(s, a, b)))
            .filter(|(later, c)| !(*later && c.a.values.is_empty() && c.b.values.is_empty()))
            .map(|(_, c)| c)
            .collect(),
        counts: COUNTS
            .iter()
            .map(|&(name, of)| count(name, of, a, b))
            .collect(),
    }
}

/// The larger (in size) of Spearman's ρ of `v` against the perturbation
/// and against its size: a smooth response may be monotone in k or
/// symmetric about 0. None below 8 runs.
fn follows(p: &[f64], v: &[f64]) -> Option<f64> {
    if v.len() < 8 {
        return None;
    }
    let size: Vec<f64> = p.iter().map(|x| x.abs()).collect();
    [spearman(p, v), spearman(&size, v)]
        .into_iter()
        .flatten()
        .max_by(|a, b| a.abs().total_cmp(&b.abs()))
}

fn side(spec: &ContinuousSpec, runs: &[RunOutcomes]) -> Side {
    let all: Vec<Option<f64>> = runs.iter().flat_map(spec.values).collect();
    let values: Vec<f64> = all.iter().flatten().copied().collect();
    let pairs: Vec<(f64, f64)> = runs
        .iter()
        .filter_map(|r| match ((spec.values)(r).as_slice(), r.perturbation) {
            ([Some(v)], Some(p)) => Some((p, *v)),
            _ => None,
        })
        .collect();
    let (p, v): (Vec<f64>, Vec<f64>) = pairs.into_iter().unzip();
    Side {
        summary: Quartiles::of(&values),
        missing: all.len() - values.len(),
        follows_perturbation: follows(&p, &v),
        values,
    }
}

fn continuous(spec: &ContinuousSpec, a: &[RunOutcomes], b: &[RunOutcomes]) -> ContinuousOutcome {
    let (sa, sb) = (side(spec, a), side(spec, b));
    let pooled: Vec<f64> = sa.values.iter().chain(&sb.values).copied().collect();
    let ranges = split_at_gaps(&pooled);
    let occupancy = |values: &[f64]| {
        let mut n = vec![0u64; ranges.len()];
        for &v in values {
            n[mode_of(&ranges, v).expect("every pooled value is in a mode")] += 1;
        }
        n
    };
    let (na, nb) = (occupancy(&sa.values), occupancy(&sb.values));
    let mut modes: Vec<Mode> = ranges
        .iter()
        .enumerate()
        .map(|(k, &(lo, hi))| Mode {
            label: format!("{lo:.4e} .. {hi:.4e}"),
            range: Some((lo, hi)),
            a: na[k],
            b: nb[k],
        })
        .collect();
    if let Some(label) = spec.missing_label {
        if sa.missing + sb.missing > 0 {
            modes.push(Mode {
                label: label.to_string(),
                range: None,
                a: sa.missing as u64,
                b: sb.missing as u64,
            });
        }
    }
    let row = |f: fn(&Mode) -> u64| modes.iter().map(f).collect::<Vec<u64>>();
    let modes_test = (!modes.is_empty())
        .then(|| exact_2xk([&row(|m| m.a), &row(|m| m.b)]))
        .flatten();
    ContinuousOutcome {
        name: spec.name,
        missing_label: spec.missing_label,
        ks: ks_two_sample(&sa.values, &sb.values),
        ad: anderson_darling_ksample(&[&sa.values, &sb.values]),
        a: sa,
        b: sb,
        modes,
        modes_test,
    }
}

fn count(name: &'static str, of: Count, a: &[RunOutcomes], b: &[RunOutcomes]) -> CountOutcome {
    let mut histogram: BTreeMap<u64, (u64, u64)> = BTreeMap::new();
    for r in a {
        histogram.entry(of(r)).or_default().0 += 1;
    }
    for r in b {
        histogram.entry(of(r)).or_default().1 += 1;
    }
    let histogram: Vec<(u64, u64, u64)> =
        histogram.into_iter().map(|(v, (x, y))| (v, x, y)).collect();
    let row = |f: fn(&(u64, u64, u64)) -> u64| histogram.iter().map(f).collect::<Vec<u64>>();
    let values = |runs: &[RunOutcomes]| runs.iter().map(|r| of(r) as f64).collect::<Vec<_>>();
    CountOutcome {
        name,
        test: (!a.is_empty() && !b.is_empty())
            .then(|| exact_2xk([&row(|h| h.1), &row(|h| h.2)]))
            .flatten(),
        a: Quartiles::of(&values(a)),
        b: Quartiles::of(&values(b)),
        histogram,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run with a first full event at `t` (None: none), `precursors`
    /// precursors of lengths 1e-3 · (1..=precursors), and `events` events.
    fn run(t: Option<f64>, precursors: u64, events: u64) -> RunOutcomes {
        let lengths: Vec<f64> = (1..=precursors).map(|k| 1e-3 * k as f64).collect();
        RunOutcomes {
            first_full_time_s: t,
            first_full_drive_ratio: t.map(|t| 0.3 + t),
            events,
            full_events: u64::from(t.is_some()),
            precursors,
            precursor_max_length_m: lengths.last().copied(),
            precursor_lengths_m: lengths,
            mean_slip_m: (events > 0).then_some(1e-6 * events as f64),
            ..RunOutcomes::default()
        }
    }

    #[test]
    fn an_outcome_that_moves_with_the_perturbation_is_marked() {
        // k = 0, +1, −1, … as a perturb sweep makes them.
        let k = |m: usize| {
            if m % 2 == 1 {
                m.div_ceil(2) as f64
            } else {
                -(m.div_ceil(2) as f64)
            }
        };
        let runs = |response: &dyn Fn(f64) -> f64| -> Vec<RunOutcomes> {
            (0..16)
                .map(|m| RunOutcomes {
                    perturbation: Some(k(m) * 1e-6),
                    ..run(Some(response(k(m))), 0, 3)
                })
                .collect()
        };
        // A smooth monotone response, a smooth symmetric one, and scrambled.
        let linear = runs(&|k| 0.35 + 1e-4 * k);
        let symmetric = runs(&|k| 0.35 + 1e-5 * k * k);
        let scrambled = runs(&|k| 0.35 + 1e-3 * ((k * 7.3).sin() * 1e3).fract());
        let rho = |a: &[RunOutcomes]| {
            compare_outcomes(a, a, "a", "b").continuous[0]
                .a
                .follows_perturbation
                .unwrap()
        };
        assert!(rho(&linear) > 0.99, "{}", rho(&linear));
        assert!(rho(&symmetric) > 0.99, "{}", rho(&symmetric));
        assert!(
            rho(&scrambled).abs() < FOLLOWS_PERTURBATION,
            "{}",
            rho(&scrambled)
        );
        // Without a perturbation column there is nothing to say.
        let plain = ensemble(16, 0.3);
        assert_eq!(
            compare_outcomes(&plain, &plain, "a", "b").continuous[0]
                .a
                .follows_perturbation,
            None
        );
    }

    /// n runs with first full events spread evenly over t0 .. t0 + 0.1.
    fn ensemble(n: usize, t0: f64) -> Vec<RunOutcomes> {
        (0..n)
            .map(|k| {
                run(
                    Some(t0 + 0.1 * k as f64 / n as f64),
                    2 + k as u64 % 3,
                    3 + k as u64 % 2,
                )
            })
            .collect()
    }

    #[test]
    fn an_ensemble_does_not_differ_from_itself() {
        let a = ensemble(40, 1.0);
        let c = compare_outcomes(&a, &a, "a", "a again");
        assert!(!c.differs(0.01), "{:?}", c.differing(0.01));
        assert!(c.min_p().unwrap().p > 0.5, "{:?}", c.min_p());
        assert_eq!(c.p_values().len(), 5 * 3 + 3);
    }

    #[test]
    fn a_shifted_first_event_differs() {
        let a = ensemble(40, 1.0);
        let b = ensemble(40, 1.06);
        let c = compare_outcomes(&a, &b, "a", "b");
        let first = &c.continuous[0];
        assert_eq!(first.name, "first_full_time_s");
        assert!(first.ks.unwrap().p < 1e-4, "{:?}", first.ks);
        assert!(first.ad.unwrap().p < 1e-3, "{:?}", first.ad);
        assert!(c.differs(0.01));
        // The counts are the same on both sides.
        assert!(c.counts.iter().all(|k| k.test.unwrap().p > 0.99));
    }

    #[test]
    fn runs_without_a_full_event_are_a_mode_of_their_own() {
        let a = ensemble(30, 1.0);
        let mut b = ensemble(30, 1.0);
        for r in b.iter_mut().step_by(2) {
            *r = run(None, r.precursors, r.events);
        }
        let c = compare_outcomes(&a, &b, "a", "b");
        let first = &c.continuous[0];
        assert_eq!((first.a.missing, first.b.missing), (0, 15));
        let none = first.modes.last().unwrap();
        assert_eq!(
            (none.label.as_str(), none.a, none.b),
            ("no full event", 0, 15)
        );
        assert!(first.modes_test.unwrap().p < 1e-4, "{:?}", first.modes_test);
        // The runs with a full event are a subsample: KS does not object.
        assert!(first.ks.unwrap().p > 0.05);
        assert!(c.differs(0.01));
    }

    #[test]
    fn two_modes_filled_differently_are_flagged() {
        // Both sides in the same two clusters, 24:6 against 6:24.
        let early = |k: usize| Some(1.0 + 0.001 * k as f64);
        let late = |k: usize| Some(2.0 + 0.001 * k as f64);
        let a: Vec<_> = (0..30)
            .map(|k| run(if k < 24 { early(k) } else { late(k) }, 2, 3))
            .collect();
        let b: Vec<_> = (0..30)
            .map(|k| run(if k < 6 { early(k) } else { late(k) }, 2, 3))
            .collect();
        let c = compare_outcomes(&a, &b, "a", "b");
        let first = &c.continuous[0];
        assert_eq!(first.modes.len(), 2);
        assert_eq!((first.modes[0].a, first.modes[0].b), (24, 6));
        assert!(first.modes_test.unwrap().p < 1e-4);
    }

    #[test]
    fn count_histograms_and_empty_sides() {
        let a = vec![run(Some(1.0), 0, 0), run(Some(1.1), 0, 1)];
        let b = vec![run(None, 0, 0)];
        let c = compare_outcomes(&a, &b, "a", "b");
        let events = c.counts.iter().find(|k| k.name == "events").unwrap();
        assert_eq!(events.histogram, vec![(0, 1, 1), (1, 1, 0)]);
        // No precursors anywhere: no continuous test, one "no precursor" mode.
        let max = &c.continuous[3];
        assert!(max.ks.is_none() && max.ad.is_none());
        assert_eq!(max.modes.len(), 1);
        assert_eq!(max.modes_test.map(|t| t.p), Some(1.0));
        // B has no full event at all: nothing to compare but the occupancy.
        assert!(c.continuous[0].ks.is_none());
        let none = compare_outcomes(&[], &[], "a", "b");
        assert!(none.min_p().is_none() && !none.differs(0.01));
    }
}
