//! Rendering a figure to PNG or SVG: the size and density options, the
//! embedded font, and writing the file only once it is complete.

use anyhow::Context;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::Once;

/// The font every figure uses, embedded so that no system font is needed
/// (DejaVu Sans; licence in assets/fonts/LICENSE-DejaVu.txt).
const FONT: &[u8] = include_bytes!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/assets/fonts/DejaVuSans.ttf"
));
/// The family name the figures ask plotters for.
pub(crate) const FAMILY: &str = "sans-serif";

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        plotters::style::register_font(FAMILY, FontStyle::Normal, FONT)
            .unwrap_or_else(|_| panic!("the embedded font assets/fonts/DejaVuSans.ttf is valid"));
    });
}

/// File format of a figure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Format {
    #[default]
    Png,
    Svg,
}

impl Format {
    pub fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Svg => "svg",
        }
    }

    /// The format a file name asks for (`.svg` or `.png`).
    pub fn from_path(path: &Path) -> anyhow::Result<Format> {
        match path.extension().and_then(|e| e.to_str()) {
            Some("png") => Ok(Format::Png),
            Some("svg") => Ok(Format::Svg),
            other => anyhow::bail!(
                "{}: a figure is written as .png or .svg, not {}",
                path.display(),
                other.map_or("a file without extension".into(), |e| format!(".{e}"))
            ),
        }
    }
}

/// Size and density of a figure. `width` × `height` is the size at
/// 100 dpi; a higher `dpi` scales the pixels, fonts and lines together, so
/// that the same figure comes out sharper rather than smaller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FigureOptions {
    pub format: Format,
    pub width: u32,
    pub height: u32,
    pub dpi: u32,
}

impl Default for FigureOptions {
    fn default() -> Self {
        FigureOptions {
            format: Format::Png,
            width: 900,
            height: 600,
            dpi: 100,
        }
    }
}

/// Smallest and largest accepted sizes (pixels at 100 dpi) and densities.
pub const SIZE_RANGE: (u32, u32) = (200, 8000);
pub const DPI_RANGE: (u32, u32) = (50, 1200);

impl FigureOptions {
    pub fn validate(&self) -> anyhow::Result<()> {
        for (name, v) in [("width", self.width), ("height", self.height)] {
            anyhow::ensure!(
                (SIZE_RANGE.0..=SIZE_RANGE.1).contains(&v),
                "--size: {name} {v} px is outside {} ..= {} px",
                SIZE_RANGE.0,
                SIZE_RANGE.1
            );
        }
        anyhow::ensure!(
            (DPI_RANGE.0..=DPI_RANGE.1).contains(&self.dpi),
            "--dpi {} is outside {} ..= {}",
            self.dpi,
            DPI_RANGE.0,
            DPI_RANGE.1
        );
        let (w, h) = self.pixels();
        anyhow::ensure!(
            (w as u64) * (h as u64) <= 100_000_000,
            "--size {}x{} at --dpi {} is {w}x{h} pixels, more than 1e8",
            self.width,
            self.height,
            self.dpi
        );
        Ok(())
    }

    pub fn scale(&self) -> f64 {
        self.dpi as f64 / 100.0
    }

    /// Pixel size of the output.
    pub fn pixels(&self) -> (u32, u32) {
        let s = self.scale();
        (
            (self.width as f64 * s).round() as u32,
            (self.height as f64 * s).round() as u32,
        )
    }

    /// Parses `WxH` (pixels at 100 dpi).
    pub fn parse_size(text: &str) -> Result<(u32, u32), String> {
        let bad = || format!("size `{text}`: expected WIDTHxHEIGHT in pixels, e.g. 900x600");
        let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
        Ok((
            w.trim().parse().map_err(|_| bad())?,
            h.trim().parse().map_err(|_| bad())?,
        ))
    }
}

/// What the figures share: the scale of fonts and lines, and the name of
/// the run for titles.
#[derive(Debug, Clone)]
pub struct Style {
    pub scale: f64,
    pub run: String,
}

impl Style {
    /// A length in pixels at 100 dpi, scaled.
    pub fn px(&self, v: f64) -> u32 {
        (v * self.scale).round().max(1.0) as u32
    }

    pub fn font(&self, size: f64) -> TextStyle<'static> {
        (FAMILY, size * self.scale).into_font().into()
    }

    pub fn title_font(&self) -> TextStyle<'static> {
        self.font(17.0)
    }

    pub fn label_font(&self) -> TextStyle<'static> {
        self.font(15.0)
    }

    pub fn tick_font(&self) -> TextStyle<'static> {
        self.font(12.5)
    }

    /// "<what> — <run>", the title of a figure.
    pub fn title(&self, what: &str) -> String {
        if self.run.is_empty() {
            what.to_string()
        } else {
            format!("{what} — {}", self.run)
        }
    }
}

/// Draws the legend of `chart`'s labelled series at `position`, in the
/// figures' one style (a white, framed box).
pub fn legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    style: &Style,
    position: SeriesLabelPosition,
) -> Drawn
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    CT: plotters::coord::CoordTranslate,
{
    chart
        .configure_series_labels()
        .label_font(style.tick_font())
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(position)
        .draw()?;
    Ok(())
}

/// A figure drawn on any plotters backend.
pub trait Figure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, style: &Style) -> Drawn
    where
        DB::ErrorType: 'static;
}

/// The result of drawing.
pub type Drawn = anyhow::Result<()>;

/// Draws `figure` into memory: PNG or SVG bytes.
pub fn render(figure: &impl Figure, options: &FigureOptions, run: &str) -> anyhow::Result<Vec<u8>> {
    options.validate()?;
    register_font();
    let style = Style {
        scale: options.scale(),
        run: run.to_string(),
    };
    let (w, h) = options.pixels();
    match options.format {
        Format::Png => {
            // Drawn at SUPERSAMPLE× and averaged down: antialiased lines, and
            // the glyph placement of plotters' font rasteriser (whole
            // pixels, no side bearing) becomes sub-pixel.
            let k = SUPERSAMPLE;
            let big = Style {
                scale: style.scale * k as f64,
                ..style
            };
            let (bw, bh) = (w * k, h * k);
            let mut rgb = vec![255u8; bw as usize * bh as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, (bw, bh)).into_drawing_area();
                root.fill(&WHITE)?;
                figure.draw(&root, &big)?;
                root.present()?;
            }
            encode_png(&downsample(&rgb, bw, bh, k), w, h, options.dpi)
        }
        Format::Svg => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
                root.fill(&WHITE)?;
                figure.draw(&root, &style)?;
                root.present()?;
            }
            Ok(svg.into_bytes())
        }
    }
}

/// Linear factor of the PNG supersampling.
const SUPERSAMPLE: u32 = 2;

/// Averages k×k blocks of an RGB raster of `w`×`h` pixels.
fn downsample(rgb: &[u8], w: u32, h: u32, k: u32) -> Vec<u8> {
    let (w, h, k) = (w as usize, h as usize, k as usize);
    let (ow, oh) = (w / k, h / k);
    let mut out = vec![0u8; ow * oh * 3];
    for y in 0..oh {
        for x in 0..ow {
            for c in 0..3 {
                let mut sum = 0u32;
                for dy in 0..k {
                    for dx in 0..k {
                        sum += rgb[((y * k + dy) * w + x * k + dx) * 3 + c] as u32;
                    }
                }
                out[(y * ow + x) * 3 + c] = ((sum + (k * k / 2) as u32) / (k * k) as u32) as u8;
            }
        }
    }
    out
}

fn encode_png(rgb: &[u8], w: u32, h: u32, dpi: u32) -> anyhow::Result<Vec<u8>> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        // Physical density, so that a document places it at its size.
        let per_metre = (dpi as f64 / 0.0254).round() as u32;
        enc.set_pixel_dims(Some(png::PixelDimensions {
            xppu: per_metre,
            yppu: per_metre,
            unit: png::Unit::Meter,
        }));
        let mut w = enc.write_header()?;
        w.write_image_data(rgb)?;
    }
    Ok(out)
}

/// Draws `figure` and writes it to `path` (format from the options); the
/// file appears only once complete, so a failed figure leaves nothing.
pub fn write(
    figure: &impl Figure,
    path: &Path,
    options: &FigureOptions,
    run: &str,
) -> anyhow::Result<PathBuf> {
    let bytes = render(figure, options, run)?;
    let tmp = path.with_extension(format!("{}.partial", options.format.extension()));
    std::fs::write(&tmp, &bytes).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("renaming to {}", path.display()))?;
    Ok(path.to_path_buf())
}

/// Tick text for a value on an axis spanning `span`: enough decimals to
/// tell ticks apart, no more.
pub fn tick(v: f64, span: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    // Plotters puts up to ~10 ticks on an axis: resolve a tenth of it.
    let decimals = (-(span.abs().max(1e-300) / 10.0).log10().floor()).clamp(0.0, 9.0) as usize;
    let text = format!("{v:.decimals$}");
    if text
        .trim_start_matches('-')
        .trim_start_matches(['0', '.'])
        .is_empty()
    {
        "0".into()
    } else {
        text
    }
}

/// Tick text on a logarithmic axis: 10^k as a plain number where short.
pub fn log_tick(v: f64) -> String {
    if v <= 0.0 || !v.is_finite() {
        return String::new();
    }
    let k = v.log10();
    if (k - k.round()).abs() < 1e-6 {
        let k = k.round() as i32;
        if (-3..=4).contains(&k) {
            format!("{}", 10f64.powi(k))
        } else {
            format!("1e{k}")
        }
    } else {
        format!("{v:.2e}")
    }
}

/// A line of many more points than the figure has pixel columns, reduced to
/// what can be seen: per column, the first, lowest, highest and last point
/// in order. The drawn envelope is unchanged; an SVG stays small.
pub fn decimate(points: &[(f64, f64)], columns: usize) -> Vec<(f64, f64)> {
    if points.len() <= 4 * columns.max(1) {
        return points.to_vec();
    }
    let (x0, x1) = (points[0].0, points[points.len() - 1].0);
    let width = (x1 - x0) / columns as f64;
    let column = |x: f64| (((x - x0) / width) as usize).min(columns - 1);
    let mut out = Vec::with_capacity(4 * columns);
    let mut start = 0;
    while start < points.len() {
        let c = column(points[start].0);
        let mut end = start + 1;
        while end < points.len() && column(points[end].0) == c {
            end += 1;
        }
        let bucket = &points[start..end];
        let lo = (0..bucket.len()).min_by(|&a, &b| bucket[a].1.total_cmp(&bucket[b].1));
        let hi = (0..bucket.len()).max_by(|&a, &b| bucket[a].1.total_cmp(&bucket[b].1));
        let mut keep = vec![0, bucket.len() - 1];
        keep.extend(lo);
        keep.extend(hi);
        keep.sort_unstable();
        keep.dedup();
        out.extend(keep.into_iter().map(|k| bucket[k]));
        start = end;
    }
    out
}

/// Lower and upper end of `values` (finite ones), or None.
pub fn extent(values: impl IntoIterator<Item = f64>) -> Option<(f64, f64)> {
    values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_have_the_decimals_their_span_needs() {
        assert_eq!(tick(0.15, 0.2), "0.15");
        assert_eq!(tick(0.2, 0.25), "0.20");
        assert_eq!(tick(1500.0, 2500.0), "1500");
        assert_eq!(tick(0.5, 4.0), "0.5");
        assert_eq!(tick(-0.0000001, 1.0), "0");
        assert_eq!(log_tick(1000.0), "1000");
        assert_eq!(log_tick(1e-5), "1e-5");
    }

    #[test]
    fn decimation_keeps_the_envelope() {
        let line: Vec<(f64, f64)> = (0..10_000)
            .map(|k| (k as f64, if k == 5_003 { 7.0 } else { (k % 7) as f64 }))
            .collect();
        let d = decimate(&line, 100);
        assert!(d.len() <= 400, "{}", d.len());
        assert!(d.contains(&(5_003.0, 7.0)), "a spike survives");
        assert_eq!(d.first(), line.first());
        assert_eq!(d.last(), line.last());
        assert!(d.windows(2).all(|p| p[0].0 < p[1].0));
        assert_eq!(decimate(&line[..50], 100), line[..50].to_vec());
    }

    #[test]
    fn sizes_and_densities_are_checked() {
        assert_eq!(FigureOptions::parse_size("1200x800"), Ok((1200, 800)));
        assert!(FigureOptions::parse_size("1200").is_err());
        let mut o = FigureOptions {
            width: 100,
            ..Default::default()
        };
        assert!(o.validate().unwrap_err().to_string().contains("width 100"));
        o.width = 900;
        o.dpi = 300;
        o.validate().unwrap();
        assert_eq!(o.pixels(), (2700, 1800));
        assert!(Format::from_path(Path::new("a.pdf")).is_err());
    }
}
