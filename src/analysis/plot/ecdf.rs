//! Two ensembles' empirical CDFs, one panel per outcome (`slipfront
//! compare -o`): where the two step curves part is what the tests saw.

use super::colour::{legend_line, PALETTE};
use super::figure::{extent, legend, tick, Drawn, Figure, Style};
use plotters::coord::Shift;
use plotters::prelude::*;

/// One outcome: both samples and the caption (its name and p-values).
pub struct EcdfPanel<'a> {
    pub caption: String,
    pub a: &'a [f64],
    pub b: &'a [f64],
}

/// Panels side by side in rows of up to three, with one legend naming the
/// two ensembles.
pub struct EcdfComparison<'a> {
    pub panels: Vec<EcdfPanel<'a>>,
    pub label_a: &'a str,
    pub label_b: &'a str,
}

/// The empirical CDF of `values` as the corners of its staircase, from 0
/// at the smallest value to 1 at the largest.
pub fn staircase(values: &[f64]) -> Vec<(f64, f64)> {
    let mut s: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    s.sort_by(f64::total_cmp);
    let n = s.len() as f64;
    let mut out = Vec::with_capacity(2 * s.len());
    for (k, &v) in s.iter().enumerate() {
        out.push((v, k as f64 / n));
        out.push((v, (k + 1) as f64 / n));
    }
    out
}

impl Figure for EcdfComparison<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static,
    {
        let panels: Vec<&EcdfPanel> = self
            .panels
            .iter()
            .filter(|p| !p.a.is_empty() || !p.b.is_empty())
            .collect();
        anyhow::ensure!(!panels.is_empty(), "no outcome has values to draw");
        let root = root.margin(style.px(6.0), 0, 0, 0);
        let root = root.titled(
            &style.title(&format!(
                "Empirical CDFs: {} against {}",
                self.label_a, self.label_b
            )),
            style.title_font(),
        )?;
        let columns = panels.len().min(3);
        let rows = panels.len().div_ceil(columns);
        let areas = root.split_evenly((rows, columns));
        for (k, (area, panel)) in areas.iter().zip(&panels).enumerate() {
            let (lo, hi) = extent(panel.a.iter().chain(panel.b).copied()).expect("values");
            // All values equal: a range around them, not a zero-width one.
            let pad = if hi > lo {
                0.05 * (hi - lo)
            } else if lo != 0.0 {
                0.05 * lo.abs()
            } else {
                1.0
            };
            let (x0, x1) = (lo - pad, hi + pad);
            let mut chart = ChartBuilder::on(area)
                .caption(&panel.caption, style.font(12.5))
                .margin(style.px(8.0))
                .margin_right(style.px(16.0))
                .x_label_area_size(style.px(36.0))
                .y_label_area_size(style.px(44.0))
                .build_cartesian_2d(x0..x1, 0.0..1.02)?;
            chart
                .configure_mesh()
                .light_line_style(RGBColor(240, 240, 240))
                .bold_line_style(RGBColor(220, 220, 220))
                .x_labels(4)
                .y_labels(5)
                .x_label_formatter(&|v| format!("{v:.2e}").replace("e0", ""))
                .y_label_formatter(&|v| tick(*v, 1.0))
                .label_style(style.font(10.5))
                .draw()?;
            for (g, (values, name)) in [(panel.a, self.label_a), (panel.b, self.label_b)]
                .into_iter()
                .enumerate()
            {
                let colour = PALETTE[g];
                // A's line wider, so that it shows where B's lies on it.
                let width = [2.6, 1.3][g];
                let mut line = staircase(values);
                // Flat at 0 and 1 beyond the sample, across the panel.
                if let (Some(&first), Some(&last)) = (line.first(), line.last()) {
                    line.insert(0, (x0, 0.0));
                    line.insert(1, (first.0, 0.0));
                    line.push((x1, last.1));
                }
                let series = chart
                    .draw_series(LineSeries::new(line, colour.stroke_width(style.px(width))))?;
                if k == 0 {
                    series.label(name).legend(legend_line(colour, style));
                }
            }
            if k == 0 {
                legend(&mut chart, style, SeriesLabelPosition::LowerRight)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_staircase_climbs_from_zero_to_one_in_value_order() {
        let s = staircase(&[3.0, 1.0, 2.0, f64::NAN]);
        assert_eq!(
            s,
            vec![
                (1.0, 0.0),
                (1.0, 1.0 / 3.0),
                (2.0, 1.0 / 3.0),
                (2.0, 2.0 / 3.0),
                (3.0, 2.0 / 3.0),
                (3.0, 1.0)
            ]
        );
        assert!(staircase(&[]).is_empty());
    }

    #[test]
    fn panels_render_with_their_captions() {
        let a = [1.0, 2.0, 3.0];
        let b = [1.5, 2.5];
        let fig = EcdfComparison {
            panels: vec![
                EcdfPanel {
                    caption: "mean_slip_m: KS p = 0.5".into(),
                    a: &a,
                    b: &b,
                },
                EcdfPanel {
                    caption: "empty".into(),
                    a: &[],
                    b: &[],
                },
            ],
            label_a: "f64",
            label_b: "f32",
        };
        let options = crate::analysis::plot::FigureOptions {
            format: crate::analysis::plot::Format::Svg,
            ..Default::default()
        };
        let svg =
            String::from_utf8(crate::analysis::plot::render(&fig, &options, "").unwrap()).unwrap();
        assert!(svg.contains("mean_slip_m: KS p = 0.5"));
        // In the title and in the legend.
        assert_eq!(svg.matches("f32").count(), 2, "{svg}");
        assert!(!svg.contains("empty"), "a panel without values is left out");
        let nothing = EcdfComparison {
            panels: Vec::new(),
            label_a: "a",
            label_b: "b",
        };
        assert!(crate::analysis::plot::render(&nothing, &options, "").is_err());
    }
}
