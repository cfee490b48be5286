//! The number types an engine computes in: `Real` for forces and velocities
//! (f64, or f32 as on the GPU), and `Coordinate` for what is accumulated over
//! a whole run (displacements, junction anchors, the drive position).
//!
//! Why two: a block creeping at the drive speed moves v·dt ≈ 1e-10 m a step,
//! below one f32 ulp of its displacement (≈ 1e-11 m at 1e-4 m, and far less
//! for blocks deep in the stuck region), so a plain f32 displacement rounds
//! creep away and changes when the interface fails. As in mixed-precision
//! molecular dynamics (OpenMM's "mixed" mode), forces stay in f32 but each
//! displacement is an unevaluated sum hi + lo of two f32 (`DoubleSingle`,
//! ≈ 48 significant bits, every adapter has it), and every force reads a
//! *difference* of two coordinates, rounded to f32 once.

use num_traits::Float;

pub trait Real:
    Float + Send + Sync + Default + std::fmt::Debug + std::fmt::Display + bytemuck::Pod + 'static
{
    const NAME: &'static str;
    /// The coordinate type this precision uses by default: f64 itself, and
    /// the double-single pair for f32 (mixed precision).
    type Coord: Coordinate<Self>;
    fn from_f64(v: f64) -> Self;
    fn as_f64(self) -> f64;
}

impl Real for f64 {
    const NAME: &'static str = "f64";
    type Coord = f64;
    #[inline]
    fn from_f64(v: f64) -> Self {
        v
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self
    }
}

impl Real for f32 {
    const NAME: &'static str = "f32";
    type Coord = DoubleSingle;
    #[inline]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self as f64
    }
}

/// A run-long accumulated position in an engine computing in `T`.
pub trait Coordinate<T: Real>:
    Copy + Send + Sync + Default + std::fmt::Debug + PartialEq + 'static
{
    /// Name for logs: "f64", "f32" (plain) or "f32+f32" (double-single).
    const NAME: &'static str;
    /// How this precision sums the forces on one block (`ForceSum`).
    type Sum: ForceSum<T>;
    /// Nearest representable coordinate.
    fn from_f64(v: f64) -> Self;
    /// Exact value (a double-single pair fits an f64 exactly).
    fn as_f64(self) -> f64;
    /// `self + d` for a small increment `d` (v·dt), keeping d's low bits.
    fn add(self, d: T) -> Self;
    /// `self − other`, rounded to `T` once.
    fn diff(self, other: Self) -> T;
    /// The value rounded to `T`.
    fn value(self) -> T;
    /// The coordinate as two f64 whose sum is its exact value: (v, 0) for
    /// a single number, (hi, lo) for a double-single pair. What checkpoints
    /// store, so that a pair comes back bit for bit.
    fn parts(self) -> [f64; 2] {
        [self.as_f64(), 0.0]
    }
    /// The coordinate from `parts`: the same bits when they came from this
    /// type, else the nearest coordinate to their sum.
    fn from_parts(parts: [f64; 2]) -> Self {
        Self::from_f64(parts[0] + parts[1])
    }
}

impl Coordinate<f64> for f64 {
    const NAME: &'static str = "f64";
    type Sum = f64;
    #[inline]
    fn from_f64(v: f64) -> Self {
        v
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self
    }
    #[inline]
    fn add(self, d: f64) -> Self {
        self + d
    }
    #[inline]
    fn diff(self, other: Self) -> f64 {
        self - other
    }
    #[inline]
    fn value(self) -> f64 {
        self
    }
}

/// Plain f32 coordinates: what the engines did before mixed precision.
/// Kept on the CPU as the negative control of the long-run accuracy tests.
impl Coordinate<f32> for f32 {
    const NAME: &'static str = "f32";
    type Sum = f32;
    #[inline]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self as f64
    }
    #[inline]
    fn add(self, d: f32) -> Self {
        self + d
    }
    #[inline]
    fn diff(self, other: Self) -> f32 {
        self - other
    }
    #[inline]
    fn value(self) -> f32 {
        self
    }
}

/// An unevaluated sum `hi + lo` of two f32 with |lo| ≤ ulp(hi)/2. Same
/// layout as the WGSL `vec2<f32>` (hi, lo) of `shaders/double_single.wgsl`,
/// whose `ds_add` and `ds_diff` are the twins of the methods of the same
/// names here, operation for operation.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DoubleSingle {
    pub hi: f32,
    pub lo: f32,
}

impl DoubleSingle {
    /// Knuth's two-sum of `hi + d`, then the error folded into `lo` and the
    /// pair renormalised (fast two-sum). The GPU twin multiplies the
    /// intermediate sums by a runtime 1.0 so that no compiler can
    /// reassociate the error terms away; multiplying by 1.0 is exact, so
    /// the results are the same bits.
    #[inline]
    pub fn ds_add(self, d: f32) -> Self {
        let s = self.hi + d;
        let b = s - self.hi;
        let err = (self.hi - (s - b)) + (d - b);
        let lo = self.lo + err;
        let hi = s + lo;
        DoubleSingle {
            hi,
            lo: lo - (hi - s),
        }
    }

    /// (hi − hi') + (lo − lo'): for nearby coordinates the first difference
    /// is exact (Sterbenz), so the result carries f32's full relative
    /// precision of the *difference*, not of the coordinates.
    #[inline]
    pub fn ds_diff(self, other: Self) -> f32 {
        (self.hi - other.hi) + (self.lo - other.lo)
    }
}

impl Coordinate<f32> for DoubleSingle {
    const NAME: &'static str = "f32+f32";
    type Sum = CompensatedSum;
    #[inline]
    fn from_f64(v: f64) -> Self {
        let hi = v as f32;
        DoubleSingle {
            hi,
            lo: (v - hi as f64) as f32,
        }
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self.hi as f64 + self.lo as f64
    }
    #[inline]
    fn add(self, d: f32) -> Self {
        self.ds_add(d)
    }
    #[inline]
    fn diff(self, other: Self) -> f32 {
        self.ds_diff(other)
    }
    #[inline]
    fn value(self) -> f32 {
        self.hi
    }
    fn parts(self) -> [f64; 2] {
        [self.hi as f64, self.lo as f64]
    }
    fn from_parts(parts: [f64; 2]) -> Self {
        let (hi, lo) = (parts[0] as f32, parts[1] as f32);
        if hi as f64 == parts[0] && lo as f64 == parts[1] {
            DoubleSingle { hi, lo }
        } else {
            Self::from_f64(parts[0] + parts[1])
        }
    }
}

/// The sum of the forces on one block, term by term.
///
/// Why mixed precision needs more than an f32 running sum: a block's terms
/// are large and nearly cancel (every bond carries the normal load's
/// compression), and a running sum rounds at the scale of its largest
/// partial sum. A bond's force on its far end is the exact negation of its
/// force on its near end, so exact sums keep action equal to reaction; the
/// running sums did not, and in a nearly uniform strain every block
/// rounded the same numbers alike: a net spurious force on the lattice,
/// step after step, that biased mixed f32's outcome distribution against
/// f64's (results/precision_ensembles.md). f64 and plain f32 sum plainly
/// (the same bits as before); mixed f32 uses `CompensatedSum`.
pub trait ForceSum<T: Real>: Copy + Send + Sync + Default + std::fmt::Debug + 'static {
    /// Whether the bond forces are split into a rest-direction and a
    /// rotation term (`bulk_forces::bulk_force` says why): true for the
    /// compensated sum; f64 and plain f32 keep their one term per bond.
    const SPLITS_BONDS: bool = false;
    /// `self + x`.
    fn add(self, x: T) -> Self;
    /// `self + spring + damper`, one bond's two terms. Plain sums add them
    /// one at a time (the same bits as ever); the compensated sum adds
    /// their f32 sum to its error word, whose rounding is antisymmetric
    /// like the terms (a bond's far end gets −spring − damper =
    /// −(spring + damper) exactly), so action still equals reaction.
    #[inline(always)]
    fn add_bond(self, spring: T, damper: T) -> Self {
        self.add(spring).add(damper)
    }
    /// `self + other`, two partial sums joined (a block's junction lanes).
    /// Plain sums add `other`'s value (the same bits as ever); the
    /// compensated sum two-sums the sums and adds both error terms.
    #[inline(always)]
    fn merge(self, other: Self) -> Self {
        self.add(other.value())
    }
    /// The sum rounded to `T` once.
    fn value(self) -> T;
}

impl ForceSum<f64> for f64 {
    #[inline(always)]
    fn add(self, x: f64) -> f64 {
        self + x
    }
    #[inline(always)]
    fn value(self) -> f64 {
        self
    }
}

impl ForceSum<f32> for f32 {
    #[inline(always)]
    fn add(self, x: f32) -> f32 {
        self + x
    }
    #[inline(always)]
    fn value(self) -> f32 {
        self
    }
}

/// An f32 sum with its rounding errors kept apart (Knuth's two-sum of each
/// term, the errors summed: Ogita, Rump and Oishi's Sum2), as accurate as
/// a sum in twice f32's precision rounded once. The running sum's chain is
/// one add per term (the error terms are off it), so it vectorises and
/// pipelines. WGSL twin: `force_sum_add` in `shaders/double_single.wgsl`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CompensatedSum {
    pub sum: f32,
    pub err: f32,
}

impl ForceSum<f32> for CompensatedSum {
    const SPLITS_BONDS: bool = true;
    #[inline(always)]
    fn add(self, x: f32) -> Self {
        let t = self.sum + x;
        let b = t - self.sum;
        let e = (self.sum - (t - b)) + (x - b);
        CompensatedSum {
            sum: t,
            err: self.err + e,
        }
    }
    /// The rotation part of a split bond (q·du and the dashpot, a strain's
    /// fraction of q·r0) needs no two-sum: only the large q·r0 terms
    /// cancel across a block. Their f32 sum goes to the error word
    /// (`force_sum_add_bond`, whose `opaque` keeps a GPU compiler from
    /// fusing the products into it).
    #[inline(always)]
    fn add_bond(self, spring: f32, damper: f32) -> Self {
        CompensatedSum {
            sum: self.sum,
            err: self.err + (spring + damper),
        }
    }
    #[inline(always)]
    fn merge(self, other: Self) -> Self {
        let joined = self.add(other.sum);
        CompensatedSum {
            sum: joined.sum,
            err: joined.err + other.err,
        }
    }
    #[inline(always)]
    fn value(self) -> f32 {
        self.sum + self.err
    }
}

/// "f64", "f32 mixed (double-single displacements)" or "f32 plain".
pub fn precision_name<T: Real, C: Coordinate<T>>() -> String {
    if T::NAME == C::NAME {
        if T::NAME == "f64" {
            "f64".into()
        } else {
            format!("{} plain", T::NAME)
        }
    } else {
        format!("{} mixed ({} coordinates)", T::NAME, C::NAME)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn double_single_keeps_increments_below_one_f32_ulp() {
        // 1e-4 m plus a million creep steps of 9e-11 m (the drive speed
        // times dt): f32 loses them, the pair keeps them to ~1e-15 m.
        let start = 1.0e-4;
        let d = 9.0e-11f32;
        let (mut plain, mut pair) = (start as f32, DoubleSingle::from_f64(start));
        for _ in 0..1_000_000 {
            plain = Coordinate::add(plain, d);
            pair = pair.add(d);
        }
        let exact = start + 1.0e6 * d as f64;
        assert!((pair.as_f64() - exact).abs() < 1e-14, "{pair:?}");
        // The plain f32 sum is off by a large fraction of the 9e-5 m crept
        // (the control: the test above could not pass with plain f32).
        assert!((plain as f64 - exact).abs() > 1e-6, "{plain}");
    }

    #[test]
    fn compensated_sum_of_cancelling_terms_is_rounded_once() {
        // 1e4 + 1e-3 − 1e4: an f32 running sum loses the 1e-3 to the
        // partial sum's ulp (≈ 1e-3); the compensated sum returns it to
        // f32's relative precision.
        let terms = [1.0e4f32, 1.0e-3, -1.0e4, 3.0e-7, 2.5e3, -2.5e3];
        let exact: f64 = terms.iter().map(|&x| x as f64).sum();
        let sum = terms
            .iter()
            .fold(CompensatedSum::default(), |s, &x| s.add(x));
        assert_eq!(sum.value(), exact as f32);
        let running = terms.iter().fold(0.0f32, |s, &x| ForceSum::add(s, x));
        assert!((running as f64 - exact).abs() > 1e-5, "{running}");
        // Adding +0.0 (the sweep engine's missing bonds) changes no bit.
        assert_eq!(sum.add(0.0), sum);
    }

    /// A block's split bonds: the q·r0 terms (large, cancelling across the
    /// block) are two-summed; each bond's q·du + dashpot (a strain's
    /// fraction of them) goes to the error word in plain f32, leaving the
    /// sum word as the large terms alone make it. The block's force is
    /// still within a few ulp of the exact sum of its terms, where an f32
    /// running sum loses the small terms to ulp(q·r0) (the control).
    #[test]
    fn split_bonds_add_their_small_terms_to_the_error_word() {
        let large = [0.3125f32, -0.312_500_3, 0.1875, -0.187_499_85];
        let small = [
            (2.1e-6f32, -3.0e-8f32),
            (-1.7e-6, 4.0e-8),
            (9.0e-7, 1.0e-8),
            (-4.0e-7, -2.0e-8),
        ];
        let mut sum = CompensatedSum::default();
        let mut large_only = CompensatedSum::default();
        let mut running = 0.0f32;
        let mut exact = 0.0f64;
        for (&l, &(spring, damper)) in large.iter().zip(&small) {
            sum = sum.add(l).add_bond(spring, damper);
            large_only = large_only.add(l);
            running = ForceSum::add_bond(ForceSum::add(running, l), spring, damper);
            exact += l as f64 + spring as f64 + damper as f64;
        }
        assert_eq!(sum.sum, large_only.sum);
        let ulp = (exact as f32).abs() * f32::EPSILON;
        let off = (sum.value() as f64 - exact).abs();
        assert!(off <= 4.0 * ulp as f64, "{} against {exact}", sum.value());
        assert!(
            (running as f64 - exact).abs() > 1000.0 * ulp as f64,
            "{running} {exact}"
        );
        // The bond seen from its other end adds exactly the negated terms.
        let far = large
            .iter()
            .zip(&small)
            .fold(CompensatedSum::default(), |s, (&l, &(spring, damper))| {
                s.add(-l).add_bond(-spring, -damper)
            });
        assert_eq!(far.value(), -sum.value());
    }

    /// A block's junction forces are alike in size and summed in lanes
    /// that are then merged (`junctions::junction_lane`): merged compensated
    /// lane sums are the exact sum rounded to f32, where running lane sums
    /// and a running merge are off by 8.5 ulp (the control).
    #[test]
    fn merged_compensated_lane_sums_are_the_sum_rounded_once() {
        let lanes = 64;
        // Junctions pinned together (after the normal-load phase) carry the
        // same force: the running sums' roundings all lean one way.
        let terms = vec![-0.0123f32; 6400];
        let exact: f64 = terms.iter().map(|&x| x as f64).sum();
        let merged = (0..lanes)
            .map(|l| {
                let lane = terms.iter().skip(l).step_by(lanes);
                lane.fold(CompensatedSum::default(), |s, &x| s.add(x))
            })
            .fold(CompensatedSum::default(), |t, lane| t.merge(lane));
        assert_eq!(merged.value(), exact as f32);
        let running = (0..lanes)
            .map(|l| {
                terms
                    .iter()
                    .skip(l)
                    .step_by(lanes)
                    .fold(0.0f32, |s, &x| s + x)
            })
            .fold(0.0f32, ForceSum::merge);
        let ulp = (exact as f32).abs() * f32::EPSILON;
        assert!(
            (running as f64 - exact).abs() > 4.0 * ulp as f64,
            "{running} {exact}"
        );
        // Merging an empty sum changes no bit.
        assert_eq!(merged.merge(CompensatedSum::default()), merged);
    }

    #[test]
    fn double_single_stays_normalised_and_differences_are_exact() {
        let mut a = DoubleSingle::from_f64(0.1234567890123);
        let mut b = DoubleSingle::from_f64(0.1234567890123);
        for k in 0..10_000 {
            let d = 1.0e-9 * ((k % 7) as f32 + 1.0);
            a = a.add(d);
            b = b.add(d * 0.5);
            assert!(a.lo.abs() <= a.hi.abs() * f32::EPSILON);
        }
        // a − b = Σ d/2 over the loop, computed exactly in f64 below.
        let expected: f64 = (0..10_000)
            .map(|k| 0.5 * (1.0e-9 * ((k % 7) as f32 + 1.0)) as f64)
            .sum();
        let got = a.diff(b) as f64;
        assert!(
            (got - expected).abs() <= expected * 1e-6,
            "{got} {expected}"
        );
        // Checkpoint parts give the pair back bit for bit, and an f64
        // coordinate's parts give the nearest pair.
        assert_eq!(DoubleSingle::from_parts(a.parts()), a);
        assert_eq!(f64::from_parts(a.parts()), a.as_f64());
        assert_eq!(
            DoubleSingle::from_parts(0.1f64.parts()),
            DoubleSingle::from_f64(0.1)
        );
        assert_eq!(DoubleSingle::from_f64(0.3).as_f64(), {
            let hi = 0.3f32;
            hi as f64 + (0.3 - hi as f64) as f32 as f64
        });
    }
}
