//! Precursors with rigid Amontons–Coulomb friction under the normal loadings
//! of Maegawa et al. (Trømborg et al., PRL 107, 074301 (2011); thesis
//! Figures 2.11–2.12): for each loading, the precursors before the first
//! full sliding event (length against F_T/F_N) and the normal-stress
//! profile along the interface at rest after each of them.

use crate::analysis::events::{Event, DEFAULT_QUIET_GAP};
use crate::analysis::precursors::PrecursorSequence;
use crate::io::output::reader::RunFile;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The scene the loadings modify.
pub const SCENARIO_PATH: &str = "scenarios/tromborg2011_coulomb_precursors.toml";

/// One of Maegawa's loadings: F_ZA at the trailing end, F_ZB at the
/// leading end (N).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Loading {
    pub trailing: f64,
    pub leading: f64,
}

impl Loading {
    pub const MAEGAWA: [Loading; 3] = [
        Loading {
            trailing: 200.0,
            leading: 200.0,
        },
        Loading {
            trailing: 300.0,
            leading: 100.0,
        },
        Loading {
            trailing: 100.0,
            leading: 300.0,
        },
    ];

    pub fn label(&self) -> String {
        format!("{}/{} N", self.trailing, self.leading)
    }

    /// The scenario overrides of this loading (total and profile).
    pub fn overrides(&self) -> Vec<String> {
        vec![
            format!("loading.normal.force={}", self.trailing + self.leading),
            format!(
                "loading.normal.trailing_to_leading={}",
                self.trailing / self.leading
            ),
        ]
    }

    pub fn file_stem(&self) -> String {
        format!("load_{}_{}", self.trailing, self.leading)
    }
}

/// A normal-stress profile along the interface at rest (Pa per block),
/// with what it follows.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    pub label: String,
    pub time: f64,
    pub normal_stress: Vec<f64>,
}

/// What one run gives.
#[derive(Debug, Clone)]
pub struct LoadingResult {
    pub loading: Loading,
    pub spacing: f64,
    pub sequence: PrecursorSequence,
    pub events: Vec<Event>,
    /// Before the first event, after each precursor, after the first full
    /// event.
    pub profiles: Vec<Profile>,
}

/// Reads a run of one loading and extracts its precursors and profiles.
pub fn analyse(loading: Loading, run_path: &Path) -> anyhow::Result<LoadingResult> {
    let run = RunFile::read(run_path)?;
    let series = run.interface_series();
    let events = series.events_separated_by(DEFAULT_QUIET_GAP);
    let sequence =
        PrecursorSequence::from_events(&events, series.spacing, |e| run.drive_ratio_at(e.start));
    let first_full = events.iter().position(|e| e.full);
    // At rest: the last interface sample before the next event starts (or
    // before the end of the run).
    let at_rest_before = |t: f64| {
        run.interface
            .iter()
            .rev()
            .find(|m| m.time < t && m.step > 0)
            .filter(|m| !m.normal_stress.is_empty())
    };
    let mut profiles = Vec::new();
    if let Some(first) = events.first() {
        if let Some(m) = at_rest_before(first.start) {
            profiles.push(Profile {
                label: "before the first event".into(),
                time: m.time,
                normal_stress: m.normal_stress.clone(),
            });
        }
    }
    let last = first_full.map_or(events.len(), |k| (k + 1).min(events.len()));
    for (k, e) in events[..last].iter().enumerate() {
        let next = events.get(k + 1).map_or(f64::INFINITY, |n| n.start);
        if let Some(m) = at_rest_before(next).filter(|m| m.time > e.end) {
            let what = if e.full {
                format!(
                    "after the full event at F/F_N {:.3}",
                    run.drive_ratio_at(e.start)
                )
            } else {
                format!(
                    "after precursor {} ({:.1} mm)",
                    k + 1,
                    1e3 * e.rupture_length
                )
            };
            profiles.push(Profile {
                label: what,
                time: m.time,
                normal_stress: m.normal_stress.clone(),
            });
        }
    }
    Ok(LoadingResult {
        loading,
        spacing: series.spacing,
        sequence,
        events,
        profiles,
    })
}

/// CSV of the precursors: one row per event before (and including) the
/// first full event.
pub fn csv(results: &[LoadingResult]) -> String {
    let mut out =
        String::from("trailing_load_n,leading_load_n,event,full,drive_ratio,length_mm,origin_mm\n");
    for r in results {
        let mut rows: Vec<(bool, f64, f64, f64)> = r
            .sequence
            .precursors
            .iter()
            .map(|p| (false, p.drive_ratio, p.length, p.origin))
            .collect();
        if let (Some(ratio), Some(e)) = (
            r.sequence.first_full_ratio,
            r.events.iter().find(|e| e.full),
        ) {
            rows.push((true, ratio, e.rupture_length, e.origin(r.spacing)));
        }
        for (k, (full, ratio, length, origin)) in rows.iter().enumerate() {
            let _ = writeln!(
                out,
                "{},{},{},{},{:.5},{:.2},{:.2}",
                r.loading.trailing,
                r.loading.leading,
                k + 1,
                full,
                ratio,
                1e3 * length,
                1e3 * origin
            );
        }
    }
    out
}

/// Figures: precursor length against F_T/F_N for every loading, and the
/// normal-stress profiles of each loading.
pub fn write_figures(
    results: &[LoadingResult],
    dir: &Path,
    mean_stress: impl Fn(&Loading) -> f64,
) -> anyhow::Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    let groups: Vec<String> = results.iter().map(|r| r.loading.label()).collect();
    let points: Vec<(f64, f64, usize)> = results
        .iter()
        .enumerate()
        .flat_map(|(g, r)| {
            r.sequence
                .extended(r.spacing)
                .into_iter()
                .map(move |p| (p.drive_ratio, 1e3 * p.length, g))
        })
        .collect();
    if !points.is_empty() {
        let path = dir.join("tromborg2011_coulomb_precursors.png");
        crate::analysis::plot::write(
            &crate::analysis::plot::scatter::Scatter {
                points: &points,
                groups: &groups,
                group_label: "F_ZA/F_ZB",
                x_label: "driving force F_T / F_N at the precursor",
                y_label: "precursor length (mm)",
                log_y: false,
                title: "Coulomb precursors, 100 mm slider, Maegawa loadings",
                connect: true,
            },
            &path,
            &crate::analysis::plot::FigureOptions::default(),
            "slipfront study coulomb-precursors",
        )?;
        written.push(path);
    }
    for r in results {
        let mean = mean_stress(&r.loading);
        let labels: Vec<String> = r.profiles.iter().map(|p| p.label.clone()).collect();
        let points: Vec<(f64, f64, usize)> = r
            .profiles
            .iter()
            .enumerate()
            .flat_map(|(g, p)| {
                p.normal_stress
                    .iter()
                    .enumerate()
                    .map(move |(ix, s)| (1e3 * ix as f64 * r.spacing, s / mean, g))
            })
            .collect();
        if points.is_empty() {
            continue;
        }
        let path = dir.join(format!(
            "tromborg2011_normal_stress_{}.png",
            r.loading.file_stem()
        ));
        let title = format!("Normal stress at rest, loading {}", r.loading.label());
        crate::analysis::plot::write(
            &crate::analysis::plot::scatter::Scatter {
                points: &points,
                groups: &labels,
                group_label: "profile",
                x_label: "x from the trailing edge (mm)",
                y_label: "normal stress p / (F_N / (L B))",
                log_y: false,
                title: &title,
                connect: true,
            },
            &path,
            &crate::analysis::plot::FigureOptions::default(),
            "slipfront study coulomb-precursors",
        )?;
        written.push(path);
    }
    Ok(written)
}

/// The study's notes.
pub fn report(
    results: &[LoadingResult],
    how: &str,
    mean_stress: impl Fn(&Loading) -> f64,
) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Precursors with rigid Coulomb friction under Maegawa's loadings (PRL 2011)\n\n\
         Regenerate: `{how}`. Scene: `{SCENARIO_PATH}` (100 mm × 50 mm slider, 41 × 21 blocks, \
         μs = 0.4, μd = 0.17, side spring 5 mm above the interface pulled at 0.4 mm/s), the normal \
         load F_ZA + F_ZB applied on the top row as a line load linear between the trailing \
         value and the leading one in the ratio F_ZA/F_ZB (a choice: `docs/model.md`). Table: \
         `tromborg2011_coulomb_precursors.csv`; figures: `tromborg2011_coulomb_precursors.png` \
         (length against F_T/F_N, precursors longer than one block), \
         `tromborg2011_normal_stress_*.png` (p(x) at rest after each event, over the mean \
         F_N/(L B)).\n"
    );
    let _ = writeln!(
        md,
        "| loading F_ZA/F_ZB | precursors before the first full event | longer than one block | F_T/F_N of the first full event | lengths (mm) at F_T/F_N | rank correlation of length with load |\n|---|---|---|---|---|---|"
    );
    for r in results {
        let ext = r.sequence.extended(r.spacing);
        let lengths: Vec<String> = ext
            .iter()
            .map(|p| format!("{:.1} at {:.3}", 1e3 * p.length, p.drive_ratio))
            .collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} |",
            r.loading.label(),
            r.sequence.precursors.len(),
            ext.len(),
            r.sequence
                .first_full_ratio
                .map_or("none in the run".into(), |v| format!("{v:.3}")),
            if lengths.is_empty() {
                "—".into()
            } else {
                lengths.join(", ")
            },
            PrecursorSequence::growth(&ext).map_or("—".into(), |g| format!("{g:.2}"))
        );
    }
    let _ = writeln!(md, "\n## Normal stress at rest (p / mean) at the trailing edge, the middle and the leading edge\n");
    let _ = writeln!(
        md,
        "| loading | profile | trailing | middle | leading |\n|---|---|---|---|---|"
    );
    for r in results {
        let mean = mean_stress(&r.loading);
        for p in &r.profiles {
            let n = p.normal_stress.len();
            if n == 0 {
                continue;
            }
            let _ = writeln!(
                md,
                "| {} | {} | {:.3} | {:.3} | {:.3} |",
                r.loading.label(),
                p.label,
                p.normal_stress[0] / mean,
                p.normal_stress[n / 2] / mean,
                p.normal_stress[n - 1] / mean
            );
        }
    }
    md
}
