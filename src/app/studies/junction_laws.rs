//! Publication 2's questions on one block: the steady-state friction μ(v)
//! of three junction laws (weakening, strengthening, non-monotonic),
//! simulated against the renewal formula, and the static threshold of the
//! next loading against the deceleration of the previous stop.

use crate::engines::single_block::law::{JunctionLaw, SlipForce};
use crate::engines::single_block::{
    next_static_threshold, simulated_steady_friction, SingleBlockScene,
};
use rayon::prelude::*;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// A named law of the study.
#[derive(Debug, Clone, Copy)]
pub struct NamedLaw {
    pub name: &'static str,
    pub law: JunctionLaw,
}

/// The three shapes from the scenario's law: the slipping force and drag
/// changed, threshold, stiffness and slip times kept.
pub fn laws(base: &JunctionLaw) -> Vec<NamedLaw> {
    let with = |slip_force: SlipForce, drag: f64| JunctionLaw {
        slip_force,
        drag,
        ..*base
    };
    vec![
        // Mean slipping force below μs/2: weakening.
        NamedLaw {
            name: "weakening (relaxing 0.4 → 0.05 in 0.2 ms)",
            law: with(
                SlipForce::Relaxing {
                    from: 0.4,
                    to: 0.05,
                    time: 2e-4,
                },
                0.0,
            ),
        },
        // Mean slipping force above μs/2: strengthening.
        NamedLaw {
            name: "strengthening (ramp 0.2 → 0.35 in 1 ms)",
            law: with(
                SlipForce::Ramp {
                    from: 0.2,
                    to: 0.35,
                    time: 1e-3,
                },
                0.0,
            ),
        },
        // Weakening at low speed, strengthening once the drag dominates.
        NamedLaw {
            name: "non-monotonic (constant 0.1, drag 2 per m/s)",
            law: with(SlipForce::Constant { level: 0.1 }, 2.0),
        },
    ]
}

/// Speeds of the μ(v) curves (m/s): 1e-6 .. 1e-1, 4 per decade.
pub fn speeds(per_decade: usize) -> Vec<f64> {
    let n = 5 * per_decade;
    (0..=n)
        .map(|i| 10f64.powf(-6.0 + 5.0 * i as f64 / n as f64))
        .collect()
}

/// One simulated point of a μ(v) curve.
#[derive(Debug, Clone, Copy)]
pub struct FrictionPoint {
    pub law: usize,
    pub speed: f64,
    pub analytic: f64,
    pub simulated: f64,
}

impl FrictionPoint {
    pub fn relative_error(&self) -> f64 {
        (self.simulated - self.analytic).abs() / self.analytic
    }
}

/// μ(v) of every law at every speed, simulated with `count` junctions
/// over `cycles` cycles.
pub fn friction_curves(
    laws: &[NamedLaw],
    speeds: &[f64],
    count: usize,
    cycles: f64,
) -> Vec<FrictionPoint> {
    let jobs: Vec<(usize, f64)> = (0..laws.len())
        .flat_map(|l| speeds.iter().map(move |&v| (l, v)))
        .collect();
    jobs.par_iter()
        .map(|&(l, v)| FrictionPoint {
            law: l,
            speed: v,
            analytic: laws[l].law.steady_friction(v),
            simulated: simulated_steady_friction(&laws[l].law, v, count, cycles, 11 + l as u32),
        })
        .collect()
}

/// Static threshold of the next loading against the deceleration of the
/// stop (m/s²), for the scenario's law at its speed.
pub fn threshold_vs_deceleration(
    scene: &SingleBlockScene,
    decelerations: &[f64],
) -> Vec<(f64, f64)> {
    let crate::engines::single_block::MotionSpec::Prescribed {
        speed,
        reload_speed,
        ..
    } = scene.motion
    else {
        return Vec::new();
    };
    decelerations
        .par_iter()
        .map(|&a| {
            (
                a,
                next_static_threshold(
                    &scene.law,
                    scene.junctions as usize,
                    scene.seed,
                    speed,
                    a,
                    reload_speed,
                ),
            )
        })
        .collect()
}

/// CSV of the μ(v) points.
pub fn friction_csv(laws: &[NamedLaw], points: &[FrictionPoint]) -> String {
    let mut out = String::from("law,speed_m_per_s,mu_analytic,mu_simulated,relative_error\n");
    for p in points {
        let _ = writeln!(
            out,
            "\"{}\",{:.4e},{:.6},{:.6},{:.2e}",
            laws[p.law].name,
            p.speed,
            p.analytic,
            p.simulated,
            p.relative_error()
        );
    }
    out
}

/// Figures: μ(v) (analytic curves, simulated points) and the threshold
/// against the deceleration.
pub fn write_figures(
    laws: &[NamedLaw],
    points: &[FrictionPoint],
    thresholds: &[(f64, f64)],
    dir: &Path,
) -> anyhow::Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    // Log10 speed on x: the scatter figure has a linear x axis.
    let mut groups: Vec<String> = Vec::new();
    let mut pts = Vec::new();
    for (l, law) in laws.iter().enumerate() {
        groups.push(format!("{} analytic", law.name));
        let g = groups.len() - 1;
        for k in 0..=100 {
            let v = 10f64.powf(-6.0 + 5.0 * k as f64 / 100.0);
            pts.push((v.log10(), law.law.steady_friction(v), g));
        }
        groups.push(format!("{} simulated", law.name));
        let g = groups.len() - 1;
        pts.extend(
            points
                .iter()
                .filter(|p| p.law == l)
                .map(|p| (p.speed.log10(), p.simulated, g)),
        );
    }
    let path = dir.join("thogersen2014_friction_vs_speed.png");
    crate::analysis::plot::write(
        &crate::analysis::plot::scatter::Scatter {
            points: &pts,
            groups: &groups,
            group_label: "law",
            x_label: "log10 sliding speed v (m/s)",
            y_label: "steady friction coefficient μ(v)",
            log_y: false,
            title: "Steady-state friction of one block, three junction laws",
            connect: true,
        },
        &path,
        &crate::analysis::plot::FigureOptions::default(),
        "slipfront study single-block",
    )?;
    written.push(path);
    if !thresholds.is_empty() {
        let pts: Vec<(f64, f64, usize)> =
            thresholds.iter().map(|&(a, m)| (a.log10(), m, 0)).collect();
        let path = dir.join("thogersen2014_threshold_vs_deceleration.png");
        crate::analysis::plot::write(
            &crate::analysis::plot::scatter::Scatter {
                points: &pts,
                groups: &[String::new()],
                group_label: "",
                x_label: "log10 deceleration of the previous stop (m/s²)",
                y_label: "static friction coefficient of the next loading",
                log_y: false,
                title: "Static threshold after a stop, scenario law",
                connect: true,
            },
            &path,
            &crate::analysis::plot::FigureOptions::default(),
            "slipfront study single-block",
        )?;
        written.push(path);
    }
    Ok(written)
}

/// The study's notes.
pub fn report(
    laws: &[NamedLaw],
    points: &[FrictionPoint],
    thresholds: &[(f64, f64)],
    scene: &SingleBlockScene,
    how: &str,
) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# One block, many junctions: steady friction and the next static threshold (Publication 2)\n\n\
         Regenerate: `{how}`. Scene: `scenarios/thogersen2014_single_block.toml` (threshold μs = {}, \
         break stretch {:e} m, slip times {:?}); model and choices in `docs/model.md` (\"Single \
         block\"). Tables: `thogersen2014_friction_vs_speed.csv`, `thogersen2014_threshold_vs_deceleration.csv`.\n",
        scene.law.threshold, scene.law.break_stretch, scene.law.slip_time
    );
    let _ = writeln!(
        md,
        "**μ(v)**: each junction repeats pinned (from zero stretch to the threshold, t_a = s_b/v, \
         mean force μs/2) then slipping (force f(τ) for a drawn time t_R); by the renewal theorem \
         μ(v) = (μs/2·t_a + E[∫₀^t_R f] + drag·v·E[t_R]) / (t_a + E[t_R]) exactly, with the \
         expectation by quadrature over the slip-time distribution. Simulated: {} junctions started \
         in their steady cycle, prescribed constant speed, time step 1/500 of a cycle, averaged over \
         the cycles after three.\n",
        scene.junctions
    );
    let _ = writeln!(
        md,
        "| law | speeds | largest |μ_sim − μ_analytic|/μ | shape of μ(v) |\n|---|---|---|---|"
    );
    for (l, law) in laws.iter().enumerate() {
        let mine: Vec<&FrictionPoint> = points.iter().filter(|p| p.law == l).collect();
        let worst = mine.iter().map(|p| p.relative_error()).fold(0.0, f64::max);
        let _ = writeln!(
            md,
            "| {} | {} | {:.2} % | {} |",
            law.name,
            mine.len(),
            100.0 * worst,
            shape(&mine.iter().map(|p| p.analytic).collect::<Vec<_>>())
        );
    }
    let _ = writeln!(
        md,
        "\nWithout drag, μ(v) = (A·t_a + B)/(t_a + C) with t_a = s_b/v and A, B, C fixed by \
         the law: a Möbius map of t_a, so monotonic whatever the slipping force f(τ) and the \
         slip times. A slipping force that relaxes or ramps in time gives weakening or \
         strengthening, never both (the first two rows); the non-monotonic row needs its drag, a \
         force set by the speed. A non-monotonic μ(v) from time dependence alone would need it \
         in the pinned state too (junctions that age), which this law family does not have."
    );
    if !thresholds.is_empty() {
        let _ = writeln!(
            md,
            "\n**Static threshold of the next loading** (scenario law; slide at the scenario's speed, \
             stop at deceleration a, hold until every junction re-pinned, reload at the scenario's \
             reload speed; the peak friction):\n\n| deceleration (m/s²) | stop time (s) | μ_s next |\n|---|---|---|"
        );
        let speed = match scene.motion {
            crate::engines::single_block::MotionSpec::Prescribed { speed, .. } => speed,
            _ => f64::NAN,
        };
        for (a, m) in thresholds {
            let _ = writeln!(md, "| {a:.0e} | {:.1e} | {m:.4} |", speed / a);
        }
        let first = thresholds.first().map(|t| t.1).unwrap_or(f64::NAN);
        let last = thresholds.last().map(|t| t.1).unwrap_or(f64::NAN);
        let _ = writeln!(
            md,
            "\nFrom the gentlest to the most abrupt stop the next threshold goes from {first:.4} to {last:.4} ({}).",
            if last > first {
                "the more abrupt the stop, the higher the next static threshold, as the paper reports"
            } else {
                "NOT the paper's trend"
            }
        );
    }
    md
}

/// "decreasing", "increasing" or "non-monotonic" (minimum inside).
pub fn shape(values: &[f64]) -> &'static str {
    let up = values.windows(2).all(|w| w[1] >= w[0]);
    let down = values.windows(2).all(|w| w[1] <= w[0]);
    match (up, down) {
        (true, false) => "increasing (velocity strengthening)",
        (false, true) => "decreasing (velocity weakening)",
        (true, true) => "flat",
        _ => "non-monotonic (weakening, then strengthening)",
    }
}
