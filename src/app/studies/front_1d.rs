//! Steady-state rupture fronts along a 1D chain (Amundsen et al., PRE 92,
//! 032406 (2015)): the chain of `scenarios/amundsen2015_1d_front.toml`
//! under a uniform prestress τ̄, triggered at the trailing edge. The front
//! speed is measured from each block's first rupture time, fitted over
//! the middle half of the chain, in units of the 1D sound speed l√(k/m),
//! and extrapolated to infinite length from several chain lengths.

use crate::engines::backend::{make_engine, Backend, Precision};
use crate::engines::{Engine, EngineError};
use crate::model::scenario::{FrictionLaw, Scenario};
use crate::model::Model;
use anyhow::Context;

/// The scene every case starts from.
pub const BASE_SCENARIO: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/amundsen2015_1d_front.toml"
));

/// Viscosity on the neighbours' relative velocity (a dashpot on every
/// spring) or on each block's absolute velocity (against the track).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Viscosity {
    Absolute,
    Relative,
}

impl Viscosity {
    pub fn name(self) -> &'static str {
        match self {
            Viscosity::Absolute => "absolute",
            Viscosity::Relative => "relative",
        }
    }
}

/// One point of the study's grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontCase {
    /// k_I / k of one junction per block; `None`: rigid Amontons–Coulomb.
    pub stiffness_ratio: Option<f64>,
    pub viscosity: Viscosity,
    /// η / √(k m).
    pub alpha: f64,
    pub tau_bar: f64,
    pub n_blocks: usize,
    /// Blocks from the trailing edge put at τ̄ = 1.001 at t = 0.
    pub trigger_blocks: u32,
}

impl FrontCase {
    pub fn law_name(&self) -> &'static str {
        if self.stiffness_ratio.is_some() {
            "junction"
        } else {
            "coulomb"
        }
    }

    /// The scene of this case, with the time step scaled by `dt_scale`.
    pub fn scenario(&self, dt_scale: f64) -> anyhow::Result<Scenario> {
        let mut s = Scenario::parse(BASE_SCENARIO, "amundsen2015_1d_front.toml", &[])?;
        let spacing = s.geometry.height;
        s.geometry.nx = self.n_blocks as u32;
        s.geometry.length = spacing * (self.n_blocks - 1) as f64;
        let (relative, absolute) = match self.viscosity {
            Viscosity::Relative => (self.alpha, 0.0),
            Viscosity::Absolute => (0.0, self.alpha),
        };
        s.damping.ratio = relative;
        s.damping.absolute_ratio = absolute;
        match self.stiffness_ratio {
            None => s.friction.law = FrictionLaw::Coulomb,
            Some(r) => {
                s.friction.law = FrictionLaw::SingleJunction;
                if let Some(j) = s.friction.junctions.as_mut() {
                    j.stiffness_ratio = Some(r);
                }
            }
        }
        if let Some(p) = s.loading.prestress.as_mut() {
            p.tau_bar = self.tau_bar;
            p.trigger_blocks = self.trigger_blocks;
        }
        if let Some(f) = s.time.dt_fraction.as_mut() {
            *f *= dt_scale;
        }
        let problems = crate::model::scenario::validate(&s, "", &[]);
        anyhow::ensure!(problems.is_empty(), "{}", problems.join("; "));
        Ok(s)
    }
}

/// What one chain gives: each block's first rupture time (s after the
/// trigger) and the fitted front speed.
#[derive(Debug, Clone, PartialEq)]
pub struct FrontRun {
    pub rupture_time: Vec<Option<f64>>,
    /// Front speed over the middle half, in units of l√(k/m); `None` when
    /// the front stopped before crossing it.
    pub front_speed: Option<f64>,
}

/// 1D sound speed l√(k/m) (m/s).
pub fn sound_speed(m: &Model) -> f64 {
    m.spacing * (m.k / m.mass).sqrt()
}

/// A front slower than this (× l√(k/m)) counts as arrested: the run stops
/// after a quiet time of one block crossing at this speed.
pub const SLOWEST_FRONT: f64 = 0.02;

/// Runs the chain until every block has ruptured (or the front stalls)
/// and measures the front.
pub fn run_chain(
    model: &Model,
    backend: Backend,
    precision: Precision,
) -> anyhow::Result<FrontRun> {
    let mut engine = make_engine(model, backend, precision, 1)?;
    crate::engines::advance_to(engine.as_mut(), model.prep_steps)?;
    let crossing_steps = (model.spacing / (SLOWEST_FRONT * sound_speed(model)) / model.dt).ceil();
    let stall = crossing_steps as u64;
    let limit = model.prep_steps + stall * model.nx as u64;
    let ns = model.junctions.map_or(0, |j| j.count);
    let mut rupture_time = vec![None; model.nx];
    let mut left = model.nx;
    let mut last_new = model.prep_steps;
    while left > 0 && engine.steps_done() < limit && engine.steps_done() - last_new < stall {
        step_once(engine.as_mut())?;
        let snap = engine.snapshot()?;
        for (ix, t) in rupture_time.iter_mut().enumerate() {
            if t.is_none() && block_ruptured(&snap, ix, ns) {
                *t = Some(snap.time);
                left -= 1;
                last_new = snap.step;
            }
        }
    }
    let front_speed = fit_front_speed(&rupture_time, model.spacing)
        .map(|v| v / sound_speed(model))
        .filter(|v| *v >= SLOWEST_FRONT);
    Ok(FrontRun {
        rupture_time,
        front_speed,
    })
}

fn step_once(engine: &mut dyn Engine) -> Result<(), EngineError> {
    engine.advance(1)
}

/// True once block `ix` has broken: any of its junctions, or its
/// Amontons–Coulomb contact.
fn block_ruptured(snap: &crate::Snapshot, ix: usize, ns: usize) -> bool {
    snap.slips.get(ix).is_some_and(|&s| s > 0)
        || snap
            .ruptures
            .get(ix * ns..(ix + 1) * ns)
            .is_some_and(|r| r.iter().any(|&c| c > 0))
}

/// Front speed (m/s) from the first rupture times of blocks `n/4 .. 3n/4`
/// (least squares of time on position: the position is exact), or `None`
/// when one of them never broke or the times do not advance.
pub fn fit_front_speed(rupture_time: &[Option<f64>], spacing: f64) -> Option<f64> {
    let n = rupture_time.len();
    let (lo, hi) = (n / 4, (3 * n).div_ceil(4));
    if hi < lo + 2 {
        return None;
    }
    let pts: Vec<(f64, f64)> = (lo..hi)
        .map(|i| rupture_time[i].map(|t| (i as f64 * spacing, t)))
        .collect::<Option<_>>()?;
    let count = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / count;
    let mt = pts.iter().map(|p| p.1).sum::<f64>() / count;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxt: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - mt)).sum();
    let slowness = sxt / sxx;
    (slowness > 0.0).then(|| 1.0 / slowness)
}

/// Extrapolation to infinite length: least squares of v(N) = v∞ + b/N over
/// the measured lengths (at least two).
pub fn extrapolate(points: &[(usize, f64)]) -> Option<f64> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let xs: Vec<f64> = points.iter().map(|p| 1.0 / p.0 as f64).collect();
    let mx = xs.iter().sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    let sxy: f64 = xs
        .iter()
        .zip(points)
        .map(|(x, p)| (x - mx) * (p.1 - my))
        .sum();
    Some(my - sxy / sxx * mx)
}

/// The grid of the study, or its quick version (a few points, short chains).
#[derive(Debug, Clone)]
pub struct Grid {
    pub stiffness_ratios: Vec<Option<f64>>,
    pub viscosities: Vec<Viscosity>,
    pub alphas: Vec<f64>,
    pub tau_bars: Vec<f64>,
    pub lengths: Vec<usize>,
    /// The length at which every point is also run at dt/2.
    pub dt_check_length: usize,
}

impl Grid {
    pub fn full() -> Grid {
        Grid {
            stiffness_ratios: vec![None, Some(10.0), Some(1.0), Some(0.1)],
            viscosities: vec![Viscosity::Absolute, Viscosity::Relative],
            alphas: vec![0.0, 0.1, 0.2, 0.5, 1.0],
            tau_bars: (1..=9).map(|i| i as f64 / 10.0).collect(),
            lengths: vec![100, 200, 400, 800],
            dt_check_length: 200,
        }
    }

    pub fn quick() -> Grid {
        Grid {
            stiffness_ratios: vec![None, Some(1.0)],
            viscosities: vec![Viscosity::Relative],
            alphas: vec![0.0, 0.5],
            tau_bars: vec![0.2, 0.5, 0.8],
            lengths: vec![60, 120],
            dt_check_length: 60,
        }
    }

    /// Every (interface, viscosity, α, τ̄) point, lengths aside.
    pub fn points(&self) -> Vec<FrontCase> {
        let mut out = Vec::new();
        for &stiffness_ratio in &self.stiffness_ratios {
            for &viscosity in &self.viscosities {
                for &alpha in &self.alphas {
                    for &tau_bar in &self.tau_bars {
                        out.push(FrontCase {
                            stiffness_ratio,
                            viscosity,
                            alpha,
                            tau_bar,
                            n_blocks: 0,
                            trigger_blocks: 1,
                        });
                    }
                }
            }
        }
        out
    }
}

/// The result of one grid point.
#[derive(Debug, Clone)]
pub struct PointResult {
    pub case: FrontCase,
    /// Time step as a fraction of the base scene's (T/50).
    pub dt_scale: f64,
    /// (length, front speed) for every length; `None`: arrested.
    pub by_length: Vec<(usize, Option<f64>)>,
    pub extrapolated: Option<f64>,
    /// |v(dt/2) − v(dt)| / v(dt/2) at the check length.
    pub dt_change: Option<f64>,
}

/// Time steps per block crossing the study keeps at least: the rupture of
/// a rigid block is found one step late at most, an error of order one
/// step per crossing (measured: 100 steps keep dt → dt/2 within 1 %).
pub const STEPS_PER_CROSSING: f64 = 100.0;

/// The largest dt scale, a power of two at most `1/8`, that gives a front
/// at `speed` (× l√(k/m)) at least STEPS_PER_CROSSING steps per block.
pub fn dt_scale_for(speed: f64) -> f64 {
    // A crossing takes √(m/k)/speed = (50/2π)/(scale·speed) steps.
    let wanted = 50.0 / (2.0 * std::f64::consts::PI) / (STEPS_PER_CROSSING * speed.max(1.0));
    let mut scale = 0.125;
    while scale > wanted {
        scale *= 0.5;
    }
    scale
}

/// Runs one grid point: a pilot on the shortest chain picks the trigger
/// length and the time step, then every length at them, and the check
/// length at dt/2. One block at τ̄ = 1.001 does not nucleate a front on a
/// soft interface at low prestress (its excess force spreads over the
/// blocks its neighbours' junctions hold): the pilot doubles the trigger
/// until a front crosses, up to an eighth of the chain.
pub fn run_point(
    mut case: FrontCase,
    grid: &Grid,
    backend: Backend,
    precision: Precision,
) -> anyhow::Result<PointResult> {
    let shortest = grid
        .lengths
        .iter()
        .copied()
        .min()
        .unwrap_or(grid.dt_check_length);
    let mut pilot = None;
    let mut trigger = case.trigger_blocks.max(1);
    while trigger as usize <= (shortest / 8).max(1) {
        case.trigger_blocks = trigger;
        pilot = speed_of(case, shortest, 0.125, backend, precision)?;
        if pilot.is_some() {
            break;
        }
        trigger *= 2;
    }
    let dt_scale = dt_scale_for(pilot.unwrap_or(1.0));
    let speed = |n: usize, dt_scale: f64| speed_of(case, n, dt_scale, backend, precision);
    let mut by_length = Vec::new();
    for &n in &grid.lengths {
        by_length.push((n, speed(n, dt_scale)?));
    }
    let measured: Vec<(usize, f64)> = by_length
        .iter()
        .filter_map(|&(n, v)| v.map(|v| (n, v)))
        .collect();
    let extrapolated = if measured.len() == by_length.len() {
        extrapolate(&measured)
    } else {
        None
    };
    let at_check = by_length
        .iter()
        .find(|p| p.0 == grid.dt_check_length)
        .and_then(|p| p.1);
    let dt_change = match (at_check, speed(grid.dt_check_length, 0.5 * dt_scale)?) {
        (Some(a), Some(b)) => Some((a - b).abs() / b),
        _ => None,
    };
    Ok(PointResult {
        case,
        dt_scale,
        by_length,
        extrapolated,
        dt_change,
    })
}

/// The front speed of `case` on a chain of `n` blocks.
fn speed_of(
    case: FrontCase,
    n: usize,
    dt_scale: f64,
    backend: Backend,
    precision: Precision,
) -> anyhow::Result<Option<f64>> {
    let c = FrontCase {
        n_blocks: n,
        ..case
    };
    let model =
        Model::from_scenario(&c.scenario(dt_scale)?, false).with_context(|| format!("{c:?}"))?;
    Ok(run_chain(&model, backend, precision)?.front_speed)
}

/// CSV of the study: one row per length and one extrapolated row
/// (`n_blocks` = inf) per point; arrested fronts are `nan`.
pub fn csv(results: &[PointResult]) -> String {
    let mut out =
        String::from("law,viscosity,alpha,stiffness_ratio,tau_bar,n_blocks,front_speed\n");
    let num = |v: Option<f64>| v.map_or("nan".to_string(), |v| format!("{v:.5}"));
    for r in results {
        let c = &r.case;
        let ratio = c
            .stiffness_ratio
            .map_or("inf".to_string(), |r| format!("{r}"));
        let prefix = format!(
            "{},{},{},{},{}",
            c.law_name(),
            c.viscosity.name(),
            c.alpha,
            ratio,
            c.tau_bar
        );
        for (n, v) in &r.by_length {
            out.push_str(&format!("{prefix},{n},{}\n", num(*v)));
        }
        out.push_str(&format!("{prefix},inf,{}\n", num(r.extrapolated)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_recovers_a_known_speed_and_refuses_a_stopped_front() {
        let times: Vec<Option<f64>> = (0..40).map(|i| Some(1.0e-3 + i as f64 * 2.0e-6)).collect();
        let v = fit_front_speed(&times, 1.0e-3).unwrap();
        assert!((v - 500.0).abs() < 1e-9 * 500.0, "{v}");
        let mut stopped = times.clone();
        stopped[25] = None;
        assert_eq!(fit_front_speed(&stopped, 1.0e-3), None);
    }

    #[test]
    fn extrapolation_in_one_over_length_is_exact_for_that_form() {
        let pts: Vec<(usize, f64)> = [100, 200, 400]
            .iter()
            .map(|&n| (n, 1.5 - 3.0 / n as f64))
            .collect();
        assert!((extrapolate(&pts).unwrap() - 1.5).abs() < 1e-12);
        assert_eq!(extrapolate(&pts[..1]), None);
    }
}

/// A published trend checked over the grid: how many neighbouring pairs
/// of points follow it, and the pairs that do not.
#[derive(Debug, Clone, PartialEq)]
pub struct TrendCheck {
    pub name: &'static str,
    pub pairs: usize,
    pub violations: Vec<String>,
}

/// Stiffness ratio as a number for ordering (rigid = ∞).
fn stiffness_order(c: &FrontCase) -> f64 {
    c.stiffness_ratio.unwrap_or(f64::INFINITY)
}

/// Pairs of points equal in everything but the quantity `along` orders,
/// consecutive in it: the extrapolated speed must grow along it.
fn increasing_along(
    results: &[PointResult],
    name: &'static str,
    along: impl Fn(&FrontCase) -> f64,
    same: impl Fn(&FrontCase, &FrontCase) -> bool,
    include: impl Fn(&FrontCase) -> bool,
) -> TrendCheck {
    let mut check = TrendCheck {
        name,
        pairs: 0,
        violations: Vec::new(),
    };
    for a in results.iter().filter(|r| include(&r.case)) {
        // The next point along the axis with everything else equal.
        let next = results
            .iter()
            .filter(|b| include(&b.case) && same(&a.case, &b.case))
            .filter(|b| along(&b.case) > along(&a.case))
            .min_by(|x, y| along(&x.case).total_cmp(&along(&y.case)));
        let (Some(b), Some(va)) = (next, a.extrapolated) else {
            continue;
        };
        check.pairs += 1;
        match b.extrapolated {
            Some(vb) if vb > va => {}
            vb => check.violations.push(format!(
                "{} {} α={} k_I/k={} τ̄={}: {va:.4} → {} at {}",
                a.case.law_name(),
                a.case.viscosity.name(),
                a.case.alpha,
                stiffness_order(&a.case),
                a.case.tau_bar,
                vb.map_or("arrested".into(), |v| format!("{v:.4}")),
                along(&b.case)
            )),
        }
    }
    check
}

/// The trends of Publication 4 over the study's grid.
pub fn trend_checks(results: &[PointResult]) -> Vec<TrendCheck> {
    let same_but_tau = |a: &FrontCase, b: &FrontCase| {
        a.stiffness_ratio == b.stiffness_ratio && a.viscosity == b.viscosity && a.alpha == b.alpha
    };
    let same_but_alpha = |a: &FrontCase, b: &FrontCase| {
        a.stiffness_ratio == b.stiffness_ratio
            && a.viscosity == b.viscosity
            && a.tau_bar == b.tau_bar
    };
    let same_but_stiffness = |a: &FrontCase, b: &FrontCase| {
        a.viscosity == b.viscosity && a.alpha == b.alpha && a.tau_bar == b.tau_bar
    };
    let mut above = TrendCheck {
        name: "faster than the 1D sound speed at τ̄ = 0.8 (points, not pairs)",
        pairs: 0,
        violations: Vec::new(),
    };
    for r in results.iter().filter(|r| r.case.tau_bar == 0.8) {
        above.pairs += 1;
        if !r.extrapolated.is_some_and(|v| v > 1.0) {
            above.violations.push(format!(
                "{} {} α={} k_I/k={}: {}",
                r.case.law_name(),
                r.case.viscosity.name(),
                r.case.alpha,
                stiffness_order(&r.case),
                r.extrapolated
                    .map_or("arrested".into(), |v| format!("{v:.4}"))
            ));
        }
    }
    vec![
        increasing_along(
            results,
            "front speed increases with the prestress τ̄",
            |c| c.tau_bar,
            same_but_tau,
            |_| true,
        ),
        above,
        increasing_along(
            results,
            "front speed increases with the relative viscosity α",
            |c| c.alpha,
            same_but_alpha,
            |c| c.viscosity == Viscosity::Relative,
        ),
        increasing_along(
            results,
            "front speed increases with the interface/bulk stiffness ratio",
            stiffness_order,
            same_but_stiffness,
            |_| true,
        ),
    ]
}

/// Picks a point for a figure and names its curve.
type Selector = dyn Fn(&FrontCase) -> Option<String>;

/// Figures of the study: v∞ against τ̄ for the rigid interface (one curve
/// per viscosity and α) and for every interface at α = 0.
pub fn write_figures(
    results: &[PointResult],
    dir: &std::path::Path,
) -> anyhow::Result<Vec<std::path::PathBuf>> {
    let mut written = Vec::new();
    let curves = |select: &dyn Fn(&FrontCase) -> Option<String>| {
        let mut groups: Vec<String> = Vec::new();
        let mut points = Vec::new();
        for r in results {
            let (Some(label), Some(v)) = (select(&r.case), r.extrapolated) else {
                continue;
            };
            let g = match groups.iter().position(|x| *x == label) {
                Some(g) => g,
                None => {
                    groups.push(label);
                    groups.len() - 1
                }
            };
            points.push((r.case.tau_bar, v, g));
        }
        (groups, points)
    };
    let figures: [(&str, &str, &str, Box<Selector>); 2] = [
        (
            "front_speed_1d_viscosity.png",
            "α",
            "1D steady-state front speed, rigid (Coulomb) interface",
            Box::new(|c: &FrontCase| {
                c.stiffness_ratio
                    .is_none()
                    .then(|| format!("{} ({} viscosity)", c.alpha, c.viscosity.name()))
            }),
        ),
        (
            "front_speed_1d_stiffness.png",
            "k_I/k",
            "1D steady-state front speed, no viscosity",
            Box::new(|c: &FrontCase| {
                (c.alpha == 0.0 && c.viscosity == Viscosity::Relative).then(|| {
                    c.stiffness_ratio
                        .map_or("∞ (Coulomb)".to_string(), |r| format!("{r}"))
                })
            }),
        ),
    ];
    for (file, label, title, select) in figures {
        let (groups, points) = curves(select.as_ref());
        if points.is_empty() {
            continue;
        }
        let path = dir.join(file);
        crate::analysis::plot::write(
            &crate::analysis::plot::scatter::Scatter {
                points: &points,
                groups: &groups,
                group_label: label,
                x_label: "prestress (τ − μd p)/((μs − μd) p)",
                y_label: "front speed v∞ / (l √(k/m))",
                log_y: false,
                title,
                connect: true,
            },
            &path,
            &crate::analysis::plot::FigureOptions::default(),
            "slipfront study front-1d",
        )?;
        written.push(path);
    }
    Ok(written)
}

/// The study's notes: definitions, the extrapolated speeds, the dt check
/// and the published trends.
pub fn report(results: &[PointResult], grid: &Grid, how: &str) -> String {
    use std::fmt::Write;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Steady-state front speed along 1D chains (Publication 4)\n"
    );
    let _ = writeln!(
        md,
        "Regenerate: `{how}`. Scene: `scenarios/amundsen2015_1d_front.toml`; model and choices in \
         `docs/model.md` (\"1D steady-state fronts\"). Table: `front_speed_1d.csv` (one row per \
         chain length, `n_blocks = inf` for the extrapolation; `nan`: the front stopped).\n"
    );
    let _ = writeln!(
        md,
        "A chain of N equal blocks (springs k, mass m) on a rigid track, each block loaded by the \
         same shear force τ and normal force p, friction Amontons–Coulomb (`coulomb`, rigid) or \
         one junction of stiffness k_I that breaks at μs p and then slides at μd p (`junction`). \
         Prestress τ̄ = (τ − μd p)/((μs − μd) p); the trailing-edge block starts at τ̄ = 1.001 (where one block does not start a front, the \
         first 2, 4, … blocks: see below). Viscosity η = α √(k m), \
         on the relative velocity of neighbours or on each block's velocity. The front speed is the \
         least-squares slope of first-rupture position against time over blocks N/4..3N/4, in \
         units of l √(k/m); v∞ extrapolates v(N) = v∞ + b/N over N ∈ {:?}. Each point's time step \
         is the largest T/50 · 2^-j (T/400 at most) giving ≥ {STEPS_PER_CROSSING} steps per block crossing \
         (a pilot run on the shortest chain); the same point is rerun at dt/2 with N = {}.\n",
        grid.lengths, grid.dt_check_length
    );
    let worst = results
        .iter()
        .filter_map(|r| r.dt_change.map(|d| (d, r)))
        .max_by(|a, b| a.0.total_cmp(&b.0));
    if let Some((d, r)) = worst {
        let over = results
            .iter()
            .filter(|r| r.dt_change.is_some_and(|d| d > 0.01))
            .count();
        let _ = writeln!(
            md,
            "**dt convergence**: largest change of v from dt to dt/2: {:.3} % ({} {} α = {} τ̄ = {}); \
             {over} of {} points above 1 %.\n",
            100.0 * d,
            r.case.law_name(),
            r.case.viscosity.name(),
            r.case.alpha,
            r.case.tau_bar,
            results.len()
        );
    }
    let longer: Vec<String> = results
        .iter()
        .filter(|r| r.case.trigger_blocks > 1)
        .map(|r| {
            format!(
                "{} k_I/k={} {} α={} τ̄={}: {} blocks",
                r.case.law_name(),
                stiffness_order(&r.case),
                r.case.viscosity.name(),
                r.case.alpha,
                r.case.tau_bar,
                r.case.trigger_blocks
            )
        })
        .collect();
    if !longer.is_empty() {
        let _ = writeln!(
            md,
            "**Longer triggers** ({} points: one block over threshold does not nucleate a front \
             there): {}.\n",
            longer.len(),
            longer.join("; ")
        );
    }
    let _ = writeln!(md, "## Published trends\n");
    for t in trend_checks(results) {
        let _ = writeln!(
            md,
            "- {}: {} of {} pairs{}",
            t.name,
            t.pairs - t.violations.len(),
            t.pairs,
            if t.violations.is_empty() {
                String::new()
            } else {
                format!("; not: {}", t.violations.join("; "))
            }
        );
    }
    let _ = writeln!(md, "\n## v∞ / (l √(k/m))\n");
    let mut interfaces: Vec<Option<f64>> = Vec::new();
    for r in results {
        if !interfaces.contains(&r.case.stiffness_ratio) {
            interfaces.push(r.case.stiffness_ratio);
        }
    }
    let mut columns: Vec<(Viscosity, f64)> = Vec::new();
    for r in results {
        if !columns.contains(&(r.case.viscosity, r.case.alpha)) {
            columns.push((r.case.viscosity, r.case.alpha));
        }
    }
    let mut taus: Vec<f64> = results.iter().map(|r| r.case.tau_bar).collect();
    taus.sort_by(f64::total_cmp);
    taus.dedup();
    for i in interfaces {
        let _ = writeln!(
            md,
            "**{}**\n",
            i.map_or("Rigid interface (Amontons–Coulomb)".into(), |r| format!(
                "Compliant interface, k_I/k = {r}"
            ))
        );
        let head: Vec<String> = columns
            .iter()
            .map(|(v, a)| format!("{} α={a}", v.name()))
            .collect();
        let _ = writeln!(md, "| τ̄ | {} |", head.join(" | "));
        let _ = writeln!(md, "|---|{}", "---|".repeat(columns.len()));
        for &t in &taus {
            let cells: Vec<String> = columns
                .iter()
                .map(|&(v, a)| {
                    results
                        .iter()
                        .find(|r| {
                            r.case.stiffness_ratio == i
                                && r.case.viscosity == v
                                && r.case.alpha == a
                                && r.case.tau_bar == t
                        })
                        .and_then(|r| r.extrapolated)
                        .map_or("—".into(), |x| format!("{x:.3}"))
                })
                .collect();
            let _ = writeln!(md, "| {t} | {} |", cells.join(" | "));
        }
        let _ = writeln!(md);
    }
    md
}
