use slipfront::output::reader::RunFile;
use slipfront::plot::{
    front_speed_plot, front_tip_plot, loading_curve, precursor_plot, spacetime_map,
    stress_ratio_map,
};
use slipfront::precursors::PrecursorSequence;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

pub fn plot(
    path: &Path,
    out_dir: Option<PathBuf>,
    event: Option<usize>,
    quiet_gap: f64,
) -> anyhow::Result<ExitCode> {
    let run = RunFile::read(path)?;
    let dir = out_dir.unwrap_or_else(|| path.parent().map(Path::to_path_buf).unwrap_or_default());
    std::fs::create_dir_all(&dir)?;
    let stem = path
        .file_stem()
        .map_or("run".into(), |s| s.to_string_lossy().into_owned());
    let series = run.interface_series();
    let events = series.events_separated_by(quiet_gap);
    let time: Vec<f64> = run.global.iter().map(|m| m.time).collect();
    let ratio: Vec<f64> = run.global.iter().map(|m| m.drive_ratio).collect();
    let ratio_at = |t: f64| {
        let k = time
            .partition_point(|&x| x < t)
            .min(time.len().saturating_sub(1));
        ratio.get(k).copied().unwrap_or(f64::NAN)
    };
    let precursors = PrecursorSequence::from_events(&events, series.spacing, |e| ratio_at(e.start));
    if let Some(n) = event.filter(|&n| n >= events.len()) {
        anyhow::bail!(
            "--event {n}: the run has {} events{}",
            events.len(),
            if events.is_empty() {
                String::new()
            } else {
                format!(" (0 to {})", events.len() - 1)
            }
        );
    }
    let length = (series.nx().max(2) - 1) as f64 * series.spacing;
    // τ/p per block and sample; the colour scale from the scenario's μd
    // (white) to μs (red).
    let ratio_rows: Vec<Vec<f64>> = run
        .interface
        .iter()
        .map(|m| {
            m.shear_stress
                .iter()
                .zip(&m.normal_stress)
                .map(|(t, p)| t / p)
                .collect()
        })
        .collect();
    let (mu_s, mu_d) = run
        .scenario
        .as_deref()
        .and_then(|t| slipfront::Scenario::parse(t, "run", &[]).ok())
        .map_or((0.6, 0.4), |s| {
            (
                s.friction.static_coefficient,
                s.friction.dynamic_coefficient,
            )
        });
    for (name, canvas) in [
        ("spacetime", spacetime_map(&series)),
        ("stress_ratio", stress_ratio_map(&ratio_rows, mu_d, mu_s)),
        ("front_tip", front_tip_plot(&series, &events)),
        ("loading", loading_curve(&time, &ratio, &events)),
        ("front_speed", front_speed_plot(&series, &events)),
        (
            "precursors",
            precursor_plot(&precursors, length, series.spacing),
        ),
    ] {
        let file = dir.join(format!("{stem}_{name}.png"));
        canvas.save(&file)?;
        println!("{}", file.display());
    }
    if let Some(n) = event {
        let e = events.get(n).ok_or_else(|| {
            anyhow::anyhow!(
                "--event {n}: the run has {} events (0 to {})",
                events.len(),
                events.len().saturating_sub(1)
            )
        })?;
        // The event with a margin of 5% of its samples on either side.
        let margin = (e.last - e.first) / 20 + 2;
        let range = e.first.saturating_sub(margin)..(e.last + margin + 1).min(series.time.len());
        let file = dir.join(format!("{stem}_event{n}_spacetime.png"));
        spacetime_map(&series.slice(range)).save(&file)?;
        println!("{}", file.display());
    }
    Ok(ExitCode::SUCCESS)
}
