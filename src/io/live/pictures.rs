//! The live view's pictures, drawn from the records as they stream:
//! space–time maps of the interface (one image row per interface sample,
//! the last [`HISTORY_ROWS`] of them, newest at the bottom; one column per
//! block, binned to at most [`MAX_COLUMNS`]) and the bulk speed field (the
//! interface row at the bottom). Each is an RGB image under one colour map,
//! scaled to what it shows (the scale goes in the image's frame id), so any
//! Foxglove Image panel draws it without settings.

use crate::io::output::messages::{Bulk, Interface};
use std::collections::VecDeque;

pub const HISTORY_ROWS: usize = 256;
pub const MAX_COLUMNS: usize = 1024;

/// Decades of slip speed the slip-speed map spans below its maximum.
const SPEED_DECADES: f32 = 4.0;

/// An RGB picture (rgb8, rows top to bottom) and the scale its colours span.
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
    /// What the colours mean: "τ/p 0.012 … 0.43" and the like.
    pub scale: String,
}

/// A colour map from dark blue through green to yellow (viridis' anchors).
const ANCHORS: [[f32; 3]; 9] = [
    [68.0, 1.0, 84.0],
    [71.0, 44.0, 122.0],
    [59.0, 81.0, 139.0],
    [44.0, 113.0, 142.0],
    [33.0, 144.0, 141.0],
    [39.0, 173.0, 129.0],
    [92.0, 200.0, 99.0],
    [170.0, 220.0, 50.0],
    [253.0, 231.0, 37.0],
];

/// The colour of `u` in [0, 1] (clamped; NaN is the lowest colour).
pub fn colour(u: f32) -> [u8; 3] {
    let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) };
    let x = u * (ANCHORS.len() - 1) as f32;
    let k = (x.floor() as usize).min(ANCHORS.len() - 2);
    let w = x - k as f32;
    let (a, b) = (ANCHORS[k], ANCHORS[k + 1]);
    std::array::from_fn(|c| (a[c] + w * (b[c] - a[c])).round() as u8)
}

/// `values` binned to `columns` (each the mean, or the largest with `max`).
fn bin(values: &[f32], columns: usize, max: bool) -> Vec<f32> {
    let n = values.len();
    (0..columns)
        .map(|c| {
            let bin = &values[c * n / columns..((c + 1) * n / columns).max(c * n / columns + 1)];
            if max {
                bin.iter().copied().fold(f32::NEG_INFINITY, f32::max)
            } else {
                bin.iter().sum::<f32>() / bin.len() as f32
            }
        })
        .collect()
}

/// Draws `values` (rows top to bottom, `width` each) mapped linearly from
/// [lo, hi] to the colour map.
fn draw(values: &[f32], width: usize, lo: f32, hi: f32, scale: String) -> Picture {
    let span = if hi > lo { hi - lo } else { 1.0 };
    let rgb = values
        .iter()
        .flat_map(|&v| colour((v - lo) / span))
        .collect();
    Picture {
        width: width as u32,
        height: (values.len() / width.max(1)) as u32,
        rgb,
        scale,
    }
}

fn finite_range(values: &[f32]) -> (f32, f32) {
    values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}

/// The last interface samples, per quantity, binned to the columns.
#[derive(Debug, Default)]
pub struct InterfaceHistory {
    columns: usize,
    stress_ratio: VecDeque<Vec<f32>>,
    slip: VecDeque<Vec<f32>>,
    /// log10 of the slip speed (m/s).
    log_speed: VecDeque<Vec<f32>>,
}

impl InterfaceHistory {
    pub fn push(&mut self, m: &Interface) {
        let n = m.shear_stress.len();
        if n == 0 {
            return;
        }
        let columns = n.min(MAX_COLUMNS);
        if columns != self.columns {
            *self = InterfaceHistory {
                columns,
                ..Default::default()
            };
        }
        let ratio: Vec<f32> = m
            .shear_stress
            .iter()
            .zip(&m.normal_stress)
            .map(|(t, p)| if *p > 0.0 { (t / p) as f32 } else { 0.0 })
            .collect();
        let slip: Vec<f32> = m.slip.iter().map(|&s| s as f32).collect();
        let speed: Vec<f32> = m
            .slip_speed
            .iter()
            .map(|&v| (v.abs().max(1e-30) as f32).log10())
            .collect();
        for (rows, values, max) in [
            (&mut self.stress_ratio, ratio, false),
            (&mut self.slip, slip, false),
            (&mut self.log_speed, speed, true),
        ] {
            if rows.len() == HISTORY_ROWS {
                rows.pop_front();
            }
            rows.push_back(bin(&values, columns, max));
        }
    }

    pub fn rows(&self) -> usize {
        self.stress_ratio.len()
    }

    /// τ/p, from the window's lowest to its highest value.
    pub fn stress_ratio(&self) -> Picture {
        self.linear(&self.stress_ratio, |lo, hi| {
            format!("tau/p {lo:.3} .. {hi:.3}")
        })
    }

    /// Slip since the start of driving (m), from the window's lowest to its
    /// highest value.
    pub fn slip(&self) -> Picture {
        self.linear(&self.slip, |lo, hi| format!("slip {lo:.3e} .. {hi:.3e} m"))
    }

    /// `rows` on a linear scale from their lowest to their highest value.
    fn linear(&self, rows: &VecDeque<Vec<f32>>, scale: impl Fn(f32, f32) -> String) -> Picture {
        let values: Vec<f32> = rows.iter().flatten().copied().collect();
        let (lo, hi) = finite_range(&values);
        draw(&values, self.columns, lo, hi, scale(lo, hi))
    }

    /// Slip speed, logarithmic: [`SPEED_DECADES`] below the window's
    /// fastest.
    pub fn slip_speed(&self) -> Picture {
        let values: Vec<f32> = self.log_speed.iter().flatten().copied().collect();
        let hi = finite_range(&values).1;
        let lo = hi - SPEED_DECADES;
        draw(
            &values,
            self.columns,
            lo,
            hi,
            format!("slip speed 1e{lo:.1} .. 1e{hi:.1} m/s (log)"),
        )
    }
}

/// The bulk speed |v| (m/s) of a bulk sample, the interface row at the
/// bottom, from 0 to its fastest block.
pub fn bulk_speed(m: &Bulk) -> Picture {
    let (nx, nz) = (m.nx as usize, m.nz as usize);
    if nx == 0 || nz == 0 || m.vx.len() < nx * nz || m.vz.len() < nx * nz {
        return draw(&[], 1, 0.0, 1.0, "no bulk field".into());
    }
    let columns = nx.min(MAX_COLUMNS);
    let values: Vec<f32> = (0..nz)
        .rev()
        .flat_map(|iz| {
            let row: Vec<f32> = (0..nx)
                .map(|ix| m.vx[iz * nx + ix].hypot(m.vz[iz * nx + ix]))
                .collect();
            bin(&row, columns, false)
        })
        .collect();
    let hi = finite_range(&values).1.max(0.0);
    draw(&values, columns, 0.0, hi, format!("|v| 0 .. {hi:.3e} m/s"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(shear: f64, slip: f64, speed: f64, n: usize) -> Interface {
        Interface {
            shear_stress: vec![shear; n],
            normal_stress: vec![2.0; n],
            pinned_fraction: vec![1.0; n],
            slip: vec![slip; n],
            slip_speed: vec![speed; n],
            ..Default::default()
        }
    }

    #[test]
    fn colour_map_ends_and_clamps() {
        assert_eq!(colour(0.0), [68, 1, 84]);
        assert_eq!(colour(1.0), [253, 231, 37]);
        assert_eq!(colour(2.0), colour(1.0));
        assert_eq!(colour(f32::NAN), colour(0.0));
        assert_eq!(colour(0.5), [33, 144, 141]);
    }

    #[test]
    fn space_time_rows_are_newest_at_the_bottom_and_keep_a_window() {
        let mut h = InterfaceHistory::default();
        h.push(&row(0.2, 0.0, 1e-6, 3));
        h.push(&row(0.8, 1e-3, 1e-2, 3));
        let p = h.stress_ratio();
        assert_eq!((p.width, p.height), (3, 2));
        // τ/p 0.1 (lowest) on top, 0.4 (highest) at the bottom.
        assert_eq!(&p.rgb[..3], &colour(0.0));
        assert_eq!(&p.rgb[9..12], &colour(1.0));
        assert!(p.scale.contains("0.100 .. 0.400"), "{}", p.scale);
        let s = h.slip_speed();
        // 1e-2 is the top of the log scale, 1e-6 exactly 4 decades below.
        assert_eq!(&s.rgb[9..12], &colour(1.0));
        assert_eq!(&s.rgb[..3], &colour(0.0));
        for k in 0..HISTORY_ROWS + 5 {
            h.push(&row(k as f64, 0.0, 1.0, 3));
        }
        assert_eq!(h.rows(), HISTORY_ROWS);
        // A wider interface is binned: the fastest block of a bin shows.
        let mut wide = row(1.0, 0.0, 1e-9, 3 * MAX_COLUMNS);
        wide.slip_speed[5] = 1.0;
        h.push(&wide);
        assert_eq!(h.rows(), 1, "a new width starts a new window");
        let s = h.slip_speed();
        assert_eq!(s.width as usize, MAX_COLUMNS);
        assert_eq!(&s.rgb[3..6], &colour(1.0), "block 5 falls in column 1");
        assert_eq!(&s.rgb[..3], &colour(0.0));
    }

    #[test]
    fn bulk_picture_puts_the_interface_at_the_bottom() {
        let m = Bulk {
            nx: 2,
            nz: 2,
            vx: vec![3.0, 0.0, 0.0, 0.0],
            vz: vec![4.0, 0.0, 0.0, 0.0],
            ux: vec![0.0; 4],
            uz: vec![0.0; 4],
            ..Default::default()
        };
        let p = bulk_speed(&m);
        assert_eq!((p.width, p.height), (2, 2));
        // Block (ix 0, iz 0) moves at 5 m/s: bottom left, top colour.
        assert_eq!(&p.rgb[6..9], &colour(1.0));
        assert_eq!(&p.rgb[..3], &colour(0.0));
        assert!(p.scale.contains("5.000e0"), "{}", p.scale);
    }
}
