//! The validation cases on the CPU engine, and negative controls: an engine
//! whose model is perturbed must be flagged by the same comparators.

use slipfront::app::verify::{failures, run_all};
use slipfront::engines::backend::{cpu_engine, Precision};
use slipfront::Model;

#[test]
fn all_cases_pass_on_cpu_f64() {
    let f = |m: &Model| cpu_engine(m, Precision::F64, 1);
    let r = run_all(&f).unwrap();
    assert_eq!(failures(&r), Vec::<String>::new());
    assert!(r.len() >= 17);
}

#[test]
fn all_cases_pass_on_cpu_f32() {
    let f = |m: &Model| cpu_engine(m, Precision::F32, 1);
    let r = run_all(&f).unwrap();
    assert_eq!(failures(&r), Vec::<String>::new());
}

fn failed_names(perturb: impl Fn(&mut Model)) -> Vec<String> {
    let f = |m: &Model| {
        let mut m = m.clone();
        perturb(&mut m);
        cpu_engine(&m, Precision::F64, 1)
    };
    run_all(&f)
        .unwrap()
        .into_iter()
        .filter(|r| !r.pass)
        .map(|r| r.name)
        .collect()
}

#[test]
fn negative_control_heavier_blocks_fail_the_wave_speed_cases() {
    // 5% more mass: waves 2.4% slower, past the 2% tolerance.
    let failed = failed_names(|m| m.mass *= 1.05);
    assert!(
        failed.iter().any(|n| n.starts_with("p_wave_speed_113")),
        "{failed:?}"
    );
    assert!(
        failed.iter().any(|n| n.starts_with("s_wave_speed_113")),
        "{failed:?}"
    );
}

#[test]
fn negative_control_stiffer_springs_fail_the_elastic_case() {
    let failed = failed_names(|m| {
        m.k *= 1.02;
        m.k_diag *= 1.02;
    });
    assert!(
        failed.contains(&"static_youngs_modulus".to_string()),
        "{failed:?}"
    );
}

#[test]
fn negative_control_changed_friction_fails_coulomb_and_drag_cases() {
    let failed = failed_names(|m| m.mu_d *= 1.05);
    assert!(
        failed.iter().any(|n| n.starts_with("coulomb_block_error")),
        "{failed:?}"
    );
    assert!(
        failed.iter().any(|n| n.starts_with("junction_drag")),
        "{failed:?}"
    );
}

#[test]
fn negative_control_another_seed_fails_the_engine_draw_case() {
    let failed = failed_names(|m| m.seed ^= 1);
    assert!(
        failed.contains(&"rng_engine_draws_match_counter".to_string()),
        "{failed:?}"
    );
}

/// The rate-and-state cases alone, printed (also run by `run_all`).
#[test]
fn rate_state_cases_pass_on_cpu_f64_and_f32() {
    use slipfront::app::verify::rate_state::rate_state_cases;
    for precision in [Precision::F64, Precision::F32] {
        let f = |m: &Model| cpu_engine(m, precision, 1);
        let r = rate_state_cases(&f).unwrap();
        for c in &r {
            println!(
                "{precision:?} {}: {} vs {}",
                c.name,
                c.measured,
                c.requirement()
            );
        }
        assert_eq!(failures(&r), Vec::<String>::new(), "{precision:?}");
    }
}

/// A law changed by 10% in b, in a, or in Dc is flagged by the cases that
/// measure it: the steady friction and its slope a − b, the direct effect,
/// the evolution distance.
#[test]
fn negative_controls_changed_law_parameters_fail_the_rate_state_cases() {
    use slipfront::app::verify::rate_state::rate_state_cases;
    use slipfront::model::scenario::RateStateTable;
    let failed = |perturb: fn(&mut RateStateTable)| -> Vec<String> {
        let f = |m: &Model| {
            let mut m = m.clone();
            perturb(
                m.law_tables
                    .rate_state
                    .as_mut()
                    .expect("a rate-and-state scene"),
            );
            cpu_engine(&m, Precision::F64, 1)
        };
        rate_state_cases(&f)
            .unwrap()
            .into_iter()
            .filter(|r| !r.pass)
            .map(|r| r.name)
            .collect()
    };
    let b = failed(|r| r.evolution_effect *= 1.1);
    for name in [
        "rate_state_steady_friction_rel_error",
        "rate_state_steady_slope_a_minus_b",
    ] {
        assert!(b.contains(&name.to_string()), "b: {b:?}");
    }
    let a = failed(|r| r.direct_effect *= 1.1);
    assert!(
        a.contains(&"rate_state_direct_effect_a".to_string()),
        "a: {a:?}"
    );
    let dc = failed(|r| r.characteristic_slip *= 1.1);
    assert!(
        dc.contains(&"rate_state_evolution_distance_dc".to_string()),
        "Dc: {dc:?}"
    );
}
