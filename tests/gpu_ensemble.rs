//! GPU ensembles (many scenes per dispatch) against the same scenes run one
//! at a time on the GPU engine, on whatever adapter is present (lavapipe in
//! CI). These tests fail, never skip, when no adapter exists.

use slipfront::app::verify::STICK_SLIP_WINDOW;
use slipfront::engines::gpu::ensemble::{incompatibility, GpuEnsemble};
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuPath};
use slipfront::engines::SamplePlan;
use slipfront::io::compare::{compare_snapshots, fields_over};
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Engine, EngineError, Model, Snapshot};

#[path = "support/ensemble_records.rs"]
mod ensemble_records;
use ensemble_records::ensemble_and_solo_records;
// Only the 257 × 65 scene's keys.
#[allow(dead_code)]
#[path = "support/record_twins.rs"]
mod record_twins;
use record_twins::large_lattice_keys;

fn model(extra: &[&str]) -> Model {
    let mut set: Vec<String> = slipfront::app::verify::SMALL_SCENE
        .iter()
        .map(|s| s.to_string())
        .collect();
    set.extend(STICK_SLIP_WINDOW.iter().map(|s| s.to_string()));
    set.extend(extra.iter().map(|s| s.to_string()));
    let s = Scenario::parse(DEFAULT_SCENARIO, "test", &set).unwrap();
    Model::from_scenario(&s, true).unwrap()
}

fn options(path: GpuPath) -> GpuOptions {
    GpuOptions {
        path,
        ..GpuOptions::default()
    }
}

fn solo(m: &Model, path: GpuPath, steps: u64) -> Result<Snapshot, EngineError> {
    solo_with(m, options(path), steps)
}

fn solo_with(m: &Model, opts: GpuOptions, steps: u64) -> Result<Snapshot, EngineError> {
    let mut g = GpuEngine::with_options(m, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"));
    advance_to(&mut g, steps)?;
    g.snapshot()
}

fn ensemble(models: &[Model], path: GpuPath) -> GpuEnsemble {
    ensemble_with(models, options(path))
}

fn ensemble_with(models: &[Model], opts: GpuOptions) -> GpuEnsemble {
    GpuEnsemble::new(models, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

/// The persistent kernel with `scenes` scenes side by side in a workgroup
/// of `threads` threads.
fn grouped(threads: u32, scenes: u32) -> GpuOptions {
    GpuOptions {
        persistent_threads: Some(threads),
        group_scenes: scenes,
        ..options(GpuPath::Persistent)
    }
}

/// Three scenes that differ in a load, a friction coefficient and the seed.
fn three_scenes() -> Vec<Model> {
    vec![
        model(&[]),
        model(&["friction.static_coefficient=0.404"]),
        model(&["time.seed=7", "loading.normal.force=1800"]),
    ]
}

/// The solo run's result and the ensemble's: the same bits on every
/// kernel. A solo run is an ensemble of one (the same compiled kernels),
/// so this holds by construction on every driver; it failed on NVIDIA
/// while solo runs had a module of their own.
fn same_run(ensemble: &Snapshot, alone: &Snapshot) -> Result<(), String> {
    if ensemble == alone {
        return Ok(());
    }
    let errors = compare_snapshots(ensemble, alone);
    let over = fields_over(&errors, 0.0, 0.0);
    let ruptures = (ensemble.total_ruptures(), alone.total_ruptures());
    Err(format!(
        "not bit for bit: fields {over:?}, ruptures {ruptures:?}"
    ))
}

/// Each scene of an ensemble ends where it ends run alone, on every
/// kernel, through the normal-load phase and into stick-slip; its result
/// does not depend on the other scenes (bit for bit); and a scene compared
/// with another's solo run is flagged (the comparison is not vacuous).
#[test]
fn each_scene_of_an_ensemble_matches_its_solo_run() {
    let models = three_scenes();
    let steps = models[0].prep_steps + 3000;
    for path in [
        GpuPath::OneStep,
        GpuPath::OneStepLanes,
        GpuPath::Persistent,
        GpuPath::Resident,
        GpuPath::Tiled,
    ] {
        let mut e = ensemble(&models, path);
        e.advance(steps).unwrap();
        assert_eq!(e.steps_done(), steps);
        let runs: Vec<Snapshot> = (0..models.len()).map(|k| e.snapshot(k).unwrap()).collect();
        let mut alone_runs = Vec::new();
        for (k, m) in models.iter().enumerate() {
            assert!(e.failure(k).is_none());
            let alone = solo(m, path, steps).unwrap();
            assert!(
                alone.total_ruptures() > 50,
                "{path:?} scene {k}: the window must hold ruptures ({})",
                alone.total_ruptures()
            );
            same_run(&runs[k], &alone).unwrap_or_else(|e| panic!("{path:?} scene {k}: {e}"));
            alone_runs.push(alone);
        }
        // Negative control: scene 1 (μs 1% higher) is not scene 0.
        assert!(same_run(&runs[1], &alone_runs[0]).is_err(), "{path:?}");
    }
}

/// Scenes side by side in one persistent workgroup (two, and four with
/// one absent: three scenes) each end where they end run alone with the
/// same launch and with the persistent kernel's own workgroup, bit for
/// bit, through ruptures: a scene's steps do not depend on the scenes
/// beside it. Control: scene 1 is not scene 0's solo run.
#[test]
fn scenes_side_by_side_in_a_workgroup_match_their_solo_runs() {
    let models = three_scenes();
    let steps = models[0].prep_steps + 3000;
    let alone: Vec<Snapshot> = models
        .iter()
        .map(|m| solo(m, GpuPath::Persistent, steps).unwrap())
        .collect();
    for (threads, scenes) in [(128, 2), (256, 4)] {
        let opts = grouped(threads, scenes);
        let mut e = ensemble_with(&models, opts);
        e.advance(steps).unwrap();
        assert_eq!(e.steps_done(), steps);
        let shape = e.describe();
        assert!(
            shape.contains(&format!("{scenes} scenes a workgroup")),
            "{shape}"
        );
        for (k, m) in models.iter().enumerate() {
            assert!(e.failure(k).is_none());
            assert!(alone[k].total_ruptures() > 50, "scene {k}");
            let run = e.snapshot(k).unwrap();
            same_run(&run, &alone[k])
                .unwrap_or_else(|e| panic!("{scenes} a workgroup, scene {k}: {e}"));
            let grouped_alone = solo_with(m, opts, steps).unwrap();
            same_run(&run, &grouped_alone)
                .unwrap_or_else(|e| panic!("{scenes} a workgroup, scene {k} alone: {e}"));
        }
        assert!(same_run(&e.snapshot(1).unwrap(), &alone[0]).is_err());
    }
}

/// A grouped workgroup's threads take their scene from their subgroup's
/// first thread (so that the compiler keeps its constants in uniform
/// registers): a subgroup that holds two scenes' threads voids the run
/// with an error. Three threads a scene do that on any adapter with
/// subgroups of more than three (lavapipe's hold 8). Control: the same
/// launch without subgroup operations (every lane's sum through storage)
/// runs, each scene bit for bit as alone.
#[test]
fn a_subgroup_holding_two_scenes_voids_the_run() {
    let models = three_scenes();
    let steps = models[0].prep_steps + 200;
    let straddled = grouped(12, 4);
    let mut e = ensemble_with(&models, straddled);
    let err = e.advance(steps).unwrap_err().to_string();
    assert!(
        err.contains("subgroups held threads of two scenes"),
        "{err}"
    );
    assert!(err.contains("4 scenes of 3 threads"), "{err}");
    let plain = GpuOptions {
        lane_shuffle: false,
        ..straddled
    };
    let mut e = ensemble_with(&models, plain);
    e.advance(steps).unwrap();
    for (k, m) in models.iter().enumerate() {
        let alone = solo(m, GpuPath::Persistent, steps).unwrap();
        same_run(&e.snapshot(k).unwrap(), &alone).unwrap_or_else(|e| panic!("scene {k}: {e}"));
    }
}

/// The scenes a workgroup must split its threads evenly, and only the
/// persistent kernel steps scenes side by side.
#[test]
fn scenes_side_by_side_are_refused_where_they_cannot_be() {
    let m = model(&[]);
    let err = |opts: GpuOptions| match GpuEngine::with_options(&m, opts) {
        Ok(_) => panic!("{opts:?} must be refused"),
        Err(e) => e.to_string(),
    };
    let text = err(grouped(90, 4));
    assert!(text.contains("must split evenly"), "{text}");
    let text = err(grouped(128, 3));
    assert!(text.contains("must be one of"), "{text}");
    let text = err(GpuOptions {
        group_scenes: 2,
        ..options(GpuPath::Resident)
    });
    assert!(text.contains("--gpu-group-scenes 2"), "{text}");
    // `auto` takes it: only a persistent launch groups scenes.
    GpuEngine::with_options(
        &m,
        GpuOptions {
            group_scenes: 2,
            ..options(GpuPath::Auto)
        },
    )
    .expect("auto takes the option");
}

/// A state saved from one scene and loaded into another at the same step
/// makes that scene continue exactly as the first.
#[test]
fn a_scene_state_moves_between_slots_of_an_ensemble() {
    let models = vec![model(&[]), model(&[])];
    let mut e = ensemble(&models, GpuPath::OneStep);
    let start = models[0].prep_steps + 500;
    e.advance(start).unwrap();
    // Disturb slot 1, then give it slot 0's state back.
    let mut moved = e.save_state(0).unwrap();
    let mut disturbed = moved.clone();
    disturbed.vel[40][0] += 1e-3;
    e.load_state(1, &disturbed).unwrap();
    e.advance(200).unwrap();
    assert!(e.snapshot(0).unwrap() != e.snapshot(1).unwrap());
    moved = e.save_state(0).unwrap();
    e.load_state(1, &moved).unwrap();
    e.advance(800).unwrap();
    assert!(e.snapshot(0).unwrap() == e.snapshot(1).unwrap());
    // A state of another step cannot join.
    let old = GpuEngine::new(&models[0]).unwrap().save_state().unwrap();
    let err = e.load_state(1, &old).unwrap_err().to_string();
    assert!(err.contains("cannot join an ensemble"), "{err}");
}

/// A scene that blows up stops alone, with its step and block; the others
/// go on and still match their solo runs: also the scene beside it in a
/// persistent workgroup of two.
#[test]
fn a_blow_up_stops_only_its_scene() {
    let stable = model(&["time.end=1e-3"]);
    let unstable = model(&[
        "time.end=1e-3",
        "friction.junctions.stiffness_coefficient=39.2e17",
    ]);
    let models = vec![stable.clone(), unstable.clone(), stable.clone()];
    let end = stable.total_steps();
    for opts in [
        options(GpuPath::OneStep),
        options(GpuPath::Persistent),
        options(GpuPath::Resident),
        grouped(128, 2),
    ] {
        let path = opts.path;
        let Err(EngineError::BlowUp { step: alone_at, .. }) = solo_with(&unstable, opts, end)
        else {
            panic!("{path:?}: the unstable scene must blow up alone");
        };
        let mut e = ensemble_with(&models, opts);
        e.advance(end).unwrap();
        let Some(EngineError::BlowUp { step, iz, .. }) = e.failure(1) else {
            panic!("{path:?}: scene 1 must have blown up");
        };
        assert_eq!(*step, alone_at, "{path:?}");
        assert!(*iz <= 1, "{path:?}");
        let text = e.failure(1).unwrap().to_string();
        assert!(text.contains("blew up at step"), "{text}");
        let alone = solo(&stable, path, end).unwrap();
        for k in [0, 2] {
            assert!(e.failure(k).is_none());
            same_run(&e.snapshot(k).unwrap(), &alone)
                .unwrap_or_else(|e| panic!("{path:?} scene {k}: {e}"));
        }
    }
}

#[test]
fn scenes_of_different_shapes_cannot_share_an_ensemble() {
    let a = model(&[]);
    let b = model(&["geometry.nx=30", "geometry.length=0.0725"]);
    let why = incompatibility(&[a.clone(), b.clone()]).unwrap();
    assert!(
        why.contains("scene 1") && why.contains("lattice size"),
        "{why}"
    );
    let Err(err) = GpuEnsemble::new(&[a.clone(), b], GpuOptions::default()) else {
        panic!("must refuse");
    };
    assert!(
        err.to_string().contains("cannot share one ensemble"),
        "{err}"
    );
    let c = model(&["loading.normal.ramp_time=3e-4"]);
    let why = incompatibility(&[a.clone(), c]).unwrap();
    assert!(why.contains("normal-load phase"), "{why}");
    // Negative control: scenes that differ in run constants only are fine.
    assert_eq!(incompatibility(&three_scenes()), None);
}

/// An ensemble holds every scene's part of a buffer in one storage
/// binding: `scenes_that_fit` is the most scenes an adapter's binding limit
/// takes, which is what a sweep caps its ensembles at. Here the limit is
/// lowered to hold three scenes: three build, four are refused naming the
/// buffer (the control: the cap is the build's own bound).
#[test]
fn an_ensemble_holds_as_many_scenes_as_one_binding_takes() {
    let ctx = slipfront::engines::gpu::context::shared()
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"));
    let m = model(&[]);
    let real = GpuEngine::<f32>::scenes_that_fit(&m, &ctx.limits);
    assert!(real >= 256, "a small scene: {real} scenes per binding");
    let fit_at = |bytes: u64| {
        let mut limits = ctx.limits.clone();
        limits.max_storage_buffer_binding_size = bytes;
        GpuEngine::<f32>::scenes_that_fit(&m, &limits)
    };
    // The smallest binding that holds three scenes (the count grows with
    // the bytes).
    let (mut lo, mut hi) = (0u64, 1u64 << 30);
    while lo + 1 < hi {
        let mid = (lo + hi) / 2;
        if fit_at(mid) >= 3 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let three = hi;
    assert_eq!((fit_at(three - 1), fit_at(three)), (2, 3));
    let mut tight = ctx.clone();
    tight.limits.max_storage_buffer_binding_size = three;
    let scenes = |n: usize| vec![m.clone(); n];
    GpuEnsemble::with_context(&scenes(3), tight.clone(), GpuOptions::default())
        .expect("three scenes fit");
    let Err(err) = GpuEnsemble::with_context(&scenes(4), tight.clone(), GpuOptions::default())
    else {
        panic!("four scenes must not fit a binding sized for three");
    };
    assert!(
        err.to_string().contains("buffer of 4 scenes needs"),
        "{err}"
    );
    // A scene alone never counts as less than one.
    assert_eq!(fit_at(16), 1);
}

/// The small triggered scene whose fast interface cadence switches on and
/// off within the first 0.3 ms of driving.
fn triggered(extra: &[&str]) -> Model {
    let s = slipfront::app::verify::small_triggered_scene(extra).unwrap();
    Model::from_scenario(&s, false).unwrap()
}

fn sample_plan(m: &Model, fast: u64) -> SamplePlan {
    let every = |t: f64| ((t / m.dt).round() as u64).max(1);
    SamplePlan {
        prep_steps: m.prep_steps,
        every_global: every(1e-5),
        every_interface: every(2e-5),
        every_bulk: every(5e-5),
        every_fast: fast,
        fast_slip_speed: 1e-3,
        fast: false,
    }
}

/// Every scene of an ensemble records its output samples on the device,
/// all scenes in one dispatch per sample: each scene's samples are bit for
/// bit those of its solo run recording on the device, on every kernel,
/// with the fast cadence switching per scene. Controls: scene 1's samples
/// are not scene 0's solo samples, and a plan with other cadences is
/// refused (that scene would take host snapshots).
#[test]
fn an_ensemble_records_every_scene_on_the_device_as_its_solo_run() {
    let models = vec![
        triggered(&[]),
        triggered(&["friction.static_coefficient=0.45"]),
        triggered(&["time.seed=11", "loading.normal.force=1800"]),
    ];
    let m = &models[0];
    let plan = sample_plan(m, ((1e-6 / m.dt).round() as u64).max(1));
    // Through the normal-load phase, then 0.3 ms of driving in chunks.
    let chunks = [m.prep_steps, 700, 1300, 1];
    // One-step-lanes records through the one-step kernel's output
    // dispatches; its own layout is held on the large lattice below.
    // The persistent kernel also with two scenes side by side in a
    // workgroup: each reduces its samples in its own slots.
    for opts in [
        options(GpuPath::OneStep),
        options(GpuPath::Persistent),
        options(GpuPath::Resident),
        options(GpuPath::Tiled),
        grouped(128, 2),
    ] {
        let path = opts.path;
        let records = ensemble_and_solo_records::<f32>(&models, opts, &plan, &chunks, |e| {
            let other = SamplePlan {
                every_bulk: plan.every_bulk + 1,
                ..plan
            };
            assert!(!e.record_samples(1, &other).unwrap(), "{path:?}");
            assert!(e.record_samples(1, &plan).unwrap(), "{path:?}");
        });
        let got = &records.ensemble;
        assert!(
            records.output_dispatches > 0
                || matches!(path, GpuPath::Persistent | GpuPath::Resident)
        );
        for (k, alone) in records.solo.iter().enumerate() {
            let fast = alone.iter().filter(|s| s.interface.is_some()).count();
            assert!(
                k > 0 || fast > 2 * alone.len() / 3,
                "{path:?} scene {k}: the fast cadence must switch on ({fast} rows in {} samples)",
                alone.len()
            );
            assert!(alone.iter().any(|s| s.bulk.is_some()));
            assert_eq!(got[k].len(), alone.len(), "{path:?} scene {k}");
            for (a, b) in got[k].iter().zip(alone) {
                assert!(
                    a == b,
                    "{path:?} scene {k}: sample of step {} differs",
                    b.step
                );
            }
        }
        assert!(
            got[1] != records.solo[0],
            "{path:?}: scene 1 is not scene 0"
        );
    }
}

/// On a large lattice (more than 16,384 blocks, 262 partials a sample and
/// scene on one-step), the step dispatch of a sample writes every scene's partials
/// (record_step.wgsl) and the batch's finish adds them: each scene's
/// samples are still bit for bit its solo run's, on both one-step kernels
/// (one-step-lanes lays out its workgroups otherwise), samples with and
/// without a bulk field among them. Control: scene 1's samples are not
/// scene 0's.
#[test]
fn a_large_lattice_ensemble_records_every_scene_as_its_solo_run() {
    let large = |extra: &[&str]| {
        let mut set = large_lattice_keys();
        set.extend(["loading.drive.velocity=2", "time.end=3e-5"].map(String::from));
        set.extend(extra.iter().map(|s| s.to_string()));
        let s = Scenario::parse(DEFAULT_SCENARIO, "large", &set).unwrap();
        Model::from_scenario(&s, true).unwrap()
    };
    let models = vec![
        large(&[]),
        large(&["time.seed=7", "loading.normal.force=1800"]),
    ];
    let m = &models[0];
    let every = |t: f64| ((t / m.dt).round() as u64).max(1);
    let plan = SamplePlan {
        every_global: every(5e-6),
        every_interface: every(1e-5),
        every_bulk: every(2e-5),
        ..sample_plan(m, every(1e-6))
    };
    let chunks = [m.prep_steps, m.total_steps() - m.prep_steps];
    for path in [GpuPath::OneStep, GpuPath::OneStepLanes] {
        let records =
            ensemble_and_solo_records::<f32>(&models, options(path), &plan, &chunks, |_| {});
        for (k, (got, alone)) in records.ensemble.iter().zip(&records.solo).enumerate() {
            assert!(
                alone.len() >= 6,
                "{path:?} scene {k}: {} samples",
                alone.len()
            );
            assert!(alone.iter().any(|s| s.bulk.is_some()));
            assert!(alone.iter().any(|s| s.bulk.is_none()));
            assert!(got == alone, "{path:?} scene {k}: the samples differ");
        }
        assert!(
            records.ensemble[1] != records.solo[0],
            "{path:?}: scene 1 is not scene 0"
        );
    }
}

/// A lockstep scene asks its runner for fixed long chunks (its advance
/// waits for every other scene, so its wall time cannot size them: sized
/// by it, a 256-scene ensemble on an H200 shrank them to one step each);
/// a solo engine sizes its own.
#[test]
fn lockstep_scenes_ask_for_fixed_chunks() {
    use slipfront::engines::gpu::lockstep::{Lockstep, LOCKSTEP_CHUNK};
    let scenes = Lockstep::split(ensemble(&three_scenes()[..2], GpuPath::OneStep));
    for s in &scenes {
        assert_eq!(s.fixed_chunk(), Some(LOCKSTEP_CHUNK));
    }
    let alone = GpuEngine::with_options(&three_scenes()[0], options(GpuPath::OneStep)).unwrap();
    assert_eq!(alone.fixed_chunk(), None);
}
