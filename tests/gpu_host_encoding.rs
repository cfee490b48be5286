//! How the host encodes the dispatches, which changes what a dispatch
//! costs the host and nothing the kernels compute:
//! - the storage arrays in arenas (`GpuOptions::pack_arrays`, the default:
//!   ranges of a few buffers) against a buffer each (as before session 55);
//! - each dispatch's step offset as an immediate
//!   (`GpuOptions::step_immediates`, the default where the adapter has
//!   them, as lavapipe does) against a dynamic offset into a table (as
//!   before session 56).
//!
//! The same arrays, the same kernels and the same step offsets, so the
//! same bits, on every kernel, alone and in an ensemble, with the samples
//! recorded on the device. These tests fail, never skip, when no adapter
//! exists (lavapipe in CI).

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

/// How the host encodes a dispatch.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Encoding {
    pack_arrays: bool,
    step_immediates: bool,
}

/// The default (arrays in arenas, the step as an immediate), and each
/// way it replaced.
const DEFAULT: Encoding = Encoding {
    pack_arrays: true,
    step_immediates: true,
};
const OLDER: [Encoding; 2] = [
    Encoding {
        pack_arrays: false,
        step_immediates: true,
    },
    Encoding {
        pack_arrays: true,
        step_immediates: false,
    },
];

fn options(path: GpuPath, encoding: Encoding) -> GpuOptions {
    GpuOptions {
        path,
        pack_arrays: encoding.pack_arrays,
        step_immediates: encoding.step_immediates,
        ..GpuOptions::default()
    }
}

/// The run of `m` to its end on `path`, its samples recorded on the device.
fn solo(
    m: &Model,
    plan: &SamplePlan,
    path: GpuPath,
    encoding: Encoding,
) -> (Snapshot, Vec<Sample>) {
    let mut g = GpuEngine::with_options(m, options(path, encoding))
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"));
    assert!(
        g.record_samples(plan).unwrap(),
        "{path:?} records on the device"
    );
    // The step offset goes as asked: lavapipe has immediates, so a run
    // that asked for them and got a dynamic offset would compare a way
    // with itself.
    for source in g.kernel_sources() {
        assert_eq!(
            source.build.step_immediate, encoding.step_immediates,
            "{path:?} {}",
            source.entry
        );
        assert_eq!(
            source.source.contains("var<immediate> step_offset"),
            encoding.step_immediates
        );
    }
    advance_to(&mut g, m.total_steps()).unwrap();
    let samples = g.take_samples();
    (g.snapshot().unwrap(), samples)
}

#[test]
fn each_way_to_encode_a_dispatch_gives_the_same_bits_on_every_kernel() {
    let (m, plan) = triggered(&["time.end=4e-4"]);
    for path in GpuPath::KERNELS {
        let default = solo(&m, &plan, path, DEFAULT);
        assert!(
            default.0.total_ruptures() > 0,
            "{path:?}: junctions must break"
        );
        assert!(
            default.1.len() > 10,
            "{path:?}: {} samples",
            default.1.len()
        );
        for older in OLDER {
            let other = solo(&m, &plan, path, older);
            assert!(
                default.0 == other.0,
                "{path:?} {older:?}: the states differ"
            );
            assert!(
                default.1 == other.1,
                "{path:?} {older:?}: the samples differ"
            );
        }
    }
    // Control: a change of 1e-6 in the mass shows in both comparisons.
    let (mut heavier, _) = triggered(&["time.end=4e-4"]);
    heavier.mass *= 1.0 + 1e-6;
    let reference = solo(&m, &plan, GpuPath::OneStep, DEFAULT);
    let control = solo(&heavier, &plan, GpuPath::OneStep, DEFAULT);
    assert!(control.0 != reference.0, "control: states");
    assert!(control.1 != reference.1, "control: samples");
}

/// Each scene of an ensemble (its slices at offsets inside the arenas'
/// regions, its step offsets shared) steps and records as with a buffer
/// per array and with dynamic offsets.
#[test]
fn each_scene_of_an_ensemble_has_the_same_bits_each_way() {
    let models: Vec<(Model, SamplePlan)> = (1..=3)
        .map(|seed| triggered(&["time.end=3e-4", &format!("time.seed={seed}")]))
        .collect();
    let run = |path: GpuPath, encoding: Encoding| {
        let ms: Vec<Model> = models.iter().map(|(m, _)| m.clone()).collect();
        let mut e = GpuEnsemble::new(&ms, options(path, encoding))
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
        let default = run(path, DEFAULT);
        // The scenes differ from each other: a scene read at another's
        // offset would show.
        assert!(default[0].0 != default[1].0 && default[1].0 != default[2].0);
        for older in OLDER {
            let other = run(path, older);
            for (k, (a, b)) in default.iter().zip(&other).enumerate() {
                assert!(
                    a.0 == b.0,
                    "{path:?} {older:?} scene {k}: the states differ"
                );
                assert!(
                    a.1 == b.1,
                    "{path:?} {older:?} scene {k}: the samples differ"
                );
            }
        }
    }
}
