//! The loading curve: driving force over normal force against time, from
//! zero, with the events marked and numbered as `slipfront info` numbers
//! them.

use super::colour::legend_line;
use super::colour::PALETTE;
use super::figure::{decimate, extent, legend, tick, Drawn, Figure, Style};
use crate::analysis::events::Event;
use plotters::coord::Shift;
use plotters::prelude::*;

/// A time unit that suits a span: (factor from seconds, name).
pub fn time_unit(span: f64) -> (f64, &'static str) {
    if span >= 0.5 {
        (1.0, "s")
    } else if span >= 0.5e-3 {
        (1e3, "ms")
    } else {
        (1e6, "µs")
    }
}

pub struct LoadingCurve<'a> {
    /// Sample times (s) and F/F_N at them.
    pub time: &'a [f64],
    pub ratio: &'a [f64],
    /// Events in `info`'s order: event k is labelled k.
    pub events: &'a [Event],
}

pub const FULL: RGBColor = RGBColor(214, 39, 40);
pub const PARTIAL: RGBColor = RGBColor(255, 160, 60);

impl LoadingCurve<'_> {
    /// Axis ranges: time over the run (s), F/F_N from 0 to above its peak.
    pub fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        let (t0, t1) = extent(self.time.iter().copied()).unwrap_or((0.0, 1.0));
        let (_, top) = extent(self.ratio.iter().copied()).unwrap_or((0.0, 1.0));
        let top = if top > 0.0 { top * 1.12 } else { 1.0 };
        ((t0, t1.max(t0 + 1e-12)), (0.0, top))
    }
}

impl Figure for LoadingCurve<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static,
    {
        let ((t0, t1), (y0, y1)) = self.ranges();
        let (f, unit) = time_unit(t1 - t0);
        let mut chart = ChartBuilder::on(root)
            .caption(style.title("Loading curve"), style.title_font())
            .margin(style.px(14.0))
            .x_label_area_size(style.px(48.0))
            .y_label_area_size(style.px(72.0))
            .build_cartesian_2d(t0 * f..t1 * f, y0..y1)?;
        let (xs, ys) = ((t1 - t0) * f, y1 - y0);
        chart
            .configure_mesh()
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(215, 215, 215))
            .x_desc(format!("time t ({unit})"))
            .y_desc("driving force / normal force  F/F_N")
            .x_label_formatter(&|v| tick(*v, xs))
            .y_label_formatter(&|v| tick(*v, ys))
            .label_style(style.tick_font())
            .axis_desc_style(style.label_font())
            .draw()?;
        let mut seen = (false, false);
        for (k, e) in self.events.iter().enumerate() {
            let colour = if e.full { FULL } else { PARTIAL };
            let x = e.start * f;
            let line = chart.draw_series(std::iter::once(PathElement::new(
                vec![(x, y0), (x, y1 * 0.93)],
                colour.stroke_width(style.px(1.0)),
            )))?;
            let first = if e.full { &mut seen.0 } else { &mut seen.1 };
            if !*first {
                *first = true;
                line.label(if e.full {
                    "full event"
                } else {
                    "partial event"
                })
                .legend(legend_line(colour, style));
            }
            // Numbers on two levels so neighbours do not overlap.
            let level = if k % 2 == 0 { 0.965 } else { 0.935 };
            chart.draw_series(std::iter::once(Text::new(
                k.to_string(),
                (x, y1 * level + 0.02 * y1),
                style.font(10.5).color(&colour),
            )))?;
        }
        chart
            .draw_series(LineSeries::new(
                decimate(
                    &self
                        .time
                        .iter()
                        .zip(self.ratio)
                        .map(|(&t, &r)| (t * f, r))
                        .collect::<Vec<_>>(),
                    root.dim_in_pixel().0 as usize,
                ),
                PALETTE[0].stroke_width(style.px(1.5)),
            ))?
            .label("F/F_N")
            .legend(legend_line(PALETTE[0], style));
        legend(&mut chart, style, SeriesLabelPosition::LowerRight)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_load_axis_starts_at_zero_whatever_the_data() {
        let time = [0.0, 0.1, 0.2];
        let ratio = [0.005, 0.011, 0.008];
        let c = LoadingCurve {
            time: &time,
            ratio: &ratio,
            events: &[],
        };
        let ((t0, t1), (y0, y1)) = c.ranges();
        assert_eq!((t0, t1), (0.0, 0.2));
        assert_eq!(y0, 0.0);
        assert!((y1 - 0.011 * 1.12).abs() < 1e-15);
        assert_eq!(time_unit(2.5).1, "s");
        assert_eq!(time_unit(0.02).1, "ms");
    }
}
