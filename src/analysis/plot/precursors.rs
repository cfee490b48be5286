//! Precursor length against the tangential load (Rubinstein et al. 2007,
//! thesis Fig. 2.11).

use super::colour::legend_line;
use super::figure::{legend, tick, Drawn, Figure, Style};
use crate::analysis::precursors::{Precursor, PrecursorSequence};
use plotters::coord::Shift;
use plotters::prelude::*;

pub struct PrecursorPlot<'a> {
    pub sequence: &'a PrecursorSequence,
    /// Interface length (m).
    pub length: f64,
    pub spacing: f64,
}

impl PrecursorPlot<'_> {
    /// F/F_N axis: from 0 to beyond the first full event's load.
    pub fn load_range(&self) -> (f64, f64) {
        let top = self
            .sequence
            .precursors
            .iter()
            .map(|p| p.drive_ratio)
            .chain(self.sequence.first_full_ratio)
            .fold(0.0f64, f64::max);
        (0.0, if top > 0.0 { top * 1.1 } else { 1.0 })
    }
}

impl Figure for PrecursorPlot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static,
    {
        anyhow::ensure!(
            !self.sequence.precursors.is_empty() || self.sequence.first_full_ratio.is_some(),
            "no precursor and no full event"
        );
        let (x0, x1) = self.load_range();
        let length = self.length * 1e3;
        let y1 = length * 1.08;
        let mut chart = ChartBuilder::on(root)
            .caption(
                style.title("Precursor length against load"),
                style.title_font(),
            )
            .margin(style.px(14.0))
            .x_label_area_size(style.px(48.0))
            .y_label_area_size(style.px(72.0))
            .build_cartesian_2d(x0..x1, 0.0..y1)?;
        chart
            .configure_mesh()
            .light_line_style(RGBColor(240, 240, 240))
            .bold_line_style(RGBColor(220, 220, 220))
            .x_desc("F/F_N when the precursor began")
            .y_desc("rupture length (mm)")
            .x_label_formatter(&|v| tick(*v, x1 - x0))
            .y_label_formatter(&|v| tick(*v, y1))
            .label_style(style.tick_font())
            .axis_desc_style(style.label_font())
            .draw()?;
        let edge = RGBColor(120, 120, 120);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x0, length), (x1, length)],
                style.px(6.0),
                style.px(4.0),
                edge.stroke_width(1),
            ))?
            .label(format!("interface length {length:.1} mm"))
            .legend(legend_line(edge, style));
        let r = style.px(4.0) as i32;
        let (trailing, elsewhere): (Vec<&Precursor>, Vec<&Precursor>) = self
            .sequence
            .precursors
            .iter()
            .partition(|p| p.at_trailing_edge(self.spacing));
        if !trailing.is_empty() {
            chart
                .draw_series(
                    trailing
                        .iter()
                        .map(|p| Circle::new((p.drive_ratio, p.length * 1e3), r, BLACK.filled())),
                )?
                .label("precursor from the trailing edge")
                .legend(move |(x, y)| Circle::new((x + 9, y), r, BLACK.filled()));
        }
        if !elsewhere.is_empty() {
            let grey = RGBColor(150, 150, 150);
            chart
                .draw_series(
                    elsewhere
                        .iter()
                        .map(|p| Circle::new((p.drive_ratio, p.length * 1e3), r, grey.filled())),
                )?
                .label("precursor starting elsewhere")
                .legend(move |(x, y)| Circle::new((x + 9, y), r, grey.filled()));
        }
        if let Some(f) = self.sequence.first_full_ratio {
            let red = RGBColor(214, 39, 40);
            chart
                .draw_series(std::iter::once(Cross::new(
                    (f, length),
                    style.px(6.0) as i32,
                    red.stroke_width(style.px(2.0)),
                )))?
                .label(format!("first full event, F/F_N = {f:.4}"))
                .legend(move |(x, y)| Cross::new((x + 9, y), 5, red.stroke_width(2)));
        }
        legend(&mut chart, style, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    }
}
