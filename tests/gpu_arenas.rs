//! The engine's storage arrays in arenas (`GpuOptions::pack_arrays`, the
//! default: ranges of a few buffers) against a buffer each (as before
//! session 55): the same arrays and the same kernels, so the same bits, on
//! every kernel, alone and in an ensemble, with the samples recorded on the
//! device. These tests fail, never skip, when no adapter exists (lavapipe
//! in CI).

use slipfront::engines::gpu::ensemble::GpuEnsemble;
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuPath};
use slipfront::engines::{Sample, SamplePlan};
use slipfront::{advance_to, Engine, Model, Scenario, Snapshot};

#[path = "support/record_twins.rs"]
#[allow(dead_code)] // this file uses its plan alone
mod record_twins;

/// The small lattice (29 × 16) with a triggered front: junctions break and
/// re-pin, and the fast interface cadence switches on and off.
fn triggered(extra: &[&str]) -> (Model, SamplePlan) {
    let s: Scenario = slipfront::app::verify::small_triggered_scene(extra).unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    let plan = record_twins::plan(&m, &s);
    (m, plan)
}

fn options(path: GpuPath, pack_arrays: bool) -> GpuOptions {
    GpuOptions {
        path,
        pack_arrays,
        ..GpuOptions::default()
    }
}

/// The run of `m` to its end on `path`, its samples recorded on the device.
fn solo(m: &Model, plan: &SamplePlan, path: GpuPath, pack_arrays: bool) -> (Snapshot, Vec<Sample>) {
    let mut g = GpuEngine::with_options(m, options(path, pack_arrays))
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"));
    assert!(
        g.record_samples(plan).unwrap(),
        "{path:?} records on the device"
    );
    advance_to(&mut g, m.total_steps()).unwrap();
    let samples = g.take_samples();
    (g.snapshot().unwrap(), samples)
}

#[test]
fn arrays_in_arenas_give_the_bits_of_a_buffer_each_on_every_kernel() {
    let (m, plan) = triggered(&["time.end=4e-4"]);
    for path in GpuPath::KERNELS {
        let packed = solo(&m, &plan, path, true);
        let apart = solo(&m, &plan, path, false);
        assert!(
            packed.0.total_ruptures() > 0,
            "{path:?}: junctions must break"
        );
        assert!(packed.1.len() > 10, "{path:?}: {} samples", packed.1.len());
        assert!(packed.0 == apart.0, "{path:?}: the states differ");
        assert!(packed.1 == apart.1, "{path:?}: the samples differ");
    }
    // Control: a change of 1e-6 in the mass shows in both comparisons.
    let (mut heavier, _) = triggered(&["time.end=4e-4"]);
    heavier.mass *= 1.0 + 1e-6;
    let reference = solo(&m, &plan, GpuPath::OneStep, true);
    let control = solo(&heavier, &plan, GpuPath::OneStep, true);
    assert!(control.0 != reference.0, "control: states");
    assert!(control.1 != reference.1, "control: samples");
}

/// Each scene of an ensemble (its slices at offsets inside the arenas'
/// regions) steps and records as with a buffer per array.
#[test]
fn each_scene_of_an_ensemble_in_arenas_has_the_bits_of_a_buffer_each() {
    let models: Vec<(Model, SamplePlan)> = (1..=3)
        .map(|seed| triggered(&["time.end=3e-4", &format!("time.seed={seed}")]))
        .collect();
    let run = |path: GpuPath, pack_arrays: bool| {
        let ms: Vec<Model> = models.iter().map(|(m, _)| m.clone()).collect();
        let mut e = GpuEnsemble::new(&ms, options(path, pack_arrays))
            .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"));
        for (k, (_, plan)) in models.iter().enumerate() {
            assert!(e.record_samples(k, plan).unwrap());
        }
        e.advance(ms[0].total_steps()).unwrap();
        (0..ms.len())
            .map(|k| (e.snapshot(k).unwrap(), e.take_samples(k)))
            .collect::<Vec<_>>()
    };
    for path in [GpuPath::OneStepLanes, GpuPath::Tiled] {
        let packed = run(path, true);
        let apart = run(path, false);
        // The scenes differ from each other: a scene read at another's
        // offset would show.
        assert!(packed[0].0 != packed[1].0 && packed[1].0 != packed[2].0);
        for (k, (a, b)) in packed.iter().zip(&apart).enumerate() {
            assert!(a.0 == b.0, "{path:?} scene {k}: the states differ");
            assert!(a.1 == b.1, "{path:?} scene {k}: the samples differ");
        }
    }
}
