//! `slipfront plot`: the figures of one run.

use slipfront::analysis::events::{Event, InterfaceSeries, FRONT_WINDOW};
use slipfront::analysis::plot::fronts::{
    FrontSpeedPlot, FrontTipPlot, SlipVsFrontPlot, WaveSpeeds,
};
use slipfront::analysis::plot::loading::LoadingCurve;
use slipfront::analysis::plot::maps::{MapField, SpaceTimeMap};
use slipfront::analysis::plot::precursors::PrecursorPlot;
use slipfront::analysis::plot::slip::{SlipHistory, SlipProfiles};
use slipfront::analysis::plot::{write, Figure, FigureOptions};
use slipfront::analysis::precursors::PrecursorSequence;
use slipfront::io::output::reader::RunFile;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The figures `plot` draws; all of them by default.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PlotKind {
    /// Space–time map of the fraction of junctions pinned.
    Spacetime,
    /// Space–time map of τ/p.
    StressRatio,
    /// Space–time map of slip speed (log colour).
    SlipSpeed,
    /// F/F_N against time, events numbered.
    Loading,
    /// Front speed against position per event.
    FrontSpeed,
    /// Front tip against time since each event began.
    FrontTip,
    /// Precursor length against F/F_N.
    Precursors,
    /// Slip against time at chosen positions (--at).
    SlipHistory,
    /// Slip profile along x after each event.
    SlipProfiles,
    /// Slip speed against front speed, log–log, with the fitted exponent.
    SlipVsFront,
}

impl PlotKind {
    pub const ALL: [PlotKind; 10] = [
        PlotKind::Spacetime,
        PlotKind::StressRatio,
        PlotKind::SlipSpeed,
        PlotKind::Loading,
        PlotKind::FrontSpeed,
        PlotKind::FrontTip,
        PlotKind::Precursors,
        PlotKind::SlipHistory,
        PlotKind::SlipProfiles,
        PlotKind::SlipVsFront,
    ];

    /// Part of the file name.
    fn file_name(self) -> &'static str {
        match self {
            PlotKind::Spacetime => "spacetime",
            PlotKind::StressRatio => "stress_ratio",
            PlotKind::SlipSpeed => "slip_speed",
            PlotKind::Loading => "loading",
            PlotKind::FrontSpeed => "front_speed",
            PlotKind::FrontTip => "front_tip",
            PlotKind::Precursors => "precursors",
            PlotKind::SlipHistory => "slip_history",
            PlotKind::SlipProfiles => "slip_profiles",
            PlotKind::SlipVsFront => "slip_vs_front",
        }
    }

    fn needs_events(self) -> bool {
        matches!(
            self,
            PlotKind::FrontSpeed
                | PlotKind::FrontTip
                | PlotKind::Precursors
                | PlotKind::SlipProfiles
                | PlotKind::SlipVsFront
        )
    }

    /// Kinds that `--event N` also draws for event N alone.
    fn has_event_view(self) -> bool {
        matches!(
            self,
            PlotKind::Spacetime
                | PlotKind::StressRatio
                | PlotKind::SlipSpeed
                | PlotKind::FrontSpeed
        )
    }
}

pub struct PlotArgs {
    pub file: PathBuf,
    pub out_dir: Option<PathBuf>,
    /// Empty: all kinds.
    pub kinds: Vec<PlotKind>,
    pub event: Option<usize>,
    /// Positions for the slip history (mm).
    pub at: Vec<f64>,
    pub options: FigureOptions,
    pub quiet_gap: f64,
}

/// What the figures of one run are drawn from.
struct RunData {
    series: InterfaceSeries,
    events: Vec<Event>,
    time: Vec<f64>,
    ratio: Vec<f64>,
    stress_ratio: Vec<Vec<f64>>,
    slip_speed: Vec<Vec<f64>>,
    precursors: PrecursorSequence,
    mu: Option<(f64, f64)>,
    waves: Option<WaveSpeeds>,
    label: String,
}

impl RunData {
    fn read(path: &Path, quiet_gap: f64) -> anyhow::Result<RunData> {
        let run = RunFile::read(path)?;
        anyhow::ensure!(
            !run.interface.is_empty(),
            "{}: no /interface messages, nothing to plot (the run recorded none: a run \
             stopped before driving, time.end = 0, or output.interface_interval off)",
            path.display()
        );
        let series = run.interface_series();
        let events = series.events_separated_by(quiet_gap);
        let precursors = PrecursorSequence::from_events(&events, series.spacing, |e| {
            run.drive_ratio_at(e.start)
        });
        let scenario = run
            .scenario
            .as_deref()
            .and_then(|t| slipfront::Scenario::parse(t, "run", &[]).ok());
        let model = scenario
            .as_ref()
            .and_then(|s| slipfront::model::Model::from_scenario(s, true).ok());
        let name = run
            .metadata
            .get("scenario")
            .map(|s| format!(" ({s})"))
            .unwrap_or_default();
        let file = path.file_name().map_or_else(
            || path.display().to_string(),
            |f| f.to_string_lossy().into(),
        );
        Ok(RunData {
            events,
            precursors,
            time: run.global.iter().map(|m| m.time).collect(),
            ratio: run.global.iter().map(|m| m.drive_ratio).collect(),
            stress_ratio: run
                .interface
                .iter()
                .map(|m| {
                    m.shear_stress
                        .iter()
                        .zip(&m.normal_stress)
                        .map(|(t, p)| t / p)
                        .collect()
                })
                .collect(),
            slip_speed: series
                .slip_speed
                .iter()
                .map(|row| row.iter().map(|v| v.abs()).collect())
                .collect(),
            mu: scenario.as_ref().map(|s| {
                (
                    s.friction.dynamic_coefficient,
                    s.friction.static_coefficient,
                )
            }),
            waves: model.map(|m| WaveSpeeds {
                shear: m.shear_wave_speed(),
                rayleigh: m.rayleigh_wave_speed(),
                pressure: m.pressure_wave_speed(),
            }),
            label: super::printable(&format!("{file}{name}")),
            series,
        })
    }

    fn map(
        &self,
        kind: PlotKind,
        window: Option<(f64, f64)>,
        subtitle: String,
    ) -> SpaceTimeMap<'_> {
        let (field, values) = match kind {
            PlotKind::StressRatio => {
                let (mu_d, mu_s) = self.mu.unwrap_or((0.4, 0.6));
                (MapField::StressRatio { mu_d, mu_s }, &self.stress_ratio)
            }
            PlotKind::SlipSpeed => (MapField::SlipSpeed, &self.slip_speed),
            _ => (MapField::Pinned, &self.series.pinned),
        };
        SpaceTimeMap {
            field,
            time: &self.series.time,
            values,
            spacing: self.series.spacing,
            window,
            // The tips only on event views: on a whole run they hide the map.
            tips: if window.is_some() {
                self.events
                    .iter()
                    .map(|e| self.series.front_tip(e))
                    .collect()
            } else {
                Vec::new()
            },
            subtitle,
        }
    }

    /// Event `n` with a margin of 5 % of its duration (at least two samples)
    /// on either side.
    fn event_window(&self, n: usize) -> (f64, f64) {
        let e = &self.events[n];
        let t = &self.series.time;
        let before = t[e.first.saturating_sub(2)];
        let after = t[(e.last + 2).min(t.len() - 1)];
        let margin = 0.05 * (e.end - e.start);
        ((e.start - margin).min(before), (e.end + margin).max(after))
    }
}

pub fn plot(args: PlotArgs) -> anyhow::Result<ExitCode> {
    args.options.validate()?;
    let data = RunData::read(&args.file, args.quiet_gap)?;
    let dir = args.out_dir.clone().unwrap_or_else(|| {
        args.file
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default()
    });
    std::fs::create_dir_all(&dir)
        .map_err(|e| anyhow::anyhow!("cannot create the folder `{}`: {e}", dir.display()))?;
    let stem = args
        .file
        .file_stem()
        .map_or("run".into(), |s| s.to_string_lossy().into_owned());
    if let Some(n) = args.event.filter(|&n| n >= data.events.len()) {
        anyhow::bail!(
            "--event {n}: the run has {} events{}",
            data.events.len(),
            if data.events.is_empty() {
                String::new()
            } else {
                format!(" (0 to {})", data.events.len() - 1)
            }
        );
    }
    let blocks = if args.at.is_empty() {
        SlipHistory::spread(data.series.nx(), 5)
    } else {
        let metres: Vec<f64> = args.at.iter().map(|mm| mm * 1e-3).collect();
        SlipHistory::blocks_at(&data.series, &metres)?
    };
    let explicit = !args.kinds.is_empty();
    let kinds = if explicit {
        args.kinds.clone()
    } else {
        PlotKind::ALL.to_vec()
    };
    let ext = args.options.format.extension();
    let failed = std::cell::RefCell::new(Vec::new());
    let draw = |name: String, figure: &dyn Fn(&Path) -> anyhow::Result<PathBuf>| {
        let file = dir.join(format!("{stem}_{name}.{ext}"));
        match figure(&file) {
            Ok(p) => println!("{}", p.display()),
            Err(e) => {
                eprintln!("{name}: not drawn: {e:#}");
                failed.borrow_mut().push(name);
            }
        }
    };
    let opts = &args.options;
    let label = data.label.as_str();
    fn out(
        fig: &impl Figure,
        file: &Path,
        opts: &FigureOptions,
        label: &str,
    ) -> anyhow::Result<PathBuf> {
        write(fig, file, opts, label)
    }
    for &kind in &kinds {
        let name = kind.file_name().to_string();
        if kind.needs_events() && data.events.is_empty() {
            let why = format!(
                "{}: not drawn: the run has no events (no block fell below half its junctions \
                 pinned; see `slipfront info`)",
                name
            );
            if explicit {
                eprintln!("{why}");
                failed.borrow_mut().push(name);
            } else {
                eprintln!("note: {why}");
            }
            continue;
        }
        match kind {
            PlotKind::Spacetime | PlotKind::StressRatio | PlotKind::SlipSpeed => {
                draw(name, &|f| {
                    out(&data.map(kind, None, String::new()), f, opts, label)
                });
            }
            PlotKind::Loading => draw(name, &|f| {
                out(
                    &LoadingCurve {
                        time: &data.time,
                        ratio: &data.ratio,
                        events: &data.events,
                    },
                    f,
                    opts,
                    label,
                )
            }),
            PlotKind::FrontSpeed => draw(name, &|f| {
                out(
                    &FrontSpeedPlot {
                        series: &data.series,
                        events: &data.events,
                        only: None,
                        waves: data.waves,
                        window: FRONT_WINDOW,
                    },
                    f,
                    opts,
                    label,
                )
            }),
            PlotKind::FrontTip => draw(name, &|f| {
                out(
                    &FrontTipPlot {
                        series: &data.series,
                        events: &data.events,
                        window: FRONT_WINDOW,
                    },
                    f,
                    opts,
                    label,
                )
            }),
            PlotKind::Precursors => draw(name, &|f| {
                out(
                    &PrecursorPlot {
                        sequence: &data.precursors,
                        length: (data.series.nx().max(2) - 1) as f64 * data.series.spacing,
                        spacing: data.series.spacing,
                    },
                    f,
                    opts,
                    label,
                )
            }),
            PlotKind::SlipHistory => draw(name, &|f| {
                out(
                    &SlipHistory {
                        series: &data.series,
                        blocks: blocks.clone(),
                    },
                    f,
                    opts,
                    label,
                )
            }),
            PlotKind::SlipProfiles => draw(name, &|f| {
                out(
                    &SlipProfiles {
                        series: &data.series,
                        events: &data.events,
                    },
                    f,
                    opts,
                    label,
                )
            }),
            PlotKind::SlipVsFront => draw(name, &|f| {
                out(
                    &SlipVsFrontPlot {
                        pairs: data.series.slip_front_pairs(&data.events, FRONT_WINDOW),
                    },
                    f,
                    opts,
                    label,
                )
            }),
        }
        if let Some(n) = args.event.filter(|_| kind.has_event_view()) {
            let name = format!("event{n}_{}", kind.file_name());
            if kind == PlotKind::FrontSpeed {
                draw(name, &|f| {
                    out(
                        &FrontSpeedPlot {
                            series: &data.series,
                            events: &data.events,
                            only: Some(n),
                            waves: data.waves,
                            window: FRONT_WINDOW,
                        },
                        f,
                        opts,
                        label,
                    )
                });
            } else {
                let window = data.event_window(n);
                let kind_of = if data.events[n].full {
                    "full"
                } else {
                    "partial"
                };
                draw(name, &|f| {
                    out(
                        &data.map(kind, Some(window), format!("event {n} ({kind_of})")),
                        f,
                        opts,
                        label,
                    )
                });
            }
        }
    }
    let failed = failed.into_inner();
    if failed.is_empty() {
        Ok(ExitCode::SUCCESS)
    } else {
        eprintln!("not drawn: {}", failed.join(", "));
        Ok(ExitCode::FAILURE)
    }
}
