//! Slip: δ(t) at chosen positions (thesis Fig. 2.8) and the slip profile
//! along the interface after each event.

use super::colour::legend_line;
use super::colour::{colour_bar, viridis, ColourScale, Ramp, BAR_WIDTH, PALETTE};
use super::figure::{decimate, extent, legend, tick, Drawn, Figure, Style};
use super::loading::time_unit;
use crate::analysis::events::{Event, InterfaceSeries};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Slip against time at a few interface blocks.
pub struct SlipHistory<'a> {
    pub series: &'a InterfaceSeries,
    /// Interface block indices to draw.
    pub blocks: Vec<usize>,
}

impl SlipHistory<'_> {
    /// `count` blocks spread evenly from the trailing to the leading edge.
    pub fn spread(nx: usize, count: usize) -> Vec<usize> {
        let count = count.clamp(1, nx.max(1));
        if count == 1 || nx <= 1 {
            return vec![0];
        }
        let mut v: Vec<usize> = (0..count)
            .map(|k| (k as f64 * (nx - 1) as f64 / (count - 1) as f64).round() as usize)
            .collect();
        v.dedup();
        v
    }

    /// The block nearest each position (m); an error names a position off
    /// the interface.
    pub fn blocks_at(series: &InterfaceSeries, positions: &[f64]) -> anyhow::Result<Vec<usize>> {
        let nx = series.nx();
        let length = (nx.max(1) - 1) as f64 * series.spacing;
        positions
            .iter()
            .map(|&x| {
                anyhow::ensure!(
                    x.is_finite()
                        && x >= -0.5 * series.spacing
                        && x <= length + 0.5 * series.spacing,
                    "--at {:.4} mm: off the interface (0 ..= {:.4} mm)",
                    x * 1e3,
                    length * 1e3
                );
                Ok(((x / series.spacing).round().max(0.0) as usize).min(nx - 1))
            })
            .collect()
    }
}

impl Figure for SlipHistory<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static,
    {
        let s = self.series;
        let (t0, t1) = extent(s.time.iter().copied()).unwrap_or((0.0, 1.0));
        let (f, unit) = time_unit(t1 - t0);
        let top = s
            .slip
            .iter()
            .flat_map(|row| self.blocks.iter().map(|&ix| row[ix]))
            .fold(0.0f64, f64::max);
        let bottom = s
            .slip
            .iter()
            .flat_map(|row| self.blocks.iter().map(|&ix| row[ix]))
            .fold(0.0f64, f64::min);
        let (ys, yu) = slip_unit(top.max(-bottom));
        let (y0, y1) = (bottom * ys, (top * ys * 1.05).max(bottom * ys + 1e-9));
        let mut chart = ChartBuilder::on(root)
            .caption(style.title("Slip at fixed positions"), style.title_font())
            .margin(style.px(14.0))
            .x_label_area_size(style.px(48.0))
            .y_label_area_size(style.px(72.0))
            .build_cartesian_2d(t0 * f..t1.max(t0 + 1e-12) * f, y0..y1)?;
        let (xspan, yspan) = ((t1 - t0) * f, y1 - y0);
        chart
            .configure_mesh()
            .light_line_style(RGBColor(240, 240, 240))
            .bold_line_style(RGBColor(220, 220, 220))
            .x_desc(format!("time t ({unit})"))
            .y_desc(format!("slip δ since driving began ({yu})"))
            .x_label_formatter(&|v| tick(*v, xspan))
            .y_label_formatter(&|v| tick(*v, yspan))
            .label_style(style.tick_font())
            .axis_desc_style(style.label_font())
            .draw()?;
        for (k, &ix) in self.blocks.iter().enumerate() {
            let colour = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(
                    decimate(
                        &s.time
                            .iter()
                            .zip(&s.slip)
                            .map(|(&t, row)| (t * f, row[ix] * ys))
                            .collect::<Vec<_>>(),
                        root.dim_in_pixel().0 as usize,
                    ),
                    colour.stroke_width(style.px(1.5)),
                ))?
                .label(format!("x = {:.1} mm", ix as f64 * s.spacing * 1e3))
                .legend(legend_line(colour, style));
        }
        legend(&mut chart, style, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    }
}

/// A unit that suits a slip of `size` metres: (factor from m, name).
pub fn slip_unit(size: f64) -> (f64, &'static str) {
    if size >= 1e-3 {
        (1e3, "mm")
    } else if size >= 1e-6 {
        (1e6, "µm")
    } else {
        (1e9, "nm")
    }
}

/// The slip profile δ(x) at the end of each event, coloured by event
/// number.
pub struct SlipProfiles<'a> {
    pub series: &'a InterfaceSeries,
    pub events: &'a [Event],
}

impl Figure for SlipProfiles<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static,
    {
        let s = self.series;
        anyhow::ensure!(!self.events.is_empty(), "no events");
        let (width, _) = root.dim_in_pixel();
        let (main, bar) = root.split_horizontally(width.saturating_sub(style.px(BAR_WIDTH)));
        let profiles: Vec<&Vec<f64>> = self.events.iter().map(|e| &s.slip[e.last]).collect();
        let (lo, hi) =
            extent(profiles.iter().flat_map(|p| p.iter().copied())).unwrap_or((0.0, 1.0));
        let (ys, yu) = slip_unit(hi.abs().max(lo.abs()));
        let (y0, y1) = ((lo.min(0.0)) * ys, (hi * ys * 1.05).max(lo * ys + 1e-9));
        let length = (s.nx().max(2) - 1) as f64 * s.spacing * 1e3;
        let mut chart = ChartBuilder::on(&main)
            .caption(
                style.title("Slip profile after each event"),
                style.title_font(),
            )
            .margin(style.px(14.0))
            .x_label_area_size(style.px(48.0))
            .y_label_area_size(style.px(72.0))
            .build_cartesian_2d(0.0..length, y0..y1)?;
        let yspan = y1 - y0;
        chart
            .configure_mesh()
            .light_line_style(RGBColor(240, 240, 240))
            .bold_line_style(RGBColor(220, 220, 220))
            .x_desc("position x (mm)")
            .y_desc(format!("slip δ since driving began ({yu})"))
            .x_label_formatter(&|v| tick(*v, length))
            .y_label_formatter(&|v| tick(*v, yspan))
            .label_style(style.tick_font())
            .axis_desc_style(style.label_font())
            .draw()?;
        let last = (self.events.len() - 1).max(1) as f64;
        for (k, (e, p)) in self.events.iter().zip(&profiles).enumerate() {
            let colour = viridis(k as f64 / last);
            let line = p
                .iter()
                .enumerate()
                .map(|(ix, &d)| (ix as f64 * s.spacing * 1e3, d * ys));
            let stroke = if e.full {
                colour.stroke_width(style.px(1.6))
            } else {
                colour.mix(0.6).stroke_width(style.px(1.0))
            };
            chart.draw_series(LineSeries::new(line, stroke))?;
        }
        let (_, y_px) = chart.plotting_area().get_pixel_range();
        colour_bar(
            &bar,
            &ColourScale {
                ramp: Ramp::Viridis,
                lo: 0.0,
                hi: last,
                log: false,
                label: "event number (as in info)",
            },
            style,
            (y_px.start.max(0) as u32, y_px.end.max(0) as u32),
        )
    }
}
