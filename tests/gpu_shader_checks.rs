//! The GPU kernels built without wgpu's run-time checks (the default,
//! `compile::ShaderChecks::Trusted`) against the same kernels with them
//! (`GpuOptions::shader_checks`, `--gpu-shader-checks`): every index of
//! the kernels is in range and every loop ends by construction, so the
//! clamps and loop counters the checks add never change what a kernel
//! computes. These tests fail, never skip, when no adapter exists
//! (lavapipe in CI).

use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuOutput, GpuPath, GpuReal};
use slipfront::engines::Sample;
use slipfront::{advance_to, Engine, Model, Snapshot};

// Only its sample plan.
#[allow(dead_code)]
#[path = "support/record_twins.rs"]
mod record_twins;
use record_twins::plan;

#[path = "support/f64_adapter.rs"]
mod f64_adapter;
use f64_adapter::f64_adapter;

const KERNELS: [GpuPath; 5] = GpuPath::KERNELS;

/// The state at the end and every sample recorded on the device on the
/// way, of `m` on kernel `path` in precision `T`, with or without wgpu's
/// checks.
fn run_in<T: GpuReal>(
    m: &Model,
    plan: &slipfront::engines::SamplePlan,
    path: GpuPath,
    checks: bool,
) -> (Snapshot, Vec<Sample>) {
    let opts = GpuOptions {
        path,
        output: GpuOutput::Device,
        shader_checks: checks,
        ..GpuOptions::default()
    };
    let mut e = GpuEngine::<T>::with_precision(m, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"));
    assert!(
        e.record_samples(plan).unwrap(),
        "{path:?}: records on the device"
    );
    advance_to(&mut e, m.total_steps() - 1).unwrap();
    e.settle().unwrap();
    let samples = e.take_samples();
    (e.snapshot().unwrap(), samples)
}

/// `m` on kernel `path` in `T` gives the same bits of state and of every
/// device record with and without the checks, through a front that broke
/// junctions and recorded samples (else the comparison holds vacuously).
fn assert_same_both_ways<T: GpuReal>(
    m: &Model,
    plan: &slipfront::engines::SamplePlan,
    path: GpuPath,
) {
    let (trusted, trusted_samples) = run_in::<T>(m, plan, path, false);
    let (checked, checked_samples) = run_in::<T>(m, plan, path, true);
    println!(
        "{path:?}, {}: {} ruptures, {} samples",
        T::NAME,
        trusted.total_ruptures(),
        trusted_samples.len()
    );
    assert!(trusted.total_ruptures() > 100, "{path:?}: no front");
    assert!(trusted_samples.len() > 100, "{path:?}: too few samples");
    assert!(trusted == checked, "{path:?}: the checks changed the state");
    assert!(
        trusted_samples == checked_samples,
        "{path:?}: the checks changed the records"
    );
}

/// The small triggered front (29 × 16, a front across the interface within
/// 0.3 ms, the fast cadence switching on and off), through 0.6 ms on every
/// kernel: the same bits of state and of every device record with and
/// without the checks. The front must break junctions and record samples,
/// or the comparison would hold vacuously; a normal load 1e-6 larger
/// (above f32 rounding) is flagged.
#[test]
fn kernels_without_run_time_checks_give_the_bits_of_checked_ones() {
    let s = slipfront::app::verify::small_triggered_scene(&["time.end=6e-4"]).unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    let plan = plan(&m, &s);
    for path in KERNELS {
        assert_same_both_ways::<f32>(&m, &plan, path);
    }
    // Control: the same comparison sees a normal load 1e-6 larger.
    let s = slipfront::app::verify::small_triggered_scene(&[
        "time.end=6e-4",
        "loading.normal.force=1920.002",
    ])
    .unwrap();
    let heavier = Model::from_scenario(&s, false).unwrap();
    let (base, base_samples) = run_in::<f32>(&m, &plan, GpuPath::OneStep, false);
    let (other, other_samples) = run_in::<f32>(&heavier, &plan, GpuPath::OneStep, false);
    assert!(base != other, "control: state");
    assert!(base_samples != other_samples, "control: records");
}

/// The f64 kernels (coordinates in f64, the RNG's own logarithm and cosine
/// with their bounded loops, `coord_f64.wgsl`) on the one-step and
/// persistent kernels: the same bits with and without the checks. Adapters
/// without SHADER_F64 run mixed f32 only; lavapipe (CI) has it.
#[test]
fn f64_kernels_without_run_time_checks_give_the_bits_of_checked_ones() {
    if !f64_adapter() {
        return;
    }
    let s = slipfront::app::verify::small_triggered_scene(&["time.end=4e-4"]).unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    let plan = plan(&m, &s);
    for path in [GpuPath::OneStep, GpuPath::Persistent] {
        assert_same_both_ways::<f64>(&m, &plan, path);
    }
}
