//! Event analysis of interface time series: slip events (start, end, full
//! or partial, rupture length, slip), the front tip against time from the
//! junction rupture times, the front speed along x, the slip speed behind
//! the tip, and the Gini coefficient of each block's slip history.

/// Interface fields sampled over time: `pinned[k][ix]` etc. at `time[k]`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InterfaceSeries {
    pub time: Vec<f64>,
    /// Block spacing along x (m).
    pub spacing: f64,
    /// Fraction of pinned junctions per block.
    pub pinned: Vec<Vec<f64>>,
    /// Slip u_x − u_x(0) per block (m).
    pub slip: Vec<Vec<f64>>,
    /// Slip speed v_x per block (m/s).
    pub slip_speed: Vec<Vec<f64>>,
}

/// A block counts as ruptured while fewer than this fraction of its
/// junctions are pinned.
pub const RUPTURED_BELOW: f64 = 0.5;

/// Default quiet gap between events (s): longer than a slow front takes to
/// cross one block, far shorter than a stick-slip cycle.
pub const DEFAULT_QUIET_GAP: f64 = 1e-3;

/// One slip event.
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    /// Sample indices of the first and last sample with a ruptured block.
    pub first: usize,
    pub last: usize,
    pub start: f64,
    pub end: f64,
    /// The rupture spanned the whole interface, trailing to leading edge
    /// (with short slip times a block inside may re-pin before it reads as
    /// ruptured).
    pub full: bool,
    /// Extent of the ruptured blocks (m).
    pub rupture_length: f64,
    /// Mean slip of the interface over the event (m).
    pub slip: f64,
    /// Per block: time it first ruptured in the event (None if it did not).
    pub rupture_time: Vec<Option<f64>>,
}

impl Event {
    /// Position of the block that ruptured first (m from the trailing
    /// edge); the trailing-most of those that ruptured in the same sample.
    pub fn origin(&self, spacing: f64) -> f64 {
        let first = self
            .rupture_time
            .iter()
            .enumerate()
            .filter_map(|(ix, t)| t.map(|t| (t, ix)))
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        first.map_or(f64::NAN, |(_, ix)| ix as f64 * spacing)
    }
}

/// Length (m) of interface that blocks `lo..=hi` stand for: l each, half
/// of it for the two edge blocks (which carry half shares of the loads),
/// so that the whole interface is L = (nx − 1)·l.
pub fn ruptured_length(lo: usize, hi: usize, nx: usize, spacing: f64) -> f64 {
    let edges = (lo == 0) as usize + (hi + 1 == nx) as usize;
    ((hi - lo + 1) as f64 - 0.5 * edges as f64).max(0.0) * spacing
}

/// The ruptured blocks reach both edges, to within one block: an edge
/// block carries half the load of the others and may re-pin before the
/// sample that would show it broken. Where the rupture started does not
/// matter.
pub fn spans_interface(lo: usize, hi: usize, nx: usize) -> bool {
    if nx < 4 {
        lo == 0 && hi + 1 == nx
    } else {
        lo <= 1 && hi + 2 >= nx
    }
}

impl InterfaceSeries {
    /// Samples `range` of the series.
    pub fn slice(&self, range: std::ops::Range<usize>) -> InterfaceSeries {
        InterfaceSeries {
            time: self.time[range.clone()].to_vec(),
            spacing: self.spacing,
            pinned: self.pinned[range.clone()].to_vec(),
            slip: self.slip[range.clone()].to_vec(),
            slip_speed: self.slip_speed[range].to_vec(),
        }
    }

    pub fn nx(&self) -> usize {
        self.pinned.first().map_or(0, Vec::len)
    }

    fn any_ruptured(&self, k: usize) -> bool {
        self.pinned[k].iter().any(|&p| p < RUPTURED_BELOW)
    }

    /// Events: runs of samples in which at least one block is ruptured,
    /// runs less than `quiet_gap` seconds apart counting as one event
    /// (0: every maximal run is its own event). With short slip
    /// times every block of a slow front can re-pin before the next one
    /// breaks, which would otherwise split one front into many events.
    pub fn events_separated_by(&self, quiet_gap: f64) -> Vec<Event> {
        let mut runs: Vec<(usize, usize)> = Vec::new();
        let n = self.time.len();
        let mut k = 0;
        while k < n {
            if !self.any_ruptured(k) {
                k += 1;
                continue;
            }
            let first = k;
            while k + 1 < n && self.any_ruptured(k + 1) {
                k += 1;
            }
            match runs.last_mut() {
                Some(last) if self.time[first] - self.time[last.1] < quiet_gap => last.1 = k,
                _ => runs.push((first, k)),
            }
            k += 1;
        }
        runs.into_iter().map(|(a, b)| self.event(a, b)).collect()
    }

    fn event(&self, first: usize, last: usize) -> Event {
        let nx = self.nx();
        let mut rupture_time = vec![None; nx];
        for k in first..=last {
            for (ix, t) in rupture_time.iter_mut().enumerate() {
                if t.is_none() && self.pinned[k][ix] < RUPTURED_BELOW {
                    *t = Some(self.time[k]);
                }
            }
        }
        let ruptured: Vec<usize> = (0..nx).filter(|&ix| rupture_time[ix].is_some()).collect();
        let (lo, hi) = (ruptured[0], *ruptured.last().expect("non-empty"));
        // Slip from the sample before the event to the last one of it.
        let before = first.saturating_sub(1);
        let slip = (0..nx)
            .map(|ix| self.slip[last][ix] - self.slip[before][ix])
            .sum::<f64>()
            / nx as f64;
        Event {
            first,
            last,
            start: self.time[first],
            end: self.time[last],
            full: spans_interface(lo, hi, nx),
            rupture_length: ruptured_length(lo, hi, nx, self.spacing),
            slip,
            rupture_time,
        }
    }

    /// Which windows of [`Self::front_speed`] the samples resolve: a
    /// window whose two blocks first read as ruptured in the same or in
    /// consecutive samples only bounds its speed from below, by w·l over
    /// the time from the sample before the first to the second. Per window
    /// of `front_speed`, in order: None when resolved, else that bound.
    pub fn front_speed_bounds(&self, e: &Event, w: usize) -> Vec<Option<f64>> {
        let t = &e.rupture_time;
        let sample = |at: f64| self.time.partition_point(|&x| x < at);
        (0..t.len().saturating_sub(w))
            .filter_map(|ix| match (t[ix], t[ix + w]) {
                (Some(a), Some(b)) => {
                    let (a, b) = (a.min(b), a.max(b));
                    let (ka, kb) = (sample(a), sample(b));
                    Some((kb <= ka + 1).then(|| {
                        let before = self.time[ka.saturating_sub(1)];
                        w as f64 * self.spacing / (b - before).max(f64::MIN_POSITIVE)
                    }))
                }
                _ => None,
            })
            .collect()
    }

    /// The front speeds of `e` the samples resolve (m/s), and the largest
    /// lower bound of the windows they do not (see
    /// [`Self::front_speed_bounds`]).
    pub fn resolved_front_speeds(&self, e: &Event, w: usize) -> (Vec<f64>, Option<f64>) {
        let bounds = self.front_speed_bounds(e, w);
        let speeds = self
            .front_speed(e, w)
            .iter()
            .zip(&bounds)
            .filter(|(_, b)| b.is_none())
            .map(|(p, _)| p.1)
            .collect();
        (speeds, bounds.iter().flatten().copied().reduce(f64::max))
    }

    /// Front tip position against time: at each sample of the event, the
    /// farthest ruptured block from the trailing edge, (t, x_tip).
    pub fn front_tip(&self, e: &Event) -> Vec<(f64, f64)> {
        (e.first..=e.last)
            .map(|k| {
                let tip = e
                    .rupture_time
                    .iter()
                    .enumerate()
                    .filter(|(_, t)| t.is_some_and(|t| t <= self.time[k]))
                    .map(|(ix, _)| ix)
                    .max()
                    .unwrap_or(0);
                (self.time[k], tip as f64 * self.spacing)
            })
            .collect()
    }

    /// Front speed along x from the rupture times: over a window of `w`
    /// blocks, v(x) = w·l / (t_r(ix + w) − t_r(ix)), at the window's centre.
    /// Infinite where both blocks ruptured in the same sample.
    pub fn front_speed(&self, e: &Event, w: usize) -> Vec<(f64, f64)> {
        let t = &e.rupture_time;
        (0..t.len().saturating_sub(w))
            .filter_map(|ix| match (t[ix], t[ix + w]) {
                (Some(a), Some(b)) => {
                    let x = (ix as f64 + 0.5 * w as f64) * self.spacing;
                    Some((x, w as f64 * self.spacing / (b - a).abs()))
                }
                _ => None,
            })
            .collect()
    }

    /// Slip speed just behind the tip, on the same windows as
    /// [`Self::front_speed`]: the mean slip speed of block ix while the
    /// front runs on from it to block ix + w (its slip over that time
    /// divided by the time), at the window's centre (x, v). A mean, not a
    /// peak: each block jumps briefly when its own junctions let go, at a
    /// speed set by the block, not by the front. Where both blocks broke in
    /// the same sample the block's slip speed in that sample is used.
    pub fn slip_speed_behind_tip(&self, e: &Event, w: usize) -> Vec<(f64, f64)> {
        let t = &e.rupture_time;
        let sample = |at: f64| e.first + self.time[e.first..=e.last].partition_point(|&x| x < at);
        (0..t.len().saturating_sub(w))
            .filter_map(|ix| match (t[ix], t[ix + w]) {
                (Some(a), Some(b)) => {
                    let (ka, kb) = (sample(a.min(b)), sample(a.max(b)));
                    let v = if kb > ka {
                        (self.slip[kb][ix] - self.slip[ka][ix]).abs()
                            / (self.time[kb] - self.time[ka])
                    } else {
                        self.slip_speed[ka][ix].abs()
                    };
                    Some(((ix as f64 + 0.5 * w as f64) * self.spacing, v))
                }
                _ => None,
            })
            .collect()
    }

    /// Gini coefficient of each block's slip increments over the event
    /// (0: slip spread evenly in time; → 1: all slip in one sample).
    pub fn slip_gini(&self, e: &Event) -> Vec<f64> {
        let before = e.first.saturating_sub(1);
        (0..self.nx())
            .map(|ix| {
                let inc: Vec<f64> = (before..e.last)
                    .map(|k| (self.slip[k + 1][ix] - self.slip[k][ix]).abs())
                    .collect();
                gini(&inc)
            })
            .collect()
    }
}

/// Blocks per front-speed window, for `info` and the figures alike.
pub const FRONT_WINDOW: usize = 3;

impl InterfaceSeries {
    /// (front speed, slip speed behind the tip) over every window of every
    /// event, the crossings [`slip_front_relation`] fits.
    pub fn slip_front_pairs(&self, events: &[Event], w: usize) -> Vec<(f64, f64)> {
        events
            .iter()
            .flat_map(|e| {
                // Same windows, so the pairs line up one to one.
                let speeds = self.front_speed(e, w);
                let slip = self.slip_speed_behind_tip(e, w);
                speeds
                    .iter()
                    .zip(&slip)
                    .map(|(f, s)| (f.1, s.1))
                    .collect::<Vec<_>>()
            })
            .collect()
    }
}

/// Front speeds above this count as fast (m/s).
pub const FAST_FRONT: f64 = 100.0;
/// Front speeds below this count as slow (m/s).
pub const SLOW_FRONT: f64 = 30.0;

/// How the front speed evolved along x in an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrontKind {
    /// Never slower than SLOW_FRONT.
    Fast,
    /// Fast, then slow, then fast again.
    FastSlowFast,
    /// Fast, then slow until arrest or the edge.
    FastSlow,
    /// Slow throughout.
    Slow,
}

impl InterfaceSeries {
    /// Classifies the front of `e` from its speed profile along x
    /// (window of `w` blocks).
    pub fn front_kind(&self, e: &Event, w: usize) -> FrontKind {
        let v: Vec<f64> = self.front_speed(e, w).into_iter().map(|p| p.1).collect();
        let first_fast = v.iter().position(|&x| x > FAST_FRONT);
        let slow_after =
            first_fast.and_then(|f| v[f..].iter().position(|&x| x < SLOW_FRONT).map(|k| f + k));
        match (first_fast, slow_after) {
            (None, _) => FrontKind::Slow,
            (Some(_), None) => FrontKind::Fast,
            (Some(_), Some(sl)) => {
                if v[sl..].iter().any(|&x| x > FAST_FRONT) {
                    FrontKind::FastSlowFast
                } else {
                    FrontKind::FastSlow
                }
            }
        }
    }
}

impl InterfaceSeries {
    /// The slow windows of `e`'s front: (front speed, slip speed behind
    /// the tip) where the front runs below `SLOW_FRONT`.
    pub fn slow_windows(&self, e: &Event, w: usize) -> Vec<(f64, f64)> {
        let fronts = self.front_speed(e, w);
        let slips = self.slip_speed_behind_tip(e, w);
        fronts
            .iter()
            .zip(&slips)
            .filter(|(f, _)| f.1 < SLOW_FRONT)
            .map(|(f, s)| (f.1, s.1))
            .collect()
    }

    /// Where the front of `e` turns fast again after its slow stretch: the
    /// centre of the first window above `FAST_FRONT` after the first one
    /// below `SLOW_FRONT` that follows a fast one (None unless the front is
    /// fast–slow–fast).
    pub fn slow_to_fast_at(&self, e: &Event, w: usize) -> Option<f64> {
        let v = self.front_speed(e, w);
        let fast = v.iter().position(|p| p.1 > FAST_FRONT)?;
        let slow = fast + v[fast..].iter().position(|p| p.1 < SLOW_FRONT)?;
        v[slow..].iter().find(|p| p.1 > FAST_FRONT).map(|p| p.0)
    }

    /// The far end of `e`'s rupture from the trailing edge: the centre of
    /// its farthest ruptured block, where a partial event from the
    /// trailing edge arrested.
    pub fn arrest_at(&self, e: &Event) -> Option<f64> {
        e.rupture_time
            .iter()
            .rposition(|t| t.is_some())
            .map(|ix| ix as f64 * self.spacing)
    }

    /// Each fast–slow–fast event's slow-to-fast position beside where the
    /// last precursor before it arrested (PNAS 2014: the transition happens
    /// at the previous arrest point): (event index, transition x, arrest
    /// x). The precursor is the last partial event from the trailing edge
    /// (starting within `TRAILING_EDGE_BLOCKS` of it) since the last full
    /// event; None when there is none.
    pub fn transitions_at_previous_arrest(
        &self,
        events: &[Event],
        w: usize,
    ) -> Vec<(usize, f64, Option<f64>)> {
        let edge = TRAILING_EDGE_BLOCKS as f64 * self.spacing;
        events
            .iter()
            .enumerate()
            .filter_map(|(n, e)| {
                let x = self.slow_to_fast_at(e, w)?;
                let arrest = events[..n]
                    .iter()
                    .rev()
                    .take_while(|p| !p.full)
                    .find(|p| p.origin(self.spacing) <= edge)
                    .and_then(|p| self.arrest_at(p));
                Some((n, x, arrest))
            })
            .collect()
    }
}

/// Blocks from the trailing edge within which an event counts as starting
/// there.
pub const TRAILING_EDGE_BLOCKS: usize = 3;

/// What a triggered front did, the classes of the PRE 2015
/// strength–prestress diagram.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrontClass {
    /// Stopped without a slow stretch (or never ran).
    Arrest,
    /// Went on slowly after its fast part: at least `SLOW_WINDOWS` front
    /// windows below `SLOW_FRONT`, not fast again.
    Slow,
    /// Fast, slow, then fast again.
    FastSlowFast,
    /// Fast to the far edge.
    Fast,
}

/// Front windows below `SLOW_FRONT` that make a slow front: one window is
/// what a dying front leaves as it stops.
pub const SLOW_WINDOWS: usize = 2;

impl FrontClass {
    pub fn name(self) -> &'static str {
        match self {
            FrontClass::Arrest => "arrest",
            FrontClass::Slow => "slow",
            FrontClass::FastSlowFast => "fast_slow_fast",
            FrontClass::Fast => "fast",
        }
    }
}

impl InterfaceSeries {
    /// The class of event `e`'s front (windows of `w` blocks).
    pub fn front_class(&self, e: &Event, w: usize) -> FrontClass {
        let slow = self
            .front_speed(e, w)
            .iter()
            .filter(|p| p.1 < SLOW_FRONT)
            .count();
        match self.front_kind(e, w) {
            FrontKind::FastSlowFast => FrontClass::FastSlowFast,
            FrontKind::Fast if e.full => FrontClass::Fast,
            FrontKind::FastSlow | FrontKind::Slow if slow >= SLOW_WINDOWS => FrontClass::Slow,
            _ => FrontClass::Arrest,
        }
    }
}

/// How slip speed follows front speed over (front speed, slip speed)
/// pairs, in log space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlipFrontRelation {
    /// v_slip = α·v_front through the origin: α = exp(mean(ln v_slip − ln v_front)).
    pub alpha: f64,
    /// Least-squares exponent b of v_slip ∝ v_front^b: 1 when proportional,
    /// 0 when slip speed does not depend on front speed.
    pub exponent: f64,
    /// Correlation of ln v_slip with ln v_front.
    pub correlation: f64,
    /// c of the least-squares line v_slip = c·v_front^exponent.
    pub prefactor: f64,
    pub points: usize,
}

/// Fits [`SlipFrontRelation`] to the finite, positive pairs (None below 3).
pub fn slip_front_relation(pairs: &[(f64, f64)]) -> Option<SlipFrontRelation> {
    let p: Vec<(f64, f64)> = pairs
        .iter()
        .filter(|(f, s)| f.is_finite() && *f > 0.0 && *s > 0.0)
        .map(|(f, s)| (f.ln(), s.ln()))
        .collect();
    if p.len() < 3 {
        return None;
    }
    let n = p.len() as f64;
    let alpha = (p.iter().map(|(f, s)| s - f).sum::<f64>() / n).exp();
    let (mf, ms) = (
        p.iter().map(|q| q.0).sum::<f64>() / n,
        p.iter().map(|q| q.1).sum::<f64>() / n,
    );
    let cov: f64 = p.iter().map(|(f, s)| (f - mf) * (s - ms)).sum();
    let vf: f64 = p.iter().map(|(f, _)| (f - mf).powi(2)).sum();
    let vs: f64 = p.iter().map(|(_, s)| (s - ms).powi(2)).sum();
    Some(SlipFrontRelation {
        alpha,
        exponent: cov / vf.max(1e-300),
        correlation: cov / (vf * vs).sqrt().max(1e-300),
        prefactor: (ms - mf * cov / vf.max(1e-300)).exp(),
        points: p.len(),
    })
}

/// (front speed, slip speed) pairs grouped by decade of front speed:
/// (decade floor, count, median front speed, median slip speed), slowest
/// first. Medians show the trend through the scatter of single crossings.
pub fn slip_front_by_decade(pairs: &[(f64, f64)]) -> Vec<(f64, usize, f64, f64)> {
    let mut groups: std::collections::BTreeMap<i32, Vec<(f64, f64)>> = Default::default();
    for &(f, s) in pairs {
        if f.is_finite() && f > 0.0 && s > 0.0 {
            groups
                .entry(f.log10().floor() as i32)
                .or_default()
                .push((f, s));
        }
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        let n = v.len();
        if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        }
    };
    groups
        .into_iter()
        .map(|(d, g)| {
            let n = g.len();
            let f = median(g.iter().map(|p| p.0).collect());
            let s = median(g.iter().map(|p| p.1).collect());
            (10f64.powi(d), n, f, s)
        })
        .collect()
}

/// Gini coefficient of non-negative values: Σ|x_i − x_j| / (2 n² mean).
pub fn gini(values: &[f64]) -> f64 {
    let n = values.len();
    let total: f64 = values.iter().sum();
    if n == 0 || total <= 0.0 {
        return 0.0;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(|a, b| a.total_cmp(b));
    // Σ_i (2i − n − 1) x_(i) / (n Σ x), i = 1..n, equals the pairwise form.
    let weighted: f64 = sorted
        .iter()
        .enumerate()
        .map(|(i, x)| (2.0 * (i as f64 + 1.0) - n as f64 - 1.0) * x)
        .sum();
    weighted / (n as f64 * total)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A front from the trailing edge at speed `c` starting at t0, the
    /// blocks behind it slipping at `v` until `t_end`; plus, earlier, a
    /// precursor over the first `arrest` blocks.
    fn synthetic(c: f64, v: f64) -> InterfaceSeries {
        let (nx, l, dt) = (50usize, 1e-3, 1e-6);
        let mut s = InterfaceSeries {
            spacing: l,
            ..Default::default()
        };
        let mut slip = vec![0.0; nx];
        for k in 0..400 {
            let t = k as f64 * dt;
            let mut pinned = vec![1.0; nx];
            let mut speed = vec![0.0; nx];
            for ix in 0..nx {
                let x = ix as f64 * l;
                // Precursor: 10 blocks, 20..40 µs.
                let precursor = ix < 10 && (20..40).contains(&k);
                // Full event: front from t0 = 100 µs, arrest at 300 µs.
                let main = t >= 100e-6 + x / c && t < 300e-6;
                if precursor || main {
                    pinned[ix] = 0.0;
                    speed[ix] = v;
                    slip[ix] += v * dt;
                }
            }
            s.time.push(t);
            s.pinned.push(pinned);
            s.slip.push(slip.clone());
            s.slip_speed.push(speed);
        }
        s
    }

    #[test]
    fn finds_a_precursor_and_a_full_event() {
        let s = synthetic(1000.0, 0.5);
        let e = s.events_separated_by(0.0);
        assert_eq!(e.len(), 2, "{e:?}");
        assert!(!e[0].full);
        // Ten blocks from the trailing edge: 9.5 l (the edge block's half).
        assert!((e[0].rupture_length - 9.5e-3).abs() < 1e-12);
        assert!((e[0].start - 20e-6).abs() < 1e-9, "{}", e[0].start);
        assert!((e[0].end - 39e-6).abs() < 1e-9, "{}", e[0].end);
        assert!(e[1].full);
        assert!((e[1].start - 100e-6).abs() <= 1.0001e-6, "{}", e[1].start);
        // The whole interface: L = (nx − 1)·l.
        assert!((e[1].rupture_length - 49e-3).abs() < 1e-12);
        assert_eq!(e[1].origin(s.spacing), 0.0);
        // Mean slip of the full event: v × (300 µs − t_r(x)) averaged over x.
        let expected: f64 = (0..50)
            .map(|ix| 0.5 * (300e-6 - (100e-6 + ix as f64 * 1e-6)))
            .sum::<f64>()
            / 50.0;
        assert!(
            (e[1].slip - expected).abs() < 0.02 * expected,
            "{} vs {expected}",
            e[1].slip
        );
    }

    #[test]
    fn a_rupture_from_edge_to_edge_is_full_even_with_a_block_that_held() {
        let mut s = synthetic(1000.0, 0.5);
        for p in &mut s.pinned {
            p[25] = 1.0;
        }
        let e = &s.events_separated_by(0.0)[1];
        assert!(e.full && e.rupture_time[25].is_none());
        // The edge block itself may hold (it carries half the load).
        for p in &mut s.pinned {
            p[49] = 1.0;
        }
        assert!(s.events_separated_by(0.0)[1].full);
        // Negative control: a rupture that stops two blocks short of the
        // leading edge.
        for p in &mut s.pinned {
            p[48] = 1.0;
        }
        assert!(!s.events_separated_by(0.0)[1].full);
    }

    #[test]
    fn events_closer_than_the_quiet_gap_merge() {
        let s = synthetic(1000.0, 0.5);
        // Precursor ends at 39 µs, the full event starts at 100 µs.
        assert_eq!(s.events_separated_by(50e-6).len(), 2);
        let merged = s.events_separated_by(70e-6);
        assert_eq!(merged.len(), 1);
        assert!(merged[0].full);
        assert_eq!(merged[0].start, s.time[20]);
    }

    #[test]
    fn front_tip_and_speed_recover_the_imposed_speed() {
        for c in [1000.0, 100.0] {
            let s = synthetic(c, 0.5);
            let e = &s.events_separated_by(0.0)[1];
            let tip = s.front_tip(e);
            // The tip reaches x at 100 µs + x/c.
            let (t, x) = tip[30];
            assert!(
                (x - (t - 100e-6) * c).abs() <= 1.5e-3,
                "c = {c}: tip {x} at {t}"
            );
            let speeds = s.front_speed(e, 10);
            let mean = speeds.iter().map(|p| p.1).sum::<f64>() / speeds.len() as f64;
            assert!((mean - c).abs() < 0.1 * c, "c = {c}: measured {mean}");
        }
    }

    #[test]
    fn slip_speed_behind_the_tip_is_the_imposed_one() {
        let mut s = synthetic(1000.0, 0.7);
        // Block 5 jumps long after the front passed: not its front slip.
        let late = s.time.iter().position(|&t| t >= 250e-6).unwrap();
        for k in late..s.time.len() {
            s.slip[k][5] += 1e-3;
        }
        let e = &s.events_separated_by(0.0)[1];
        let v = s.slip_speed_behind_tip(e, 3);
        assert_eq!(v.len(), 47);
        for (_, v) in &v {
            assert!((v - 0.7).abs() < 1e-9, "{v}");
        }
        // Pairs with the front speeds at the same positions.
        let f = s.front_speed(e, 3);
        assert!(f.iter().zip(&v).all(|(a, b)| a.0 == b.0));
    }

    #[test]
    fn front_kinds_and_the_slip_front_relation() {
        let s = synthetic(1000.0, 0.5);
        assert_eq!(
            s.front_kind(&s.events_separated_by(0.0)[1], 5),
            FrontKind::Fast
        );
        let slow = synthetic(10.0, 0.5);
        assert_eq!(
            slow.front_kind(&slow.events_separated_by(0.0)[1], 5),
            FrontKind::Slow
        );
        // v_slip = 1e-3 v_front exactly.
        let pairs: Vec<(f64, f64)> = [1.0, 10.0, 100.0, 1000.0]
            .iter()
            .map(|&f| (f, 1e-3 * f))
            .collect();
        let fit = slip_front_relation(&pairs).unwrap();
        assert!((fit.alpha - 1e-3).abs() < 1e-12 && (fit.correlation - 1.0).abs() < 1e-12);
        assert!((fit.exponent - 1.0).abs() < 1e-12);
        // Negative control: slip speed that ignores the front speed (with
        // scatter) has exponent near 0, not 1.
        let flat: Vec<(f64, f64)> = [1.0, 10.0, 100.0, 1000.0]
            .iter()
            .zip([0.05, 0.07, 0.04, 0.06])
            .map(|(&f, s)| (f, s))
            .collect();
        assert!(slip_front_relation(&flat).unwrap().exponent.abs() < 0.1);
    }

    #[test]
    fn fast_slow_fast_is_recognised() {
        // Rupture times: fast over blocks 0..15, slow over 15..30, fast after.
        let mut t = 0.0;
        let mut times = Vec::new();
        for ix in 0..50 {
            times.push(Some(t));
            t += if (15..30).contains(&ix) {
                1e-3 / 5.0
            } else {
                1e-3 / 1000.0
            };
        }
        let s = InterfaceSeries {
            spacing: 1e-3,
            ..Default::default()
        };
        let e = Event {
            first: 0,
            last: 0,
            start: 0.0,
            end: t,
            full: true,
            rupture_length: 0.05,
            slip: 0.0,
            rupture_time: times,
        };
        assert_eq!(s.front_kind(&e, 3), FrontKind::FastSlowFast);
        assert_eq!(s.front_class(&e, 3), FrontClass::FastSlowFast);
        // It turns fast again at block 30: the first fast window after the
        // slow stretch spans blocks 30..33, centred at 31.5 mm.
        let x = s.slow_to_fast_at(&e, 3).unwrap();
        assert!((x - 31.5e-3).abs() < 1e-12, "{x}");
        // An event that arrested at block 29 before it: 1.5 mm apart.
        let mut before = e.clone();
        before.full = false;
        for t in &mut before.rupture_time[30..] {
            *t = None;
        }
        assert_eq!(s.arrest_at(&before), Some(29e-3));
        let pairs = s.transitions_at_previous_arrest(&[before.clone(), e], 3);
        assert_eq!(pairs.len(), 1);
        assert_eq!((pairs[0].0, pairs[0].2), (1, Some(29e-3)));
        // A front that is never slow has no transition.
        assert_eq!(s.slow_to_fast_at(&before, 3), None);
    }

    /// An event whose front runs at 1000 m/s over `fast` blocks, then at
    /// 5 m/s over `slow` blocks, and stops there (`full`: it reached the
    /// far edge).
    fn front(fast: usize, slow: usize, full: bool) -> Event {
        let mut t = 0.0;
        let mut times = Vec::new();
        for ix in 0..50 {
            if ix > fast + slow {
                times.push(None);
                continue;
            }
            times.push(Some(t));
            t += 1e-3 / if ix < fast { 1000.0 } else { 5.0 };
        }
        Event {
            first: 0,
            last: 0,
            start: 0.0,
            end: t,
            full,
            rupture_length: 1e-3 * (fast + slow) as f64,
            slip: 0.0,
            rupture_time: times,
        }
    }

    #[test]
    fn triggered_fronts_are_classed_as_in_the_strength_prestress_diagram() {
        let s = InterfaceSeries {
            spacing: 1e-3,
            ..Default::default()
        };
        assert_eq!(s.front_class(&front(49, 0, true), 3), FrontClass::Fast);
        // Fast, then slow over 10 blocks before it stops: a slow front.
        assert_eq!(s.front_class(&front(20, 10, false), 3), FrontClass::Slow);
        // Fast, then dying within a block: one slow window, an arrest.
        assert_eq!(s.front_class(&front(20, 1, false), 3), FrontClass::Arrest);
        // Fast but not to the edge: an arrest.
        assert_eq!(s.front_class(&front(20, 0, false), 3), FrontClass::Arrest);
        assert_eq!(FrontClass::FastSlowFast.name(), "fast_slow_fast");
    }

    #[test]
    fn slip_front_pairs_group_by_decade_with_medians() {
        let pairs = [
            (15.0, 0.015),
            (20.0, 0.02),
            (50.0, 0.9),
            (1500.0, 1.5),
            (f64::INFINITY, 3.0),
        ];
        let g = slip_front_by_decade(&pairs);
        assert_eq!(g.len(), 2);
        assert_eq!((g[0].0, g[0].1, g[0].2, g[0].3), (10.0, 3, 20.0, 0.02));
        assert_eq!((g[1].0, g[1].1, g[1].2, g[1].3), (1000.0, 1, 1500.0, 1.5));
    }

    #[test]
    fn gini_of_even_and_concentrated_slip() {
        assert!(gini(&[1.0; 10]).abs() < 1e-12);
        let mut one = vec![0.0; 10];
        one[3] = 5.0;
        assert!((gini(&one) - 0.9).abs() < 1e-12);
        assert_eq!(gini(&[]), 0.0);
        // Pairwise definition on a small sample.
        let x: [f64; 3] = [1.0, 2.0, 7.0];
        let pairwise: f64 = x
            .iter()
            .flat_map(|a| x.iter().map(move |b| (a - b).abs()))
            .sum::<f64>()
            / (2.0 * 9.0 * (10.0 / 3.0));
        assert!((gini(&x) - pairwise).abs() < 1e-12);
        // In the synthetic event every block slips evenly while it slips.
        let s = synthetic(1000.0, 0.5);
        let e = &s.events_separated_by(0.0)[1];
        let g = s.slip_gini(e);
        assert!(
            g[0] < g[49],
            "blocks that slip for less time concentrate their slip"
        );
    }
}
