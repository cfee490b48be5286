//! Fronts: speed against position per event (classes coloured, wave speeds
//! and the resolution limit drawn, clipped and unresolved values marked),
//! the front tip against time, and slip speed against front speed.

use super::colour::legend_line;
use super::colour::PALETTE;
use super::figure::{extent, legend, log_tick, tick, Drawn, Figure, Style};
use crate::analysis::events::{slip_front_relation, Event, FrontKind, InterfaceSeries};
use plotters::coord::Shift;
use plotters::prelude::*;

/// The lattice wave speeds drawn as reference lines (m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaveSpeeds {
    pub shear: f64,
    pub rayleigh: f64,
    pub pressure: f64,
}

/// Colour and name of a front class.
pub fn class_style(kind: FrontKind) -> (RGBColor, &'static str) {
    match kind {
        FrontKind::Fast => (PALETTE[1], "fast"),
        FrontKind::FastSlowFast => (PALETTE[3], "fast–slow–fast"),
        FrontKind::FastSlow => (PALETTE[4], "fast–slow"),
        FrontKind::Slow => (PALETTE[0], "slow"),
    }
}

/// A front tip path up to its arrest: after the tip's last advance it only
/// repeats its final position.
pub fn until_arrest(tip: &[(f64, f64)]) -> &[(f64, f64)] {
    let last = tip.last().map_or(0.0, |p| p.1);
    let stop = tip
        .iter()
        .position(|p| p.1 >= last)
        .map_or(tip.len(), |k| k + 1);
    &tip[..stop]
}

/// One point of the front-speed plot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedPoint {
    pub event: usize,
    pub x: f64,
    /// The speed, or for an unresolved window the lower bound.
    pub speed: f64,
    pub lower_bound: bool,
    pub kind: FrontKind,
    pub full: bool,
}

pub struct FrontSpeedPlot<'a> {
    pub series: &'a InterfaceSeries,
    pub events: &'a [Event],
    /// Draw this event only.
    pub only: Option<usize>,
    pub waves: Option<WaveSpeeds>,
    /// Blocks per window.
    pub window: usize,
}

impl FrontSpeedPlot<'_> {
    fn chosen(&self) -> impl Iterator<Item = (usize, &Event)> {
        self.events
            .iter()
            .enumerate()
            .filter(move |(k, _)| self.only.is_none_or(|n| n == *k))
    }

    pub fn points(&self) -> Vec<SpeedPoint> {
        let mut out = Vec::new();
        for (k, e) in self.chosen() {
            let kind = self.series.front_kind(e, self.window);
            let speeds = self.series.front_speed(e, self.window);
            let bounds = self.series.front_speed_bounds(e, self.window);
            for ((x, v), bound) in speeds.into_iter().zip(bounds) {
                out.push(SpeedPoint {
                    event: k,
                    x,
                    speed: bound.unwrap_or(v),
                    lower_bound: bound.is_some(),
                    kind,
                    full: e.full,
                });
            }
        }
        out
    }

    /// The fastest speed the output cadence resolves: a window of w blocks
    /// crossed within one output interval (the median one during the
    /// events drawn).
    pub fn resolution_limit(&self) -> Option<f64> {
        let mut dt: Vec<f64> = self
            .chosen()
            .flat_map(|(_, e)| {
                self.series.time[e.first..=e.last]
                    .windows(2)
                    .map(|p| p[1] - p[0])
            })
            .filter(|d| *d > 0.0)
            .collect();
        dt.sort_by(f64::total_cmp);
        dt.get(dt.len() / 2)
            .map(|dt| self.window as f64 * self.series.spacing / dt)
    }

    /// Vertical range (m/s, log): whole decades around the data, the wave
    /// speeds and the resolution limit, at most 0.1 ..= 10⁵.
    pub fn speed_range(&self, points: &[SpeedPoint]) -> (f64, f64) {
        let mut all: Vec<f64> = points.iter().map(|p| p.speed).collect();
        if let Some(w) = self.waves {
            all.extend([w.shear, w.pressure]);
        }
        all.extend(self.resolution_limit());
        let (lo, hi) = extent(all.into_iter().filter(|v| *v > 0.0)).unwrap_or((1.0, 1e4));
        (
            10f64.powf(lo.log10().floor()).max(0.1),
            10f64.powf((hi * 1.5).log10().ceil()).min(1e5),
        )
    }
}

impl Figure for FrontSpeedPlot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static,
    {
        let points = self.points();
        let (lo, hi) = self.speed_range(&points);
        let length = (self.series.nx().max(2) - 1) as f64 * self.series.spacing * 1e3;
        let title = match self.only {
            Some(n) => format!("Front speed, event {n}"),
            None => format!("Front speed, {} events", self.events.len()),
        };
        let mut chart = ChartBuilder::on(root)
            .caption(style.title(&title), style.title_font())
            .margin(style.px(14.0))
            .x_label_area_size(style.px(48.0))
            .y_label_area_size(style.px(72.0))
            .build_cartesian_2d(0.0..length, (lo..hi).log_scale())?;
        chart
            .configure_mesh()
            .light_line_style(RGBColor(240, 240, 240))
            .bold_line_style(RGBColor(220, 220, 220))
            .x_desc("position x (mm), window centre")
            .y_desc("front speed (m/s)")
            .x_label_formatter(&|v| tick(*v, length))
            .y_label_formatter(&|v| log_tick(*v))
            .label_style(style.tick_font())
            .axis_desc_style(style.label_font())
            .draw()?;
        let mut refs: Vec<(f64, &str, RGBColor)> = Vec::new();
        if let Some(w) = self.waves {
            refs.push((w.shear, "c_s", RGBColor(90, 90, 90)));
            refs.push((w.rayleigh, "c_R", RGBColor(0, 120, 120)));
            refs.push((w.pressure, "c_p", RGBColor(0, 0, 0)));
        }
        let limit = self.resolution_limit();
        for (v, name, colour) in &refs {
            let colour = *colour;
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(0.0, *v), (length, *v)],
                    style.px(6.0),
                    style.px(4.0),
                    colour.stroke_width(style.px(1.0)),
                ))?
                .label(format!("{name} = {v:.0} m/s"))
                .legend(legend_line(colour, style));
        }
        if let Some(v) = limit.filter(|v| *v < hi) {
            let grey = RGBColor(170, 170, 170);
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(0.0, v), (length, v)],
                    style.px(2.0),
                    style.px(3.0),
                    grey.stroke_width(style.px(2.0)),
                ))?
                .label(format!("resolution limit {v:.0} m/s"))
                .legend(legend_line(grey, style));
        }
        let r = style.px(3.0) as i32;
        for kind in [
            FrontKind::Fast,
            FrontKind::FastSlowFast,
            FrontKind::FastSlow,
            FrontKind::Slow,
        ] {
            let (colour, name) = class_style(kind);
            let of_kind: Vec<&SpeedPoint> = points
                .iter()
                .filter(|p| p.kind == kind && !p.lower_bound && p.speed <= hi)
                .collect();
            if of_kind.is_empty() && !points.iter().any(|p| p.kind == kind) {
                continue;
            }
            chart
                .draw_series(of_kind.iter().map(|p| {
                    let s = if p.full {
                        colour.filled()
                    } else {
                        colour.stroke_width(1)
                    };
                    Circle::new((p.x * 1e3, p.speed.max(lo)), r, s)
                }))?
                .label(format!("{name} front"))
                .legend(move |(x, y)| Circle::new((x + 9, y), r, colour.filled()));
        }
        // Lower bounds and values above the axis: triangles pointing up.
        let up = |x: f64, v: f64, colour: RGBColor| {
            Polygon::new(
                vec![
                    (x, v * 1.0),
                    (x - 0.006 * length, v / 1.25),
                    (x + 0.006 * length, v / 1.25),
                ],
                colour.filled(),
            )
        };
        let marked: Vec<&SpeedPoint> = points
            .iter()
            .filter(|p| p.lower_bound || p.speed > hi)
            .collect();
        if !marked.is_empty() {
            chart
                .draw_series(
                    marked
                        .iter()
                        .map(|p| up(p.x * 1e3, p.speed.min(hi / 1.02), class_style(p.kind).0)),
                )?
                .label("faster than shown (unresolved or clipped)")
                .legend(|(x, y)| {
                    Polygon::new(vec![(x + 9, y - 5), (x + 4, y + 4), (x + 14, y + 4)], BLACK)
                });
        }
        for (full, name) in [(true, "full event"), (false, "partial event")] {
            if points.iter().any(|p| p.full == full) {
                chart
                    .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
                    .label(name)
                    .legend(move |(x, y)| {
                        let s = if full {
                            BLACK.filled()
                        } else {
                            BLACK.stroke_width(1)
                        };
                        Circle::new((x + 9, y), r, s)
                    });
            }
        }
        legend(&mut chart, style, SeriesLabelPosition::UpperRight)?;
        Ok(())
    }
}

/// Front tip position against the time since each event began.
pub struct FrontTipPlot<'a> {
    pub series: &'a InterfaceSeries,
    pub events: &'a [Event],
    pub window: usize,
}

impl Figure for FrontTipPlot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static,
    {
        let tips: Vec<Vec<(f64, f64)>> = self
            .events
            .iter()
            .map(|e| until_arrest(&self.series.front_tip(e)).to_vec())
            .collect();
        let longest = self
            .events
            .iter()
            .zip(&tips)
            .map(|(e, tip)| tip.last().map_or(0.0, |p| p.0 - e.start))
            .fold(0.0f64, f64::max)
            .max(1e-9)
            * 1.04;
        let (f, unit) = super::loading::time_unit(longest);
        let length = (self.series.nx().max(2) - 1) as f64 * self.series.spacing * 1e3;
        let mut chart = ChartBuilder::on(root)
            .caption(style.title("Front tip"), style.title_font())
            .margin(style.px(14.0))
            .x_label_area_size(style.px(48.0))
            .y_label_area_size(style.px(72.0))
            .build_cartesian_2d(0.0..longest * f, 0.0..length)?;
        chart
            .configure_mesh()
            .light_line_style(RGBColor(240, 240, 240))
            .bold_line_style(RGBColor(220, 220, 220))
            .x_desc(format!("time since the event began ({unit})"))
            .y_desc("front tip x_tip (mm)")
            .x_label_formatter(&|v| tick(*v, longest * f))
            .y_label_formatter(&|v| tick(*v, length))
            .label_style(style.tick_font())
            .axis_desc_style(style.label_font())
            .draw()?;
        let mut seen: Vec<FrontKind> = Vec::new();
        for (k, (e, tip)) in self.events.iter().zip(&tips).enumerate() {
            let kind = self.series.front_kind(e, self.window);
            let (colour, name) = class_style(kind);
            let tip: Vec<(f64, f64)> = tip
                .iter()
                .map(|&(t, x)| ((t - e.start) * f, x * 1e3))
                .collect();
            let end = tip.last().copied();
            let s = chart.draw_series(LineSeries::new(tip, colour.stroke_width(style.px(1.2))))?;
            if !seen.contains(&kind) {
                seen.push(kind);
                s.label(format!("{name} front"))
                    .legend(legend_line(colour, style));
            }
            if let Some(p) = end {
                chart.draw_series(std::iter::once(Text::new(
                    k.to_string(),
                    p,
                    style.font(10.0).color(&colour),
                )))?;
            }
        }
        legend(&mut chart, style, SeriesLabelPosition::LowerRight)?;
        Ok(())
    }
}

/// Slip speed behind the tip against front speed over every crossing,
/// log–log, with the fitted power law.
pub struct SlipVsFrontPlot {
    pub pairs: Vec<(f64, f64)>,
}

impl SlipVsFrontPlot {
    fn finite(&self) -> Vec<(f64, f64)> {
        self.pairs
            .iter()
            .copied()
            .filter(|(f, s)| f.is_finite() && *f > 0.0 && s.is_finite() && *s > 0.0)
            .collect()
    }
}

impl Figure for SlipVsFrontPlot {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static,
    {
        let pts = self.finite();
        anyhow::ensure!(
            !pts.is_empty(),
            "no crossing with a finite front speed and slip speed"
        );
        let decades = |(lo, hi): (f64, f64)| {
            (
                10f64.powf(lo.log10().floor()),
                10f64
                    .powf(hi.log10().ceil())
                    .max(10f64.powf(lo.log10().floor() + 1.0)),
            )
        };
        let xr = decades(extent(pts.iter().map(|p| p.0)).expect("non-empty"));
        let yr = decades(extent(pts.iter().map(|p| p.1)).expect("non-empty"));
        let mut chart = ChartBuilder::on(root)
            .caption(
                style.title("Slip speed against front speed"),
                style.title_font(),
            )
            .margin(style.px(14.0))
            .margin_right(style.px(36.0))
            .x_label_area_size(style.px(48.0))
            .y_label_area_size(style.px(72.0))
            .build_cartesian_2d((xr.0..xr.1).log_scale(), (yr.0..yr.1).log_scale())?;
        chart
            .configure_mesh()
            .light_line_style(RGBColor(240, 240, 240))
            .bold_line_style(RGBColor(220, 220, 220))
            .x_desc("front speed (m/s)")
            .y_desc("slip speed behind the tip (m/s)")
            .x_label_formatter(&|v| log_tick(*v))
            .y_label_formatter(&|v| log_tick(*v))
            .label_style(style.tick_font())
            .axis_desc_style(style.label_font())
            .draw()?;
        let r = style.px(2.5) as i32;
        chart
            .draw_series(
                pts.iter()
                    .map(|&p| Circle::new(p, r, PALETTE[0].mix(0.6).filled())),
            )?
            .label(format!("{} crossings (window of 3 blocks)", pts.len()))
            .legend(move |(x, y)| Circle::new((x + 9, y), r, PALETTE[0].filled()));
        if let Some(fit) = slip_front_relation(&pts) {
            let line: Vec<(f64, f64)> = (0..=50)
                .map(|k| {
                    let f = 10f64.powf(xr.0.log10() + k as f64 / 50.0 * (xr.1 / xr.0).log10());
                    (f, fit.prefactor * f.powf(fit.exponent))
                })
                .filter(|p| p.1 >= yr.0 && p.1 <= yr.1)
                .collect();
            chart
                .draw_series(LineSeries::new(
                    line,
                    PALETTE[1].stroke_width(style.px(2.0)),
                ))?
                .label(format!(
                    "fit v_slip = {:.2e}·v_front^{:.2}  (log–log r = {:.2})",
                    fit.prefactor, fit.exponent, fit.correlation
                ))
                .legend(legend_line(PALETTE[1], style));
        }
        legend(&mut chart, style, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    }
}
