//! Colour scales (a value → colour, linear or logarithmic) and the colour
//! bar that makes a map readable.

use super::figure::{log_tick, tick, Drawn, Style};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Discrete colours for groups and classes, distinguishable in print.
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
];

/// How a value is mapped to colour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Ramp {
    /// Black at `lo` to white at `hi`.
    Grey,
    /// Blue at `lo`, white at `mid`, red at `hi`.
    Diverging { mid: f64 },
    /// Viridis from `lo` to `hi`.
    Viridis,
}

/// A colour scale: a ramp over a value range, linear or logarithmic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColourScale {
    pub ramp: Ramp,
    pub lo: f64,
    pub hi: f64,
    pub log: bool,
    /// What the colour means, with its unit, for the bar.
    pub label: &'static str,
}

/// Colour of non-finite values (τ/p where p = 0).
pub const MISSING: RGBColor = RGBColor(0, 160, 0);

impl ColourScale {
    /// Position of `v` on the scale, 0 at `lo` to 1 at `hi`, clamped.
    pub fn fraction(&self, v: f64) -> f64 {
        let f = if self.log {
            let l = |x: f64| x.max(f64::MIN_POSITIVE).log10();
            (l(v) - l(self.lo)) / (l(self.hi) - l(self.lo))
        } else {
            (v - self.lo) / (self.hi - self.lo)
        };
        if f.is_finite() {
            f.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    pub fn colour(&self, v: f64) -> RGBColor {
        if !v.is_finite() {
            return MISSING;
        }
        let f = self.fraction(v);
        match self.ramp {
            Ramp::Grey => {
                let g = (255.0 * f).round() as u8;
                RGBColor(g, g, g)
            }
            Ramp::Diverging { mid } => {
                let m = self.fraction(mid);
                let fade = |x: f64| (255.0 * x.clamp(0.0, 1.0)).round() as u8;
                if f <= m {
                    let g = fade(f / m.max(1e-12));
                    RGBColor(g, g, 255)
                } else {
                    let g = fade(1.0 - (f - m) / (1.0 - m).max(1e-12));
                    RGBColor(255, g, g)
                }
            }
            Ramp::Viridis => viridis(f),
        }
    }
}

/// The viridis colour map (matplotlib's default), by linear interpolation
/// between nine of its stops.
pub fn viridis(f: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 9] = [
        (68, 1, 84),
        (71, 44, 122),
        (59, 81, 139),
        (44, 113, 142),
        (33, 144, 141),
        (39, 173, 129),
        (92, 200, 99),
        (170, 220, 50),
        (253, 231, 37),
    ];
    let x = f.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let k = (x.floor() as usize).min(STOPS.len() - 2);
    let t = x - k as f64;
    let mix = |a: u8, b: u8| (a as f64 + t * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A legend mark for a line of `colour`, thick enough to see its colour.
pub fn legend_line(
    colour: RGBColor,
    style: &Style,
) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    let (len, width) = (style.px(11.0) as i32, style.px(2.5));
    move |(x, y)| PathElement::new(vec![(x, y), (x + len, y)], colour.stroke_width(width))
}

/// Width of the strip a colour bar takes on the right of a figure (px at
/// 100 dpi).
pub const BAR_WIDTH: f64 = 110.0;

/// Draws a vertical colour bar for `scale` into `area`, aligned with a
/// plot whose drawing box spans `top..bottom` pixels of the figure.
pub fn colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    scale: &ColourScale,
    style: &Style,
    (top, bottom): (u32, u32),
) -> Drawn
where
    DB::ErrorType: 'static,
{
    let (_, height) = area.dim_in_pixel();
    let area = area.margin(
        top,
        height.saturating_sub(bottom),
        style.px(8.0),
        style.px(10.0),
    );
    let steps = 256;
    let value = |k: f64| {
        let f = k / steps as f64;
        if scale.log {
            10f64.powf(scale.lo.log10() + f * (scale.hi.log10() - scale.lo.log10()))
        } else {
            scale.lo + f * (scale.hi - scale.lo)
        }
    };
    let span = scale.hi - scale.lo;
    let mut builder = ChartBuilder::on(&area);
    builder
        .set_label_area_size(LabelAreaPosition::Right, style.px(64.0))
        .margin(0);
    if scale.log {
        let mut chart = builder.build_cartesian_2d(0.0..1.0, (scale.lo..scale.hi).log_scale())?;
        chart.draw_series((0..steps).map(|k| {
            Rectangle::new(
                [(0.0, value(k as f64)), (1.0, value(k as f64 + 1.0))],
                scale.colour(value(k as f64 + 0.5)).filled(),
            )
        }))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_labels(6)
            .y_label_formatter(&|v| log_tick(*v))
            .y_desc(scale.label)
            .label_style(style.tick_font())
            .axis_desc_style(style.label_font())
            .draw()?;
    } else {
        let mut chart = builder.build_cartesian_2d(0.0..1.0, scale.lo..scale.hi)?;
        chart.draw_series((0..steps).map(|k| {
            Rectangle::new(
                [(0.0, value(k as f64)), (1.0, value(k as f64 + 1.0))],
                scale.colour(value(k as f64 + 0.5)).filled(),
            )
        }))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_labels(6)
            .y_label_formatter(&|v| tick(*v, span))
            .y_desc(scale.label)
            .label_style(style.tick_font())
            .axis_desc_style(style.label_font())
            .draw()?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_put_their_ends_and_middle_where_they_should() {
        let grey = ColourScale {
            ramp: Ramp::Grey,
            lo: 0.0,
            hi: 1.0,
            log: false,
            label: "",
        };
        assert_eq!(grey.colour(1.0), WHITE);
        assert_eq!(grey.colour(0.0), BLACK);
        let div = ColourScale {
            ramp: Ramp::Diverging { mid: 0.4 },
            lo: 0.0,
            hi: 0.6,
            log: false,
            label: "",
        };
        assert_eq!(div.colour(0.4), WHITE);
        assert_eq!(div.colour(0.0), RGBColor(0, 0, 255));
        assert_eq!(div.colour(0.7), RGBColor(255, 0, 0));
        assert_eq!(div.colour(f64::NAN), MISSING);
        let log = ColourScale {
            ramp: Ramp::Viridis,
            lo: 1e-4,
            hi: 1.0,
            log: true,
            label: "",
        };
        assert!((log.fraction(1e-2) - 0.5).abs() < 1e-12);
        assert_eq!(log.colour(1e-9), viridis(0.0));
    }
}
