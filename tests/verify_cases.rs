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
