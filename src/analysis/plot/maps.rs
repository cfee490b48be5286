//! Space–time maps (thesis Fig. C.1, Rubinstein et al. 2007): a field of the
//! interface (pinned fraction, τ/p, slip speed) against position across and
//! time down, on a true time axis, with a colour bar and the front tip.

use super::colour::{colour_bar, legend_line, ColourScale, Ramp, BAR_WIDTH};
use super::figure::{legend, tick, Drawn, Figure, Style};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Which interface field a map shows, and how it is coloured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MapField {
    /// Fraction of junctions pinned: white all pinned, black none.
    Pinned,
    /// Shear over normal stress τ/p: blue below μd, white at μd, red at μs.
    StressRatio { mu_d: f64, mu_s: f64 },
    /// Slip speed (m/s), log colour.
    SlipSpeed,
}

/// Slip speeds below this (m/s) take the bottom colour of the map.
pub const SLOWEST_SHOWN: f64 = 1e-5;

impl MapField {
    pub fn name(&self) -> &'static str {
        match self {
            MapField::Pinned => "Fraction of junctions pinned",
            MapField::StressRatio { .. } => "Shear-to-normal stress ratio τ/p",
            MapField::SlipSpeed => "Slip speed",
        }
    }

    /// How the samples falling on one row of the picture combine. Pinned
    /// fraction: the least, and slip speed: the largest, so that a brief
    /// event is never lost between rows. τ/p: the mean, since an extreme
    /// of a field that oscillates near the row period aliases into stripes.
    fn combine(&self, samples: &[Vec<f64>]) -> Vec<f64> {
        let mut out = samples[0].clone();
        for row in &samples[1..] {
            for (v, &x) in out.iter_mut().zip(row) {
                *v = match self {
                    MapField::Pinned => v.min(x),
                    MapField::SlipSpeed => v.max(x),
                    MapField::StressRatio { .. } => *v + x,
                };
            }
        }
        if let MapField::StressRatio { .. } = self {
            out.iter_mut().for_each(|v| *v /= samples.len() as f64);
        }
        out
    }

    fn scale(&self, values: &[Vec<f64>]) -> ColourScale {
        match *self {
            MapField::Pinned => ColourScale {
                ramp: Ramp::Grey,
                lo: 0.0,
                hi: 1.0,
                log: false,
                label: "fraction of junctions pinned",
            },
            MapField::StressRatio { mu_d, mu_s } => ColourScale {
                ramp: Ramp::Diverging { mid: mu_d },
                lo: 0.0,
                hi: mu_s,
                log: false,
                label: "τ/p (white μd, red μs)",
            },
            MapField::SlipSpeed => {
                let top = values
                    .iter()
                    .flatten()
                    .filter(|v| v.is_finite())
                    .fold(0.0f64, |a, v| a.max(v.abs()));
                ColourScale {
                    ramp: Ramp::Viridis,
                    lo: SLOWEST_SHOWN,
                    hi: top.max(SLOWEST_SHOWN * 10.0),
                    log: true,
                    label: "slip speed (m/s)",
                }
            }
        }
    }
}

/// One row of the picture: the time interval it covers and the value per
/// block.
#[derive(Debug, Clone, PartialEq)]
pub struct MapRow {
    pub t0: f64,
    pub t1: f64,
    pub values: Vec<f64>,
}

/// A space–time map of one interface field.
pub struct SpaceTimeMap<'a> {
    pub field: MapField,
    /// Sample times (s), increasing.
    pub time: &'a [f64],
    /// Per sample, the value per interface block.
    pub values: &'a [Vec<f64>],
    /// Block spacing (m).
    pub spacing: f64,
    /// Time window drawn (s); the whole run when None.
    pub window: Option<(f64, f64)>,
    /// Front tip polylines (t, x) to draw over the map.
    pub tips: Vec<Vec<(f64, f64)>>,
    /// Added to the title, e.g. "event 4".
    pub subtitle: String,
}

impl SpaceTimeMap<'_> {
    /// The time the map's vertical axis spans (s): the window, or the
    /// first to the last sample.
    pub fn time_range(&self) -> (f64, f64) {
        let run = (
            self.time.first().copied().unwrap_or(0.0),
            self.time.last().copied().unwrap_or(0.0),
        );
        let (a, b) = self.window.unwrap_or(run);
        if b > a {
            (a, b)
        } else {
            (a, a + self.spacing.max(1e-9) * 1e-3)
        }
    }

    /// Position range across (m): block centres ± half a spacing.
    pub fn x_range(&self) -> (f64, f64) {
        let nx = self.values.first().map_or(1, Vec::len).max(1);
        (-0.5 * self.spacing, (nx as f64 - 0.5) * self.spacing)
    }

    /// The rows of the picture, at most `max_rows`: each sample held until
    /// the next one (the last for one median interval), on a uniform time
    /// grid when the samples in the window outnumber the rows, the values of
    /// the samples sharing a row combined as [`MapField::combine`] says.
    pub fn rows(&self, max_rows: usize) -> Vec<MapRow> {
        let n = self.time.len();
        if n == 0 || max_rows == 0 {
            return Vec::new();
        }
        let (w0, w1) = self.time_range();
        let mut gaps: Vec<f64> = self.time.windows(2).map(|p| p[1] - p[0]).collect();
        gaps.sort_by(f64::total_cmp);
        let last_hold = gaps.get(gaps.len() / 2).copied().unwrap_or(w1 - w0);
        let end = |k: usize| {
            self.time
                .get(k + 1)
                .copied()
                .unwrap_or(self.time[k] + last_hold)
        };
        // Samples whose hold interval meets the window.
        let first = self.time.partition_point(|&t| t <= w0).saturating_sub(1);
        let last = self.time.partition_point(|&t| t < w1).max(first + 1);
        let samples = first..last.min(n);
        if samples.len() <= max_rows {
            return samples
                .map(|k| MapRow {
                    t0: self.time[k].max(w0),
                    t1: end(k).min(w1),
                    values: self.values[k].clone(),
                })
                .filter(|r| r.t1 > r.t0)
                .collect();
        }
        let dt = (w1 - w0) / max_rows as f64;
        (0..max_rows)
            .filter_map(|r| {
                let (a, b) = (w0 + r as f64 * dt, w0 + (r + 1) as f64 * dt);
                let k0 = self.time.partition_point(|&t| t <= a).checked_sub(1)?;
                let k1 = self.time.partition_point(|&t| t < b).max(k0 + 1);
                Some(MapRow {
                    t0: a,
                    t1: b,
                    values: self.field.combine(&self.values[k0..k1.min(n)]),
                })
            })
            .collect()
    }
}

impl Figure for SpaceTimeMap<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static,
    {
        let (width, _) = root.dim_in_pixel();
        let (main, bar) = root.split_horizontally(width.saturating_sub(style.px(BAR_WIDTH)));
        let (t0, t1) = self.time_range();
        let (x0, x1) = self.x_range();
        let ms = |t: f64| t * 1e3;
        let mm = |x: f64| x * 1e3;
        let mut title = self.field.name().to_string();
        if !self.subtitle.is_empty() {
            title = format!("{title}, {}", self.subtitle);
        }
        // Time runs down: the chart's y is −t (ms), labelled as t.
        let mut chart = ChartBuilder::on(&main)
            .caption(style.title(&title), style.title_font())
            .margin(style.px(12.0))
            .x_label_area_size(style.px(48.0))
            .y_label_area_size(style.px(72.0))
            .build_cartesian_2d(mm(x0)..mm(x1), -ms(t1)..-ms(t0))?;
        let (_, rows_px) = chart.plotting_area().get_pixel_range();
        let max_rows = (rows_px.end - rows_px.start).max(1) as usize;
        let scale = self.field.scale(self.values);
        let centre = |ix: usize| ix as f64 * self.spacing;
        for row in self.rows(max_rows) {
            // Runs of one colour along x as one rectangle: fewer elements
            // in an SVG.
            let colours: Vec<RGBColor> = row.values.iter().map(|&v| scale.colour(v)).collect();
            let mut start = 0;
            for ix in 1..=colours.len() {
                if ix == colours.len() || colours[ix] != colours[start] {
                    chart.draw_series(std::iter::once(Rectangle::new(
                        [
                            (mm(centre(start) - 0.5 * self.spacing), -ms(row.t0)),
                            (mm(centre(ix - 1) + 0.5 * self.spacing), -ms(row.t1)),
                        ],
                        colours[start].filled(),
                    )))?;
                    start = ix;
                }
            }
        }
        let span = ms(t1 - t0);
        let x_span = mm(x1 - x0);
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("position along the interface x (mm)")
            .y_desc("time t (ms)")
            .x_label_formatter(&|v| tick(*v, x_span))
            .y_label_formatter(&|v| tick(-*v, span))
            .label_style(style.tick_font())
            .axis_desc_style(style.label_font())
            .draw()?;
        let tip_colour = match self.field {
            MapField::Pinned => RGBColor(230, 30, 30),
            _ => RGBColor(0, 0, 0),
        };
        let mut labelled = false;
        for tip in &self.tips {
            let inside: Vec<(f64, f64)> = super::fronts::until_arrest(tip)
                .iter()
                .filter(|(t, _)| (t0..=t1).contains(t))
                .map(|&(t, x)| (mm(x), -ms(t)))
                .collect();
            if inside.len() < 2 {
                continue;
            }
            let series = chart.draw_series(LineSeries::new(
                inside,
                tip_colour.stroke_width(style.px(1.5)),
            ))?;
            if !labelled {
                series
                    .label("front tip")
                    .legend(legend_line(tip_colour, style));
                labelled = true;
            }
        }
        if labelled {
            legend(&mut chart, style, SeriesLabelPosition::LowerRight)?;
        }
        let (_, y_px) = chart.plotting_area().get_pixel_range();
        colour_bar(
            &bar,
            &scale,
            style,
            (y_px.start.max(0) as u32, y_px.end.max(0) as u32),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A series sampled every 20 µs for 1 ms, then every 1 µs for 0.1 ms
    /// while one block (3) is unpinned: the cadence switch of a real run.
    fn mixed_cadence() -> (Vec<f64>, Vec<Vec<f64>>) {
        let mut time = Vec::new();
        let mut t = 0.0;
        while t < 1e-3 - 1e-12 {
            time.push(t);
            t += 20e-6;
        }
        while t < 1.1e-3 - 1e-12 {
            time.push(t);
            t += 1e-6;
        }
        let values = time
            .iter()
            .map(|&t| {
                (0..5)
                    .map(|ix| if ix == 3 && t >= 1e-3 { 0.0 } else { 1.0 })
                    .collect()
            })
            .collect();
        (time, values)
    }

    #[test]
    fn the_time_axis_is_time_not_sample_count() {
        let (time, values) = mixed_cadence();
        let map = SpaceTimeMap {
            field: MapField::Pinned,
            time: &time,
            values: &values,
            spacing: 1e-3,
            window: None,
            tips: Vec::new(),
            subtitle: String::new(),
        };
        let (t0, t1) = map.time_range();
        assert_eq!(t0, 0.0);
        assert!((t1 - time[time.len() - 1]).abs() < 1e-15);
        // 150 samples on 100 rows: uniform rows of (t1 − t0)/100, so the
        // stuck millisecond takes ~91 rows, not the 50 its samples would.
        let rows = map.rows(100);
        assert_eq!(rows.len(), 100);
        let slipping = rows.iter().filter(|r| r.values[3] == 0.0).count();
        assert!(
            (9..=10).contains(&slipping),
            "{slipping} rows show block 3 unpinned"
        );
        assert!(rows.iter().all(|r| r.values[2] == 1.0));
        // Negative control: a sample-indexed picture would give the
        // slipping samples (100 of 150) two thirds of the rows.
        let by_index = time.iter().filter(|&&t| t >= 1e-3).count() * 100 / time.len();
        assert!(by_index > 60);
        // Fewer samples than rows: one row per sample, held until the next
        // (the last sample ends the axis, so it has no row of its own).
        let rows = map.rows(1000);
        assert_eq!(rows.len(), time.len() - 1);
        assert_eq!(rows[1].t0, time[1]);
        assert_eq!(rows[1].t1, time[2]);
    }

    #[test]
    fn a_brief_event_between_rows_is_not_lost() {
        let (time, values) = mixed_cadence();
        let map = SpaceTimeMap {
            field: MapField::Pinned,
            time: &time,
            values: &values,
            spacing: 1e-3,
            window: None,
            tips: Vec::new(),
            subtitle: String::new(),
        };
        // 3 rows: the last covers the event and shows its least pinned value.
        let rows = map.rows(3);
        assert_eq!(rows[2].values[3], 0.0);
        assert_eq!(rows[0].values[3], 1.0);
    }

    #[test]
    fn a_window_zooms_on_its_time() {
        let (time, values) = mixed_cadence();
        let map = SpaceTimeMap {
            field: MapField::Pinned,
            time: &time,
            values: &values,
            spacing: 1e-3,
            window: Some((0.99e-3, 1.05e-3)),
            tips: Vec::new(),
            subtitle: String::new(),
        };
        assert_eq!(map.time_range(), (0.99e-3, 1.05e-3));
        let rows = map.rows(1000);
        assert_eq!(rows[0].t0, 0.99e-3);
        assert!(rows.iter().all(|r| r.t1 <= 1.05e-3 && r.t0 >= 0.99e-3));
        assert!((map.x_range().0 + 0.5e-3).abs() < 1e-15);
        assert!((map.x_range().1 - 4.5e-3).abs() < 1e-15);
    }
}
