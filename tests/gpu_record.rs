//! Output samples recorded on the device, in the step kernels' steps
//! (`shaders/record_common.wgsl`), against
//! their CPU twin (`engine::record_sample`) on host snapshots of the same
//! GPU run, and whole run files written both ways. These tests fail, never
//! skip, when no adapter exists (lavapipe in CI).

use slipfront::app::runner::{run_scene, RunOptions};
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuOutput, GpuPath};
use slipfront::engines::Sample;
use slipfront::io::compare::compare_run_files;
use slipfront::io::output::reader::RunFile;
use slipfront::{advance_to, Engine, EngineError, Model, Scenario};

#[path = "support/record_twins.rs"]
mod record_twins;
use record_twins::{large_lattice, large_lattice_keys, plan, twins, worst_error};

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

/// The small lattice (29 × 16) with a triggered front: the interface slips
/// within the first 0.3 ms, so the fast interface cadence (1 µs, against
/// 20 µs otherwise) switches on and off.
fn triggered(extra: &[&str]) -> Scenario {
    slipfront::app::verify::small_triggered_scene(extra).unwrap()
}

fn engine(m: &Model, path: GpuPath, output: GpuOutput) -> GpuEngine {
    engine_with_threads(m, path, output, None)
}

fn engine_with_threads(
    m: &Model,
    path: GpuPath,
    output: GpuOutput,
    threads: Option<u32>,
) -> GpuEngine {
    let opts = GpuOptions {
        path,
        output,
        persistent_threads: threads,
        ..GpuOptions::default()
    };
    GpuEngine::with_options(m, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

/// Every sample the device recorded equals the CPU twin applied to a host
/// snapshot of a second GPU run at the same step (same bits of state: the
/// record kernels only read), to f32 summation round-off, on every kernel
/// (the persistent one records inside its loop); the fast cadence was
/// decided on the device the host's way.
/// Negative control: the twin one step later (the state a record reading
/// the wrong copy would see) is flagged.
#[test]
fn device_samples_match_the_cpu_twin_on_host_snapshots() {
    let s = triggered(&["time.end=6e-4"]);
    let m = Model::from_scenario(&s, false).unwrap();
    let plan = plan(&m, &s);
    // The resident kernel of 256 threads (its default on software
    // adapters) folds them into its 64 reduction slots before the tree
    // (shaders/record_common.wgsl reduce_threads); of 64, the tree alone.
    let kernels = [
        (GpuPath::OneStep, None),
        (GpuPath::OneStepLanes, None),
        (GpuPath::Persistent, None),
        (GpuPath::Resident, Some(256)),
        (GpuPath::Resident, Some(64)),
        (GpuPath::Tiled, None),
    ];
    for (path, threads) in kernels {
        let mut dev = engine_with_threads(&m, path, GpuOutput::Device, threads);
        assert!(
            dev.record_samples(&plan).unwrap(),
            "{path:?} records on the device"
        );
        // Chunks that end on and off sample steps.
        let mut samples = Vec::new();
        while dev.steps_done() < m.total_steps() {
            let target = (dev.steps_done() + 777).min(m.total_steps());
            advance_to(&mut dev, target).unwrap();
            samples.extend(dev.take_samples());
        }
        let mut host = engine(&m, path, GpuOutput::Host);
        assert!(!host.record_samples(&plan).unwrap());
        let (twin, later) = twins(&m, &mut host, &samples);
        let fixed = samples.iter().filter(|x| plan.due(x.step).fixed()).count();
        let rows = samples.iter().filter(|x| x.interface.is_some()).count();
        let fast_rows = samples
            .iter()
            .filter(|x| x.interface.is_some() && !plan.due(x.step).interface)
            .count();
        println!(
            "{path:?}: {} samples ({fixed} by the fixed cadences), {rows} interface rows \
             ({fast_rows} by the fast cadence), {} bulk fields",
            samples.len(),
            samples.iter().filter(|x| x.bulk.is_some()).count()
        );
        assert!(fast_rows > 20, "the fast cadence switched on");
        assert!(samples.windows(2).all(|w| w[0].step < w[1].step));
        // The fast cadence follows the host's rule from the samples.
        let mut fast = false;
        for smp in &samples {
            let due = plan.due(smp.step);
            assert!(
                due.fixed() || (fast && due.fast),
                "step {} not due",
                smp.step
            );
            assert_eq!(smp.interface.is_some(), due.interface || (fast && due.fast));
            fast = smp.sums.max_slip_speed > plan.fast_slip_speed;
        }
        for (d, t) in samples.iter().zip(&twin) {
            assert_eq!(d.sums.ruptures, t.sums.ruptures, "step {}", d.step);
            assert_eq!(d.time, t.time);
        }
        let (err, field) = worst_error(&twin, &samples);
        println!("{path:?}: device against twin {err:.2e} ({field})");
        assert!(
            err < 1e-5,
            "{path:?}: {field} off by {err:.2e} of its scale"
        );
        let (shifted, field) = worst_error(&later, &samples);
        println!("{path:?}: device against the twin a step later {shifted:.2e} ({field})");
        assert!(shifted > 1e-4, "a one-step shift must be flagged");
    }
}

/// A large lattice's samples are summed in many partials (a workgroup's
/// each, in the sample's step dispatch; record_step.wgsl) and added after
/// the batch (`record_batch_finish`): the device's samples equal the CPU
/// twin on host snapshots there too, and the twin a step later is flagged.
#[test]
fn a_large_lattice_records_in_the_partials_of_its_steps() {
    // The side spring's driven block and the top row's reaction each lie
    // in one workgroup's partial; one-step-lanes lays its workgroups out
    // differently (junction workgroups first).
    let side = large_lattice();
    let top = large_lattice_driven_at_the_top();
    // The one-step kernels with bond patches sum their partials by their
    // threads' items (interface blocks, then 2×2 patches): the top row's
    // partials and the driven block's follow that layout.
    let runs = [
        ("side spring", &side, GpuPath::OneStep, false),
        ("side spring", &side, GpuPath::OneStepLanes, false),
        ("top velocity", &top, GpuPath::OneStep, false),
        ("side spring, bond patches", &side, GpuPath::OneStep, true),
        (
            "side spring, bond patches",
            &side,
            GpuPath::OneStepLanes,
            true,
        ),
        ("top velocity, bond patches", &top, GpuPath::OneStep, true),
    ];
    for (driver, s, path, bond_patches) in runs {
        let m = Model::from_scenario(s, false).unwrap();
        let plan = plan(&m, s);
        let engine = |output| {
            let opts = GpuOptions {
                path,
                output,
                bond_patches,
                ..GpuOptions::default()
            };
            GpuEngine::with_options(&m, opts)
                .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
        };
        let mut dev = engine(GpuOutput::Device);
        assert!(dev.record_samples(&plan).unwrap());
        advance_to(&mut dev, m.total_steps()).unwrap();
        let samples = dev.take_samples();
        let mut host = engine(GpuOutput::Host);
        let (twin, later) = twins(&m, &mut host, &samples);
        assert!(samples.len() >= 8, "{} samples", samples.len());
        assert!(samples.iter().any(|x| x.bulk.is_some()));
        assert!(samples.iter().any(|x| x.bulk.is_none()));
        let driven = |x: &Sample| x.sums.driven_ux != 0.0 || x.sums.top_reaction != 0.0;
        assert!(twin.iter().all(driven), "the driver's sums are not zero");
        let (err, field) = worst_error(&twin, &samples);
        println!(
            "{path:?}, {driver}: {} samples: device against twin {err:.2e} ({field})",
            samples.len()
        );
        assert!(err < 1e-5, "{field} off by {err:.2e} of its scale");
        let (shifted, field) = worst_error(&later, &samples);
        println!("device against the twin a step later {shifted:.2e} ({field})");
        assert!(shifted > 1e-4, "a one-step shift must be flagged");
    }
}

/// large_lattice with its top row moved at a constant velocity instead
/// of the side spring.
fn large_lattice_driven_at_the_top() -> Scenario {
    let text = slipfront::model::scenario::DEFAULT_SCENARIO;
    let edited: String = text
        .lines()
        .filter(|l| !l.starts_with("stiffness = 4.0e6") && !l.starts_with("height = 5.0e-3"))
        .map(|l| l.replace("mode = \"side_spring\"", "mode = \"top_velocity\""))
        .collect::<Vec<_>>()
        .join("\n");
    assert!(edited.contains("top_velocity") && edited.len() < text.len());
    Scenario::parse(&edited, "large, top", &large_lattice_keys()).unwrap()
}

/// Timestamps inside the pass split its device time between the steps,
/// the samples' steps (the recording variant) and the batches' record
/// finishes (lavapipe has them): every dispatch is counted once, each part
/// is timed, and the parts add up to the passes' time.
#[test]
fn the_device_time_splits_between_step_and_record_dispatches() {
    let s = large_lattice();
    let m = Model::from_scenario(&s, false).unwrap();
    let mut dev = engine(&m, GpuPath::OneStep, GpuOutput::Device);
    assert!(dev.record_samples(&plan(&m, &s)).unwrap());
    let adapter = dev.describe();
    assert!(
        dev.time_each_dispatch().unwrap(),
        "{adapter}: no timestamps inside passes"
    );
    let (d0, o0, busy0) = (
        dev.dispatches().unwrap(),
        dev.output_dispatches().unwrap(),
        dev.device_seconds().unwrap(),
    );
    advance_to(&mut dev, m.total_steps()).unwrap();
    let t = dev.dispatch_times().expect("dispatches timed");
    let busy = dev.device_seconds().unwrap() - busy0;
    println!("{t}; passes {busy:.4} s");
    assert_eq!(t.steps + t.sample_steps, dev.dispatches().unwrap() - d0);
    let records = dev.output_dispatches().unwrap() - o0;
    assert!(t.sample_steps >= 8 && t.finishes >= 1, "{t:?}");
    assert_eq!(t.finishes, records);
    assert!(
        (t.total_seconds() - busy).abs() <= 1e-9 * busy + 1e-9,
        "parts {} s, passes {busy} s",
        t.total_seconds()
    );
    assert!(t.step_seconds > 0.0 && t.finish_seconds > 0.0);
    assert!(t.sample_step_seconds > 0.0);
    // Which kind of dispatch costs more is a timing, not asserted: on
    // lavapipe a step of 16,705 blocks and a finish each take 3-4.5 ms,
    // and their order flipped one run in three (session 67, with strict
    // arithmetic and with the guarded modules alike).
}

/// The one-step kernels record a sample in the sample's own step dispatch
/// (their recording variant): a run that records its samples makes the
/// step dispatches of the run without (and one forces-only pass where it
/// ends at a sample), and its only output dispatches are the batches'
/// record finishes, far fewer than its samples (the build before made one
/// or two output dispatches a sample).
#[test]
fn one_step_kernels_record_in_their_steps_with_one_finish_a_batch() {
    let s = triggered(&["time.end=6e-4"]);
    let m = Model::from_scenario(&s, false).unwrap();
    let plan = plan(&m, &s);
    for path in [GpuPath::OneStep, GpuPath::OneStepLanes] {
        let run = |record: bool| {
            let mut e = engine(&m, path, GpuOutput::Device);
            if record {
                assert!(e.record_samples(&plan).unwrap());
            }
            advance_to(&mut e, m.total_steps()).unwrap();
            let samples = e.take_samples().len() as u64;
            (
                samples,
                e.dispatches().unwrap(),
                e.output_dispatches().unwrap(),
                e.device_samples(),
            )
        };
        let (_, quiet, none, _) = run(false);
        let (samples, steps, finishes, computed) = run(true);
        let computed = computed.unwrap();
        println!(
            "{path:?}: {samples} samples; {steps} step dispatches recording, {quiet} without; \
             {finishes} record finishes; {} planned, {} computed",
            computed.planned, computed.computed
        );
        assert_eq!(none, 0);
        assert!(samples >= 100, "{samples} samples");
        // The fast cadence switches off after the front: its planned
        // samples are then skipped, and every sample taken was computed.
        assert!(
            computed.computed >= samples && computed.computed < computed.planned,
            "{computed:?} for {samples} samples"
        );
        assert!(
            steps == quiet || steps == quiet + 1,
            "{steps} step dispatches recording, {quiet} without"
        );
        assert!(
            finishes >= 1 && 20 * finishes < samples,
            "{finishes} output dispatches for {samples} samples"
        );
    }
}

/// A scratch folder for one test's run file (`name`).
fn temp(name: &str) -> Scratch {
    Scratch::new("record", name)
}

fn run_file(s: &Scenario, path: GpuPath, output: GpuOutput, name: &str) -> RunFile {
    let m = Model::from_scenario(s, false).unwrap();
    let mut e = engine(&m, path, output);
    let dir = temp(name);
    let path = dir.join("run.mcap");
    let opts = RunOptions {
        output: Some(path.clone()),
        progress: slipfront::app::runner::ProgressMode::None,
        ..RunOptions::default()
    };
    run_scene(&mut e, s, &opts).unwrap();
    assert_eq!(e.records_on_device(), output == GpuOutput::Device);
    RunFile::read(&path).unwrap()
}

/// A whole run written from device records equals the same run written
/// from host snapshots: every channel has the same records at the same
/// steps (the fast cadence included) and the same values to f32 round-off,
/// for the side-spring drive on the one-step kernel (its drive force from
/// the driven block) and a triggered front on the persistent kernel (bulk
/// fields, fast cadence). The state is the same bits
/// (host snapshots end a batch at every sample, device records do not, and
/// batches are anchored so that this changes nothing): every field read
/// from the state is exact, and only what the device sums in f32 (friction
/// total, kinetic energy, pinned fraction) or computes in f32 (the
/// velocity at the instant) differs, by round-off.
#[test]
fn run_files_from_device_records_equal_those_from_host_snapshots() {
    let side = slipfront::app::verify::small_scene(&[
        "time.end=4e-4",
        "loading.drive.velocity=0.4",
        "output.bulk_interval=1e-4",
    ])
    .unwrap();
    let front = triggered(&["time.end=4e-4"]);
    let runs = [
        ("side", side, GpuPath::OneStep),
        ("front", front, GpuPath::Persistent),
    ];
    for (name, s, path) in runs {
        let host = run_file(&s, path, GpuOutput::Host, &format!("{name}-host.mcap"));
        let dev = run_file(&s, path, GpuOutput::Device, &format!("{name}-device.mcap"));
        println!(
            "{name}: {} global, {} interface, {} bulk records",
            host.global.len(),
            host.interface.len(),
            host.bulk.len()
        );
        assert!(host.global.len() > 10 && host.interface.len() > 10 && !host.bulk.is_empty());
        let errors = compare_run_files(&host, &dev).unwrap_or_else(|e| panic!("{name}: {e}"));
        let exact = [
            "global.drive_force",
            "global.ruptures",
            "interface.shear_stress",
            "interface.normal_stress",
            "interface.slip",
            "bulk.ux",
            "bulk.uz",
        ];
        for e in &errors {
            println!("  {:26} {:.2e} of {:.2e}", e.field, e.max_error, e.scale);
            if exact.contains(&e.field) {
                assert_eq!(e.max_error, 0.0, "{name}: {e:?}");
            } else {
                // f32 sums over ~500 blocks: √n·2⁻²⁴ ≈ 1e-6 typically.
                assert!(e.relative() < 1e-5, "{name}: {e:?}");
            }
        }
        if name == "side" {
            assert!(host.global.iter().any(|g| g.drive_force != 0.0));
        } else {
            assert!(host.interface.len() > 2 * host.global.len(), "fast cadence");
        }
    }
}

/// An engine recording on the device that may run ahead by the default
/// number of batches, or not at all (`GpuOptions::run_ahead` 0).
fn engine_running_ahead(m: &Model, path: GpuPath, ahead: bool) -> GpuEngine {
    let opts = GpuOptions {
        path,
        output: GpuOutput::Device,
        run_ahead: if ahead {
            GpuOptions::default().run_ahead
        } else {
            0
        },
        ..GpuOptions::default()
    };
    GpuEngine::with_options(m, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

/// Running ahead (`Engine::run_ahead`): `advance` returns with its last
/// batches still running, and their samples come only once the engine has
/// waited for them (`settle`); without it (`GpuOptions::run_ahead` 0) an advance
/// hands over every sample up to its step. Either way the samples are the
/// same, in the same order, with the same bits.
#[test]
fn running_ahead_hands_over_the_same_samples_later() {
    let s = triggered(&["time.end=6e-4"]);
    let m = Model::from_scenario(&s, false).unwrap();
    for path in [GpuPath::OneStep, GpuPath::Persistent] {
        let mut taken = Vec::new();
        for ahead in [true, false] {
            let mut e = engine_running_ahead(&m, path, ahead);
            assert!(e.record_samples(&plan(&m, &s)).unwrap());
            e.run_ahead();
            let mut samples = Vec::new();
            let mut late = 0;
            while e.steps_done() < m.total_steps() - 1 {
                let target = (e.steps_done() + 1500).min(m.total_steps() - 1);
                advance_to(&mut e, target).unwrap();
                samples.extend(e.take_samples());
                e.settle().unwrap();
                let after = e.take_samples();
                late += after.len();
                samples.extend(after);
            }
            println!(
                "{path:?}, ahead {ahead}: {} samples, {late} late",
                samples.len()
            );
            assert!(samples.len() > 100);
            if ahead {
                assert!(late > 0, "{path:?}: nothing was left running");
            } else {
                assert_eq!(late, 0, "{path:?}: an advance that waits left samples");
            }
            taken.push(samples);
        }
        assert!(taken[0] == taken[1], "{path:?}: the samples differ");
    }
}

/// A whole run, written by a runner that lets the engine run ahead (every
/// GPU run with an output file, by default), equals the same run with an
/// engine that waits at every advance, record for record and bit for bit.
#[test]
fn a_run_file_written_while_the_device_runs_ahead_is_the_same() {
    let s = triggered(&["time.end=4e-4", "output.bulk_interval=1e-4"]);
    let m = Model::from_scenario(&s, false).unwrap();
    let mut files = Vec::new();
    for ahead in [true, false] {
        let mut e = engine_running_ahead(&m, GpuPath::OneStep, ahead);
        let dir = temp(&format!("ahead-{ahead}"));
        let path = dir.join("run.mcap");
        let opts = RunOptions {
            output: Some(path.clone()),
            progress: slipfront::app::runner::ProgressMode::None,
            ..RunOptions::default()
        };
        run_scene(&mut e, &s, &opts).unwrap();
        files.push(RunFile::read(&path).unwrap());
    }
    let (a, b) = (&files[0], &files[1]);
    assert!(a.global.len() > 10 && a.interface.len() > 10 && !a.bulk.is_empty());
    assert!(a.global == b.global && a.interface == b.interface && a.bulk == b.bulk);
}

/// The comparator's negative control: a run file whose interface records
/// are one sample short, or whose drive differs by 1e-3, is flagged.
#[test]
fn the_run_file_comparison_flags_a_missing_record_and_another_run() {
    let s = slipfront::app::verify::small_scene(&["time.end=2e-4", "loading.drive.velocity=0.4"])
        .unwrap();
    let a = run_file(&s, GpuPath::Auto, GpuOutput::Device, "control-a.mcap");
    let mut short = a.clone();
    short.interface.pop();
    assert!(compare_run_files(&a, &short).is_err());
    let faster =
        slipfront::app::verify::small_scene(&["time.end=2e-4", "loading.drive.velocity=0.4004"])
            .unwrap();
    let b = run_file(&faster, GpuPath::Auto, GpuOutput::Device, "control-b.mcap");
    let errors = compare_run_files(&a, &b).unwrap();
    assert!(errors.iter().any(|e| e.relative() > 1e-4), "{errors:?}");
}

/// A run that blows up while recording on the device stops with the step
/// and block, and its file holds the samples before the blow-up (and none
/// after it): the side spring pulled at 5 km/s, past the P-wave speed (the
/// model is edited: the scenario check refuses it), with a sample every step.
#[test]
fn a_blow_up_while_recording_keeps_the_samples_before_it() {
    let s = slipfront::app::verify::small_scene(&[
        "loading.drive.velocity=0.4",
        "time.end=1e-4",
        "output.global_interval=2e-7",
    ])
    .unwrap();
    let mut m = Model::from_scenario(&s, false).unwrap();
    if let slipfront::model::Driver::SideSpring { velocity, .. } = &mut m.driver {
        *velocity = 5e3;
    }
    let mut e = engine(&m, GpuPath::OneStep, GpuOutput::Device);
    let dir = temp("blow-up");
    let path = dir.join("run.mcap");
    let opts = RunOptions {
        output: Some(path.clone()),
        progress: slipfront::app::runner::ProgressMode::None,
        ..RunOptions::default()
    };
    let err = run_scene(&mut e, &s, &opts).unwrap_err();
    let text = err.to_string();
    assert!(text.contains("blew up at step"), "{text}");
    let slipfront::app::runner::RunError::Engine(EngineError::BlowUp { step, .. }) = err else {
        panic!("{text}");
    };
    let run = RunFile::read(&path).unwrap();
    let steps: Vec<u64> = run.global.iter().map(|g| g.step).collect();
    println!(
        "blew up at step {step} (driving from {}); samples at {steps:?}",
        m.prep_steps
    );
    assert!(step > m.prep_steps + 5, "the blow-up comes while driving");
    assert_eq!(
        steps,
        (m.prep_steps + 1..step).collect::<Vec<_>>(),
        "every step before the blow-up, none after"
    );
    assert!(run.global.iter().all(|g| g.kinetic_energy.is_finite()));
}

/// A persistent kernel whose workgroup cannot be reduced as a tree (not a
/// power of two) keeps host snapshots.
#[test]
fn a_persistent_kernel_of_96_threads_takes_host_snapshots() {
    let s = triggered(&["time.end=1e-4"]);
    let m = Model::from_scenario(&s, false).unwrap();
    let opts = GpuOptions {
        path: GpuPath::Persistent,
        persistent_threads: Some(96),
        ..GpuOptions::default()
    };
    let mut e = GpuEngine::with_options(&m, opts).unwrap();
    assert!(!e.record_samples(&plan(&m, &s)).unwrap());
    let mut e = engine(&m, GpuPath::Persistent, GpuOutput::Device);
    assert!(e.record_samples(&plan(&m, &s)).unwrap());
}
