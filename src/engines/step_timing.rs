//! What a step costs in a run, timed on an engine from spans of steps:
//! a warm-up (sustained where a GPU's clocks must rise), then the time a
//! long span takes beyond a short one, over its extra steps
//! (`marginal_step_seconds`). The GPU kernel choice times its launches
//! this way (`gpu::kernel_choice::timing`), and `--backend auto` times the
//! GPU engine against the CPU engine this way (`backend_choice`), so their
//! figures are alike.

use crate::engines::EngineError;

/// Steps run before timing: the pipeline is compiled and warm, and their
/// time sizes the spans (on a software adapter; on hardware the sustained
/// warm-up's last span does).
pub const WARM_UP_STEPS: u64 = 32;
/// Wall time a launch is stepped without pause before it is timed, on a
/// hardware adapter: a GPU's clocks fall while the host builds the launch
/// (its pipelines compile with the device idle) and rise again only under
/// sustained work, which a run gives them. On an H200 (BENCHMARKS.md,
/// session 50) every launch timed after another launch's build ran 5.2 to
/// 5.5 times slower in `auto` (a 32-step warm-up) than timed again over a
/// second after the load phase; the benches' figures, which follow at
/// least 0.08 s of stepping, agreed with runs. Software adapters have no
/// clocks to raise.
pub const SUSTAINED_WARM_UP_SECONDS: f64 = 0.2;
/// Timed repeats of each span; the fastest of each counts (others share
/// the machine).
pub const REPEATS: usize = 3;
/// The wall time the short span aims at, and its fewest steps (a large
/// lattice is timed over fewer steps, a small one over more).
pub const TARGET_SPAN_SECONDS: f64 = 0.01;
pub const MIN_SPAN_STEPS: u64 = 8;
/// The long span is this many short spans.
pub const LONG_SPANS: u64 = 3;

/// Steps spans of `span` (which steps its steps, waits for them and
/// returns their wall seconds) one after another until `seconds` of wall
/// time have passed, each span sized from the step time of the one
/// before (the first from `rough`); returns the short span sized from
/// the last one, whose steps ran at the clocks a run has. With `seconds`
/// zero, steps nothing and sizes the span from `rough`.
pub fn sustained_warm_up(
    mut span: impl FnMut(u64) -> Result<f64, EngineError>,
    rough: f64,
    batch: u64,
    seconds: f64,
) -> Result<u64, EngineError> {
    let mut steps = short_span_steps(rough, batch);
    let mut spent = 0.0;
    while spent < seconds {
        let took = span(steps)?;
        spent += took;
        steps = short_span_steps(took / steps as f64, batch);
    }
    Ok(steps)
}

/// The short span's steps, from a rough step time: about
/// `TARGET_SPAN_SECONDS` of them, at least `MIN_SPAN_STEPS`, and at most
/// a batch (`batch`: the most steps one submit holds), so that the long
/// span is several batches where the span's time allows, stepped as a run
/// steps them: the host encoding a batch while the device runs the one
/// before.
pub fn short_span_steps(rough: f64, batch: u64) -> u64 {
    ((TARGET_SPAN_SECONDS / rough.max(1e-9)) as u64)
        .clamp(MIN_SPAN_STEPS, batch.max(MIN_SPAN_STEPS))
}

/// What a step costs in a run, from spans of `short` and
/// `LONG_SPANS`·`short` steps (`span` steps its steps, waits for them and
/// returns their wall seconds), each the fastest of `REPEATS`: the long
/// span's time beyond the short one's, over its extra steps.
///
/// Why not a span's mean step: each advance also pays costs a run pays
/// once, not a step, and a span within one batch pays the host's encoding
/// and the device's steps one after the other (the batch is encoded whole,
/// then run), where a run overlaps them. On the H200 the host did about
/// 3.7 µs of work a step of one-step-lanes on Table S1's lattice, which
/// the device stepped in 10.1 (BENCHMARKS.md, session 14): a mean step
/// would have been about 13.8 µs. A persistent or chained dispatch has
/// almost nothing to encode, so the mean step favoured it. What an advance
/// pays once is in both spans and drops out of the difference; the long
/// span's extra batches overlap as a run's do.
/// Where noise leaves the long span no slower than the short one, the
/// long span's mean step is the figure.
pub fn marginal_step_seconds(
    mut span: impl FnMut(u64) -> Result<f64, EngineError>,
    short: u64,
) -> Result<f64, EngineError> {
    let long = LONG_SPANS * short;
    let (mut best_short, mut best_long) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..REPEATS {
        best_short = best_short.min(span(short)?);
        best_long = best_long.min(span(long)?);
    }
    let extra = best_long - best_short;
    Ok(if extra > 0.0 {
        extra / (long - short) as f64
    } else {
        best_long / long as f64
    })
}

/// What a step of `span` costs in a run: a warm-up of `sustain` seconds
/// (none: the short span is sized from `rough`, the wall seconds of a
/// step so far), then `marginal_step_seconds` over spans of at most
/// `batch` steps.
pub fn step_seconds(
    mut span: impl FnMut(u64) -> Result<f64, EngineError>,
    rough: f64,
    batch: u64,
    sustain: f64,
) -> Result<f64, EngineError> {
    let short = sustained_warm_up(&mut span, rough, batch, sustain)?;
    marginal_step_seconds(&mut span, short)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A made-up engine that pays, per advance, a fixed wait (`fixed`
    /// seconds), and encodes its batches of at most `batch` steps at
    /// `encode` seconds a step while the device runs the batch before at
    /// `device` a step: the seconds of `steps` steps.
    fn pipelined(steps: u64, batch: u64, fixed: f64, encode: f64, device: f64) -> f64 {
        let sizes: Vec<f64> = (0..steps.div_ceil(batch))
            .map(|k| (steps - k * batch).min(batch) as f64)
            .collect();
        let mut t = fixed + encode * sizes[0];
        for pair in sizes.windows(2) {
            t += (encode * pair[1]).max(device * pair[0]);
        }
        t + device * sizes[sizes.len() - 1]
    }

    /// The H200's one-step-lanes on Table S1, modelled: the device's 10.1
    /// µs a step, the host's 3.7 µs of work a step, 200 µs an advance to
    /// wait, batches of 1024. A span's mean step gives 14.0 µs; the
    /// marginal step gives the device's, what a run pays, to within the
    /// encoding of the short span's last steps.
    #[test]
    fn the_marginal_step_leaves_out_what_each_advance_pays_once() {
        let (fixed, encode, device) = (200e-6, 3.7e-6, 10.1e-6);
        let batch = 1024;
        let short = short_span_steps(device, batch);
        assert_eq!(short, 990, "about 10 ms of steps");
        let mean = pipelined(short, batch, fixed, encode, device) / short as f64;
        assert!((mean - 14.0e-6).abs() < 0.01e-6, "{mean}");
        let marginal =
            marginal_step_seconds(|n| Ok(pipelined(n, batch, fixed, encode, device)), short)
                .unwrap();
        assert!((marginal / device - 1.0).abs() < 0.01, "{marginal}");
        // Whole batches: the device's step exactly.
        let whole =
            marginal_step_seconds(|n| Ok(pipelined(n, batch, fixed, encode, device)), batch)
                .unwrap();
        assert!((whole - device).abs() < 1e-12, "{whole}");
        // A host slower than the device: about the host's pace.
        let host_bound =
            marginal_step_seconds(|n| Ok(pipelined(n, batch, fixed, 12e-6, device)), short)
                .unwrap();
        assert!((host_bound / 12e-6 - 1.0).abs() < 0.05, "{host_bound}");
    }

    /// Each span counts its fastest repeat; a long span no slower than the
    /// short one (noise) gives the long span's mean step, never a figure of
    /// zero or below.
    #[test]
    fn the_marginal_step_takes_the_fastest_repeats_and_is_never_zero() {
        let mut calls = Vec::new();
        let mut slow_first = true;
        let s = marginal_step_seconds(
            |n| {
                calls.push(n);
                let hiccup = if std::mem::take(&mut slow_first) {
                    1.0
                } else {
                    0.0
                };
                Ok(1e-3 + n as f64 * 1e-5 + hiccup)
            },
            10,
        )
        .unwrap();
        assert!((s - 1e-5).abs() < 1e-12, "{s}");
        assert_eq!(calls, [10, 30, 10, 30, 10, 30]);
        let flat = marginal_step_seconds(|_| Ok(3e-3), 10).unwrap();
        assert!((flat - 1e-4).abs() < 1e-15, "{flat}");
        // Spans sized by the rough step: small lattices up to a batch,
        // large ones at least MIN_SPAN_STEPS.
        assert_eq!(short_span_steps(1e-4, 1024), 100);
        assert_eq!(short_span_steps(1.0, 1024), MIN_SPAN_STEPS);
        assert_eq!(short_span_steps(1e-7, 4096), 4096);
    }

    /// A device whose step falls from 50 to 10 µs as its clocks rise: the
    /// warm-up steps until its seconds are spent and sizes the short span
    /// from the last span's (fast) step; without seconds it steps nothing
    /// and sizes it from the rough step.
    #[test]
    fn the_sustained_warm_up_sizes_the_span_at_the_risen_clocks() {
        let mut spent = 0.0;
        let mut spans = Vec::new();
        let short = sustained_warm_up(
            |n| {
                let step = if spent < 0.05 { 50e-6 } else { 10e-6 };
                let took = n as f64 * step;
                spent += took;
                spans.push(n);
                Ok(took)
            },
            50e-6,
            4096,
            0.2,
        )
        .unwrap();
        assert!(spent >= 0.2, "{spent}");
        assert_eq!(spans[0], 200, "the first span from the rough step");
        assert_eq!(
            short,
            short_span_steps(10e-6, 4096),
            "the last span's 10 µs step"
        );
        assert!((999..=1000).contains(&short), "{short}");
        let none = sustained_warm_up(|_| panic!("no span without seconds"), 50e-6, 4096, 0.0);
        assert_eq!(none.unwrap(), 200);
    }
}
