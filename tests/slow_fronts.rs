//! Slow fronts on the Table S1 slider, pinned against the values stored in
//! `results/pre2015_strength_prestress.md` and `results/slow_slip_dt.md`,
//! with their negative controls:
//! - a triggered front in the slow band is fast–slow–fast at ~4 m/s, and
//!   stays so at dt/2 and at 4× the density, while 0.02 less prestress
//!   arrests and 0.02 more runs fast;
//! - the first precursor of the stick-slip scene and its slow front hold
//!   at dt/2 under the at-rest rule `hold`, and not under sign(v).

use slipfront::analysis::events::{
    Event, FrontClass, InterfaceSeries, DEFAULT_QUIET_GAP, FRONT_WINDOW,
};
use slipfront::analysis::stats::Quartiles;
use slipfront::app::runner::{run_scene, RunOptions};
use slipfront::engines::backend::{cpu_engine, Precision};
use slipfront::io::output::reader::RunFile;
use slipfront::model::scenario::Scenario;
use slipfront::Model;

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

const TRIGGERED: &str = include_str!("../scenarios/triggered_front.toml");
const PRECURSORS: &str = include_str!("../scenarios/tromborg2014_precursors.toml");

/// The first event of `text` with `set`, its series, run on the CPU in f64.
fn first_event(text: &str, name: &str, set: &[String]) -> (InterfaceSeries, Event) {
    let scenario = Scenario::parse(text, name, set).unwrap();
    let model = Model::from_scenario(&scenario, false).unwrap();
    let dir = Scratch::new("slow", &format!("{:016x}", fingerprint(set)));
    let path = dir.join("run.mcap");
    let mut engine = cpu_engine(&model, Precision::F64, 1).unwrap();
    let opts = RunOptions {
        output: Some(path.clone()),
        ..RunOptions::default()
    };
    run_scene(engine.as_mut(), &scenario, &opts).unwrap();
    let series = RunFile::read(&path).unwrap().interface_series();
    let _ = std::fs::remove_file(&path);
    let event = series
        .events_separated_by(DEFAULT_QUIET_GAP)
        .into_iter()
        .next()
        .expect("an event");
    (series, event)
}

fn fingerprint(set: &[String]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    set.hash(&mut h);
    h.finish()
}

/// Median slow-front speed of an event (m/s), as the sweep table's column.
fn slow_front(series: &InterfaceSeries, e: &Event) -> f64 {
    let v: Vec<f64> = series
        .slow_windows(e, FRONT_WINDOW)
        .iter()
        .map(|p| p.0)
        .collect();
    Quartiles::of(&v).expect("slow windows").median
}

/// The triggered slider of the PRE 2015 diagram: a 40 mm strip, 20 ms.
fn triggered(width: f64, prestress: f64, extra: &[&str]) -> (InterfaceSeries, Event) {
    let mut set: Vec<String> = [
        "time.end=0.02",
        "loading.trigger.strip_prestress=0.6",
        "loading.trigger.strip_length=0.04",
        "output.bulk_interval=0",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    set.push(format!("loading.trigger.force_width={width}"));
    set.push(format!("loading.trigger.shear_prestress={prestress}"));
    set.extend(extra.iter().map(|s| s.to_string()));
    first_event(TRIGGERED, "triggered", &set)
}

#[test]
fn a_front_in_the_slow_band_is_slow_at_4_m_per_s_at_dt_over_2_and_at_4_rho() {
    // Stored: w = 0.10, τ/p = 0.26 is fast–slow–fast, its slow front at
    // 4.020 m/s (4.018 at dt/2, 3.984 at 4ρ).
    let (s, e) = triggered(0.1, 0.26, &[]);
    assert_eq!(s.front_class(&e, FRONT_WINDOW), FrontClass::FastSlowFast);
    let v = slow_front(&s, &e);
    assert!((v - 4.020).abs() < 0.03 * 4.020, "slow front {v} m/s");
    for extra in ["time.dt_fraction=0.01", "material.density=4800"] {
        let (s, e) = triggered(0.1, 0.26, &[extra]);
        assert_eq!(
            s.front_class(&e, FRONT_WINDOW),
            FrontClass::FastSlowFast,
            "{extra}"
        );
        let w = slow_front(&s, &e);
        assert!(
            (w - v).abs() < 0.05 * v,
            "{extra}: slow front {w} against {v} m/s"
        );
    }
    // The band's edges: 0.02 less prestress arrests, 0.02 more runs fast.
    let (s, e) = triggered(0.1, 0.24, &[]);
    assert_eq!(s.front_class(&e, FRONT_WINDOW), FrontClass::Arrest);
    let (s, e) = triggered(0.1, 0.28, &[]);
    assert_eq!(s.front_class(&e, FRONT_WINDOW), FrontClass::Fast);
}

/// The first precursor of the stick-slip scene (0.22 s of driving).
fn precursor(rule: &str, dt_fraction: f64) -> (f64, f64) {
    let set: Vec<String> = vec![
        "time.end=0.22".into(),
        "output.bulk_interval=0".into(),
        format!("friction.junctions.at_rest=\"{rule}\""),
        format!("time.dt_fraction={dt_fraction}"),
    ];
    let (s, e) = first_event(PRECURSORS, "precursors", &set);
    (e.rupture_length, slow_front(&s, &e))
}

#[test]
fn the_first_precursor_holds_at_dt_over_2_under_hold_and_not_under_sign() {
    // Stored: 21.25 mm and 14.44 m/s at T/50 and T/100 under hold; 28.75
    // and 26.25 mm, 23.65 and 16.02 m/s under sign.
    // The four runs at once (each is one CPU thread).
    let runs: Vec<(f64, f64)> = std::thread::scope(|sc| {
        let handles: Vec<_> = [
            ("hold", 0.02),
            ("hold", 0.01),
            ("sign", 0.02),
            ("sign", 0.01),
        ]
        .map(|(rule, f)| sc.spawn(move || precursor(rule, f)))
        .into_iter()
        .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let (coarse, fine) = (runs[0], runs[1]);
    assert!((coarse.0 - 0.02125).abs() < 1e-9, "{coarse:?}");
    assert!((coarse.1 - 14.44).abs() < 0.02 * 14.44, "{coarse:?}");
    assert_eq!(coarse.0, fine.0, "length at dt/2");
    assert!(
        (fine.1 - coarse.1).abs() < 0.05 * coarse.1,
        "{coarse:?} {fine:?}"
    );
    // The negative control: the same comparison flags the sign rule.
    let (coarse, fine) = (runs[2], runs[3]);
    assert!(
        coarse.0 > 0.025 && fine.0 != coarse.0,
        "{coarse:?} {fine:?}"
    );
    assert!(
        (fine.1 - coarse.1).abs() > 0.05 * coarse.1,
        "{coarse:?} {fine:?}"
    );
}
