//! The GPU engine in f64 (`--precision f64 --backend gpu`) against the CPU
//! reference engine in f64, on whatever adapter is present (lavapipe in
//! CI, which has SHADER_F64). These tests fail, never skip, when no
//! adapter (or no f64 on it) exists.

use slipfront::app::verify::STICK_SLIP_WINDOW;
use slipfront::engines::cpu::CpuEngine;
use slipfront::engines::gpu::{Arithmetic, GpuEngine, GpuOptions, GpuOutput, GpuPath};
use slipfront::io::compare::{compare_snapshots, fields_over};
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Engine, Model, Snapshot};

#[path = "support/record_twins.rs"]
mod record_twins;
use record_twins::{large_lattice, plan, twins, worst_error};
#[path = "support/ensemble_records.rs"]
mod ensemble_records;
use ensemble_records::ensemble_and_solo_records;

fn model(extra: &[&str]) -> Model {
    let mut set: Vec<String> = slipfront::app::verify::SMALL_SCENE
        .iter()
        .map(|s| s.to_string())
        .collect();
    set.extend(STICK_SLIP_WINDOW.iter().map(|s| s.to_string()));
    set.extend(extra.iter().map(|s| s.to_string()));
    let s = Scenario::parse(DEFAULT_SCENARIO, "test", &set).unwrap();
    Model::from_scenario(&s, false).unwrap()
}

fn gpu_f64(m: &Model, path: GpuPath) -> GpuEngine<f64> {
    let opts = GpuOptions {
        path,
        ..GpuOptions::default()
    };
    GpuEngine::<f64>::with_precision(m, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter with f64 is required (lavapipe in CI): {e}"))
}

fn snapshot_at(e: &mut dyn Engine, step: u64) -> Snapshot {
    advance_to(e, step).unwrap();
    e.snapshot().unwrap()
}

/// f64 kernels compute what the CPU's f64 twin does, operation for
/// operation; only a driver's fused multiply-adds (which the twin does not
/// use; `Arithmetic::Strict` forbids them where the engine writes the
/// SPIR-V, the default f64 build allows them), its division and square
/// roots, and the RNG's own ln and cos (Vulkan has no f64 ones) may round
/// differently: 1e-12 of each field's scale.
const F64_TOLERANCE: f64 = 1e-12;

#[test]
fn gpu_f64_matches_cpu_f64_through_junction_ruptures_on_every_kernel() {
    let m = model(&[]);
    let end = m.prep_steps + 2500;
    let mut cpu = CpuEngine::<f64>::new(&m, 1).unwrap();
    let reference = snapshot_at(&mut cpu, end);
    assert!(
        reference.total_ruptures() > 20,
        "the window must contain ruptures: {}",
        reference.total_ruptures()
    );
    let mut one_step = None;
    for path in [
        GpuPath::OneStep,
        GpuPath::OneStepLanes,
        GpuPath::Persistent,
        GpuPath::Resident,
        GpuPath::Tiled,
    ] {
        let mut g = gpu_f64(&m, path);
        assert!(g.describe().starts_with("gpu f64, "), "{}", g.describe());
        let started = std::time::Instant::now();
        let on_gpu = snapshot_at(&mut g, end);
        let errors = compare_snapshots(&reference, &on_gpu);
        let worst = errors.iter().map(|e| e.relative()).fold(0.0f64, f64::max);
        println!(
            "{path:?}: worst relative error {worst:.2e}, {} ruptures, {:.1} s",
            on_gpu.total_ruptures(),
            started.elapsed().as_secs_f64()
        );
        assert_eq!(
            fields_over(&errors, F64_TOLERANCE, 0.0),
            Vec::<String>::new(),
            "{path:?}: {errors:?}"
        );
        assert_eq!(on_gpu.ruptures, reference.ruptures, "{path:?}");
        assert_eq!(on_gpu.slips, reference.slips, "{path:?}");
        assert_eq!(g.save_state().unwrap().precision, "f64");
        one_step.get_or_insert(on_gpu);
    }
    // Negative control: the CPU with the drive 1e-9 faster is flagged by
    // the same comparator.
    let perturbed = model(&["loading.drive.velocity=0.4000000004"]);
    let mut cpu = CpuEngine::<f64>::new(&perturbed, 1).unwrap();
    let changed = snapshot_at(&mut cpu, end);
    let errors = compare_snapshots(&changed, &one_step.unwrap());
    println!("perturbed drive: {errors:?}");
    assert!(
        !fields_over(&errors, F64_TOLERANCE, 0.0).is_empty(),
        "{errors:?}"
    );
}

/// Through the whole stick-slip window (6,000 driving steps, 13,633
/// ruptures), every f64 kernel built strict (`Arithmetic::Strict`,
/// `--gpu-arithmetic strict`: NoContraction throughout, where the engine
/// writes the SPIR-V) ends in the CPU reference's bits on an adapter that
/// rounds division and square roots as IEEE does (llvmpipe): the driver may
/// not fuse, and the slip draws' ln and cos (the kernels' own f64 ones,
/// `shaders/coord_f64.wgsl`, against libm) give every draw the same whole
/// number of slip steps. Elsewhere, the total ruptures agree within 0.1 %;
/// `SLIPFRONT_TEST_CPU_BITS=1` asks for the bits on a hardware adapter too
/// (`gpu_call.sh`'s `f64-bits` step: whether its f64 division and square
/// roots round as IEEE's). The control: the default f64 build (wgpu's
/// module), which the driver may fuse (llvmpipe does), parts from the
/// reference before driving.
#[test]
fn every_f64_kernel_built_strict_is_the_cpu_reference_bit_for_bit_through_the_stick_slip_window() {
    let m = model(&[]);
    let end = m.prep_steps + 6000;
    let reference = snapshot_at(&mut CpuEngine::<f64>::new(&m, 1).unwrap(), end);
    assert!(
        reference.total_ruptures() > 10_000,
        "{}",
        reference.total_ruptures()
    );
    let software = slipfront::engines::gpu::context::shared()
        .expect("an adapter")
        .is_software();
    let bits = software || std::env::var("SLIPFRONT_TEST_CPU_BITS").is_ok_and(|v| v == "1");
    for path in GpuPath::KERNELS {
        let strict = GpuOptions {
            path,
            arithmetic: Arithmetic::Strict,
            ..GpuOptions::default()
        };
        let mut g = GpuEngine::<f64>::with_precision(&m, strict).unwrap();
        assert!(
            g.describe().contains("strict arithmetic"),
            "{}",
            g.describe()
        );
        let on_gpu = snapshot_at(&mut g, end);
        if bits {
            assert!(
                on_gpu == reference,
                "{path:?}: not the CPU reference's bits"
            );
        }
        let (a, b) = (on_gpu.total_ruptures(), reference.total_ruptures());
        assert!(
            a.abs_diff(b) * 1000 <= b,
            "{path:?}: {a} ruptures, the CPU {b}"
        );
    }
    if software {
        let mut g = gpu_f64(&m, GpuPath::OneStep);
        assert!(!g.describe().contains("strict arithmetic"));
        let at_load = snapshot_at(&mut CpuEngine::<f64>::new(&m, 1).unwrap(), m.prep_steps);
        assert!(
            snapshot_at(&mut g, m.prep_steps) != at_load,
            "control: the driver's fused module"
        );
    }
}

/// A state saved by the CPU's f64 engine continues on the GPU's bit for bit
/// where both compute alike: one step later the two agree to 1e-12, and
/// the mixed engine, loading the same state, does not.
#[test]
fn f64_states_cross_between_cpu_and_gpu() {
    let m = model(&[]);
    let at = m.prep_steps + 500;
    let mut cpu = CpuEngine::<f64>::new(&m, 1).unwrap();
    advance_to(&mut cpu, at).unwrap();
    let state = cpu.save_state().unwrap();
    assert_eq!(state.precision, "f64");
    let mut g = gpu_f64(&m, GpuPath::OneStep);
    g.load_state(&state).unwrap();
    let reloaded = g.save_state().unwrap();
    assert_eq!(reloaded, state, "an f64 state comes back bit for bit");
    let reference = snapshot_at(&mut cpu, at + 200);
    let errors = compare_snapshots(&reference, &snapshot_at(&mut g, at + 200));
    assert_eq!(
        fields_over(&errors, F64_TOLERANCE, 0.0),
        Vec::<String>::new(),
        "{errors:?}"
    );
    let mut mixed = GpuEngine::with_options(&m, GpuOptions::default()).unwrap();
    mixed.load_state(&state).unwrap();
    let errors = compare_snapshots(&reference, &snapshot_at(&mut mixed, at + 200));
    assert!(
        !fields_over(&errors, F64_TOLERANCE, 0.0).is_empty(),
        "{errors:?}"
    );
}

/// An f64 GPU ensemble (what `sweep --backend gpu --precision f64` runs):
/// each scene matches the CPU's f64 run of its own model to f64 round-off
/// with the same ruptures, and a scene compared with another scene's CPU
/// run is flagged (the comparison is not vacuous).
#[test]
fn gpu_f64_ensemble_scenes_match_their_cpu_f64_runs() {
    use slipfront::engines::gpu::ensemble::GpuEnsemble;
    let models = [
        model(&[]),
        model(&["friction.static_coefficient=0.404"]),
        model(&["time.seed=7", "loading.normal.force=1800"]),
    ];
    let end = models[0].prep_steps + 2500;
    let opts = GpuOptions {
        path: GpuPath::OneStepLanes,
        ..GpuOptions::default()
    };
    let mut ensemble = GpuEnsemble::<f64>::with_precision(&models, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter with f64 is required (lavapipe in CI): {e}"));
    assert!(
        ensemble
            .describe()
            .starts_with("gpu f64, ensemble of 3 scenes"),
        "{}",
        ensemble.describe()
    );
    ensemble.advance(end).unwrap();
    let cpu: Vec<Snapshot> = models
        .iter()
        .map(|m| snapshot_at(&mut CpuEngine::<f64>::new(m, 1).unwrap(), end))
        .collect();
    for (k, reference) in cpu.iter().enumerate() {
        assert!(ensemble.failure(k).is_none());
        let scene = ensemble.snapshot(k).unwrap();
        assert!(reference.total_ruptures() > 20, "scene {k}");
        let errors = compare_snapshots(reference, &scene);
        assert_eq!(
            fields_over(&errors, F64_TOLERANCE, 0.0),
            Vec::<String>::new(),
            "scene {k}: {errors:?}"
        );
        assert_eq!(scene.ruptures, reference.ruptures, "scene {k}");
        assert_eq!(ensemble.save_state(k).unwrap().precision, "f64");
    }
    // Negative control: scene 1 (μs 1 % higher) against scene 0's run.
    let errors = compare_snapshots(&cpu[0], &ensemble.snapshot(1).unwrap());
    assert!(!fields_over(&errors, F64_TOLERANCE, 0.0).is_empty());
}

/// Rate-and-state friction in f64 on every kernel: the implicit solve and
/// the state's evolution (the kernels' own f64 exp and ln, as Vulkan has
/// none) give the CPU's f64 fields, θ included, through the first slips.
/// Not to the bit, even built strict on llvmpipe: those exp and ln are not
/// libm's, and they round differently.
#[test]
fn gpu_f64_rate_state_matches_cpu_f64_on_every_kernel() {
    let text = std::fs::read_to_string("scenarios/rate_state.toml").unwrap();
    let mut set: Vec<String> = slipfront::app::verify::SMALL_SCENE
        .iter()
        .map(|s| s.to_string())
        .collect();
    set.push("loading.drive.velocity=0.4".into());
    let s = Scenario::parse(&text, "rate_state", &set).unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    let end = m.prep_steps + 3000;
    let mut cpu = CpuEngine::<f64>::new(&m, 1).unwrap();
    let reference = snapshot_at(&mut cpu, end);
    let slips: u32 = reference.slips.iter().sum();
    assert!(slips > 0, "the window must contain slips");
    for path in [
        GpuPath::OneStep,
        GpuPath::OneStepLanes,
        GpuPath::Persistent,
        GpuPath::Resident,
    ] {
        let mut g = gpu_f64(&m, path);
        let got = snapshot_at(&mut g, end);
        let errors = compare_snapshots(&reference, &got);
        println!("{path:?}: {errors:?}");
        assert_eq!(
            fields_over(&errors, 1e-9, 1e-12),
            Vec::<String>::new(),
            "{path:?}: {errors:?}"
        );
        assert_eq!(got.slips, reference.slips, "{path:?}");
    }
}

/// f64 runs record their output samples on the device as mixed ones do
/// (f64 is the default precision where the adapter has it): each sample
/// equals the CPU twin (`engine::record_sample`) on a host snapshot of a
/// second f64 run at its step, to f64 round-off in the sums. On the small
/// triggered scene (in the step of the sample on one-step; in the loop of
/// the persistent kernel) and on 257×65 (262 partials a sample, bulk
/// fields).
/// Negative control: the twin a step later is flagged.
#[test]
fn f64_output_samples_are_recorded_on_the_device() {
    let triggered = slipfront::app::verify::small_triggered_scene(&["time.end=3e-4"]).unwrap();
    let large = large_lattice();
    let runs = [
        (&triggered, GpuPath::OneStep),
        (&triggered, GpuPath::Persistent),
        (&large, GpuPath::OneStep),
    ];
    for (s, path) in runs {
        let m = Model::from_scenario(s, false).unwrap();
        let engine = |output: GpuOutput| {
            let opts = GpuOptions {
                path,
                output,
                ..GpuOptions::default()
            };
            GpuEngine::<f64>::with_precision(&m, opts)
                .unwrap_or_else(|e| panic!("a GPU adapter with f64 is required: {e}"))
        };
        let mut dev = engine(GpuOutput::Device);
        advance_to(&mut dev, m.prep_steps).unwrap();
        assert!(dev.record_samples(&plan(&m, s)).unwrap(), "{path:?}");
        advance_to(&mut dev, m.total_steps()).unwrap();
        let samples = dev.take_samples();
        assert!(samples.len() >= 8, "{path:?}: {} samples", samples.len());
        assert!(samples.iter().any(|x| x.bulk.is_some()));
        assert!(samples.iter().any(|x| x.interface.is_some()));
        let mut host = engine(GpuOutput::Host);
        let (twin, later) = twins(&m, &mut host, &samples);
        let (err, field) = worst_error(&twin, &samples);
        println!(
            "{path:?}, {} blocks: {} samples, device against twin {err:.2e} ({field})",
            m.n_blocks(),
            samples.len()
        );
        // Sums in another order (a tree against the twin's loop), and
        // bulk fields rounded to f32 alike.
        assert!(
            err < 1e-12,
            "{path:?}: {field} off by {err:.2e} of its scale"
        );
        let (shifted, field) = worst_error(&later, &samples);
        assert!(
            shifted > 1e-6,
            "{path:?}: a one-step shift must be flagged ({field})"
        );
    }
}

/// An f64 ensemble records each scene's samples on the device as the
/// scene's solo f64 run does: the same samples at the same steps, to f64
/// round-off (lavapipe may round an ensemble's per-scene constants' last
/// bit otherwise than a solo run's), with the fast cadence switching per
/// scene. Each scene's region of the record buffers follows the f64
/// layout: a plan's fast flag written at the f32 layout's offset broke
/// every scene but the last. Control: scene 1's samples are not scene 0's.
#[test]
fn an_f64_ensemble_records_every_scene_as_its_solo_run() {
    use slipfront::engines::SamplePlan;
    let triggered = |extra: &[&str]| {
        let s = slipfront::app::verify::small_triggered_scene(extra).unwrap();
        Model::from_scenario(&s, false).unwrap()
    };
    let models = vec![
        triggered(&[]),
        triggered(&["friction.static_coefficient=0.45"]),
        triggered(&["time.seed=11", "loading.normal.force=1800"]),
    ];
    let m = &models[0];
    let every = |t: f64| ((t / m.dt).round() as u64).max(1);
    let plan = SamplePlan {
        prep_steps: m.prep_steps,
        every_global: every(1e-5),
        every_interface: every(2e-5),
        every_bulk: every(5e-5),
        every_fast: every(1e-6),
        fast_slip_speed: 1e-3,
        fast: false,
    };
    let chunks = [m.prep_steps, 700, 1300, 1];
    for path in [GpuPath::OneStep, GpuPath::Persistent] {
        let opts = GpuOptions {
            path,
            ..GpuOptions::default()
        };
        let records = ensemble_and_solo_records::<f64>(&models, opts, &plan, &chunks, |_| {});
        let (got, solos) = (&records.ensemble, &records.solo);
        // Recorded on the device (the persistent kernel in its loop).
        assert!(records.output_dispatches > 0 || path == GpuPath::Persistent);
        for (k, alone) in solos.iter().enumerate() {
            assert!(
                alone.len() > 50,
                "{path:?} scene {k}: {} samples",
                alone.len()
            );
            let steps =
                |v: &[slipfront::engines::Sample]| v.iter().map(|x| x.step).collect::<Vec<_>>();
            assert_eq!(steps(&got[k]), steps(alone), "{path:?} scene {k}");
            let (err, field) = worst_error(alone, &got[k]);
            assert!(err < 1e-12, "{path:?} scene {k}: {field} off by {err:.2e}");
        }
        // Scene 1 slips otherwise than scene 0: other samples (a
        // comparison of two lists of other lengths would not be one).
        let differs = got[1].len() != solos[0].len() || worst_error(&solos[0], &got[1]).0 > 1e-6;
        assert!(differs, "{path:?}: scene 1 is not scene 0");
    }
}

/// Where a lattice's u fits workgroup memory and its u and v together do
/// not (f64 Table S1 on NVIDIA's 48 KB), the resident kernel keeps v in
/// storage, as the persistent kernel does: the same arithmetic on the same
/// values, so the same bits as the persistent kernel (and the one-step
/// kernel), through junction ruptures and across dispatches. Here 36 × 30 blocks in f64: u and v
/// would take about 40 KB, u alone about 23 KB, and lavapipe offers 32 KB.
/// Negative control: V × (1 + 1e-9) differs.
#[test]
fn the_resident_kernel_keeps_v_in_storage_where_only_u_fits_bit_for_bit() {
    let spacing = 0.0025;
    let lattice = [
        "geometry.nx=36".to_string(),
        "geometry.nz=30".to_string(),
        format!("geometry.length={}", spacing * 35.0),
        format!("geometry.height={}", spacing * 29.0),
    ];
    let lattice: Vec<&str> = lattice.iter().map(String::as_str).collect();
    let m = model(&lattice);
    let end = m.prep_steps + 1500;
    let on = |m: &Model, path| {
        let opts = GpuOptions {
            path,
            ..GpuOptions::default()
        };
        let mut g = GpuEngine::<f64>::with_precision(m, opts)
            .unwrap_or_else(|e| panic!("a GPU adapter with f64 is required (lavapipe in CI): {e}"));
        advance_to(&mut g, end).unwrap();
        (g.describe(), g.snapshot().unwrap())
    };
    let (resident_how, resident) = on(&m, GpuPath::Resident);
    assert!(resident_how.contains("v in storage"), "{resident_how}");
    let (_, persistent) = on(&m, GpuPath::Persistent);
    assert!(persistent.total_ruptures() > 0, "junctions broke");
    assert!(persistent == resident, "resident and persistent differ");
    let (_, one_step) = on(&m, GpuPath::OneStep);
    assert!(one_step == resident, "resident and one-step differ");
    let mut faster = m.clone();
    if let slipfront::model::Driver::SideSpring { velocity, .. } = &mut faster.driver {
        *velocity *= 1.0 + 1e-9;
    }
    let (_, other) = on(&faster, GpuPath::Resident);
    assert_ne!(other.disp, resident.disp, "control");
}
