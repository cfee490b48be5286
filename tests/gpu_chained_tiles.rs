//! The tiled kernel with its rounds chained in one dispatch
//! (`GpuOptions::chained_tiles`, `shaders/tiled.wgsl`) against the same
//! kernel a dispatch a round, on whatever adapter is present (lavapipe in
//! CI): the same rounds in the same order, so the same bits and samples,
//! in fewer dispatches. Chained tiles wait on each other, so a scene's
//! tiles must run at once: lavapipe runs as many workgroups at once as it
//! has threads (one a CPU core), so these scenes have two tiles, and a
//! scene of far more tiles than that must stop with an error, not hang.
//! These tests fail, never skip, when no adapter exists.

use slipfront::engines::gpu::tiles::TileShape;
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuOutput, GpuPath};
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Engine, Model};

#[allow(dead_code)]
#[path = "support/record_twins.rs"]
mod record_twins;
use record_twins::plan;

fn scenario(extra: &[&str]) -> Scenario {
    let small: &[&str] = &slipfront::app::verify::SMALL_SCENE;
    let set: Vec<String> = [small, &["loading.drive.velocity=0.4"], extra]
        .concat()
        .iter()
        .map(|s| s.to_string())
        .collect();
    Scenario::parse(DEFAULT_SCENARIO, "test", &set).unwrap()
}

/// The small side-driven scene of the cross-checks (29 × 16 blocks),
/// driven fast enough that junctions break within the run.
fn driven() -> Model {
    Model::from_scenario(&scenario(&[]), false).unwrap()
}

fn tiled(m: &Model, shape: TileShape, chained: bool, output: GpuOutput) -> GpuEngine {
    let opts = GpuOptions {
        path: GpuPath::Tiled,
        tile: Some(shape),
        chained_tiles: chained,
        output,
        ..GpuOptions::default()
    };
    GpuEngine::with_options(m, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

/// Through the normal-load phase and into ruptures, chained tiles end in
/// the bits of the unchained kernel, in a third of its dispatches or
/// fewer: two tiles of 16 and 13 columns with halos of 4 and 8 (a halo
/// as wide as half a tile). Negative control: a drive 1e-9 faster,
/// chained, is flagged.
#[test]
fn chained_tiles_are_the_tiled_kernel_bit_for_bit() {
    let m = driven();
    let end = m.prep_steps + 2500;
    for halo in [4, 8] {
        let shape = TileShape { width: 16, halo };
        let mut plain = tiled(&m, shape, false, GpuOutput::Device);
        advance_to(&mut plain, end).unwrap();
        let reference = plain.snapshot().unwrap();
        assert!(reference.total_ruptures() > 100, "junctions broke");
        let mut chained = tiled(&m, shape, true, GpuOutput::Device);
        let how = chained.describe();
        assert!(how.contains("chained") && how.contains("2 tiles"), "{how}");
        advance_to(&mut chained, end).unwrap();
        let got = chained.snapshot().unwrap();
        assert!(
            got == reference,
            "halo {halo}: {} ruptures against {}",
            got.total_ruptures(),
            reference.total_ruptures()
        );
        let (few, many) = (chained.dispatches().unwrap(), plain.dispatches().unwrap());
        println!("halo {halo}: {few} chained dispatches against {many}");
        assert!(3 * few <= many, "{few} dispatches against {many}");
    }
    let mut faster = m.clone();
    if let slipfront::model::Driver::SideSpring { velocity, .. } = &mut faster.driver {
        *velocity *= 1.0 + 1e-9;
    }
    let shape = TileShape { width: 16, halo: 4 };
    let mut other = tiled(&faster, shape, true, GpuOutput::Device);
    advance_to(&mut other, end).unwrap();
    let mut plain = tiled(&m, shape, false, GpuOutput::Device);
    advance_to(&mut plain, end).unwrap();
    assert_ne!(
        other.snapshot().unwrap().disp,
        plain.snapshot().unwrap().disp,
        "control"
    );
}

/// The tiled kernel records a sample in the sample's step, so no sample
/// ends a dispatch: with a sample planned every few steps (the fast
/// cadence's), chained or not, it makes the step dispatches it makes
/// without output (and a forces-only pass where the run ends at a
/// sample), and one `record_batch_finish` a batch. Chained tiles'
/// device samples are the unchained kernel's, and one sample later is
/// flagged.
#[test]
fn chained_tiles_record_the_samples_of_the_tiled_kernel() {
    let s = scenario(&[]);
    let m = Model::from_scenario(&s, false).unwrap();
    let plan = plan(&m, &s);
    let end = m.prep_steps + 1500;
    let shape = TileShape { width: 16, halo: 4 };
    let run = |chained, record| {
        let mut e = tiled(&m, shape, chained, GpuOutput::Device);
        if record {
            assert!(e.record_samples(&plan).unwrap());
        }
        advance_to(&mut e, end).unwrap();
        let counts = (e.dispatches().unwrap(), e.output_dispatches().unwrap());
        (e.take_samples(), counts)
    };
    let mut recorded = Vec::new();
    for chained in [false, true] {
        let (_, (quiet, none)) = run(chained, false);
        let (samples, (steps, finishes)) = run(chained, true);
        println!(
            "chained {chained}: {} samples; {steps} step dispatches recording, {quiet} \
             without; {finishes} record dispatches",
            samples.len()
        );
        assert_eq!(none, 0);
        // The run's last step, where it is a sample, takes a forces-only
        // pass of its own (a dispatch).
        let last = plan.due(end).any() as u64;
        assert_eq!(
            steps,
            quiet + last,
            "chained {chained}: samples ended dispatches"
        );
        assert!(
            (1..=8).contains(&finishes),
            "chained {chained}: {finishes} record dispatches in 1500 steps"
        );
        recorded.push(samples);
    }
    let (plain, chained) = (&recorded[0], &recorded[1]);
    assert!(plain.len() >= 8, "{} samples", plain.len());
    assert!(
        chained == plain,
        "{} samples against {}",
        chained.len(),
        plain.len()
    );
    assert!(
        chained[1..] != plain[..plain.len() - 1],
        "a shift is flagged"
    );
}

/// A scene of 64 one-column tiles: far more than lavapipe runs at once
/// (a thread a CPU core, at most 32), so a tile waits for a neighbour
/// that cannot start. It gives up after its polls, and the run stops with
/// an error naming the cause and what to use instead, not a hang. A GPU
/// holds 64 small workgroups at once: there the run is the unchained
/// kernel's, bit for bit.
#[test]
fn chained_tiles_that_cannot_all_run_at_once_stop_with_an_error() {
    let m = Model::from_scenario(
        &scenario(&["geometry.nx=64", "geometry.length=0.1575"]),
        false,
    )
    .unwrap();
    let shape = TileShape { width: 1, halo: 1 };
    let mut e = tiled(&m, shape, true, GpuOutput::Device);
    let end = m.prep_steps + 200;
    if !e.is_software() {
        advance_to(&mut e, end).unwrap();
        let mut plain = tiled(&m, shape, false, GpuOutput::Device);
        advance_to(&mut plain, end).unwrap();
        assert!(e.snapshot().unwrap() == plain.snapshot().unwrap());
        return;
    }
    let err = advance_to(&mut e, end)
        .expect_err("64 tiles cannot all run at once on lavapipe")
        .to_string();
    assert!(
        err.contains("did not run a scene's chained tiles at once") && err.contains("unchained"),
        "{err}"
    );
}

/// An ensemble of chained scenes is the same compiled kernel as a solo
/// run, each scene's tiles waiting only on their own scene's. On hardware
/// each scene of three ends in its solo run's bits, and scene 1 against
/// scene 0's solo run is flagged. A software adapter hands each thread a
/// run of a dispatch's workgroups (two scenes' tiles on one thread would
/// wait on each other), so there the ensemble is refused with the reason.
#[test]
fn each_chained_scene_of_an_ensemble_matches_its_solo_run() {
    let models = [
        driven(),
        Model::from_scenario(&scenario(&["friction.static_coefficient=0.404"]), false).unwrap(),
        Model::from_scenario(&scenario(&["time.seed=7"]), false).unwrap(),
    ];
    let steps = models[0].prep_steps + 1500;
    let opts = GpuOptions {
        path: GpuPath::Tiled,
        tile: Some(TileShape { width: 16, halo: 4 }),
        chained_tiles: true,
        ..GpuOptions::default()
    };
    let solo = GpuEngine::with_options(&models[0], opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"));
    let built = slipfront::engines::gpu::ensemble::GpuEnsemble::new(&models, opts);
    if solo.is_software() {
        let err = built
            .err()
            .expect("refused on a software adapter")
            .to_string();
        assert!(err.contains("one scene at a time"), "{err}");
        return;
    }
    let mut e = built.unwrap();
    e.advance(steps).unwrap();
    let mut alone = Vec::new();
    for (k, m) in models.iter().enumerate() {
        let mut solo = GpuEngine::with_options(m, opts).unwrap();
        advance_to(&mut solo, steps).unwrap();
        let solo = solo.snapshot().unwrap();
        assert!(e.snapshot(k).unwrap() == solo, "scene {k}: not bit for bit");
        alone.push(solo);
    }
    assert!(e.snapshot(1).unwrap() != alone[0], "control");
}

/// A chained run that blows up stops where the unchained kernel's does: the
/// same step (the same rounds), at an interface block, and the tiles past
/// it neither hang nor report a stall. Junctions 10⁴× too stiff for the
/// time step (forced past the stability check) blow up within a few
/// hundred steps. Several blocks of both tiles blow up at that step, and
/// the first to report it is named, in either kernel: the block is not
/// compared.
#[test]
fn a_chained_blow_up_stops_at_the_step_and_block_of_the_tiled_kernel() {
    let s = slipfront::app::verify::small_scene(&slipfront::app::verify::STIFF_JUNCTIONS_BLOW_UP)
        .unwrap();
    let m = Model::from_scenario(&s, true).unwrap();
    let shape = TileShape { width: 16, halo: 4 };
    let stop = |chained| {
        let mut e = tiled(&m, shape, chained, GpuOutput::Device);
        let err = advance_to(&mut e, m.total_steps()).unwrap_err();
        let text = err.to_string();
        let slipfront::EngineError::BlowUp { step, ix, iz, .. } = err else {
            panic!("chained {chained}: {text}");
        };
        assert_eq!(e.steps_done(), step);
        (step, ix, iz)
    };
    let (step, _, iz) = stop(false);
    let (chained_step, _, chained_iz) = stop(true);
    assert_eq!(chained_step, step);
    assert!(iz <= 1 && chained_iz <= 1, "rows {iz} and {chained_iz}");
}

/// `--gpu-chained-tiles` with a kernel named that has no rounds to chain is
/// refused, naming the flag, the kernel and what to use; `auto` and
/// `measure` take it (they chain only the tiled kernel).
#[test]
fn chained_tiles_with_another_kernel_are_refused() {
    let m = driven();
    let opts = GpuOptions {
        path: GpuPath::Persistent,
        chained_tiles: true,
        ..GpuOptions::default()
    };
    let err = GpuEngine::with_options(&m, opts)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        err.contains("--gpu-chained-tiles") && err.contains("--gpu-path persistent"),
        "{err}"
    );
    assert!(err.contains("use --gpu-path tiled"), "{err}");
    let auto = GpuOptions {
        path: GpuPath::Auto,
        ..opts
    };
    GpuEngine::with_options(&m, auto).expect("auto takes the flag");
}
