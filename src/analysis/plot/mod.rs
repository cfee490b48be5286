//! Figures of a run, on plotters (PNG or SVG, font embedded): space–time
//! maps, the loading curve, fronts, slip and precursors; and the figures of
//! tables (sweeps, the work–precision benchmark). Each figure is a struct
//! holding its data that implements [`Figure`]; [`write`] renders it.

pub mod colour;
pub mod ecdf;
mod figure;
pub mod fronts;
pub mod loading;
pub mod maps;
pub mod precursors;
pub mod scatter;
pub mod slip;

pub use figure::{
    decimate, extent, log_tick, render, tick, write, Drawn, Figure, FigureOptions, Format, Style,
    DPI_RANGE, SIZE_RANGE,
};

#[cfg(test)]
mod tests {
    use super::fronts::{FrontSpeedPlot, FrontTipPlot, SlipVsFrontPlot, WaveSpeeds};
    use super::loading::LoadingCurve;
    use super::maps::{MapField, SpaceTimeMap};
    use super::precursors::PrecursorPlot;
    use super::scatter::{Scatter, WorkPoint, WorkPrecision};
    use super::slip::{SlipHistory, SlipProfiles};
    use super::*;
    use crate::analysis::events::InterfaceSeries;
    use crate::analysis::precursors::PrecursorSequence;

    /// 40 blocks, 400 samples: a front leaves the trailing edge at sample
    /// 50 and crosses one block per 10 samples; broken blocks slip at
    /// 1 mm/s.
    fn front() -> InterfaceSeries {
        let (nx, n, dt) = (40usize, 400usize, 1e-6);
        let mut s = InterfaceSeries {
            spacing: 1e-3,
            ..Default::default()
        };
        for k in 0..n {
            s.time.push(k as f64 * dt);
            let broken = |ix: usize| k >= 50 + 10 * ix;
            s.pinned.push(
                (0..nx)
                    .map(|ix| if broken(ix) { 0.0 } else { 1.0 })
                    .collect(),
            );
            s.slip.push(
                (0..nx)
                    .map(|ix| {
                        let since = k as f64 - (50 + 10 * ix) as f64;
                        1e-3 * dt * since.max(0.0)
                    })
                    .collect(),
            );
            s.slip_speed.push(
                (0..nx)
                    .map(|ix| if broken(ix) { 1e-3 } else { 0.0 })
                    .collect(),
            );
        }
        s
    }

    fn is_png(bytes: &[u8], (w, h): (u32, u32)) {
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let reader = decoder.read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (w, h));
    }

    /// Every figure renders as PNG (at its size) and SVG (with its axis
    /// label text) from synthetic data.
    #[test]
    fn every_figure_renders_in_both_formats() {
        let s = front();
        let events = s.events_separated_by(1e-3);
        assert_eq!(events.len(), 1);
        let time: Vec<f64> = s.time.clone();
        let ratio: Vec<f64> = time.iter().map(|t| 0.1 + 100.0 * t).collect();
        let seq = PrecursorSequence::from_events(&events, s.spacing, |_| 0.12);
        let pairs = s.slip_front_pairs(&events, 3);
        let groups = vec!["a".to_string(), "b".to_string()];
        let points = [(1.0, 2.0, 0), (2.0, 3.0, 1), (3.0, 5.0, 0)];
        let work = [
            WorkPoint {
                observable: "a".into(),
                engine: "cpu f64".into(),
                fraction: 0.02,
                seconds: 1.0,
                error: 1e-3,
            },
            WorkPoint {
                observable: "a".into(),
                engine: "cpu f64".into(),
                fraction: 0.01,
                seconds: 2.0,
                error: 2.5e-4,
            },
        ];
        let map = |field| SpaceTimeMap {
            field,
            time: &s.time,
            values: match field {
                MapField::SlipSpeed => &s.slip_speed,
                _ => &s.pinned,
            },
            spacing: s.spacing,
            window: None,
            tips: vec![s.front_tip(&events[0])],
            subtitle: String::new(),
        };
        let options = |format| FigureOptions {
            format,
            width: 500,
            height: 300,
            dpi: 100,
        };
        macro_rules! both {
            ($fig:expr, $label:expr) => {{
                let fig = $fig;
                is_png(
                    &render(&fig, &options(Format::Png), "test").unwrap(),
                    (500, 300),
                );
                let svg = String::from_utf8(render(&fig, &options(Format::Svg), "test").unwrap())
                    .unwrap();
                assert!(
                    svg.contains($label),
                    "{} lacks {:?}",
                    stringify!($fig),
                    $label
                );
            }};
        }
        both!(map(MapField::Pinned), "time t (ms)");
        both!(
            map(MapField::StressRatio {
                mu_d: 0.4,
                mu_s: 0.6
            }),
            "τ/p"
        );
        both!(map(MapField::SlipSpeed), "slip speed (m/s)");
        both!(
            LoadingCurve {
                time: &time,
                ratio: &ratio,
                events: &events
            },
            "F/F_N"
        );
        both!(
            FrontSpeedPlot {
                series: &s,
                events: &events,
                only: None,
                waves: Some(WaveSpeeds {
                    shear: 1000.0,
                    rayleigh: 920.0,
                    pressure: 1700.0
                }),
                window: 3
            },
            "c_R = 920 m/s"
        );
        both!(
            FrontTipPlot {
                series: &s,
                events: &events,
                window: 3
            },
            "front tip x_tip (mm)"
        );
        both!(
            PrecursorPlot {
                sequence: &seq,
                length: 0.039,
                spacing: s.spacing
            },
            "rupture length (mm)"
        );
        both!(
            SlipHistory {
                series: &s,
                blocks: SlipHistory::spread(40, 5)
            },
            "x = 39.0 mm"
        );
        both!(
            SlipProfiles {
                series: &s,
                events: &events
            },
            "event number"
        );
        both!(SlipVsFrontPlot { pairs }, "fit v_slip");
        both!(
            Scatter {
                points: &points,
                groups: &groups,
                group_label: "law",
                x_label: "prestress",
                y_label: "speed",
                log_y: true,
                title: "t",
                connect: false,
            },
            "law = b"
        );
        both!(WorkPrecision { points: &work }, "run time (s)");
    }

    #[test]
    fn the_front_speed_axis_holds_the_data_and_marks_what_it_cannot_resolve() {
        let s = front();
        let events = s.events_separated_by(1e-3);
        let plot = FrontSpeedPlot {
            series: &s,
            events: &events,
            only: None,
            waves: None,
            window: 3,
        };
        // One block per 10 µs: 100 m/s everywhere, resolved.
        let points = plot.points();
        assert!(points
            .iter()
            .all(|p| (p.speed - 100.0).abs() < 1e-6 && !p.lower_bound));
        // Resolution: 3 blocks in one 1 µs sample = 3000 m/s.
        assert!((plot.resolution_limit().unwrap() - 3000.0).abs() < 1e-6);
        let (lo, hi) = plot.speed_range(&points);
        assert!(lo <= 100.0 && hi >= 3000.0 && lo >= 0.1, "{lo} .. {hi}");
        // Negative control: a front crossing several blocks per sample is
        // a lower bound, not a speed.
        let mut fast = front();
        for (k, row) in fast.pinned.iter_mut().enumerate() {
            for (ix, p) in row.iter_mut().enumerate() {
                *p = if k >= 50 + ix / 4 { 0.0 } else { 1.0 };
            }
        }
        let events = fast.events_separated_by(1e-3);
        let plot = FrontSpeedPlot {
            series: &fast,
            events: &events,
            only: None,
            waves: None,
            window: 3,
        };
        assert!(plot.points().iter().any(|p| p.lower_bound));
    }

    #[test]
    fn a_figure_with_nothing_to_draw_writes_no_file() {
        let dir = std::env::temp_dir().join(format!("slipfront-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("empty.png");
        let empty = SlipVsFrontPlot { pairs: Vec::new() };
        let err = write(&empty, &path, &FigureOptions::default(), "t").unwrap_err();
        assert!(err.to_string().contains("no crossing"), "{err}");
        assert!(!path.exists());
        assert!(!dir.join("empty.png.partial").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
