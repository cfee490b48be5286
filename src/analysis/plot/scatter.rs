//! Plots of tables: an outcome against a swept key (sweeps), and error
//! against run time (the work–precision benchmark).

use super::colour::legend_line;
use super::colour::PALETTE;
use super::figure::{extent, legend, log_tick, tick, Drawn, Figure, Style};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Points (x, y, group) with one colour per group and a legend.
pub struct Scatter<'a> {
    pub points: &'a [(f64, f64, usize)],
    pub groups: &'a [String],
    /// Column the groups come from, for the legend.
    pub group_label: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub log_y: bool,
    pub title: &'a str,
    /// Join each group's points in order of x (a curve, not a cloud).
    pub connect: bool,
}

impl Scatter<'_> {
    fn padded(lo: f64, hi: f64) -> (f64, f64) {
        let pad = 0.05 * (hi - lo).max(1e-12 * hi.abs().max(1.0));
        (lo - pad, hi + pad)
    }

    /// The plot corner where the legend hides the fewest data (points, and
    /// for connected curves the points along each segment, counted in a
    /// legend-sized box in each corner), and how many it hides there.
    fn emptiest_corner(
        &self,
        pts: &[(f64, f64, usize)],
        (x0, x1): (f64, f64),
        y_fraction: impl Fn(f64) -> f64,
    ) -> (SeriesLabelPosition, usize) {
        let fraction = |p: &(f64, f64, usize)| ((p.0 - x0) / (x1 - x0), y_fraction(p.1));
        let mut marks: Vec<(f64, f64)> = pts.iter().map(fraction).collect();
        if self.connect {
            for g in 0..self.groups.len() {
                let mut line: Vec<(f64, f64)> =
                    pts.iter().filter(|p| p.2 == g).map(fraction).collect();
                line.sort_by(|a, b| a.0.total_cmp(&b.0));
                for w in line.windows(2) {
                    marks.extend((1..8).map(|k| {
                        let t = k as f64 / 8.0;
                        (
                            w[0].0 + t * (w[1].0 - w[0].0),
                            w[0].1 + t * (w[1].1 - w[0].1),
                        )
                    }));
                }
            }
        }
        let (w, h) = self.legend_size();
        let corners = [
            (SeriesLabelPosition::UpperRight, 1.0 - w, 1.0 - h),
            (SeriesLabelPosition::UpperLeft, 0.0, 1.0 - h),
            (SeriesLabelPosition::LowerRight, 1.0 - w, 0.0),
            (SeriesLabelPosition::LowerLeft, 0.0, 0.0),
        ];
        let hidden = |&(_, x, y): &(SeriesLabelPosition, f64, f64)| {
            marks
                .iter()
                .filter(|m| m.0 >= x && m.0 <= x + w && m.1 >= y && m.1 <= y + h)
                .count()
        };
        // The first of the emptiest, so ties keep the upper right.
        let fewest = corners.iter().map(hidden).min().unwrap_or(0);
        let corner = corners
            .into_iter()
            .find(|c| hidden(c) == fewest)
            .map_or(SeriesLabelPosition::UpperRight, |c| c.0);
        (corner, fewest)
    }

    /// The legend's size as fractions of a default figure's plot area:
    /// about 7 px a character of label plus the marker, 22 px a row.
    fn legend_size(&self) -> (f64, f64) {
        let chars = self
            .groups
            .iter()
            .map(|g| g.chars().count() + self.group_label.chars().count() + 3)
            .max()
            .unwrap_or(0);
        (
            ((7.0 * chars as f64 + 40.0) / 790.0).min(0.95),
            ((22.0 * self.groups.len() as f64 + 16.0) / 470.0).min(0.9),
        )
    }

    /// The upper end of the y range `lo..hi`, raised so that the legend
    /// fits above the data when every corner would hide some (`hidden`).
    fn headroom(&self, hidden: usize, lo: f64, hi: f64) -> f64 {
        if hidden == 0 {
            return hi;
        }
        // 3 % more for the legend's margin.
        lo + (hi - lo) / (0.97 - self.legend_size().1)
    }
}

impl Figure for Scatter<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static,
    {
        let pts: Vec<(f64, f64, usize)> = self
            .points
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite() && (!self.log_y || p.1 > 0.0))
            .collect();
        anyhow::ensure!(!pts.is_empty(), "no finite points to plot");
        let (x0, x1) = extent(pts.iter().map(|p| p.0)).expect("non-empty");
        let (x0, x1) = Self::padded(x0, x1);
        let (y0, y1) = extent(pts.iter().map(|p| p.1)).expect("non-empty");
        let mut builder = ChartBuilder::on(root);
        builder
            .caption(style.title(self.title), style.title_font())
            .margin(style.px(14.0))
            .x_label_area_size(style.px(48.0))
            .y_label_area_size(style.px(80.0));
        let r = style.px(3.5) as i32;
        let xspan = x1 - x0;
        macro_rules! finish {
            ($chart:expr, $yfmt:expr, $corner:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .light_line_style(RGBColor(240, 240, 240))
                    .bold_line_style(RGBColor(220, 220, 220))
                    .x_desc(self.x_label)
                    .y_desc(self.y_label)
                    .x_label_formatter(&|v| tick(*v, xspan))
                    .y_label_formatter($yfmt)
                    .label_style(style.tick_font())
                    .axis_desc_style(style.label_font())
                    .draw()?;
                for (g, name) in self.groups.iter().enumerate() {
                    let colour = PALETTE[g % PALETTE.len()];
                    if self.connect {
                        let mut line: Vec<(f64, f64)> = pts
                            .iter()
                            .filter(|p| p.2 == g)
                            .map(|p| (p.0, p.1))
                            .collect();
                        line.sort_by(|a, b| a.0.total_cmp(&b.0));
                        chart.draw_series(LineSeries::new(
                            line,
                            colour.stroke_width(style.px(1.5)),
                        ))?;
                    }
                    let series = chart.draw_series(
                        pts.iter()
                            .filter(|p| p.2 == g)
                            .map(|p| Circle::new((p.0, p.1), r, colour.mix(0.75).filled())),
                    )?;
                    if self.groups.len() > 1 || !name.is_empty() {
                        series
                            .label(format!("{} = {name}", self.group_label))
                            .legend(move |(x, y)| Circle::new((x + 9, y), r, colour.filled()));
                    }
                }
                if self.groups.len() > 1 || self.groups.iter().any(|g| !g.is_empty()) {
                    legend(&mut chart, style, $corner)?;
                }
            }};
        }
        if self.log_y {
            let (a, b) = (
                10f64.powf(y0.log10().floor()),
                10f64
                    .powf(y1.log10().ceil())
                    .max(10f64.powf(y0.log10().floor() + 1.0)),
            );
            let (la, lb) = (a.log10(), b.log10());
            let (_, hidden) =
                self.emptiest_corner(&pts, (x0, x1), |y| (y.log10() - la) / (lb - la));
            let lb = self.headroom(hidden, la, lb);
            let b = 10f64.powf(lb);
            let (corner, _) =
                self.emptiest_corner(&pts, (x0, x1), |y| (y.log10() - la) / (lb - la));
            finish!(
                builder.build_cartesian_2d(x0..x1, (a..b).log_scale())?,
                &|v: &f64| log_tick(*v),
                corner
            );
        } else {
            let (a, b) = Self::padded(y0, y1);
            let (_, hidden) = self.emptiest_corner(&pts, (x0, x1), |y| (y - a) / (b - a));
            let b = self.headroom(hidden, a, b);
            let span = b - a;
            let (corner, _) = self.emptiest_corner(&pts, (x0, x1), |y| (y - a) / span);
            finish!(
                builder.build_cartesian_2d(x0..x1, a..b)?,
                &|v: &f64| tick(*v, span),
                corner
            );
        }
        Ok(())
    }
}

/// One measured point of the work–precision benchmark.
#[derive(Debug, Clone, PartialEq)]
pub struct WorkPoint {
    pub observable: String,
    pub engine: String,
    /// Time step as a fraction of the oscillation period.
    pub fraction: f64,
    pub seconds: f64,
    pub error: f64,
}

/// One log–log panel per observable: error against run time, one line per
/// engine, points labelled with their time step.
pub struct WorkPrecision<'a> {
    pub points: &'a [WorkPoint],
}

impl Figure for WorkPrecision<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static,
    {
        let mut observables: Vec<&str> = Vec::new();
        let mut engines: Vec<&str> = Vec::new();
        for p in self.points.iter().filter(|p| p.error > 0.0) {
            if !observables.contains(&p.observable.as_str()) {
                observables.push(&p.observable);
            }
            if !engines.contains(&p.engine.as_str()) {
                engines.push(&p.engine);
            }
        }
        anyhow::ensure!(!observables.is_empty(), "no point with a positive error");
        let root = root.margin(style.px(6.0), 0, 0, 0);
        let root = root.titled(
            &style.title("Work–precision: error against run time"),
            style.title_font(),
        )?;
        let panels = root.split_evenly((1, observables.len()));
        for (panel, obs) in panels.iter().zip(&observables) {
            let pts: Vec<&WorkPoint> = self
                .points
                .iter()
                .filter(|p| p.observable == *obs && p.error > 0.0 && p.seconds > 0.0)
                .collect();
            let decade = |(lo, hi): (f64, f64)| {
                (
                    10f64.powf(lo.log10().floor()),
                    10f64
                        .powf(hi.log10().ceil())
                        .max(10f64.powf(lo.log10().floor() + 1.0)),
                )
            };
            let xr = decade(extent(pts.iter().map(|p| p.seconds)).unwrap_or((0.1, 1.0)));
            let yr = decade(extent(pts.iter().map(|p| p.error)).unwrap_or((1e-6, 1.0)));
            let mut chart = ChartBuilder::on(panel)
                .caption(*obs, style.label_font())
                .margin(style.px(10.0))
                .margin_right(style.px(30.0))
                .x_label_area_size(style.px(44.0))
                .y_label_area_size(style.px(64.0))
                .build_cartesian_2d((xr.0..xr.1).log_scale(), (yr.0..yr.1).log_scale())?;
            chart
                .configure_mesh()
                .light_line_style(RGBColor(240, 240, 240))
                .bold_line_style(RGBColor(220, 220, 220))
                .x_desc("run time (s)")
                .y_desc("relative error")
                .x_label_formatter(&|v| log_tick(*v))
                .y_label_formatter(&|v| log_tick(*v))
                .label_style(style.tick_font())
                .axis_desc_style(style.label_font())
                .draw()?;
            for (k, engine) in engines.iter().enumerate() {
                let colour = PALETTE[k % PALETTE.len()];
                // In order of time step, coarsest first.
                let mut of_engine: Vec<&&WorkPoint> =
                    pts.iter().filter(|p| p.engine == *engine).collect();
                of_engine.sort_by(|a, b| b.fraction.total_cmp(&a.fraction));
                let line: Vec<(f64, f64)> =
                    of_engine.iter().map(|p| (p.seconds, p.error)).collect();
                chart
                    .draw_series(LineSeries::new(
                        line.clone(),
                        colour.stroke_width(style.px(1.5)),
                    ))?
                    .label(*engine)
                    .legend(legend_line(colour, style));
                chart.draw_series(
                    line.iter()
                        .map(|&p| Circle::new(p, style.px(3.0) as i32, colour.filled())),
                )?;
                chart.draw_series(pts.iter().filter(|p| p.engine == *engine).map(|p| {
                    Text::new(
                        format!("T/{:.0}", 1.0 / p.fraction),
                        (p.seconds * 1.08, p.error * 1.15),
                        style.font(9.5).color(&colour),
                    )
                }))?;
            }
            legend(&mut chart, style, SeriesLabelPosition::UpperRight)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scatter<'a>(points: &'a [(f64, f64, usize)], groups: &'a [String]) -> Scatter<'a> {
        Scatter {
            points,
            groups,
            group_label: "g",
            x_label: "x",
            y_label: "y",
            log_y: false,
            title: "t",
            connect: true,
        }
    }

    #[test]
    fn the_legend_goes_where_the_curves_are_not() {
        let groups = vec!["a".to_string(), "b".to_string()];
        // Rising curves fill the upper right: the legend moves to the upper left.
        let rising: Vec<(f64, f64, usize)> = (0..10)
            .flat_map(|i| {
                let x = i as f64 / 9.0;
                [(x, x * x, 0), (x, x.powi(3), 1)]
            })
            .collect();
        let s = scatter(&rising, &groups);
        let (corner, hidden) = s.emptiest_corner(&rising, (0.0, 1.0), |y| y);
        assert_eq!(hidden, 0);
        assert!(
            matches!(corner, SeriesLabelPosition::UpperLeft),
            "{corner:?}"
        );
        // Falling curves leave the upper right free (the default).
        let falling: Vec<(f64, f64, usize)> =
            rising.iter().map(|&(x, y, g)| (x, 1.0 - y, g)).collect();
        let s = scatter(&falling, &groups);
        let (corner, _) = s.emptiest_corner(&falling, (0.0, 1.0), |y| y);
        assert!(
            matches!(corner, SeriesLabelPosition::UpperRight),
            "{corner:?}"
        );
        // Data everywhere: no corner is free, so the y range grows until
        // the legend fits above the data.
        let full: Vec<(f64, f64, usize)> = (0..400)
            .map(|i| ((i % 20) as f64 / 19.0, (i / 20) as f64 / 19.0, i % 2))
            .collect();
        let s = Scatter {
            connect: false,
            ..scatter(&full, &groups)
        };
        let (_, hidden) = s.emptiest_corner(&full, (0.0, 1.0), |y| y);
        assert!(hidden > 0);
        let top = s.headroom(hidden, 0.0, 1.0);
        assert!(top > 1.0);
        let (_, hidden) = s.emptiest_corner(&full, (0.0, 1.0), |y| y / top);
        assert_eq!(hidden, 0);
    }
}
