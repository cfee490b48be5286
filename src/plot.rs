//! PNG pictures of a run: the space–time map of the fraction of pinned
//! junctions (x across, time down, as in the thesis figures), the loading
//! curve with events marked, front speed against position, and precursor
//! length against load.

use crate::analysis::{Event, InterfaceSeries};
use crate::precursors::PrecursorSequence;
use std::path::Path;

/// A grey/RGB raster with simple drawing.
pub struct Canvas {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<[u8; 3]>,
}

impl Canvas {
    pub fn new(width: usize, height: usize) -> Canvas {
        Canvas {
            width,
            height,
            rgb: vec![[255; 3]; width * height],
        }
    }

    pub fn set(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            self.rgb[y as usize * self.width + x as usize] = c;
        }
    }

    pub fn get(&self, x: usize, y: usize) -> [u8; 3] {
        self.rgb[y * self.width + x]
    }

    /// Bresenham line.
    pub fn line(&mut self, (x0, y0): (i64, i64), (x1, y1): (i64, i64), c: [u8; 3]) {
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
        let (mut x, mut y, mut err) = (x0, y0, dx + dy);
        loop {
            self.set(x, y, c);
            if x == x1 && y == y1 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
        }
    }

    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        let file = std::io::BufWriter::new(std::fs::File::create(path)?);
        let mut enc = png::Encoder::new(file, self.width as u32, self.height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().map_err(std::io::Error::other)?;
        w.write_image_data(self.rgb.as_flattened())
            .map_err(std::io::Error::other)?;
        Ok(())
    }
}

/// Pixels per interface block across the space–time map.
pub const PIXELS_PER_BLOCK: usize = 4;

/// Rows of the space–time map at most; longer series take the nearest
/// sample per row.
pub const MAX_ROWS: usize = 1200;

/// Space–time map: column = block (PIXELS_PER_BLOCK each), row = sample
/// (time down, uniform in sample index); white = all junctions pinned,
/// black = none.
pub fn spacetime_map(s: &InterfaceSeries) -> Canvas {
    let nx = s.nx();
    let n = s.time.len();
    let rows = n.clamp(1, MAX_ROWS);
    let mut c = Canvas::new(nx * PIXELS_PER_BLOCK, rows);
    for row in 0..rows.min(n) {
        let pinned = &s.pinned[row * n / rows];
        for (ix, &p) in pinned.iter().enumerate() {
            let g = (255.0 * p.clamp(0.0, 1.0)).round() as u8;
            for k in 0..PIXELS_PER_BLOCK {
                c.set((ix * PIXELS_PER_BLOCK + k) as i64, row as i64, [g, g, g]);
            }
        }
    }
    c
}

/// Space–time map of the stress ratio τ/p per interface block (column),
/// time down as in [`spacetime_map`]: dark blue at 0, through white at
/// `mid`, to dark red at `top` and above (μs is the natural top, μd the
/// middle).
pub fn stress_ratio_map(rows: &[Vec<f64>], mid: f64, top: f64) -> Canvas {
    let nx = rows.first().map_or(0, Vec::len);
    let n = rows.len();
    let height = n.clamp(1, MAX_ROWS);
    let mut c = Canvas::new(nx.max(1) * PIXELS_PER_BLOCK, height);
    let colour = |r: f64| -> [u8; 3] {
        if !r.is_finite() {
            return [0, 160, 0];
        }
        let ramp = |f: f64| (255.0 * (1.0 - f.clamp(0.0, 1.0))).round() as u8;
        if r <= mid {
            let g = ramp(1.0 - r.max(0.0) / mid.max(1e-300));
            [g, g, 255]
        } else {
            let g = ramp((r - mid) / (top - mid).max(1e-300));
            [255, g, g]
        }
    };
    for row in 0..height.min(n) {
        for (ix, &r) in rows[row * n / height].iter().enumerate() {
            for k in 0..PIXELS_PER_BLOCK {
                c.set((ix * PIXELS_PER_BLOCK + k) as i64, row as i64, colour(r));
            }
        }
    }
    c
}

/// Front tip position x_tip against the time since each event began
/// (x from 0 to the longest event, y from 0 to the interface length): full
/// events black, partial ones grey.
pub fn front_tip_plot(s: &InterfaceSeries, events: &[Event]) -> Canvas {
    let mut c = Canvas::new(PLOT_W, PLOT_H);
    frame(&mut c);
    let longest = events
        .iter()
        .map(|e| e.end - e.start)
        .fold(0.0f64, f64::max);
    let length = (s.nx().max(2) - 1) as f64 * s.spacing;
    let map = mapper((0.0, longest.max(1e-300)), (0.0, length));
    for e in events {
        let colour = if e.full { [0, 0, 0] } else { [150, 150, 150] };
        let tip = s.front_tip(e);
        for pair in tip.windows(2) {
            c.line(
                map(pair[0].0 - e.start, pair[0].1),
                map(pair[1].0 - e.start, pair[1].1),
                colour,
            );
        }
    }
    c
}

/// Scatter of (x, y, group): one colour per group (in order of first
/// appearance), axes from the data, y on a log scale when `log_y`.
pub fn scatter(points: &[(f64, f64, usize)], log_y: bool) -> Canvas {
    const PALETTE: [[u8; 3]; 6] = [
        [0, 0, 0],
        [200, 0, 0],
        [0, 90, 200],
        [0, 150, 0],
        [180, 100, 0],
        [130, 0, 160],
    ];
    let mut c = Canvas::new(PLOT_W, PLOT_H);
    frame(&mut c);
    let y = |v: f64| if log_y { v.log10() } else { v };
    let finite: Vec<(f64, f64, usize)> = points
        .iter()
        .map(|&(a, b, g)| (a, y(b), g))
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    if finite.is_empty() {
        return c;
    }
    let range = |f: &dyn Fn(&(f64, f64, usize)) -> f64| {
        let (lo, hi) = finite
            .iter()
            .map(f)
            .fold((f64::MAX, f64::MIN), |a, v| (a.0.min(v), a.1.max(v)));
        let pad = 0.05 * (hi - lo).max(1e-12 * hi.abs().max(1.0));
        (lo - pad, hi + pad)
    };
    let map = mapper(range(&|p| p.0), range(&|p| p.1));
    for &(a, b, g) in &finite {
        let (px, py) = map(a, b);
        let colour = PALETTE[g % PALETTE.len()];
        for dx in -3..=3 {
            for dy in -3..=3 {
                if dx * dx + dy * dy <= 9 {
                    c.set(px + dx, py + dy, colour);
                }
            }
        }
    }
    c
}

const PLOT_W: usize = 800;
const PLOT_H: usize = 400;
const MARGIN: i64 = 40;

fn frame(c: &mut Canvas) {
    let (w, h) = (c.width as i64, c.height as i64);
    let k = [0, 0, 0];
    c.line((MARGIN, MARGIN), (MARGIN, h - MARGIN), k);
    c.line((MARGIN, h - MARGIN), (w - MARGIN, h - MARGIN), k);
}

/// Maps data (x, y) into the plot area of a canvas.
fn mapper(x: (f64, f64), y: (f64, f64)) -> impl Fn(f64, f64) -> (i64, i64) {
    move |a, b| {
        let px = MARGIN as f64
            + (a - x.0) / (x.1 - x.0).max(1e-300) * (PLOT_W as f64 - 2.0 * MARGIN as f64);
        let py = (PLOT_H as i64 - MARGIN) as f64
            - (b - y.0) / (y.1 - y.0).max(1e-300) * (PLOT_H as f64 - 2.0 * MARGIN as f64);
        (px.round() as i64, py.round() as i64)
    }
}

/// Loading curve F/F_N against time, events marked in red at their start.
pub fn loading_curve(time: &[f64], ratio: &[f64], events: &[Event]) -> Canvas {
    let mut c = Canvas::new(PLOT_W, PLOT_H);
    frame(&mut c);
    if time.len() < 2 {
        return c;
    }
    let xr = (time[0], *time.last().expect("non-empty"));
    let yr = ratio
        .iter()
        .fold((0.0f64, f64::MIN), |a, &r| (a.0.min(r), a.1.max(r)));
    let map = mapper(xr, (yr.0, yr.1.max(yr.0 + 1e-12)));
    for e in events {
        let (x, _) = map(e.start, 0.0);
        let colour = if e.full { [220, 0, 0] } else { [250, 170, 170] };
        c.line((x, MARGIN), (x, PLOT_H as i64 - MARGIN), colour);
    }
    for k in 1..time.len() {
        c.line(
            map(time[k - 1], ratio[k - 1]),
            map(time[k], ratio[k]),
            [0, 0, 160],
        );
    }
    c
}

/// Front speed against position, log scale from 0.1 to 10 000 m/s, one
/// colour per event (full events dark, partial light).
pub fn front_speed_plot(s: &InterfaceSeries, events: &[Event]) -> Canvas {
    let mut c = Canvas::new(PLOT_W, PLOT_H);
    frame(&mut c);
    let length = (s.nx().max(2) - 1) as f64 * s.spacing;
    let map = mapper((0.0, length), (-1.0, 4.0));
    for e in events {
        let colour = if e.full { [0, 0, 0] } else { [150, 150, 150] };
        for (x, v) in s.front_speed(e, 3) {
            let (px, py) = map(x, v.clamp(0.1, 1e4).log10());
            for d in -1..=1 {
                c.set(px + d, py, colour);
                c.set(px, py + d, colour);
            }
        }
    }
    c
}

/// Precursor length against F/F_N (x from 0 to the first full event's
/// load, y from 0 to the interface length `length`): trailing-edge
/// precursors black, the others grey, the first full event a red cross at
/// full length. The picture of Rubinstein et al. (2007), Fig. 2.11 of the
/// thesis.
pub fn precursor_plot(seq: &PrecursorSequence, length: f64, spacing: f64) -> Canvas {
    let mut c = Canvas::new(PLOT_W, PLOT_H);
    frame(&mut c);
    let top = seq
        .precursors
        .iter()
        .map(|p| p.drive_ratio)
        .chain(seq.first_full_ratio)
        .fold(0.0f64, f64::max)
        * 1.05;
    let map = mapper((0.0, top.max(1e-12)), (0.0, length));
    let dot = |c: &mut Canvas, (px, py): (i64, i64), colour| {
        for dx in -3..=3 {
            for dy in -3..=3 {
                c.set(px + dx, py + dy, colour);
            }
        }
    };
    for p in &seq.precursors {
        let colour = if p.at_trailing_edge(spacing) {
            [0, 0, 0]
        } else {
            [160, 160, 160]
        };
        dot(&mut c, map(p.drive_ratio, p.length), colour);
    }
    if let Some(r) = seq.first_full_ratio {
        let (px, py) = map(r, length);
        c.line((px - 6, py - 6), (px + 6, py + 6), [220, 0, 0]);
        c.line((px - 6, py + 6), (px + 6, py - 6), [220, 0, 0]);
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn precursors_are_drawn_at_their_load_and_length() {
        use crate::precursors::Precursor;
        let seq = PrecursorSequence {
            precursors: vec![
                Precursor {
                    drive_ratio: 0.1,
                    length: 0.03,
                    origin: 0.0,
                },
                Precursor {
                    drive_ratio: 0.15,
                    length: 0.06,
                    origin: 0.05,
                },
            ],
            first_full_ratio: Some(0.2),
        };
        let c = precursor_plot(&seq, 0.14, 0.0025);
        let map = mapper((0.0, 0.21), (0.0, 0.14));
        let (x, y) = map(0.1, 0.03);
        assert_eq!(c.get(x as usize, y as usize), [0, 0, 0]);
        let (x, y) = map(0.15, 0.06);
        assert_eq!(c.get(x as usize, y as usize), [160, 160, 160]);
        let (x, y) = map(0.2, 0.14);
        assert_eq!(c.get(x as usize, y as usize), [220, 0, 0]);
        // Negative control: nothing where no precursor is.
        let (x, y) = map(0.05, 0.1);
        assert_eq!(c.get(x as usize, y as usize), [255, 255, 255]);
    }

    #[test]
    fn a_front_appears_where_it_should_in_the_spacetime_png() {
        // Front from the trailing edge at 10 blocks per 100 samples.
        let (nx, n) = (40usize, 400usize);
        let mut s = InterfaceSeries {
            spacing: 1e-3,
            ..Default::default()
        };
        for k in 0..n {
            s.time.push(k as f64 * 1e-6);
            s.pinned.push(
                (0..nx)
                    .map(|ix| if k >= 50 + 10 * ix { 0.0 } else { 1.0 })
                    .collect(),
            );
            s.slip.push(vec![0.0; nx]);
            s.slip_speed.push(vec![0.0; nx]);
        }
        let dir = std::env::temp_dir().join(format!("slipfront-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("map.png");
        spacetime_map(&s).save(&path).unwrap();
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(
            (info.width as usize, info.height as usize),
            (nx * PIXELS_PER_BLOCK, n)
        );
        let pixel = |x: usize, y: usize| buf[(y * info.width as usize + x) * 3];
        for ix in [0usize, 10, 30] {
            let col = ix * PIXELS_PER_BLOCK + 1;
            let t_front = 50 + 10 * ix;
            assert_eq!(
                pixel(col, t_front - 1),
                255,
                "block {ix} pinned before the front"
            );
            if t_front < n {
                assert_eq!(pixel(col, t_front), 0, "block {ix} broken at the front");
            }
        }
    }
}
