//! How many threads the sweep engine steps a small lattice with when the
//! run leaves it to the engine (`--threads 0`, the default): timed on the
//! run's own steps, as `--gpu-path auto` times the GPU's kernels.
//!
//! Why measure: on a small lattice a thread's band is a few rows and the
//! threads meet at a barrier every step, so whether a second thread (or a
//! fourth) pays depends on the lattice, the precision, the machine and how
//! often the caller stops the engine for a sample. On the 2-core container
//! two threads ran the default job (Table S1, 57×31) 1.38× faster than
//! one, 1.49× with its output file (BENCHMARKS.md, session 69), where an
//! earlier build had measured 0.95–1.65 and so kept one thread below
//! `PARALLEL_MIN_BLOCKS`.
//!
//! How: each phase of loading (the normal load, then the driving) starts
//! with a trial, and another follows every `RETRIAL_SECONDS` of stepping.
//! The engine steps the run itself on each candidate count in turn, a span
//! of at least `SPAN_SECONDS` each after a few untimed steps, for `ROUNDS`
//! rounds, and keeps the fastest (a trial on the scene's first steps would
//! time the normal load, whose junction work is not the driving's). The
//! steps of the trial are the run's, and any count gives the same bits
//! (`tests/sweep_engine.rs`), so a trial costs only its slower spans' time:
//! about 70 ms of stepping for counts 1 and 2, a fraction of which is lost.
//! The trials that follow keep the choice right when the machine's load
//! changes: threads that meet at a spinning barrier every step slow down
//! badly when another process takes a core they need (a run of the default
//! job on two threads took 3.4× its time while a build ran beside it).

use std::ops::Range;

/// Untimed steps after a change of count: the bands of a count first run
/// evenly split, and are rebalanced by their measured work after a call of
/// 16 steps or more.
const WARM_STEPS: u64 = 48;

/// A timed span lasts at least this long (`Plan::span_seconds`) and
/// `SPAN_STEPS.0` steps, and at most `SPAN_STEPS.1` steps.
pub const SPAN_SECONDS: f64 = 10e-3;
const SPAN_STEPS: (u64, u64) = (32, 20_000);

/// Rounds over the candidates, each timed once a round in turn; the best
/// span of each counts.
const ROUNDS: usize = 3;

/// Seconds of stepping on the chosen count before the counts are timed
/// again (`Plan::retrial_seconds`).
pub const RETRIAL_SECONDS: f64 = 30.0;

/// A count with more threads is taken only where it steps at least this
/// much faster than the fewer-thread count taken so far: a tie goes to
/// fewer threads, which leave cores to the rest of the machine.
const GAIN_NEEDED: f64 = 0.95;

/// What a trial times: its thread counts, the first to start on, how long
/// a span of each lasts at least, and how long the engine steps on its
/// choice before the next trial.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    pub candidates: Vec<usize>,
    pub span_seconds: f64,
    pub retrial_seconds: f64,
}

impl Plan {
    /// The counts worth timing on a lattice of `rows` rows on a machine
    /// with `cores` cores: 1, 2, 4, … and the most (a band a row at most),
    /// each for `SPAN_SECONDS` a span, timed again every
    /// `RETRIAL_SECONDS`.
    pub fn for_machine(rows: usize, cores: usize) -> Plan {
        Plan {
            candidates: candidates(rows, cores),
            span_seconds: SPAN_SECONDS,
            retrial_seconds: RETRIAL_SECONDS,
        }
    }
}

/// 1, 2, 4, … below the most of `cores` and `rows`, and that most.
fn candidates(rows: usize, cores: usize) -> Vec<usize> {
    let most = cores.min(rows).max(1);
    let mut out: Vec<usize> = std::iter::successors(Some(1usize), |k| Some(k * 2))
        .take_while(|&k| k < most)
        .collect();
    out.push(most);
    out
}

/// A measured thread count and the figures behind it: each count timed,
/// with its best seconds a step.
#[derive(Debug, Clone, PartialEq)]
pub struct Timed {
    pub threads: usize,
    pub figures: Vec<(usize, f64)>,
}

impl Timed {
    /// "1: 48.2 µs, 2: 33.0 µs a step": each count's figure.
    pub fn describe(&self) -> String {
        let figures: Vec<String> = self
            .figures
            .iter()
            .map(|(k, s)| format!("{k}: {:.1} µs", s * 1e6))
            .collect();
        format!("{} a step", figures.join(", "))
    }
}

/// What the engine does after a span of the trial.
#[derive(Debug, Clone, PartialEq)]
pub enum Next {
    /// Go on with the same count.
    Keep,
    /// Step with this many threads from now on, the trial going on.
    Run(usize),
    /// The trial is over: step with the chosen count.
    Chosen(Timed),
}

/// A trial under way: the candidates, the count being stepped, and the
/// best figure of each so far.
#[derive(Debug)]
pub struct Trial<P> {
    counts: Vec<usize>,
    best: Vec<f64>,
    at: usize,
    round: usize,
    warm_left: u64,
    span_steps: u64,
    span_seconds: f64,
    span_least_seconds: f64,
    /// What the engine set aside of each count it left (its bands as last
    /// rebalanced, its thread pool), to take up again on its next turn.
    parked: Vec<Option<(Vec<Range<usize>>, P)>>,
}

impl<P> Trial<P> {
    /// A trial of `plan`'s counts (at least two), starting on the first.
    pub fn new(plan: &Plan) -> Trial<P> {
        let n = plan.candidates.len();
        Trial {
            best: vec![f64::INFINITY; n],
            parked: (0..n).map(|_| None).collect(),
            counts: plan.candidates.clone(),
            span_least_seconds: plan.span_seconds,
            at: 0,
            round: 0,
            warm_left: WARM_STEPS,
            span_steps: 0,
            span_seconds: 0.0,
        }
    }

    /// The count the engine should be stepping now.
    pub fn threads(&self) -> usize {
        self.counts[self.at]
    }

    /// The most steps the engine should take before it calls `record`:
    /// the untimed steps' rest; or a span's first `SPAN_STEPS.0`, then as
    /// many as its pace so far says it still needs (a caller that asks for
    /// many steps at once would otherwise run a whole span of
    /// `SPAN_STEPS.1` on a count that may be slow).
    pub fn steps_wanted(&self) -> u64 {
        if self.warm_left > 0 {
            return self.warm_left;
        }
        let most = SPAN_STEPS.1 - self.span_steps;
        if self.span_steps < SPAN_STEPS.0 {
            return (SPAN_STEPS.0 - self.span_steps).min(most);
        }
        let pace = self.span_seconds / self.span_steps as f64;
        let short = (self.span_least_seconds - self.span_seconds).max(0.0);
        let more = (short / pace.max(1e-12)).ceil().min(most as f64) as u64;
        more.clamp(1, most)
    }

    /// Sets aside the bands and pool of count `threads`, which the engine
    /// is leaving.
    pub fn park(&mut self, threads: usize, bands: Vec<Range<usize>>, pool: P) {
        if let Some(i) = self.counts.iter().position(|&k| k == threads) {
            self.parked[i] = Some((bands, pool));
        }
    }

    /// What was set aside of count `threads`, if anything.
    pub fn unpark(&mut self, threads: usize) -> Option<(Vec<Range<usize>>, P)> {
        let i = self.counts.iter().position(|&k| k == threads)?;
        self.parked[i].take()
    }

    /// `steps` (at most `steps_wanted`) taken in `seconds` on `threads()`.
    pub fn record(&mut self, steps: u64, seconds: f64) -> Next {
        if self.warm_left > 0 {
            self.warm_left -= steps.min(self.warm_left);
            return Next::Keep;
        }
        self.span_steps += steps;
        self.span_seconds += seconds;
        let long_enough =
            self.span_steps >= SPAN_STEPS.0 && self.span_seconds >= self.span_least_seconds;
        if !long_enough && self.span_steps < SPAN_STEPS.1 {
            return Next::Keep;
        }
        let step = self.span_seconds / self.span_steps as f64;
        self.best[self.at] = self.best[self.at].min(step);
        self.span_steps = 0;
        self.span_seconds = 0.0;
        self.warm_left = WARM_STEPS;
        self.at += 1;
        if self.at == self.counts.len() {
            self.at = 0;
            self.round += 1;
            if self.round == ROUNDS {
                return Next::Chosen(self.chosen());
            }
        }
        Next::Run(self.threads())
    }

    /// The fewest threads within `GAIN_NEEDED` of any more.
    fn chosen(&self) -> Timed {
        let mut chosen = 0;
        for k in 1..self.counts.len() {
            if self.best[k] < GAIN_NEEDED * self.best[chosen] {
                chosen = k;
            }
        }
        Timed {
            threads: self.counts[chosen],
            figures: self.counts.iter().copied().zip(self.best.clone()).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_candidates_double_up_to_the_cores_or_the_rows() {
        assert_eq!(candidates(31, 1), vec![1]);
        assert_eq!(candidates(31, 2), vec![1, 2]);
        assert_eq!(candidates(31, 6), vec![1, 2, 4, 6]);
        assert_eq!(candidates(31, 16), vec![1, 2, 4, 8, 16]);
        assert_eq!(candidates(31, 64), vec![1, 2, 4, 8, 16, 31]);
        assert_eq!(candidates(3, 16), vec![1, 2, 3]);
        assert_eq!(candidates(1, 16), vec![1]);
    }

    /// Steps a trial to its end with each count's seconds a step given,
    /// in calls of `call` steps; returns the counts stepped, in order of
    /// change, and the choice.
    fn run_trial(counts: &[usize], step_seconds: &[f64], call: u64) -> (Vec<usize>, Timed) {
        let mut trial = Trial::<()>::new(&Plan {
            candidates: counts.to_vec(),
            ..Plan::for_machine(31, 2)
        });
        let mut order = vec![trial.threads()];
        for _ in 0..1_000_000 {
            let k = trial.steps_wanted().min(call);
            let i = counts.iter().position(|&c| c == trial.threads()).unwrap();
            match trial.record(k, k as f64 * step_seconds[i]) {
                Next::Keep => {}
                Next::Run(t) => order.push(t),
                Next::Chosen(timed) => return (order, timed),
            }
        }
        panic!("the trial never ended");
    }

    #[test]
    fn the_trial_takes_the_fastest_count_in_rounds_and_ties_go_to_fewer_threads() {
        let (order, timed) = run_trial(&[1, 2, 4], &[50e-6, 30e-6, 35e-6], 45);
        assert_eq!(order, vec![1, 2, 4, 1, 2, 4, 1, 2, 4]);
        assert_eq!(timed.threads, 2);
        assert_eq!(timed.figures.len(), 3);
        assert!((timed.figures[1].1 - 30e-6).abs() < 1e-12);
        // 4 threads 3 % faster than 2: not enough to take two more cores.
        let (_, timed) = run_trial(&[1, 2, 4], &[50e-6, 30e-6, 29.1e-6], 7);
        assert_eq!(timed.threads, 2);
        // More threads slower throughout: one.
        let (_, timed) = run_trial(&[1, 2], &[30e-6, 31e-6], 1000);
        assert_eq!(timed.threads, 1);
        assert_eq!(timed.describe(), "1: 30.0 µs, 2: 31.0 µs a step");
    }

    #[test]
    fn a_span_lasts_its_time_or_its_most_steps() {
        // 10 µs a step: a span of 10 ms is 1000 steps; 1 ns a step: the
        // span stops at its most steps. In calls of 7 steps, and in calls
        // of as many as the trial wants (a caller that asks for many steps
        // at once).
        for call in [7, u64::MAX] {
            for (seconds, steps) in [(10e-6, 1000), (1e-9, SPAN_STEPS.1)] {
                let mut trial = Trial::<()>::new(&Plan::for_machine(31, 2));
                let mut taken = 0;
                loop {
                    let k = trial.steps_wanted().min(call);
                    taken += k;
                    if trial.record(k, k as f64 * seconds) != Next::Keep {
                        break;
                    }
                }
                let timed = taken - WARM_STEPS;
                assert!(
                    timed >= steps && timed < steps + 14,
                    "{seconds} s a step, calls of {call}: {timed} steps"
                );
            }
        }
    }
}
