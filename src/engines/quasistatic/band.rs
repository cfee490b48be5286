//! Banded Cholesky factorisation of a symmetric positive definite matrix.
//!
//! The lattice's stiffness matrix, numbered with the shorter lattice side
//! running fastest, is banded with half-bandwidth 2·(short side + 1) + 1:
//! a direct factorisation costs n·b²/2 flops and n·b numbers, with no fill
//! outside the band, so no ordering library is needed.

/// Lower band of a symmetric matrix: `band[i * (b + 1) + (b - (i - j))]`
/// holds A[i][j] for i − b ≤ j ≤ i.
#[derive(Debug, Clone)]
pub struct BandMatrix {
    pub n: usize,
    pub half_bandwidth: usize,
    band: Vec<f64>,
}

impl BandMatrix {
    pub fn zeros(n: usize, half_bandwidth: usize) -> Self {
        BandMatrix {
            n,
            half_bandwidth,
            band: vec![0.0; n * (half_bandwidth + 1)],
        }
    }

    #[inline]
    fn index(&self, i: usize, j: usize) -> usize {
        debug_assert!(j <= i && i - j <= self.half_bandwidth);
        let b = self.half_bandwidth;
        i * (b + 1) + (b - (i - j))
    }

    /// Adds `v` to A[i][j] (and so to A[j][i]); |i − j| ≤ half bandwidth.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        assert!(
            i - j <= self.half_bandwidth,
            "entry ({i}, {j}) outside the band {}",
            self.half_bandwidth
        );
        let k = self.index(i, j);
        self.band[k] += v;
    }

    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        if i - j > self.half_bandwidth {
            0.0
        } else {
            self.band[self.index(i, j)]
        }
    }

    /// Replaces row and column `i` by those of the identity (a constrained
    /// degree of freedom).
    pub fn constrain(&mut self, i: usize) {
        let b = self.half_bandwidth;
        for j in i.saturating_sub(b)..=(i + b).min(self.n - 1) {
            let (r, c) = if i >= j { (i, j) } else { (j, i) };
            let k = self.index(r, c);
            self.band[k] = if i == j { 1.0 } else { 0.0 };
        }
    }

    /// y = A·x.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        let b = self.half_bandwidth;
        y.iter_mut().for_each(|v| *v = 0.0);
        for i in 0..self.n {
            let row = &self.band[i * (b + 1)..(i + 1) * (b + 1)];
            let first = i.saturating_sub(b);
            let mut acc = 0.0;
            for j in first..i {
                let a = row[b - (i - j)];
                acc += a * x[j];
                y[j] += a * x[i];
            }
            y[i] += acc + row[b] * x[i];
        }
    }

    /// Factorises A = L·Lᵀ in place of a copy. Fails (with the pivot) if A
    /// is not positive definite.
    pub fn cholesky(&self) -> Result<BandCholesky, usize> {
        let b = self.half_bandwidth;
        let w = b + 1;
        let mut l = self.band.clone();
        for i in 0..self.n {
            let first = i.saturating_sub(b);
            for j in first..=i {
                // L[i][j] = (A[i][j] − Σ_k L[i][k]·L[j][k]) / L[j][j], k from
                // the first column both rows reach to j − 1.
                let kfirst = first.max(j.saturating_sub(b));
                let mut s = l[i * w + (b - (i - j))];
                let (ri, rj) = (i * w + b - i, j * w + b - j);
                for k in kfirst..j {
                    s -= l[ri + k] * l[rj + k];
                }
                if j == i {
                    if s <= 0.0 || !s.is_finite() {
                        return Err(i);
                    }
                    l[i * w + b] = s.sqrt();
                } else {
                    l[i * w + (b - (i - j))] = s / l[j * w + b];
                }
            }
        }
        Ok(BandCholesky {
            n: self.n,
            half_bandwidth: b,
            l,
        })
    }
}

/// The factor L of a banded Cholesky factorisation.
#[derive(Debug, Clone)]
pub struct BandCholesky {
    n: usize,
    half_bandwidth: usize,
    l: Vec<f64>,
}

impl BandCholesky {
    /// (size, half bandwidth, entries): what a checkpoint stores.
    pub fn parts(&self) -> (usize, usize, &[f64]) {
        (self.n, self.half_bandwidth, &self.l)
    }

    /// A factor from `parts`; None when the entries do not fit the shape.
    pub fn from_parts(n: usize, half_bandwidth: usize, l: Vec<f64>) -> Option<Self> {
        (l.len() == n * (half_bandwidth + 1)).then_some(BandCholesky {
            n,
            half_bandwidth,
            l,
        })
    }
    /// Solves A·x = r in place (x starts as r).
    pub fn solve(&self, x: &mut [f64]) {
        let b = self.half_bandwidth;
        let w = b + 1;
        for i in 0..self.n {
            let first = i.saturating_sub(b);
            let row = i * w + b - i;
            let l = &self.l[row + first..row + i];
            let s: f64 = l.iter().zip(&x[first..i]).map(|(a, b)| a * b).sum();
            x[i] = (x[i] - s) / self.l[i * w + b];
        }
        for i in (0..self.n).rev() {
            x[i] /= self.l[i * w + b];
            let xi = x[i];
            let first = i.saturating_sub(b);
            let row = i * w + b - i;
            let l = &self.l[row + first..row + i];
            for (xk, l) in x[first..i].iter_mut().zip(l) {
                *xk -= l * xi;
            }
        }
    }

    /// Bytes held by the factor.
    pub fn bytes(&self) -> usize {
        self.l.len() * 8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1D chain of springs to the ground and to each other, with a
    /// second-neighbour coupling: symmetric positive definite, bandwidth 2.
    fn chain(n: usize) -> BandMatrix {
        let mut a = BandMatrix::zeros(n, 2);
        for i in 0..n {
            a.add(i, i, 3.0);
            if i + 1 < n {
                a.add(i, i, 1.0);
                a.add(i + 1, i + 1, 1.0);
                a.add(i, i + 1, -1.0);
            }
            if i + 2 < n {
                a.add(i, i + 2, 0.25);
            }
        }
        a
    }

    #[test]
    fn cholesky_solves_and_mul_is_symmetric() {
        let a = chain(40);
        let x_true: Vec<f64> = (0..40).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut r = vec![0.0; 40];
        a.mul(&x_true, &mut r);
        let f = a.cholesky().unwrap();
        f.solve(&mut r);
        let err = r
            .iter()
            .zip(&x_true)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-12, "{err}");
        assert_eq!(a.get(3, 5), a.get(5, 3));
        assert_eq!(a.get(0, 5), 0.0);
    }

    #[test]
    fn an_indefinite_matrix_is_refused_with_its_pivot() {
        let mut a = chain(10);
        a.add(4, 4, -100.0);
        assert_eq!(a.cholesky().unwrap_err(), 4);
    }

    #[test]
    fn a_constrained_row_solves_to_its_right_hand_side() {
        let mut a = chain(10);
        a.constrain(3);
        let f = a.cholesky().unwrap();
        let mut r = vec![0.0; 10];
        r[3] = 2.5;
        f.solve(&mut r);
        assert!((r[3] - 2.5).abs() < 1e-14);
        assert!(r.iter().enumerate().all(|(i, v)| i == 3 || *v == 0.0));
    }
}
