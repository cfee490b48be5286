//! One verdict from a comparison's many tests: the smallest p-value times
//! the number of tests weighed (Bonferroni), where which tests are weighed
//! depends on whether the two ensembles ran the same perturbations. The
//! precision test and the GPU precision bench judge engines with it.

use super::compare::{Comparison, PValue};
use super::outcome_rows::RunOutcomes;

/// Which perturbations two ensembles share (`compare --members`).
///
/// Disjoint members are judged on the whole-run outcomes chaos has mixed
/// (`Comparison::mixed_p_values`) without the first full event's. In a
/// short run that event comes before the chaos has grown and still moves
/// with k, so two disjoint ranges of k differ there by construction
/// (measured on `small_stick_slip`: F/F_N at the first event, p = 2e-5
/// between two f64 ensembles), even where its rank correlation with k is
/// below `FOLLOWS_PERTURBATION`. The same members are judged on every
/// outcome: a smooth function of k must be the same function on both sides.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Members {
    /// Other perturbations or seeds: the whole-run outcomes chaos has mixed.
    Disjoint,
    /// The same perturbations on both sides: every outcome.
    Same,
}

/// The Bonferroni verdict over the tests `Members` weighs.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Verdict {
    pub members: Members,
    /// The smallest p-value weighed (the first of equals).
    pub smallest: PValue,
    /// How many tests were weighed.
    pub tests: usize,
    /// `smallest.p × tests`, at most 1.
    pub corrected: f64,
}

impl Verdict {
    /// Whether the corrected p is below `alpha`.
    pub fn differs(&self, alpha: f64) -> bool {
        self.corrected < alpha
    }

    /// What the corrected p comes from: "mean_slip_m ks, p 3.10e-3 of 30
    /// tests".
    pub fn describe(&self) -> String {
        format!(
            "{} {}, p {:.2e} of {} tests",
            self.smallest.outcome, self.smallest.test, self.smallest.p, self.tests
        )
    }
}

impl Comparison {
    /// The tests weighed for two ensembles whose members are `members`.
    pub fn weighed_p_values(&self, members: Members) -> Vec<PValue> {
        match members {
            Members::Disjoint => self
                .mixed_p_values()
                .into_iter()
                .filter(|v| !v.outcome.starts_with("first_full"))
                .collect(),
            Members::Same => self.p_values(),
        }
    }

    /// The smallest p-value times the number of tests, at most 1 (every
    /// test weighed, as for the same members).
    pub fn bonferroni_min_p(&self) -> Option<f64> {
        self.verdict(Members::Same).map(|v| v.corrected)
    }

    /// The Bonferroni verdict over `weighed_p_values(members)`; None when
    /// no such test ran.
    pub fn verdict(&self, members: Members) -> Option<Verdict> {
        let tests = self.weighed_p_values(members);
        let smallest = tests
            .iter()
            .cloned()
            .reduce(|best, v| if v.p < best.p { v } else { best })?;
        let corrected = (smallest.p * tests.len() as f64).min(1.0);
        Some(Verdict {
            members,
            smallest,
            tests: tests.len(),
            corrected,
        })
    }
}

/// How many runs of `a` have a perturbation that some run of `b` has.
/// Same-member comparisons need them to be most runs: an outcome that
/// still follows the perturbation differs between disjoint ranges by
/// construction.
pub fn shared_perturbations(a: &[RunOutcomes], b: &[RunOutcomes]) -> usize {
    let mut theirs: Vec<f64> = b.iter().filter_map(|r| r.perturbation).collect();
    theirs.sort_by(f64::total_cmp);
    a.iter()
        .filter_map(|r| r.perturbation)
        .filter(|p| theirs.binary_search_by(|t| t.total_cmp(p)).is_ok())
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::sweeps::compare::{compare_outcomes, FOLLOWS_PERTURBATION};
    use crate::app::sweeps::outcome_rows::RunOutcomes;

    /// 16 runs of a perturb sweep (k = 0, +1, −1, …): a first full event
    /// at `first(k)`, mean slip `slip(m)` of member m, 3 events.
    fn runs(first: &dyn Fn(f64) -> f64, slip: &dyn Fn(usize) -> f64) -> Vec<RunOutcomes> {
        (0..16usize)
            .map(|m| {
                let k = if m % 2 == 1 {
                    m.div_ceil(2) as f64
                } else {
                    -(m.div_ceil(2) as f64)
                };
                RunOutcomes {
                    perturbation: Some(k * 1e-6),
                    first_full_time_s: Some(first(k)),
                    first_full_drive_ratio: Some(0.3 + first(k)),
                    events: 3,
                    full_events: 1,
                    mean_slip_m: Some(slip(m)),
                    ..RunOutcomes::default()
                }
            })
            .collect()
    }

    /// Scrambled by member: no rank correlation with k.
    fn scrambled(m: usize) -> f64 {
        1e-6 * (1.0 + ((m as f64 * 7.3).sin() * 1e3).fract().abs())
    }

    #[test]
    fn disjoint_members_leave_out_the_first_full_event_and_smooth_outcomes() {
        // The first full event scattered, not marked as following k, but
        // in disjoint intervals for the two ranges of k (as a short run's
        // first event can be).
        let jitter = |k: f64| 1e-3 * ((k * 13.7).sin() * 1e3).fract().abs();
        let a = runs(&|k| 0.35 + jitter(k), &scrambled);
        let b = runs(&|k| 0.50 + jitter(k), &scrambled);
        let c = compare_outcomes(&a, &b, "a", "b");
        let rho = c.continuous[0].a.follows_perturbation.unwrap();
        assert!(rho.abs() < FOLLOWS_PERTURBATION, "{rho}");
        let same = c.verdict(Members::Same).unwrap();
        assert!(same.differs(0.01), "{}", same.describe());
        assert!(same.smallest.outcome.starts_with("first_full"));
        let disjoint = c.verdict(Members::Disjoint).unwrap();
        assert!(!disjoint.differs(0.01), "{}", disjoint.describe());
        assert!(disjoint.tests < same.tests);
        assert!(c
            .weighed_p_values(Members::Disjoint)
            .iter()
            .all(|v| !v.outcome.starts_with("first_full")));
    }

    #[test]
    fn the_correction_multiplies_by_the_tests_weighed_and_stops_at_one() {
        let a = runs(&|k| 0.35 + 1e-3 * (k * 3.1).sin().abs(), &scrambled);
        let b = runs(&|k| 0.35 + 1e-3 * (k * 3.1).sin().abs(), &|m| {
            scrambled(m) * 3.0
        });
        let c = compare_outcomes(&a, &b, "a", "b");
        for members in [Members::Same, Members::Disjoint] {
            let v = c.verdict(members).unwrap();
            let weighed = c.weighed_p_values(members);
            assert_eq!(v.tests, weighed.len());
            let min = weighed.iter().map(|t| t.p).fold(f64::INFINITY, f64::min);
            assert_eq!(v.smallest.p, min);
            assert_eq!(v.corrected, (min * weighed.len() as f64).min(1.0));
        }
        // The slip of every run 3× larger is seen in both verdicts.
        assert!(c.verdict(Members::Disjoint).unwrap().differs(0.01));
        // An ensemble against itself: nothing differs, the correction caps.
        let same = compare_outcomes(&a, &a, "a", "a").verdict(Members::Same);
        assert_eq!(same.unwrap().corrected, 1.0);
        assert!(compare_outcomes(&[], &[], "a", "b")
            .verdict(Members::Same)
            .is_none());
    }
}
