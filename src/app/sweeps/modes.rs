//! Modes of a pooled sample: the ranges of values separated by gaps much
//! wider than the sample's spread. A chaotic outcome is often multimodal
//! (a first full event in one stick phase or the next); two ensembles can
//! share the modes' shapes and still fill them differently, which the
//! occupancy of each mode shows.

use crate::analysis::stats::median_absolute_deviation;

/// A gap splits a sample when it is wider than this many times the median
/// absolute deviation of either part it leaves,
pub const GAP_FACTOR: f64 = 4.0;
/// wider than this fraction of the whole sample's range (two near values
/// are not two modes),
pub const RANGE_FRACTION: f64 = 0.05;
/// and wider than this fraction of the largest magnitude (round-off is no
/// gap).
pub const RELATIVE_FLOOR: f64 = 1e-6;

/// The modes of `values` as closed ranges (lo, hi), lowest first, every
/// finite value in exactly one. Empty for an empty sample; one mode when
/// the values are all equal.
///
/// The sample is split at its widest gap while that gap passes the three
/// tests above, then each part likewise. The spread is each part's own:
/// against the whole sample's median absolute deviation, two clusters of
/// equal size would never split (that deviation is then half the gap).
pub fn split_at_gaps(values: &[f64]) -> Vec<(f64, f64)> {
    let mut s: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if s.is_empty() {
        return Vec::new();
    }
    s.sort_by(f64::total_cmp);
    let largest = s[0].abs().max(s[s.len() - 1].abs());
    let min_gap = (RANGE_FRACTION * (s[s.len() - 1] - s[0])).max(RELATIVE_FLOOR * largest);
    let mut modes = Vec::new();
    split_sorted(&s, min_gap, &mut modes);
    modes
}

/// Appends the modes of sorted, non-empty `s` to `modes`.
fn split_sorted(s: &[f64], min_gap: f64, modes: &mut Vec<(f64, f64)>) {
    let widest = (1..s.len()).max_by(|&i, &j| (s[i] - s[i - 1]).total_cmp(&(s[j] - s[j - 1])));
    if let Some(i) = widest {
        let gap = s[i] - s[i - 1];
        let spread = median_absolute_deviation(&s[..i]).max(median_absolute_deviation(&s[i..]));
        if gap > min_gap && gap > GAP_FACTOR * spread {
            split_sorted(&s[..i], min_gap, modes);
            split_sorted(&s[i..], min_gap, modes);
            return;
        }
    }
    modes.push((s[0], s[s.len() - 1]));
}

/// Index of the mode holding `v` (modes from [`split_at_gaps`] of a sample
/// holding `v`).
pub fn mode_of(modes: &[(f64, f64)], v: f64) -> Option<usize> {
    modes.iter().position(|&(lo, hi)| v >= lo && v <= hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_clusters_are_two_modes_and_one_cluster_is_one() {
        let mut v: Vec<f64> = (0..20).map(|k| 1.0 + 0.01 * k as f64).collect();
        assert_eq!(split_at_gaps(&v), vec![(1.0, 1.19)]);
        v.extend((0..10).map(|k| 5.0 + 0.01 * k as f64));
        let modes = split_at_gaps(&v);
        assert_eq!(modes, vec![(1.0, 1.19), (5.0, 5.09)]);
        assert_eq!(mode_of(&modes, 5.05), Some(1));
        assert_eq!(mode_of(&modes, 3.0), None);
    }

    #[test]
    fn degenerate_samples_give_no_mode_or_one() {
        assert!(split_at_gaps(&[]).is_empty());
        assert_eq!(split_at_gaps(&[2.5; 6]), vec![(2.5, 2.5)]);
        // Round-off differences are not gaps.
        assert_eq!(split_at_gaps(&[1.0, 1.0, 1.0 + 1e-12]).len(), 1);
    }

    #[test]
    fn equal_clusters_split_and_a_smooth_sample_does_not() {
        // Two clusters of equal size: the whole sample's median absolute
        // deviation is half the gap, each cluster's is small.
        let v: Vec<f64> = (0..30)
            .map(|k| if k < 15 { 1.0 } else { 2.0 } + 0.001 * k as f64)
            .collect();
        assert_eq!(split_at_gaps(&v).len(), 2);
        // A majority of equal values and a pair: two modes, the pair one.
        let v = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 3.0, 3.1];
        assert_eq!(split_at_gaps(&v), vec![(0.0, 0.0), (3.0, 3.1)]);
        // Evenly spread values (a uniform sample) are one mode.
        let v: Vec<f64> = (0..200).map(|k| (k as f64 * 0.618_034).fract()).collect();
        assert_eq!(split_at_gaps(&v).len(), 1);
    }
}
