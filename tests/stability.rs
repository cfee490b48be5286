//! Numerical stability: the empirical largest stable time step against the
//! analytic bound, stress scenes that must run stably or stop with the clear
//! blow-up error, and the energy balance of a stick-slip run.

use slipfront::analysis::energy::{step_power, stored_energy};
use slipfront::app::verify::STICK_SLIP_WINDOW;
use slipfront::engines::backend::{cpu_engine, Precision};
use slipfront::model::scenario::{Component, Pulse, Scenario};
use slipfront::model::{Driver, ModelError};
use slipfront::{advance_to, EngineError, Model};

/// A 29 × 16 Table S1 lattice with short loading phases, and `extra` keys.
fn small(extra: &[&str]) -> Scenario {
    let mut set = STICK_SLIP_WINDOW.to_vec();
    set.extend_from_slice(extra);
    slipfront::app::verify::small_scene(&set).unwrap()
}

/// Whether `s` at `dt` runs `steps` steps without blowing up.
fn stable_at(s: &Scenario, dt: f64, steps: u64) -> bool {
    let mut s = s.clone();
    s.time.dt = Some(dt);
    s.time.dt_fraction = None;
    let m = Model::from_scenario(&s, true).unwrap();
    let mut e = cpu_engine(&m, Precision::F64, 1).unwrap();
    match advance_to(e.as_mut(), steps) {
        Ok(()) => true,
        Err(EngineError::BlowUp { .. }) => false,
        Err(e) => panic!("{e}"),
    }
}

/// Largest stable dt by bisection between `lo` (stable) and `hi` (unstable).
fn largest_stable_dt(s: &Scenario, mut lo: f64, mut hi: f64, steps: u64) -> f64 {
    assert!(stable_at(s, lo, steps) && !stable_at(s, hi, steps));
    for _ in 0..12 {
        let mid = 0.5 * (lo + hi);
        if stable_at(s, mid, steps) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

fn pulsed_bulk(damping: f64) -> Scenario {
    let mut s = slipfront::app::verify::bare_scene("bulk");
    s.geometry.nx = 21;
    s.geometry.nz = 11;
    s.geometry.length = 0.05;
    s.geometry.height = 0.025;
    s.damping.ratio = damping;
    s.pulse = Some(Pulse {
        component: Component::X,
        center: 0.025,
        width: 0.003,
        amplitude: 1e-6,
    });
    s
}

#[test]
fn empirical_stability_limit_of_the_bulk_matches_the_analytic_bound() {
    for damping in [0.0, 0.1f64.sqrt()] {
        let s = pulsed_bulk(damping);
        let m = Model::from_scenario(&s, true).unwrap();
        let analytic = if damping == 0.0 {
            m.stability_limit().bulk_undamped
        } else {
            m.stability_limit().bulk
        };
        let found = largest_stable_dt(&s, 0.5 * analytic, 4.0 * analytic, 4000);
        let ratio = found / analytic;
        println!("bulk, damping ratio {damping:.3}: empirical {found:.4e} s, analytic {analytic:.4e} s, ratio {ratio:.3}");
        // The bound is for the infinite lattice; free edges only lower the
        // highest frequency, so the bound must hold and be nearly sharp.
        assert!((1.0..1.15).contains(&ratio), "ratio {ratio}");
    }
}

#[test]
fn empirical_stability_limit_with_stiff_junctions_matches_the_bound() {
    // Constant junction stiffness 1e6 N/m × 100: the interface feels 7.4k.
    let s = small(&[
        "friction.junctions.stiffness=constant",
        "friction.junctions.constant_stiffness=1e6",
        "loading.drive.velocity=0.0",
        "loading.normal.relax_time=0",
        "time.end=0",
    ]);
    let m = Model::from_scenario(&s, true).unwrap();
    let analytic = m.stability_limit().interface;
    let found = largest_stable_dt(&s, 0.5 * analytic, 4.0 * analytic, 4000);
    let ratio = found / analytic;
    println!("interface with stiff junctions: empirical {found:.4e} s, analytic {analytic:.4e} s, ratio {ratio:.3}");
    assert!((1.0..1.6).contains(&ratio), "ratio {ratio}");
}

#[test]
fn empirical_stability_limit_of_a_stiff_side_spring_matches_the_bound() {
    // K = 1e10 N/m, ~120× the lattice's 6k: the pulled block sets the
    // limit (check used to call this scene stable, and it blew up).
    let s = small(&[
        "loading.drive.stiffness=1e10",
        "loading.normal.relax_time=0",
        "time.end=2e-3",
    ]);
    let m = Model::from_scenario(&s, true).unwrap();
    let lim = m.stability_limit();
    assert_eq!(lim.min(), lim.driven);
    assert!(matches!(
        Model::from_scenario(&s, false),
        Err(ModelError::Unstable { which, .. }) if which.contains("side spring")
    ));
    let steps = m.prep_steps + 4000;
    let analytic = lim.driven;
    let found = largest_stable_dt(&s, 0.5 * analytic, 4.0 * analytic, steps);
    let ratio = found / analytic;
    println!(
        "stiff side spring: empirical {found:.4e} s, analytic {analytic:.4e} s, ratio {ratio:.3}"
    );
    assert!((1.0..1.6).contains(&ratio), "ratio {ratio}");
}

/// Runs a stress scene: it must be refused with the stability limit, run
/// stably, or stop with the blow-up error; never produce NaN silently.
fn stress(name: &str, extra: &[&str]) {
    stress_scene(name, small(&[&["time.end=2e-3"], extra].concat()));
}

fn stress_scene(name: &str, s: Scenario) {
    let m = match Model::from_scenario(&s, false) {
        Ok(m) => m,
        Err(e @ ModelError::Unstable { .. }) => {
            println!("{name}: refused: {e}");
            return;
        }
        Err(e) => panic!("{name}: {e}"),
    };
    let mut e = cpu_engine(&m, Precision::F64, 1).unwrap();
    match advance_to(e.as_mut(), m.total_steps()) {
        Ok(()) => {
            let snap = e.snapshot().unwrap();
            assert!(snap.disp.iter().flatten().all(|x| x.is_finite()), "{name}");
            println!("{name}: stable, {} ruptures", snap.total_ruptures());
        }
        Err(err @ EngineError::BlowUp { .. }) => {
            let text = err.to_string();
            assert!(
                text.contains("blew up at step") && text.contains("block"),
                "{text}"
            );
            println!("{name}: {text}");
        }
        Err(err) => panic!("{name}: {err}"),
    }
}

#[test]
fn stress_scenes_run_stably_or_stop_clearly() {
    stress("zero damping", &["damping.ratio=0"]);
    stress(
        "junctions 100x stiffer",
        &["friction.junctions.stiffness_coefficient=39.2e13"],
    );
    stress("Ns = 1", &["friction.junctions.count=1"]);
    stress("Ns = 1000", &["friction.junctions.count=1000"]);
    stress("very low normal load", &["loading.normal.force=1.0"]);
    stress("very high normal load", &["loading.normal.force=1.9e5"]);
    // Pulled hard from the top with no normal load: the slider lifts off.
    let mut s = small(&["time.end=2e-3", "loading.normal.force=0"]);
    s.loading.drive = slipfront::model::scenario::Drive {
        mode: slipfront::model::scenario::DriveMode::TopForce,
        stiffness: None,
        height: None,
        velocity: None,
        force_rate: Some(1e6),
    };
    stress_scene("lift-off", s);
}

#[test]
fn junctions_1e4x_stiffer_are_refused_at_the_default_step_and_blow_up_when_forced() {
    // 100× stiffer junctions are still stable at T/50 (the stress scene
    // above); 10⁴× stiffer ones (coefficient ×10⁸) are not.
    let s = small(&[
        "friction.junctions.stiffness_coefficient=39.2e17",
        "time.end=1e-3",
    ]);
    let err = Model::from_scenario(&s, false).unwrap_err().to_string();
    assert!(err.contains("above the stability limit"), "{err}");
    let m = Model::from_scenario(&s, true).unwrap();
    let mut e = cpu_engine(&m, Precision::F64, 1).unwrap();
    let err = advance_to(e.as_mut(), m.total_steps())
        .unwrap_err()
        .to_string();
    assert!(err.contains("blew up at step"), "{err}");
}

#[test]
fn energy_balance_of_a_stick_slip_run() {
    let s = small(&["time.end=4e-3"]);
    let m = Model::from_scenario(&s, false).unwrap();
    let Driver::SideSpring { row, .. } = m.driver else {
        unreachable!()
    };
    let mut e = cpu_engine(&m, Precision::F64, 1).unwrap();
    advance_to(e.as_mut(), m.prep_steps).unwrap();
    let start = e.snapshot().unwrap();
    let origin = start.disp[row * m.nx][0];
    let e0 = stored_energy(&m, &start, origin);
    let (mut w_drive, mut w_top, mut w_friction, mut dissipated) = (0.0, 0.0, 0.0, 0.0);
    let mut before = start;
    while before.step < m.total_steps() {
        advance_to(e.as_mut(), before.step + 1).unwrap();
        let after = e.snapshot().unwrap();
        let p = step_power(&m, &before, &after, origin);
        w_drive += p.drive * m.dt;
        w_top += p.top_loads * m.dt;
        w_friction += p.friction * m.dt;
        dissipated += p.damping * m.dt;
        before = after;
    }
    assert!(before.total_ruptures() > 1000, "the run must slip");
    let e1 = stored_energy(&m, &before, origin);
    let change = e1.total() - e0.total();
    let net_in = w_drive + w_top + w_friction - dissipated;
    let rel = (change - net_in).abs() / w_drive;
    println!(
        "work of driving {w_drive:.4e} J, top loads {w_top:.4e} J, friction {w_friction:.4e} J, \
         damping {dissipated:.4e} J; stored energy change {change:.4e} J; mismatch {rel:.2e} of the driving work"
    );
    assert!(rel < 0.01, "energy balance off by {rel}");
    // Negative control: the same ledger without the friction work must fail.
    let without_friction = (change - (net_in - w_friction)).abs() / w_drive;
    assert!(without_friction > 0.5, "{without_friction}");
}
