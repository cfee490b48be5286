//! CPU engine properties: threads do not change results, blow-ups stop with
//! the step, time and block, the normal load is carried by the foundation.

use slipfront::engines::backend::{cpu_engine, Precision};
use slipfront::engines::cpu::CpuEngine;
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Engine, EngineError, Model};

fn model(set: &[&str], allow_unstable: bool) -> Model {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let s = Scenario::parse(DEFAULT_SCENARIO, "test", &set).unwrap();
    Model::from_scenario(&s, allow_unstable).unwrap()
}

#[test]
fn two_threads_give_bit_identical_results() {
    // 129 × 65 = 8385 blocks, above the parallel threshold; short relaxation,
    // then driving hard enough for ruptures.
    let m = model(
        &[
            "geometry.nx=129",
            "geometry.nz=65",
            "geometry.height=0.073125",
            "geometry.length=0.14625",
            "loading.normal.ramp_time=2e-5",
            "loading.normal.relax_time=2e-5",
            "loading.drive.velocity=2.0",
        ],
        false,
    );
    let mut one = CpuEngine::<f64>::new(&m, 1).unwrap();
    let mut two = CpuEngine::<f64>::new(&m, 2).unwrap();
    assert_eq!(one.threads(), 1);
    assert_eq!(two.threads(), 2);
    let target = m.prep_steps + 400;
    advance_to(&mut one, target).unwrap();
    advance_to(&mut two, target).unwrap();
    let (a, b) = (one.snapshot().unwrap(), two.snapshot().unwrap());
    assert!(a.total_ruptures() > 0, "the comparison must cover ruptures");
    assert_eq!(a, b);
}

#[test]
fn unstable_step_stops_with_step_time_and_block() {
    let m = model(&["time.dt_fraction=0.2"], true);
    let mut e = cpu_engine(&m, Precision::F64, 1).unwrap();
    let err = advance_to(e.as_mut(), m.total_steps()).unwrap_err();
    let EngineError::BlowUp { step, ix, iz, .. } = err else {
        panic!("expected a blow-up, got {err}")
    };
    assert!(step > 0 && ix < m.nx && iz < m.nz);
    let text = err_text(&m);
    assert!(
        text.contains("blew up at step") && text.contains("block (ix ="),
        "{text}"
    );
}

fn err_text(m: &Model) -> String {
    let mut e = cpu_engine(m, Precision::F64, 1).unwrap();
    advance_to(e.as_mut(), m.total_steps())
        .unwrap_err()
        .to_string()
}

#[test]
fn foundation_carries_the_normal_load_after_relaxation() {
    let m = model(&["time.end=0"], false);
    let mut e = cpu_engine(&m, Precision::F64, 1).unwrap();
    advance_to(e.as_mut(), m.total_steps()).unwrap();
    let s = e.snapshot().unwrap();
    let carried: f64 = s.normal.iter().sum();
    assert!((carried - 1920.0).abs() < 1e-3 * 1920.0, "{carried}");
    assert!(s.kinetic_energy(m.mass) < 1e-9, "not at rest");
    // No junction broke while the load was applied.
    assert_eq!(s.total_ruptures(), 0);
}

#[test]
fn f32_tracks_f64_on_the_table_s1_scene() {
    let m = model(&["loading.drive.velocity=0.5"], false);
    let target = m.prep_steps + 2000;
    let mut a = cpu_engine(&m, Precision::F64, 1).unwrap();
    let mut b = cpu_engine(&m, Precision::F32, 1).unwrap();
    advance_to(a.as_mut(), target).unwrap();
    advance_to(b.as_mut(), target).unwrap();
    let (a, b) = (a.snapshot().unwrap(), b.snapshot().unwrap());
    let scale = a
        .disp
        .iter()
        .map(|u| u[0].abs().max(u[1].abs()))
        .fold(0.0, f64::max);
    let err = a
        .disp
        .iter()
        .zip(&b.disp)
        .map(|(x, y)| (x[0] - y[0]).abs().max((x[1] - y[1]).abs()))
        .fold(0.0, f64::max);
    assert!(
        err < 1e-4 * scale,
        "max |u64 - u32| = {err:e}, scale {scale:e}"
    );
}

#[test]
fn trigger_breaks_the_strip_at_once_and_holds_the_rest() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/triggered_front.toml"
    );
    let s = Scenario::load(std::path::Path::new(path), &[]).unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    let mut e = cpu_engine(&m, Precision::F64, 0).unwrap();
    advance_to(e.as_mut(), m.prep_steps + 1).unwrap();
    let snap = e.snapshot().unwrap();
    let ns = m.junctions.unwrap().count;
    let strip = m.trigger.unwrap().strip_blocks;
    // Every junction of a loaded strip block broke on the first step (the
    // top-row prestress force lifts the trailing corner off the track: with
    // p = 0 there is nothing to break); none far ahead of the strip did.
    for ix in 0..strip {
        let broken = snap.ruptures[ix * ns..(ix + 1) * ns]
            .iter()
            .filter(|&&r| r == 1)
            .count();
        let expected = if snap.normal[ix] > 0.0 { ns } else { 0 };
        assert_eq!(broken, expected, "block {ix}, normal {}", snap.normal[ix]);
    }
    assert!(snap.normal[strip - 1] > 0.0);
    assert_eq!(snap.ruptures[(m.nx / 2) * ns..].iter().sum::<u32>(), 0);
    // Junction forces away from the strip sit at the prescribed prestress.
    let ix = m.nx / 2;
    let f_n = snap.normal[ix] / ns as f64;
    let mean: f64 = (0..ns)
        .map(|j| {
            let k = ix * ns + j;
            snap.junction_stiffness[k] * (snap.disp[ix][0] - snap.anchor[k]) / f_n
        })
        .sum::<f64>()
        / ns as f64;
    assert!(
        (mean - 0.3).abs() < 0.02,
        "mean junction force ratio {mean}"
    );
}

/// Largest x displacement, relative to the slider's own motion, by which a
/// run started 1 cm along the track differs from the run started at 0
/// (their displacements less the start), after the normal load and 3000
/// steps of driving on the 29 × 16 scene.
fn start_position_error(precision: Precision) -> f64 {
    let run = |position: f64| {
        let mut set = slipfront::app::verify::SMALL_SCENE.to_vec();
        let start = format!("start.position={position}");
        set.push(&start);
        let m = model(&set, false);
        let mut e = cpu_engine(&m, precision, 1).unwrap();
        advance_to(e.as_mut(), m.prep_steps + 3000).unwrap();
        e.snapshot().unwrap()
    };
    let (at_zero, moved) = (run(0.0), run(0.01));
    let scale = at_zero.disp.iter().map(|u| u[0].abs()).fold(0.0, f64::max);
    let worst = at_zero
        .disp
        .iter()
        .zip(&moved.disp)
        .map(|(a, b)| (b[0] - 0.01 - a[0]).abs())
        .fold(0.0, f64::max);
    worst / scale
}

/// The track is uniform: where the slider starts changes nothing in f64 and
/// in mixed f32 (48-bit displacements); plain f32 displacements see it (one
/// ulp of 1 cm is 0.9 nm), the negative control.
#[test]
fn where_the_slider_starts_changes_nothing_unless_displacements_are_plain_f32() {
    let f64_error = start_position_error(Precision::F64);
    let mixed = start_position_error(Precision::F32);
    let plain = start_position_error(Precision::F32Plain);
    println!("relative error: f64 {f64_error:.2e}, mixed f32 {mixed:.2e}, plain f32 {plain:.2e}");
    // Measured: 2.4e-13, 2.2e-9 and 8.9e-5 (plain f32: one ulp of 1 cm
    // against displacements of about 10 µm).
    assert!(f64_error < 1e-10, "{f64_error}");
    assert!(mixed < 1e-6, "{mixed}");
    assert!(plain > 1e-5, "{plain}");
}
