//! Two-sample tests for comparing ensembles of chaotic runs: the
//! Kolmogorov–Smirnov and Anderson–Darling tests on continuous outcomes
//! and an exact test on contingency tables of counts or mode occupancies.
//! Pure std: no numerical library, every p-value computed here.

/// A test's statistic and p-value.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TestResult {
    pub statistic: f64,
    pub p: f64,
}

/// Largest n·m for which the KS p-value is exact (the lattice-path
/// recursion costs n·m operations, well under a millisecond here).
pub const KS_EXACT_MAX_CELLS: usize = 1_000_000;

/// Two-sample Kolmogorov–Smirnov test, two-sided. D is the largest gap
/// between the two empirical CDFs, taken after each distinct pooled value
/// (so tied values step both CDFs at once). None when a sample is empty
/// or holds a non-finite value.
///
/// p-value: for n·m ≤ [`KS_EXACT_MAX_CELLS`], exact under the no-ties null
/// by the lattice-path recursion (the probability that a random path from
/// (0,0) to (n,m) reaches |i/n − j/m| ≥ D); with ties this is
/// conservative (the p-value is at least the one conditional on the ties).
/// Beyond, the asymptotic Kolmogorov distribution with Stephens's
/// small-sample correction, λ = (√nₑ + 0.12 + 0.11/√nₑ)·D, nₑ = nm/(n+m).
pub fn ks_two_sample(a: &[f64], b: &[f64]) -> Option<TestResult> {
    let (n, m) = (a.len(), b.len());
    if n == 0 || m == 0 || a.iter().chain(b).any(|v| !v.is_finite()) {
        return None;
    }
    let (a, b) = (sorted(a), sorted(b));
    // D·n·m as an integer: |i·m − j·n| after each distinct value.
    let (mut i, mut j, mut gap) = (0usize, 0usize, 0usize);
    while i < n || j < m {
        let x = match (a.get(i), b.get(j)) {
            (Some(&x), Some(&y)) => x.min(y),
            (Some(&x), None) => x,
            (None, Some(&y)) => y,
            (None, None) => unreachable!(),
        };
        while i < n && a[i] == x {
            i += 1;
        }
        while j < m && b[j] == x {
            j += 1;
        }
        gap = gap.max((i * m).abs_diff(j * n));
    }
    let statistic = gap as f64 / (n * m) as f64;
    let p = if gap == 0 {
        1.0
    } else if n * m <= KS_EXACT_MAX_CELLS {
        ks_exact_p(n, m, gap)
    } else {
        let ne = (n * m) as f64 / (n + m) as f64;
        kolmogorov_q((ne.sqrt() + 0.12 + 0.11 / ne.sqrt()) * statistic)
    };
    Some(TestResult {
        statistic,
        p: p.clamp(0.0, 1.0),
    })
}

/// P(D·n·m ≥ gap) under the null: the fraction of the C(n+m, n) lattice
/// paths that touch |i·m − j·n| ≥ gap. Kept as fractions of the paths into
/// each node (the crossing fraction), so nothing overflows and small
/// p-values keep their relative precision.
fn ks_exact_p(n: usize, m: usize, gap: usize) -> f64 {
    let crossed = |i: usize, j: usize| (i * m).abs_diff(j * n) >= gap;
    // row[j]: crossing fraction of the paths into (i, j).
    let mut row = vec![0.0f64; m + 1];
    for j in 1..=m {
        row[j] = if crossed(0, j) { 1.0 } else { row[j - 1] };
    }
    for i in 1..=n {
        row[0] = if crossed(i, 0) { 1.0 } else { row[0] };
        for j in 1..=m {
            row[j] = if crossed(i, j) {
                1.0
            } else {
                // Of the paths into (i, j), a fraction i/(i+j) come from
                // (i−1, j) and j/(i+j) from (i, j−1).
                (i as f64 * row[j] + j as f64 * row[j - 1]) / (i + j) as f64
            };
        }
    }
    row[m]
}

/// The Kolmogorov distribution's upper tail Q(λ) = 2 Σ (−1)^(k−1) e^(−2k²λ²).
pub fn kolmogorov_q(lambda: f64) -> f64 {
    if lambda < 0.2 {
        return 1.0;
    }
    let mut sum = 0.0;
    for k in 1..=100 {
        let term = (-2.0 * (k * k) as f64 * lambda * lambda).exp();
        sum += if k % 2 == 1 { term } else { -term };
        if term < 1e-16 * sum.abs() {
            break;
        }
    }
    (2.0 * sum).clamp(0.0, 1.0)
}

fn sorted(v: &[f64]) -> Vec<f64> {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s
}

/// Permutations behind the Anderson–Darling p-value.
pub const AD_PERMUTATIONS: usize = 20_000;
/// Seed of the permutations, fixed so that a comparison is reproducible.
pub const AD_SEED: u64 = 0x5eed_ad2a;

/// The k-sample Anderson–Darling test of Scholz & Stephens (1987), in its
/// form for ties (A²akN, eq. 7, midranks: the same as scipy's
/// `anderson_ksamp`), for two or more samples.
///
/// `statistic` is A²akN itself (its null mean is k − 1); the p-value is a
/// permutation p-value: the pooled values are dealt back to samples of the
/// same sizes [`AD_PERMUTATIONS`] times with a fixed seed, and p = (1 + the
/// deals whose A² ≥ the observed) / (1 + deals). Unlike Scholz & Stephens's
/// interpolation table (which scipy clips to 0.001 ..= 0.25) this is valid
/// with ties and resolves p down to 1/(1 + deals) ≈ 5e-5.
/// None when fewer than two samples, one is empty, or a value is not finite.
/// All values equal: A² = 0, p = 1.
pub fn anderson_darling_ksample(samples: &[&[f64]]) -> Option<TestResult> {
    let k = samples.len();
    if k < 2
        || samples.iter().any(|s| s.is_empty())
        || samples
            .iter()
            .flat_map(|s| s.iter())
            .any(|v| !v.is_finite())
    {
        return None;
    }
    // The pooled values in order, each with its sample; ties grouped.
    let mut pooled: Vec<(f64, usize)> = samples
        .iter()
        .enumerate()
        .flat_map(|(g, s)| s.iter().map(move |&v| (v, g)))
        .collect();
    pooled.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut ties = Vec::new();
    let mut start = 0;
    for idx in 1..=pooled.len() {
        if idx == pooled.len() || pooled[idx].0 != pooled[start].0 {
            ties.push(idx - start);
            start = idx;
        }
    }
    if ties.len() == 1 {
        return Some(TestResult {
            statistic: 0.0,
            p: 1.0,
        });
    }
    let sizes: Vec<usize> = samples.iter().map(|s| s.len()).collect();
    let mut labels: Vec<usize> = pooled.iter().map(|p| p.1).collect();
    let observed = ad_statistic(&labels, &ties, &sizes);
    let mut rng = SplitMix64(AD_SEED);
    let mut as_large = 0usize;
    for _ in 0..AD_PERMUTATIONS {
        rng.shuffle(&mut labels);
        // Relative slack: a deal equal to the observed up to round-off counts.
        if ad_statistic(&labels, &ties, &sizes) >= observed * (1.0 - 1e-12) {
            as_large += 1;
        }
    }
    Some(TestResult {
        statistic: observed,
        p: (1 + as_large) as f64 / (1 + AD_PERMUTATIONS) as f64,
    })
}

/// A²akN of the pooled values' sample `labels` (in value order) with tie
/// groups of sizes `ties`.
fn ad_statistic(labels: &[usize], ties: &[usize], sizes: &[usize]) -> f64 {
    let n_total = labels.len() as f64;
    let k = sizes.len();
    // Per sample: values below the current tie group, and in it.
    let mut below = vec![0usize; k];
    let mut within = vec![0usize; k];
    let mut sums = vec![0.0f64; k];
    let mut start = 0usize;
    for &l in ties {
        within.iter_mut().for_each(|w| *w = 0);
        for &g in &labels[start..start + l] {
            within[g] += 1;
        }
        let (lj, bj) = (l as f64, start as f64 + l as f64 / 2.0);
        let denominator = bj * (n_total - bj) - n_total * lj / 4.0;
        if denominator > 0.0 {
            for g in 0..k {
                let mij = below[g] as f64 + within[g] as f64 / 2.0;
                let d = n_total * mij - bj * sizes[g] as f64;
                sums[g] += lj / n_total * d * d / denominator;
            }
        }
        for g in 0..k {
            below[g] += within[g];
        }
        start += l;
    }
    let total: f64 = sums.iter().zip(sizes).map(|(s, &n)| s / n as f64).sum();
    total * (n_total - 1.0) / n_total
}

/// A small, fixed-seed generator for the permutations (SplitMix64).
struct SplitMix64(u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in 0..n (Lemire's multiply-shift; the bias is < n/2⁶⁴).
    fn below(&mut self, n: usize) -> usize {
        ((self.next() as u128 * n as u128) >> 64) as usize
    }

    fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            v.swap(i, self.below(i + 1));
        }
    }
}

/// Subtrees the exact 2×k enumeration may open before it gives way to a
/// Monte Carlo estimate (a fraction of a second).
pub const EXACT_TABLE_NODES: usize = 2_000_000;
/// Random tables behind a Monte Carlo 2×k p-value.
pub const TABLE_SIMULATIONS: usize = 100_000;
/// Seed of the random tables, fixed so that a comparison is reproducible.
pub const TABLE_SEED: u64 = 0x5eed_2b0c;

/// A contingency-table test's p-value and how it was found.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TableTest {
    pub p: f64,
    /// Random tables drawn for a Monte Carlo estimate; 0 when exact.
    pub simulated: usize,
}

/// Test of independence on a 2×k table (`rows[0][j]`, `rows[1][j]`: the
/// two sides' counts in category j): Fisher's exact test for k = 2,
/// Freeman–Halton for more. p is the total null probability (hypergeometric,
/// margins fixed) of the tables no more probable than the observed one
/// (within a relative 1e-7, as R and scipy do). Categories empty on both
/// sides are dropped; one category left (or an empty side): p = 1.
///
/// Exact by enumerating the tables column by column, with the network
/// algorithm's bounds pruning whole subtrees: where every completion is at
/// most as probable as the observed table their total probability is added
/// at once (Vandermonde's identity), where none is the subtree is skipped.
/// Tables far in a tail of many columns can still need more than
/// [`EXACT_TABLE_NODES`] subtrees; then p is the Monte Carlo estimate
/// (1 + as probable or less) / (1 + [`TABLE_SIMULATIONS`]) over random
/// tables with the same margins and a fixed seed (as R's
/// `simulate.p.value`), said in `simulated`.
/// None when the two rows differ in length.
pub fn exact_2xk(rows: [&[u64]; 2]) -> Option<TableTest> {
    if rows[0].len() != rows[1].len() {
        return None;
    }
    let (top, columns): (Vec<u64>, Vec<u64>) = rows[0]
        .iter()
        .zip(rows[1])
        .filter(|(a, b)| **a + **b > 0)
        .map(|(&a, &b)| (a, a + b))
        .unzip();
    let n_top: u64 = top.iter().sum();
    let n: u64 = columns.iter().sum();
    if columns.len() < 2 || n_top == 0 || n_top == n {
        return Some(TableTest {
            p: 1.0,
            simulated: 0,
        });
    }
    let table = Margins::new(columns, n_top);
    let observed = table.weight(&top);
    let threshold = observed + 1e-7 * observed.abs().max(1.0);
    Some(match table.enumerate(threshold) {
        Some(p) => TableTest {
            p: p.min(1.0),
            simulated: 0,
        },
        None => TableTest {
            p: table.simulate(threshold),
            simulated: TABLE_SIMULATIONS,
        },
    })
}

/// The margins of a 2×k table: column totals and the top row's total.
struct Margins {
    columns: Vec<u64>,
    n_top: u64,
    ln_factorials: Vec<f64>,
}

impl Margins {
    fn new(columns: Vec<u64>, n_top: u64) -> Margins {
        let n = columns.iter().sum::<u64>() as usize;
        Margins {
            columns,
            n_top,
            ln_factorials: ln_factorials(n),
        }
    }

    fn ln_choose(&self, a: u64, b: u64) -> f64 {
        let f = &self.ln_factorials;
        f[a as usize] - f[b as usize] - f[(a - b) as usize]
    }

    /// ln of the weight of column j holding x of the top row; a table's
    /// probability is Π C(c_j, x_j) / C(n, n_top).
    fn column_weight(&self, j: usize, x: u64) -> f64 {
        self.ln_choose(self.columns[j], x)
    }

    fn weight(&self, top: &[u64]) -> f64 {
        top.iter()
            .enumerate()
            .map(|(j, &x)| self.column_weight(j, x))
            .sum()
    }

    /// The total probability of the tables of ln-weight ≤ threshold, or
    /// None past [`EXACT_TABLE_NODES`] subtrees.
    fn enumerate(&self, threshold: f64) -> Option<f64> {
        let k = self.columns.len();
        // Before column j: the columns from j on hold `rest[j]`, and can
        // add at most `most[j][r]` and at least `least[j][r]` to the
        // ln-weight with r still to place on top.
        let mut rest = vec![0u64; k + 1];
        for j in (0..k).rev() {
            rest[j] = rest[j + 1] + self.columns[j];
        }
        let r_max = self.n_top as usize;
        let mut most = vec![vec![f64::NEG_INFINITY; r_max + 1]; k + 1];
        let mut least = vec![vec![f64::INFINITY; r_max + 1]; k + 1];
        most[k][0] = 0.0;
        least[k][0] = 0.0;
        for j in (0..k).rev() {
            for r in 0..=r_max {
                for x in 0..=self.columns[j].min(r as u64) {
                    let after = r - x as usize;
                    if most[j + 1][after].is_finite() {
                        let w = self.column_weight(j, x);
                        most[j][r] = most[j][r].max(w + most[j + 1][after]);
                        least[j][r] = least[j][r].min(w + least[j + 1][after]);
                    }
                }
            }
        }
        let total = self.ln_choose(rest[0], self.n_top);
        let mut p = 0.0;
        let mut opened = 0usize;
        // Depth-first over (column, count still to place, weight so far).
        let mut stack = vec![(0usize, self.n_top, 0.0f64)];
        while let Some((j, r, w)) = stack.pop() {
            let ru = r as usize;
            if w + most[j][ru] <= threshold {
                // Every completion counts: they weigh C(rest, r) in all.
                p += (w + self.ln_choose(rest[j], r) - total).exp();
            } else if w + least[j][ru] <= threshold {
                // Some do (j < k here: at k, most = least = 0).
                opened += 1;
                if opened > EXACT_TABLE_NODES {
                    return None;
                }
                for x in 0..=self.columns[j].min(r) {
                    if most[j + 1][ru - x as usize].is_finite() {
                        stack.push((j + 1, r - x, w + self.column_weight(j, x)));
                    }
                }
            }
        }
        Some(p)
    }

    /// Monte Carlo p: random tables with these margins (the top row a
    /// random n_top of the n items), as probable as the observed or less.
    fn simulate(&self, threshold: f64) -> f64 {
        let mut items: Vec<usize> = self
            .columns
            .iter()
            .enumerate()
            .flat_map(|(j, &c)| std::iter::repeat_n(j, c as usize))
            .collect();
        let mut rng = SplitMix64(TABLE_SEED);
        let mut top = vec![0u64; self.columns.len()];
        let mut as_extreme = 0usize;
        for _ in 0..TABLE_SIMULATIONS {
            // The first n_top of a partial Fisher–Yates shuffle.
            top.iter_mut().for_each(|t| *t = 0);
            for i in 0..self.n_top as usize {
                let pick = i + rng.below(items.len() - i);
                items.swap(i, pick);
                top[items[i]] += 1;
            }
            if self.weight(&top) <= threshold {
                as_extreme += 1;
            }
        }
        (1 + as_extreme) as f64 / (1 + TABLE_SIMULATIONS) as f64
    }
}

/// ln(i!) for i in 0..=n.
fn ln_factorials(n: usize) -> Vec<f64> {
    let mut out = vec![0.0; n + 1];
    for i in 1..=n {
        out[i] = out[i - 1] + (i as f64).ln();
    }
    out
}

/// Location and spread of a sample: size, extremes, quartiles (linear
/// interpolation between order statistics, numpy's default).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Quartiles {
    pub n: usize,
    pub min: f64,
    pub q1: f64,
    pub median: f64,
    pub q3: f64,
    pub max: f64,
}

impl Quartiles {
    /// None for an empty sample.
    pub fn of(values: &[f64]) -> Option<Quartiles> {
        if values.is_empty() {
            return None;
        }
        let s = sorted(values);
        Some(Quartiles {
            n: s.len(),
            min: s[0],
            q1: quantile_sorted(&s, 0.25),
            median: quantile_sorted(&s, 0.5),
            q3: quantile_sorted(&s, 0.75),
            max: s[s.len() - 1],
        })
    }
}

/// The q-quantile of sorted, non-empty `s` (linear interpolation).
pub fn quantile_sorted(s: &[f64], q: f64) -> f64 {
    let h = q * (s.len() - 1) as f64;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(s.len() - 1);
    s[lo] + (h - lo as f64) * (s[hi] - s[lo])
}

/// Median absolute deviation from the median (unscaled); 0 for an empty sample.
pub fn median_absolute_deviation(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let s = sorted(values);
    let median = quantile_sorted(&s, 0.5);
    let deviations = sorted(&s.iter().map(|v| (v - median).abs()).collect::<Vec<_>>());
    quantile_sorted(&deviations, 0.5)
}

/// Midranks (1-based; tied values share the mean of their ranks).
fn midranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&i, &j| values[i].total_cmp(&values[j]));
    let mut ranks = vec![0.0; values.len()];
    let mut k = 0;
    while k < order.len() {
        let mut end = k + 1;
        while end < order.len() && values[order[end]] == values[order[k]] {
            end += 1;
        }
        let rank = (k + end + 1) as f64 / 2.0;
        for &i in &order[k..end] {
            ranks[i] = rank;
        }
        k = end;
    }
    ranks
}

/// Spearman's rank correlation of paired samples (Pearson's on midranks);
/// None with fewer than 3 pairs or a constant sample.
pub fn spearman(x: &[f64], y: &[f64]) -> Option<f64> {
    let n = x.len().min(y.len());
    if n < 3 {
        return None;
    }
    let (rx, ry) = (midranks(&x[..n]), midranks(&y[..n]));
    let mean = (n as f64 + 1.0) / 2.0;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in rx.iter().zip(&ry) {
        sxy += (a - mean) * (b - mean);
        sxx += (a - mean) * (a - mean);
        syy += (b - mean) * (b - mean);
    }
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spearman_of_monotone_reversed_and_tied_samples() {
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(spearman(&x, &[2.0, 4.0, 8.0, 16.0, 32.0]), Some(1.0));
        assert_eq!(spearman(&x, &[5.0, 4.0, 3.0, 2.0, 1.0]), Some(-1.0));
        // Ties share ranks: y = [1, 1, 2, 2, 3] against x gives 3/√10
        let r = spearman(&x, &[1.0, 1.0, 2.0, 2.0, 3.0]).unwrap();
        assert!((r - 0.948_683_298_050_513_8).abs() < 1e-12, "{r}");
        assert_eq!(spearman(&x, &[1.0; 5]), None);
        assert_eq!(spearman(&x[..2], &x[..2]), None);
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    /// Deterministic pseudo-random uniforms for samples.
    fn uniforms(seed: u64, n: usize) -> Vec<f64> {
        let mut r = SplitMix64(seed);
        (0..n)
            .map(|_| (r.next() >> 11) as f64 / (1u64 << 53) as f64)
            .collect()
    }

    #[test]
    fn ks_of_fully_separated_samples_is_two_paths_in_all() {
        let a = [1.0, 2.0, 3.0, 4.0, 5.0];
        let b = [6.0, 7.0, 8.0, 9.0, 10.0];
        let r = ks_two_sample(&a, &b).unwrap();
        assert_eq!(r.statistic, 1.0);
        // Only the two paths along the edges reach D = 1: 2 / C(10, 5).
        assert!(close(r.p, 2.0 / 252.0, 1e-12), "{}", r.p);
        // Symmetric in the samples.
        assert_eq!(ks_two_sample(&b, &a).unwrap(), r);
    }

    #[test]
    fn ks_matches_scipy_exact_values() {
        // scipy.stats.ks_2samp(a, b, method="exact") (scipy 1.17):
        // D = 0.4, p = 0.28294924889...
        let a = [
            0.61, 0.29, 0.06, 0.59, -1.73, -0.74, 0.51, -0.56, 0.39, 1.64,
        ];
        let b = [
            0.45, 1.75, 0.52, 0.10, 1.24, 0.30, -0.36, 1.60, 0.61, 0.83, 0.94, 1.08,
        ];
        let r = ks_two_sample(&a, &b).unwrap();
        assert!(close(r.statistic, SCIPY_KS.0, 1e-12), "{r:?}");
        assert!(close(r.p, SCIPY_KS.1, 1e-9), "{r:?}");
    }

    #[test]
    fn ks_identical_samples_give_p_one_and_empty_ones_nothing() {
        let a = [3.0, 1.0, 2.0, 2.0];
        let r = ks_two_sample(&a, &a).unwrap();
        assert_eq!((r.statistic, r.p), (0.0, 1.0));
        assert!(ks_two_sample(&a, &[]).is_none());
        assert!(ks_two_sample(&a, &[f64::NAN]).is_none());
        // All values equal on both sides: no difference.
        assert_eq!(ks_two_sample(&[1.0; 5], &[1.0; 7]).unwrap().p, 1.0);
    }

    #[test]
    fn ks_asymptotic_agrees_with_the_exact_distribution_for_large_samples() {
        let a = uniforms(1, 400);
        let b: Vec<f64> = uniforms(2, 500).iter().map(|v| v * 1.12).collect();
        let r = ks_two_sample(&a, &b).unwrap();
        let ne = 400.0 * 500.0 / 900.0f64;
        let asymptotic = kolmogorov_q((ne.sqrt() + 0.12 + 0.11 / ne.sqrt()) * r.statistic);
        assert!(r.p < 0.1, "{r:?}");
        assert!(close(asymptotic, r.p, 0.1), "{asymptotic} vs exact {}", r.p);
        // Q at the classic 5 % point λ = 1.358.
        assert!(close(kolmogorov_q(1.3581), 0.05, 1e-3));
    }

    #[test]
    fn ad_statistic_matches_scipy_with_and_without_ties() {
        // scipy.stats.anderson_ksamp([a, b]).statistic is standardised:
        // (A²akN − (k−1)) / σ; the raw A²akN values below are from scipy's
        // _anderson_ksamp_midrank (scipy 1.17).
        let a = [
            0.61, 0.29, 0.06, 0.59, -1.73, -0.74, 0.51, -0.56, 0.39, 1.64,
        ];
        let b = [
            0.45, 1.75, 0.52, 0.10, 1.24, 0.30, -0.36, 1.60, 0.61, 0.83, 0.94, 1.08,
        ];
        let r = anderson_darling_ksample(&[&a, &b]).unwrap();
        assert!(close(r.statistic, SCIPY_AD_RAW, 1e-10), "{r:?}");
        // scipy's permutation p-value (its table gives 0.074); ours comes
        // from 20000 deals, within ~4 standard errors (σ ≈ 0.0019).
        assert!((r.p - SCIPY_AD_PERMUTATION_P).abs() < 0.008, "{r:?}");
        let ties_a = [1.0, 2.0, 2.0, 3.0, 3.0, 3.0, 4.0];
        let ties_b = [2.0, 3.0, 4.0, 4.0, 5.0, 5.0];
        let r = anderson_darling_ksample(&[&ties_a, &ties_b]).unwrap();
        assert!(close(r.statistic, SCIPY_AD_RAW_TIES, 1e-10), "{r:?}");
    }

    #[test]
    fn ad_p_value_is_a_reproducible_permutation_estimate() {
        // Fully separated 5 and 5: only the 2 of the C(10,5) = 252 deals
        // that separate them reach the observed A², so p ≈ 2/252 within the
        // permutation error (√(p/20000) ≈ 6e-4).
        let a = [1.0, 2.0, 3.0, 4.0, 5.0];
        let b = [6.0, 7.0, 8.0, 9.0, 10.0];
        let r = anderson_darling_ksample(&[&a, &b]).unwrap();
        assert!((r.p - 2.0 / 252.0).abs() < 3e-3, "{r:?}");
        assert_eq!(anderson_darling_ksample(&[&a, &b]).unwrap(), r);
        // The same sample twice: A² at its smallest, p = 1.
        let same = anderson_darling_ksample(&[&a, &a]).unwrap();
        assert!(same.p > 0.99, "{same:?}");
        let equal = anderson_darling_ksample(&[&[2.0; 4], &[2.0; 3]]).unwrap();
        assert_eq!((equal.statistic, equal.p), (0.0, 1.0));
        assert!(anderson_darling_ksample(&[&a]).is_none());
        assert!(anderson_darling_ksample(&[&a, &[]]).is_none());
    }

    #[test]
    fn ad_and_ks_find_a_shift_and_not_a_second_draw() {
        let a = uniforms(3, 150);
        let b = uniforms(4, 150);
        let shifted: Vec<f64> = b.iter().map(|v| v + 0.25).collect();
        assert!(anderson_darling_ksample(&[&a, &b]).unwrap().p > 0.01);
        assert!(ks_two_sample(&a, &b).unwrap().p > 0.01);
        assert!(anderson_darling_ksample(&[&a, &shifted]).unwrap().p < 1e-3);
        assert!(ks_two_sample(&a, &shifted).unwrap().p < 1e-3);
    }

    #[test]
    fn fisher_tea_tasting() {
        // Fisher's lady: 3 of 4 milk-first cups named right.
        let p = exact_2xk([&[3, 1], &[1, 3]]).unwrap().p;
        assert!(close(p, 34.0 / 70.0, 1e-12), "{p}");
        // All right: the most extreme of both tails, 2/70.
        let p = exact_2xk([&[4, 0], &[0, 4]]).unwrap().p;
        assert!(close(p, 2.0 / 70.0, 1e-12), "{p}");
    }

    /// p by listing every table with the margins of `rows`.
    fn brute_force(rows: [&[u64]; 2]) -> f64 {
        let columns: Vec<u64> = rows[0].iter().zip(rows[1]).map(|(a, b)| a + b).collect();
        let n_top: u64 = rows[0].iter().sum();
        let lnf = ln_factorials(columns.iter().sum::<u64>() as usize);
        let ln_c = |a: u64, b: u64| lnf[a as usize] - lnf[b as usize] - lnf[(a - b) as usize];
        let weight = |t: &[u64]| -> f64 { t.iter().zip(&columns).map(|(&x, &c)| ln_c(c, x)).sum() };
        let observed = weight(rows[0]);
        let mut tables = vec![vec![]];
        for &c in &columns {
            tables = tables
                .into_iter()
                .flat_map(|t: Vec<u64>| {
                    (0..=c).map(move |x| {
                        let mut t = t.clone();
                        t.push(x);
                        t
                    })
                })
                .collect();
        }
        let total = ln_c(columns.iter().sum(), n_top);
        tables
            .iter()
            .filter(|t| t.iter().sum::<u64>() == n_top)
            .map(|t| weight(t))
            .filter(|&w| w <= observed + 1e-7 * observed.abs().max(1.0))
            .map(|w| (w - total).exp())
            .sum()
    }

    #[test]
    fn freeman_halton_matches_listing_every_table() {
        let cases: [[&[u64]; 2]; 5] = [
            [&[2, 5, 1, 0], &[4, 1, 3, 2]],
            [&[0, 0, 7], &[3, 3, 1]],
            [&[5, 5, 5, 5], &[5, 5, 5, 5]],
            [&[1, 2, 3, 4, 5], &[5, 4, 3, 2, 1]],
            [&[6, 0, 2], &[0, 0, 6]],
        ];
        for rows in cases {
            let p = exact_2xk(rows).unwrap().p;
            let want = brute_force(rows);
            assert!(close(p, want, 1e-9), "{rows:?}: {p} vs {want}");
        }
        // scipy.stats.fisher_exact on 2×2 (scipy 1.17): [[8, 2], [1, 5]]
        // gives 0.0349650...
        let fisher = exact_2xk([&[8, 2], &[1, 5]]).unwrap();
        assert!(close(fisher.p, 0.034965034965035, 1e-9), "{fisher:?}");
        assert_eq!(fisher.simulated, 0);
    }

    #[test]
    fn exact_test_is_fast_and_sane_for_two_hundred_runs_a_side() {
        // 200 runs a side over 12 categories.
        let a: Vec<u64> = vec![10, 20, 30, 25, 20, 15, 20, 20, 15, 10, 10, 5];
        let started = std::time::Instant::now();
        let same = exact_2xk([&a, &a]).unwrap();
        assert!(same.p > 0.999, "{same:?}");
        let b: Vec<u64> = a.iter().rev().copied().collect();
        let reversed = exact_2xk([&a, &b]).unwrap();
        // Far in the tail of 12 columns: past the enumeration budget, so
        // a Monte Carlo estimate (≈ 1.3e-4).
        assert!(reversed.p < 1e-3, "{reversed:?}");
        let near: Vec<u64> = vec![12, 18, 30, 25, 22, 13, 20, 20, 15, 10, 11, 4];
        let close_by = exact_2xk([&a, &near]).unwrap();
        assert!(close_by.p > 0.5, "{close_by:?}");
        assert!(
            started.elapsed().as_secs_f64() < 5.0,
            "{:?}",
            started.elapsed()
        );
        // Degenerate tables.
        let one = TableTest {
            p: 1.0,
            simulated: 0,
        };
        assert_eq!(exact_2xk([&[5, 0], &[3, 0]]), Some(one));
        assert_eq!(exact_2xk([&[0, 0], &[3, 4]]), Some(one));
        assert_eq!(exact_2xk([&[1], &[1, 2]]), None);
    }

    #[test]
    fn the_monte_carlo_p_agrees_with_the_exact_one() {
        let (a, b): (&[u64], &[u64]) = (&[12, 9, 4, 7, 3], &[5, 11, 10, 3, 9]);
        let exact = exact_2xk([a, b]).unwrap();
        assert_eq!(exact.simulated, 0);
        let columns: Vec<u64> = a.iter().zip(b).map(|(x, y)| x + y).collect();
        let table = Margins::new(columns, a.iter().sum());
        let observed = table.weight(a);
        let simulated = table.simulate(observed + 1e-7 * observed.abs());
        // Standard error √(p(1−p)/1e5) ≈ 1e-3 at p ≈ 0.1.
        assert!(
            (simulated - exact.p).abs() < 5e-3,
            "{simulated} vs {}",
            exact.p
        );
    }

    #[test]
    fn quartiles_interpolate_as_numpy_does() {
        let q = Quartiles::of(&[4.0, 1.0, 3.0, 2.0]).unwrap();
        assert_eq!((q.n, q.min, q.max), (4, 1.0, 4.0));
        assert_eq!((q.q1, q.median, q.q3), (1.75, 2.5, 3.25));
        assert!(Quartiles::of(&[]).is_none());
        assert_eq!(median_absolute_deviation(&[1.0, 2.0, 3.0, 4.0, 100.0]), 1.0);
    }

    // Reference values from scipy 1.17.1; see the tests that use them.
    const SCIPY_KS: (f64, f64) = (0.4, 0.2829492488935213);
    const SCIPY_AD_RAW: f64 = 2.0911264802403524;
    const SCIPY_AD_RAW_TIES: f64 = 2.4806147630799136;
    /// anderson_ksamp(..., method=PermutationMethod(n_resamples=200000)).
    const SCIPY_AD_PERMUTATION_P: f64 = 0.0798;
}
