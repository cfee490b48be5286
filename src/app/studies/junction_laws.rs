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

/// One stick-slip event of the spring-pulled block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlipEvent {
    pub start: f64,
    pub duration: f64,
    pub peak_speed: f64,
    /// Time from the peak until the speed last exceeds a tenth of it: the
    /// fast slip. The rest of the event is the slow tail.
    pub fast: f64,
    pub slip: f64,
}

/// The spring-pulled block of the study: the scenario's law, a spring a
/// hundredth as stiff as the pinned junctions, a block period of about one
/// millisecond, pulled at 0.1 mm/s.
pub struct PulledBlock {
    pub mass: f64,
    pub stiffness: f64,
    pub speed: f64,
    pub duration: f64,
    pub dt: f64,
}

impl PulledBlock {
    pub fn study(law: &JunctionLaw) -> PulledBlock {
        PulledBlock::with_mass(law, 1e-3)
    }

    /// The study's block with another mass (kg per newton of normal load).
    pub fn with_mass(law: &JunctionLaw, mass: f64) -> PulledBlock {
        let junctions = law.threshold / law.break_stretch;
        PulledBlock {
            mass,
            stiffness: junctions / 100.0,
            speed: 1e-4,
            duration: 0.5,
            // 1/100 of the period on the pinned junctions.
            dt: 2.0 * std::f64::consts::PI * (mass / junctions).sqrt() / 100.0,
        }
    }
}

/// Runs the pulled block and splits its history into slip events (speed
/// above ten times the pulling speed); returns the events and the
/// (time, speed, friction) samples of the first complete one, padded.
pub fn slow_slip(
    law: &JunctionLaw,
    count: usize,
    seed: u32,
    p: &PulledBlock,
) -> (Vec<SlipEvent>, Vec<(f64, f64, f64)>) {
    let mut j = crate::engines::single_block::sim::Junctions::pinned(*law, count, seed);
    let mut samples: Vec<(f64, f64, f64, f64)> = Vec::new();
    crate::engines::single_block::sim::pull(
        &mut j,
        p.mass,
        p.stiffness,
        p.speed,
        p.duration,
        p.dt,
        |s| samples.push((s.time, s.velocity, s.friction, s.position)),
    );
    let moving = 10.0 * p.speed;
    let mut events = Vec::new();
    let mut first: Option<(usize, usize)> = None;
    let mut i = 0;
    while i < samples.len() {
        if samples[i].1 > moving {
            let a = i;
            while i < samples.len() && samples[i].1 > moving {
                i += 1;
            }
            if i == samples.len() {
                break;
            }
            let ev = &samples[a..i];
            let (k, peak) = ev
                .iter()
                .enumerate()
                .map(|(k, s)| (k, s.1))
                .fold((0, 0.0), |m, x| if x.1 > m.1 { x } else { m });
            let last_fast = ev.iter().rposition(|s| s.1 > 0.1 * peak).unwrap_or(k);
            events.push(SlipEvent {
                start: ev[0].0,
                duration: ev[ev.len() - 1].0 - ev[0].0,
                peak_speed: peak,
                fast: ev[last_fast].0 - ev[k].0,
                slip: ev[ev.len() - 1].3 - ev[0].3,
            });
            if first.is_none() && a > 0 {
                first = Some((a, i));
            }
        }
        i += 1;
    }
    let trace = first.map_or(Vec::new(), |(a, b)| {
        let pad = (b - a) / 4;
        samples[a.saturating_sub(pad)..(b + pad).min(samples.len())]
            .iter()
            .map(|s| (s.0, s.1, s.2))
            .collect()
    });
    (events, trace)
}

/// What a run's slip events say about slow slip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TailSummary {
    pub events: usize,
    /// Median over the events of the slow tail (s).
    pub median_tail: f64,
    /// The longest event (s).
    pub longest: f64,
}

impl TailSummary {
    pub fn of(events: &[SlipEvent]) -> Option<TailSummary> {
        if events.is_empty() {
            return None;
        }
        let mut tails: Vec<f64> = events.iter().map(|e| e.duration - e.fast).collect();
        tails.sort_by(f64::total_cmp);
        Some(TailSummary {
            events: events.len(),
            median_tail: tails[tails.len() / 2],
            longest: events.iter().map(|e| e.duration).fold(0.0, f64::max),
        })
    }

    /// Slow slip: the median tail lasts at least half the mean slip time.
    pub fn is_slow(&self, law: &JunctionLaw) -> bool {
        self.median_tail > 0.5 * law.slip_time.mean()
    }
}

/// Block masses (kg per newton of normal load) of the slow-slip search:
/// the study's block and two lighter ones, whose inertial time falls
/// further below the junctions' slip time.
pub const SEARCH_MASSES: [f64; 3] = [1e-3, 1e-4, 1e-5];

/// One configuration of the slow-slip search.
#[derive(Debug, Clone)]
pub struct SlowSlipProbe {
    pub law: String,
    pub mass: f64,
    pub half_period: f64,
    pub mean_slip_time: f64,
    pub summary: Option<TailSummary>,
    pub slow: bool,
}

/// Searches for slow slip: the scenario's law and the three μ(v) laws,
/// each at every mass of [`SEARCH_MASSES`], pulled for `duration` seconds.
pub fn slow_slip_search(
    base: &JunctionLaw,
    count: usize,
    seed: u32,
    duration: f64,
) -> Vec<SlowSlipProbe> {
    let mut all = vec![("the scenario's law".to_string(), *base)];
    all.extend(laws(base).into_iter().map(|l| (l.name.to_string(), l.law)));
    let cases: Vec<(String, JunctionLaw, f64)> = all
        .iter()
        .flat_map(|(name, law)| SEARCH_MASSES.map(|m| (name.clone(), *law, m)))
        .collect();
    cases
        .into_par_iter()
        .map(|(name, law, mass)| {
            let p = PulledBlock {
                duration,
                ..PulledBlock::with_mass(&law, mass)
            };
            let (events, _) = slow_slip(&law, count, seed, &p);
            let summary = TailSummary::of(&events);
            SlowSlipProbe {
                law: name,
                mass,
                half_period: std::f64::consts::PI * (mass / p.stiffness).sqrt(),
                mean_slip_time: law.slip_time.mean(),
                slow: summary.is_some_and(|s| s.is_slow(&law)),
                summary,
            }
        })
        .collect()
}

/// The search's table for the notes.
pub fn slow_slip_search_report(probes: &[SlowSlipProbe], duration: f64) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\n**Where slow slip could appear**: the same spring, pulling speed and event rule, \
         every law of this study at three block masses ({duration} s each; a lighter block's \
         inertial time falls further below the slip time):\n\n\
         | law | mass (kg/N) | half period (ms) | events | median slow tail (ms) | longest \
         event (ms) | slow slip |\n|---|---|---|---|---|---|---|"
    );
    for p in probes {
        let (events, tail, longest) = p.summary.map_or(
            ("0".to_string(), "—".to_string(), "—".to_string()),
            |s| {
                (
                    s.events.to_string(),
                    format!("{:.3}", 1e3 * s.median_tail),
                    format!("{:.3}", 1e3 * s.longest),
                )
            },
        );
        let _ = writeln!(
            md,
            "| {} | {:e} | {:.3} | {events} | {tail} | {longest} | {} |",
            p.law,
            p.mass,
            1e3 * p.half_period,
            if p.slow { "yes" } else { "no" }
        );
    }
    let slow = probes.iter().filter(|p| p.slow).count();
    let _ = writeln!(
        md,
        "\n{slow} of {} configurations show slow slip (a median tail of at least half the \
         mean slip time, {:.2} ms).",
        probes.len(),
        1e3 * probes.first().map_or(0.0, |p| p.mean_slip_time)
    );
    let longest = probes
        .iter()
        .filter_map(|p| p.summary.map(|s| s.longest / p.mean_slip_time))
        .fold(0.0, f64::max);
    if slow == 0 {
        let _ = writeln!(
            md,
            "The longest event of the search lasts {:.2} ⟨t_R⟩: events end on the block's \
             inertial time scale (they shorten with the half period), before the junctions \
             re-pin, and the lightest blocks chatter (many short events). Slow slip of one \
             block, as Publication 2 reports it, is not reproduced here; which block, spring \
             and law would show it is an open question of this study.",
            longest
        );
    }
    md
}

/// The slow-slip section of the notes.
pub fn slow_slip_report(law: &JunctionLaw, p: &PulledBlock, events: &[SlipEvent]) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\n**Slow slip** (the scenario's law; the block, {} kg per newton of normal load, pulled \
         at {:e} m/s through a spring of {:e} per metre per newton, 1/100 of the pinned junctions' \
         stiffness; {:.1} s; an event is a stretch with speed above 10× the pulling speed, its \
         fast part from the peak speed until the speed last exceeds a tenth of the peak, the \
         rest its slow tail):\n",
        p.mass, p.speed, p.stiffness, p.duration
    );
    let Some(summary) = TailSummary::of(events) else {
        let _ = writeln!(md, "No slip event in the run.");
        return md;
    };
    let _ = writeln!(md, "| event | start (s) | duration (ms) | peak speed (m/s) | fast part (ms) | slow tail (ms) | slip (µm) |\n|---|---|---|---|---|---|---|");
    for (n, e) in events.iter().enumerate().take(12) {
        let _ = writeln!(
            md,
            "| {n} | {:.4} | {:.3} | {:.2e} | {:.3} | {:.3} | {:.2} |",
            e.start,
            1e3 * e.duration,
            e.peak_speed,
            1e3 * e.fast,
            1e3 * (e.duration - e.fast),
            1e6 * e.slip
        );
    }
    let half_period = std::f64::consts::PI * (p.mass / p.stiffness).sqrt();
    let slow = summary.is_slow(law);
    let _ = writeln!(
        md,
        "\n{} events; median slow tail {:.3} ms, longest event {:.3} ms, against a mean slip \
         time ⟨t_R⟩ = {:.2} ms and half the block's period on the spring, {:.3} ms. {}",
        summary.events,
        1e3 * summary.median_tail,
        1e3 * summary.longest,
        1e3 * law.slip_time.mean(),
        1e3 * half_period,
        if slow {
            "The tails last as long as the junctions take to re-pin: slow slip on the time \
             scale of t_R."
        } else {
            "The events end on the block's inertial time scale, well before the junctions \
             re-pin: no slow slip in this configuration (a spring 1/2 of the pinned junctions' \
             stiffness gave the same)."
        }
    );
    md
}

/// Speed and friction through the first complete slip event.
pub fn write_slow_slip_figure(
    trace: &[(f64, f64, f64)],
    dir: &Path,
) -> anyhow::Result<Vec<PathBuf>> {
    if trace.is_empty() {
        return Ok(Vec::new());
    }
    let t0 = trace[0].0;
    let points: Vec<(f64, f64, usize)> = trace
        .iter()
        .filter(|s| s.1 > 0.0)
        .map(|s| (1e3 * (s.0 - t0), s.1, 0))
        .collect();
    let path = dir.join("thogersen2014_slow_slip.png");
    crate::analysis::plot::write(
        &crate::analysis::plot::scatter::Scatter {
            points: &points,
            groups: &[String::new()],
            group_label: "",
            x_label: "time in the event (ms)",
            y_label: "block speed (m/s)",
            log_y: true,
            title: "Spring-pulled block: speed through its first slip event",
            connect: true,
        },
        &path,
        &crate::analysis::plot::FigureOptions::default(),
        "slipfront study single-block",
    )?;
    Ok(vec![path])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::single_block::law::SlipTime;

    fn event(duration: f64, fast: f64) -> SlipEvent {
        SlipEvent {
            start: 0.0,
            duration,
            peak_speed: 1e-2,
            fast,
            slip: 1e-6,
        }
    }

    #[test]
    fn slow_slip_is_a_median_tail_of_half_the_mean_slip_time() {
        let law = JunctionLaw {
            slip_time: SlipTime::Fixed { time: 2e-3 },
            ..SingleBlockScene::parse(crate::engines::single_block::SCENARIO, "built in")
                .unwrap()
                .law
        };
        assert_eq!(TailSummary::of(&[]), None);
        // Tails 0.1, 1.5 and 1.8 ms: median 1.5 ms > 1 ms.
        let slow = [
            event(0.3e-3, 0.2e-3),
            event(2.0e-3, 0.5e-3),
            event(2.1e-3, 0.3e-3),
        ];
        let s = TailSummary::of(&slow).unwrap();
        assert_eq!(s.events, 3);
        assert!((s.median_tail - 1.5e-3).abs() < 1e-12, "{s:?}");
        assert!((s.longest - 2.1e-3).abs() < 1e-12, "{s:?}");
        assert!(s.is_slow(&law));
        // Inertial events: tails of a quarter period, well below 1 ms.
        let fast = [event(0.49e-3, 0.23e-3), event(0.49e-3, 0.24e-3)];
        assert!(!TailSummary::of(&fast).unwrap().is_slow(&law));
    }
}
