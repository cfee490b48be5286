//! `--gpu-path auto` chooses by measurement on hardware; `measure` times
//! the kernels on any adapter. Here (lavapipe in CI) `measure` is timed
//! for real, the cache is written and read back, and the run header shows
//! the figures. These tests fail, never skip, when no adapter exists.

use slipfront::app::runner::sample_plan;
use slipfront::engines::gpu::context::{self, GpuContext};
use slipfront::engines::gpu::kernel_choice::{
    cache_key, candidates, chained_halo_search, driving_start, launches, measure_within, resolve,
    resolve_scenes, scenes_cache_key, time_kernel, ChoiceCache, ChoiceSource, KernelChoice, Launch,
    TimedPhase, CACHE_FILE, ENSEMBLE_THREADS,
};
use slipfront::engines::gpu::shaders::Kernel;
use slipfront::engines::gpu::tiles::TileShape;
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuPath};
use slipfront::engines::{Engine, SamplePlan};
use slipfront::model::scenario::Scenario;
use slipfront::Model;

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

fn ctx() -> GpuContext {
    context::shared().unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

fn small_scenario(extra: &[&str]) -> Scenario {
    slipfront::app::verify::small_scene(extra).unwrap()
}

fn small(extra: &[&str]) -> Model {
    Model::from_scenario(&small_scenario(extra), false).unwrap()
}

fn scratch(name: &str) -> Scratch {
    Scratch::new("choice", name)
}

fn options(path: GpuPath) -> GpuOptions {
    GpuOptions {
        path,
        ..GpuOptions::default()
    }
}

/// The launch with the least time per step among those `choice` timed.
fn fastest(choice: &KernelChoice) -> Launch {
    choice
        .timings
        .iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap()
        .0
}

/// `measure` times every kernel that fits this scene, takes the fastest,
/// and caches it; the cached line is read back as the same choice with the
/// same figures. The engine it builds runs the chosen kernel.
#[test]
fn measure_times_every_candidate_takes_the_fastest_and_caches_it() {
    let ctx = ctx();
    let m = small(&[]);
    let dir = scratch("measure");
    let cache = ChoiceCache::at(&dir);
    let (opts, choice) = resolve::<f32>(&m, &ctx, options(GpuPath::Measure), &cache).unwrap();
    let choice = choice.expect("measure always measures");
    assert_eq!(choice.source, ChoiceSource::Measured);
    // Last, the fastest launch is timed again with its bulk forces by
    // patches of blocks.
    type Timed = (Launch, f64);
    let (patched, unpatched): (Vec<Timed>, Vec<Timed>) =
        choice.timings.iter().partition(|t| t.0.bond_patches);
    assert_eq!(patched.len(), 1, "{}", choice.describe());
    assert_eq!(choice.timings.last(), patched.first());
    let fastest_patched = unpatched
        .iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|t| t.0.with_bond_patches());
    assert_eq!(fastest_patched, Some(patched[0].0));
    // Before it, where the lanes merged in subgroups (lavapipe: runs of 8),
    // the fastest launch that merged them is timed with every lane's sum
    // through storage.
    let (in_storage, choice_timings): (Vec<Timed>, Vec<Timed>) =
        unpatched.iter().partition(|t| t.0.lanes_in_storage);
    if ctx.has_subgroups() {
        assert_eq!(in_storage.len(), 1, "{}", choice.describe());
        assert_eq!(unpatched.last(), in_storage.first());
        let twin = Launch {
            lanes_in_storage: false,
            ..in_storage[0].0
        };
        assert!(twin.kernel.merges_lanes_through_storage());
        let merged_in_subgroups = choice_timings
            .iter()
            .filter(|t| t.0.kernel.merges_lanes_through_storage());
        let fastest_merged = merged_in_subgroups.min_by(|a, b| a.1.total_cmp(&b.1));
        assert_eq!(fastest_merged.map(|t| t.0), Some(twin));
    } else {
        assert!(in_storage.is_empty(), "{}", choice.describe());
    }
    let mut timed: Vec<Kernel> = choice_timings.iter().map(|t| t.0.kernel).collect();
    timed.dedup();
    assert_eq!(timed, candidates(&m));
    // A scene alone is timed at each kernel's default threads, but the
    // tiled kernel at several, and then at four other tile shapes
    // (search_tile_shapes) with the threads that were fastest.
    for (launch, _) in &choice.timings {
        let tiled = launch.kernel == Kernel::Tiled;
        assert_eq!(launch.threads.is_some(), tiled, "{}", launch.name());
    }
    // Then the fastest tiled launch once more with its rounds chained, and
    // where that beat it, the smaller halos chained at its width.
    let chained: Vec<Launch> = choice_timings
        .iter()
        .map(|t| t.0)
        .chain(choice.skipped.iter().map(|s| s.0))
        .filter(|l| l.chained_tiles)
        .collect();
    let fastest_tiled = choice_timings
        .iter()
        .filter(|t| t.0.kernel == Kernel::Tiled && !t.0.chained_tiles)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .copied()
        .unwrap();
    assert_eq!(
        chained.first(),
        Some(&fastest_tiled.0.with_chained_tiles()),
        "{}",
        choice.describe()
    );
    let won = choice_timings
        .iter()
        .find(|t| t.0 == chained[0])
        .is_some_and(|t| t.1 < fastest_tiled.1);
    let searched = chained_halo_search(fastest_tiled.0);
    let expected = if won { searched } else { Vec::new() };
    assert_eq!(chained[1..], expected[..], "{}", choice.describe());
    let (plain, shaped): (Vec<&Timed>, Vec<&Timed>) = choice_timings
        .iter()
        .filter(|t| t.0.kernel == Kernel::Tiled && !t.0.chained_tiles)
        .partition(|t| t.0.tile.is_none());
    assert_eq!(plain.len(), 3);
    let threads = plain
        .iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap()
        .0
        .threads;
    let searched: Vec<Launch> = shaped
        .iter()
        .map(|t| t.0)
        .chain(
            choice
                .skipped
                .iter()
                .map(|s| s.0)
                .filter(|l| l.tile.is_some() && !l.chained_tiles),
        )
        .collect();
    assert_eq!(searched.len(), 4, "{}", choice.describe());
    assert!(searched.iter().all(|l| l.threads == threads));
    assert!(
        choice.describe().contains("tiled/") && choice.describe().contains("x4 "),
        "{}",
        choice.describe()
    );
    assert_eq!(timed.len(), 5, "all five kernels fit a 29 × 16 scene");
    for (k, s) in &choice.timings {
        // lavapipe: 10 µs .. 100 ms per step of 464 blocks.
        assert!(*s > 1e-5 && *s < 0.1, "{k:?}: {s} s/step");
    }
    let fastest = fastest(&choice);
    assert_eq!(choice.launch, fastest);
    // Timed where a run spends its steps: from the last step of the
    // normal-load phase (about 2,300 steps here, under a second on an idle
    // lavapipe), unless a busy machine makes that longer than the budget
    // (the budget itself: the test below).
    match &choice.phase {
        TimedPhase::Driving { from_step } => assert_eq!(*from_step, m.prep_steps - 1),
        TimedPhase::NormalLoad { why } => assert!(why.contains("over the 3 s budget"), "{why}"),
    }
    assert!(
        choice.describe().contains("timed in "),
        "{}",
        choice.describe()
    );
    assert!(
        choice.describe().contains("µs/step"),
        "{}",
        choice.describe()
    );
    // The options now name the kernel, the tile shape if one won, and
    // where the lanes merge.
    let mut engine = GpuEngine::with_options(&m, opts).unwrap();
    assert_eq!(engine.kernel(), choice.kernel());
    if let Some(shape) = choice.launch.tile {
        let g = engine.tile_geometry().expect("tiled");
        assert_eq!((g.width, g.halo), (shape.width, shape.halo));
    }
    assert_eq!(opts.lane_shuffle, !choice.launch.lanes_in_storage);
    assert_eq!(opts.bond_patches, choice.launch.bond_patches);
    engine.advance(2).unwrap();
    if choice.launch.lanes_in_storage {
        assert_eq!(engine.lane_shuffle_levels(), 0);
    }

    // The cache holds it, and reads back the same choice.
    let key = cache_key::<f32>(&m, &ctx, options(GpuPath::Measure));
    let text = std::fs::read_to_string(dir.join(CACHE_FILE)).unwrap();
    assert!(text.starts_with(&key), "{text}");
    let cached = cache.lookup(&key).expect("stored");
    assert_eq!(cached.source, ChoiceSource::Cached);
    assert_eq!(cached.launch, choice.launch);
    assert_eq!(cached.timings, choice.timings);
    assert_eq!(cached.phase, choice.phase);
    // Timed without output (no `GpuOptions::samples`): none recorded.
    assert_eq!((choice.recorded, cached.recorded), (None, None));

    // Another seed is the same shape (the same choice); controls: other
    // junction counts, another precision and damaged lines are not.
    let reseeded = small(&["time.seed=9"]);
    assert_eq!(
        cache_key::<f32>(&reseeded, &ctx, options(GpuPath::Measure)),
        key
    );
    let fewer = small(&["friction.junctions.count=50"]);
    assert_eq!(
        cache.lookup(&cache_key::<f32>(&fewer, &ctx, options(GpuPath::Measure))),
        None
    );
    if ctx.check_precision::<f64>().is_ok() {
        assert_ne!(cache_key::<f64>(&m, &ctx, options(GpuPath::Measure)), key);
    }
    // A choice made with the tile shape searched is not one for a fixed
    // shape (`--gpu-tile`), which is never searched.
    let fixed = GpuOptions {
        tile: Some(TileShape::DEFAULT),
        ..options(GpuPath::Measure)
    };
    assert_eq!(cache.lookup(&cache_key::<f32>(&m, &ctx, fixed)), None);
    // Nor one made with the lanes' merge searched for lanes fixed in
    // storage.
    let storage = GpuOptions {
        lane_shuffle: false,
        ..options(GpuPath::Measure)
    };
    assert_eq!(cache.lookup(&cache_key::<f32>(&m, &ctx, storage)), None);
    // Nor one timed without wgpu's run-time checks one for kernels with them.
    let checked = GpuOptions {
        shader_checks: true,
        ..options(GpuPath::Measure)
    };
    assert_eq!(cache.lookup(&cache_key::<f32>(&m, &ctx, checked)), None);
    // Nor one timed without output one for a run that records its samples
    // on the device (output weighs on the launches unequally), nor one
    // timed at other cadences.
    let plan = sample_plan(&m, &small_scenario(&[]));
    let recording = GpuOptions {
        samples: Some(plan),
        ..options(GpuPath::Measure)
    };
    assert_eq!(cache.lookup(&cache_key::<f32>(&m, &ctx, recording)), None);
    let faster = GpuOptions {
        samples: Some(SamplePlan {
            every_fast: plan.every_fast + 1,
            ..plan
        }),
        ..options(GpuPath::Measure)
    };
    assert_ne!(
        cache_key::<f32>(&m, &ctx, faster),
        cache_key::<f32>(&m, &ctx, recording)
    );
    let driving = "timed in driving from step 10";
    for damaged in [
        format!("{key}\tone-step\tone-step=oops\t{driving}\tno output\n"),
        format!("{key}\twarp\tone-step=1e-4\t{driving}\tno output\n"),
        // An older build's line, timed in the load phase without saying so.
        format!("{key}\tone-step\tone-step=1e-4\n"),
        format!("{key}\tone-step\tone-step=1e-4\ttimed somewhere\tno output\n"),
        // One without its output field (before session 39), or a damaged one.
        format!("{key}\tone-step\tone-step=1e-4\t{driving}\n"),
        format!("{key}\tone-step\tone-step=1e-4\t{driving}\trecorded some\n"),
    ] {
        std::fs::write(dir.join(CACHE_FILE), &damaged).unwrap();
        assert_eq!(cache.lookup(&key), None, "{damaged}");
    }
    for (field, recorded) in [("no output", None), ("recorded 12", Some(12))] {
        std::fs::write(
            dir.join(CACHE_FILE),
            format!("{key}\tone-step\tone-step=1e-4\t{driving}\t{field}\n"),
        )
        .unwrap();
        let read = cache.lookup(&key).unwrap();
        assert_eq!(read.phase, TimedPhase::Driving { from_step: 10 });
        assert_eq!(read.recorded, recorded, "{field}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The state the kernels are timed from: an ensemble's scenes step their
/// normal-load phase together to its last step, and each launch is timed
/// on from there. A load phase that would take longer than the budget is
/// not stepped (the kernels are then timed from the initial state) and
/// the choice says why; so are scenes whose load phases differ.
#[test]
fn the_kernels_are_timed_from_the_end_of_the_load_phase_within_a_budget() {
    let ctx = ctx();
    let m = small(&[]);
    let opts = GpuOptions::default();
    let one_step = Launch::of(Kernel::OneStep);
    let pair = [m.clone(), small(&["time.seed=5"])];
    let (states, phase) = driving_start::<f32>(&pair, &ctx, opts, one_step, 60.0);
    let end = m.prep_steps - 1;
    assert_eq!(phase, TimedPhase::Driving { from_step: end });
    let states = states.expect("stepped within the budget");
    assert_eq!(states.len(), 2);
    assert!(states.iter().all(|s| s.step == end));
    for launch in [one_step, Launch::of(Kernel::Resident)] {
        let s = time_kernel::<f32>(&pair, &ctx, opts, launch, Some(&states)).unwrap();
        assert!(s > 1e-5 && s < 0.1, "{}: {s} s/step", launch.name());
    }
    // Control: the states are loaded, so those of another lattice are
    // refused.
    let taller = ["geometry.nz=17", "geometry.height=0.04"];
    let other = [small(&taller), small(&taller)];
    assert!(time_kernel::<f32>(&other, &ctx, opts, one_step, Some(&states)).is_err());

    let (states, phase) = driving_start::<f32>(&pair, &ctx, opts, one_step, 0.0);
    assert!(states.is_none());
    let TimedPhase::NormalLoad { why } = &phase else {
        panic!("timed in driving with no budget: {phase:?}");
    };
    assert!(why.contains("over the 0 s budget"), "{why}");
    assert!(
        phase
            .describe()
            .starts_with("timed in the normal-load phase: reaching driving"),
        "{}",
        phase.describe()
    );
    assert_eq!(TimedPhase::described(&phase.describe()), Some(phase));

    let longer = small(&["loading.normal.relax_time=4e-4"]);
    assert!(longer.prep_steps > m.prep_steps);
    let (states, phase) = driving_start::<f32>(&[m, longer], &ctx, opts, one_step, 60.0);
    assert!(states.is_none());
    assert_eq!(
        phase,
        TimedPhase::NormalLoad {
            why: "the scenes' normal-load phases differ in length".into()
        }
    );
}

/// An ensemble is timed with the single-workgroup kernels at each of
/// `ENSEMBLE_THREADS` (how many scenes share a multiprocessor depends on
/// their threads); the choice carries its threads into the options and
/// through the cache. `--gpu-threads` fixes them: then nothing varies.
#[test]
fn an_ensemble_times_the_single_workgroup_kernels_at_several_threads() {
    let ctx = ctx();
    let m = small(&[]);
    let most = ctx.limits.max_compute_invocations_per_workgroup;
    let variants: Vec<u32> = ENSEMBLE_THREADS
        .into_iter()
        .filter(|&t| t <= most)
        .collect();
    assert!(!variants.is_empty());
    let dir = scratch("ensemble");
    let cache = ChoiceCache::at(&dir);
    let opts = options(GpuPath::Measure);
    let (chosen, choice) = resolve_scenes::<f32>(&m, 3, &ctx, opts, &cache).unwrap();
    let choice = choice.expect("measure always measures");
    // Every launch, then the tile shapes searched (as a scene alone),
    // then the lanes through storage, then the bulk forces by patches.
    let timed: Vec<Launch> = choice
        .timings
        .iter()
        .map(|t| t.0)
        .filter(|l| !l.lanes_in_storage && !l.bond_patches && !l.chained_tiles)
        .collect();
    let (timed, shaped): (Vec<Launch>, Vec<Launch>) =
        timed.into_iter().partition(|l| l.tile.is_none());
    assert_eq!(timed, launches(&m, 3, opts, &ctx.limits));
    let skipped_shapes = choice
        .skipped
        .iter()
        .filter(|s| s.0.tile.is_some() && !s.0.chained_tiles)
        .count();
    assert_eq!(shaped.len() + skipped_shapes, 4, "{}", choice.describe());
    // Chained tiles, timed once more on the fastest tiled launch, cannot
    // run an ensemble on a software adapter: skipped with the reason.
    let chained = choice.skipped.iter().find(|s| s.0.chained_tiles);
    if ctx.is_software() {
        let why = &chained.expect("chained tiles skipped").1;
        assert!(why.contains("one scene at a time"), "{why}");
    }
    for kernel in [Kernel::Persistent, Kernel::Resident, Kernel::Tiled] {
        let threads: Vec<Option<u32>> = timed
            .iter()
            .filter(|l| l.kernel == kernel && l.group_scenes.is_none())
            .map(|l| l.threads)
            .collect();
        assert_eq!(
            threads,
            variants.iter().map(|&t| Some(t)).collect::<Vec<_>>()
        );
    }
    // And the persistent kernel in its largest workgroup, two scenes side
    // by side (three scenes: not four).
    let grouped: Vec<Launch> = timed
        .iter()
        .filter(|l| l.group_scenes.is_some())
        .copied()
        .collect();
    let largest = *variants.last().unwrap();
    assert_eq!(
        grouped,
        vec![Launch::with_threads(Kernel::Persistent, largest).with_group_scenes(2)]
    );
    let fastest = fastest(&choice);
    assert_eq!(choice.launch, fastest);
    assert_eq!(chosen.path, GpuPath::of(fastest.kernel));
    assert_eq!(chosen.persistent_threads, fastest.threads);
    assert_eq!(chosen.group_scenes, fastest.group_scenes.unwrap_or(1));
    let key = scenes_cache_key::<f32>(&m, 3, &ctx, opts);
    let cached = cache.lookup(&key).expect("stored");
    assert_eq!(
        (cached.launch, &cached.timings),
        (choice.launch, &choice.timings)
    );
    // Fixed threads: each kernel once, at its threads; a scene alone:
    // each at its default threads but the tiled kernel, at each.
    let fixed = GpuOptions {
        persistent_threads: Some(64),
        ..opts
    };
    let plain: Vec<Launch> = candidates(&m).into_iter().map(Launch::of).collect();
    assert_eq!(launches(&m, 3, fixed, &ctx.limits), plain);
    let alone = launches(&m, 1, opts, &ctx.limits);
    for launch in &alone {
        assert_eq!(launch.threads.is_some(), launch.kernel == Kernel::Tiled);
    }
    assert_eq!(alone.len(), plain.len() + variants.len() - 1);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--gpu-tile` fixes the tiled kernel's shape, `lane_shuffle` false
/// fixes every lane's sum in storage, and `--gpu-bond-patches` the bulk
/// forces by patches: `measure` times the kernels without searching
/// shapes, lane merges or patches, and the options it returns keep what
/// was asked for, whichever kernel wins.
#[test]
fn a_fixed_tile_shape_lane_merge_or_bond_patching_is_not_searched() {
    let ctx = ctx();
    let m = small(&[]);
    let dir = scratch("fixed-tile");
    let cache = ChoiceCache::at(&dir);
    let shape = TileShape { width: 16, halo: 2 };
    let opts = GpuOptions {
        tile: Some(shape),
        lane_shuffle: false,
        bond_patches: true,
        ..options(GpuPath::Measure)
    };
    let (chosen, choice) = resolve::<f32>(&m, &ctx, opts, &cache).unwrap();
    let choice = choice.expect("measure always measures");
    assert!(choice.timings.iter().any(|t| t.0.kernel == Kernel::Tiled));
    for (launch, _) in &choice.timings {
        assert_eq!(launch.tile, None, "{}", choice.describe());
        assert!(!launch.lanes_in_storage, "{}", choice.describe());
        assert!(!launch.bond_patches, "{}", choice.describe());
    }
    assert_eq!(chosen.tile, Some(shape));
    assert!(!chosen.lane_shuffle);
    assert!(chosen.bond_patches);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run with an output file is timed recording its samples on the
/// device at its cadences (`GpuOptions::samples`): from the start of
/// driving every launch records some, and the choice says how many.
/// Control: timed without, none is recorded
/// (`measure_times_every_candidate_takes_the_fastest_and_caches_it`).
#[test]
fn a_run_with_an_output_file_is_timed_recording_its_samples() {
    let ctx = ctx();
    let scenario = small_scenario(&[]);
    let m = Model::from_scenario(&scenario, false).unwrap();
    let plan = sample_plan(&m, &scenario);
    assert!(plan.every_global > 0 && plan.every_fast > 0);
    // Fixed where `measure` would search, to time fewer launches.
    let opts = GpuOptions {
        tile: Some(TileShape { width: 16, halo: 2 }),
        lane_shuffle: false,
        bond_patches: true,
        samples: Some(plan),
        ..options(GpuPath::Measure)
    };
    // A budget no load of this machine exceeds: timed in driving, where
    // samples fall.
    let choice = measure_within::<f32>(std::slice::from_ref(&m), &ctx, opts, 600.0).unwrap();
    let text = choice.describe();
    assert!(matches!(choice.phase, TimedPhase::Driving { .. }), "{text}");
    let recorded = choice.recorded.expect("timed with the run's cadences");
    assert!(recorded > 0, "{text}");
    assert!(
        text.contains(&format!(
            "recording the run's output on the device ({recorded} samples or more a launch)"
        )),
        "{text}"
    );
}

/// Launch names: `resident`, `resident/512`, `tiled/1024/16x4`,
/// `resident/1024/lanes-in-storage`, `persistent/bond-patches`; anything else is not one (a damaged cache line is measured again).
#[test]
fn launch_names_read_back() {
    let shape = TileShape { width: 16, halo: 2 };
    for l in [
        Launch::of(Kernel::OneStepLanes),
        Launch::with_threads(Kernel::Resident, 512),
        Launch::with_threads(Kernel::Tiled, 1024).with_tile(shape),
        Launch::of(Kernel::Tiled).with_tile(shape),
        Launch::with_threads(Kernel::Resident, 1024).with_lanes_in_storage(),
        Launch::with_threads(Kernel::Tiled, 256)
            .with_tile(shape)
            .with_lanes_in_storage(),
        Launch::of(Kernel::Persistent).with_lanes_in_storage(),
        Launch::with_threads(Kernel::Resident, 1024).with_bond_patches(),
        Launch::of(Kernel::Persistent)
            .with_lanes_in_storage()
            .with_bond_patches(),
        Launch::with_threads(Kernel::Tiled, 256)
            .with_tile(shape)
            .with_bond_patches(),
        Launch::of(Kernel::OneStep).with_bond_patches(),
        Launch::of(Kernel::OneStepLanes).with_bond_patches(),
        Launch::with_threads(Kernel::Resident, 256).with_one_lane_a_round(),
        Launch::of(Kernel::Persistent)
            .with_lanes_in_storage()
            .with_bond_patches()
            .with_one_lane_a_round(),
        Launch::with_threads(Kernel::Tiled, 256)
            .with_tile(shape)
            .with_chained_tiles(),
        Launch::of(Kernel::Tiled).with_chained_tiles(),
        Launch::of(Kernel::Tiled)
            .with_chained_tiles()
            .with_lanes_in_storage()
            .with_bond_patches(),
        Launch::with_threads(Kernel::Persistent, 1024).with_group_scenes(2),
        Launch::of(Kernel::Persistent).with_group_scenes(4),
        Launch::with_threads(Kernel::Persistent, 1024)
            .with_group_scenes(2)
            .with_lanes_in_storage()
            .with_one_lane_a_round()
            .with_lane_run(4),
    ] {
        assert_eq!(Launch::named(&l.name()), Some(l));
    }
    assert_eq!(
        Launch::with_threads(Kernel::Persistent, 1024)
            .with_group_scenes(2)
            .with_bond_patches()
            .name(),
        "persistent/1024/2-scenes/bond-patches"
    );
    assert_eq!(
        Launch::with_threads(Kernel::Resident, 1024)
            .with_bond_patches()
            .with_one_lane_a_round()
            .name(),
        "resident/1024/bond-patches/one-lane-a-round"
    );
    assert_eq!(
        Launch::with_threads(Kernel::Resident, 512)
            .with_lanes_in_storage()
            .name(),
        "resident/512/lanes-in-storage"
    );
    assert_eq!(Launch::of(Kernel::Resident).name(), "resident");
    assert_eq!(
        Launch::with_threads(Kernel::Persistent, 256)
            .with_lanes_in_storage()
            .with_bond_patches()
            .name(),
        "persistent/256/lanes-in-storage/bond-patches"
    );
    assert_eq!(
        Launch::with_threads(Kernel::Tiled, 1024)
            .with_tile(shape)
            .name(),
        "tiled/1024/16x2"
    );
    assert_eq!(
        Launch::with_threads(Kernel::Tiled, 256)
            .with_tile(shape)
            .with_chained_tiles()
            .with_bond_patches()
            .name(),
        "tiled/256/16x2/chained/bond-patches"
    );
    for bad in [
        "resident/0",
        "resident/x",
        "resident/",
        "warp/256",
        "warp",
        "resident/256/8x4",
        "tiled/256/8x0",
        "tiled/256/8x4/2",
        "tiled/8x4/256",
        "tiled/256/",
        // The one-step kernels merge their lanes without storage.
        "one-step-lanes/lanes-in-storage",
        "resident/lanes-in-storage/256",
        "tiled/lanes-in-storage/8x4",
        "resident/256/lanes-in-storage/lanes-in-storage",
        "resident/256/lanes",
        "one-step/bond-patches/lanes-in-storage",
        "tiled/256/bond-patches/8x4",
        "resident/bond-patches/lanes-in-storage",
        "resident/256/bond-patches/bond-patches",
        // Only the persistent kernels step lanes two a round.
        "tiled/256/8x4/one-lane-a-round",
        "one-step-lanes/one-lane-a-round",
        "resident/one-lane-a-round/bond-patches",
        "resident/256/one-lane-a-round/one-lane-a-round",
        // Only the tiled kernel chains its rounds, after its shape.
        "resident/256/chained",
        "one-step/chained",
        "tiled/chained/8x4",
        "tiled/256/8x4/bond-patches/chained",
        "tiled/chained/chained",
        // Only the persistent kernel steps scenes side by side, 1, 2 or
        // 4 of them, after its threads.
        "resident/1024/2-scenes",
        "tiled/256/2-scenes",
        "persistent/1024/3-scenes",
        "persistent/1024/0-scenes",
        "persistent/x-scenes",
        "persistent/2-scenes/1024",
        "persistent/1024/bond-patches/2-scenes",
        "persistent/1024/2-scenes/2-scenes",
    ] {
        assert_eq!(Launch::named(bad), None, "{bad}");
    }
}

/// `auto` on a software adapter keeps the measured rule (no timing, no
/// cache); an explicit kernel is never measured.
#[test]
fn auto_on_a_software_adapter_and_explicit_kernels_do_not_measure() {
    let ctx = ctx();
    let m = small(&[]);
    let dir = scratch("rule");
    let cache = ChoiceCache::at(&dir);
    let (opts, choice) = resolve::<f32>(&m, &ctx, options(GpuPath::OneStepLanes), &cache).unwrap();
    assert_eq!((opts.path, choice), (GpuPath::OneStepLanes, None));
    if ctx.is_software() {
        let (opts, choice) = resolve::<f32>(&m, &ctx, options(GpuPath::Auto), &cache).unwrap();
        assert_eq!((opts.path, choice), (GpuPath::Auto, None));
        assert!(!dir.join(CACHE_FILE).exists());
    }
}

/// `auto` with a cached choice takes it without timing anything: a cache
/// line naming the persistent kernel (not what lavapipe's rule picks) is
/// obeyed when the adapter measures (`auto` on hardware), and `measure`
/// replaces it with its own figures.
#[test]
fn a_cached_choice_is_taken_and_measure_refreshes_it() {
    let ctx = ctx();
    let m = small(&[]);
    let dir = scratch("cached");
    let cache = ChoiceCache::at(&dir);
    let key = cache_key::<f32>(&m, &ctx, options(GpuPath::Auto));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join(CACHE_FILE),
        format!(
            "other key\tone-step\tone-step=1e-3\ttimed in driving from step 5\tno output\n\
             {key}\tpersistent\tone-step=2e-3,persistent=1e-3\ttimed in driving from step 5\t\
             no output\n"
        ),
    )
    .unwrap();
    let cached = cache.lookup(&key).unwrap();
    assert_eq!(cached.kernel(), Kernel::Persistent);
    if !ctx.is_software() {
        let (opts, choice) = resolve::<f32>(&m, &ctx, options(GpuPath::Auto), &cache).unwrap();
        assert_eq!(opts.path, GpuPath::Persistent);
        assert_eq!(choice.unwrap().source, ChoiceSource::Cached);
    }
    let (_, fresh) = resolve::<f32>(&m, &ctx, options(GpuPath::Measure), &cache).unwrap();
    let fresh = fresh.unwrap();
    assert_eq!(fresh.source, ChoiceSource::Measured);
    let text = std::fs::read_to_string(dir.join(CACHE_FILE)).unwrap();
    assert!(text.contains("other key\t"), "other lines kept: {text}");
    assert_eq!(text.lines().filter(|l| l.starts_with(&key)).count(), 1);
    assert_eq!(cache.lookup(&key).unwrap().timings, fresh.timings);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The run header shows the figures behind the choice. A run with an
/// output file is timed recording its samples on the device, as it runs
/// (without one: `measure_times_every_candidate_takes_the_fastest_and_caches_it`).
#[test]
fn a_run_with_gpu_path_measure_prints_the_figures() {
    let dir = scratch("cli");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("run.mcap");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args([
            "run",
            "--backend",
            "gpu",
            "--gpu-path",
            "measure",
            "--precision",
            "f32",
            "--t-end",
            "1e-5",
            "-o",
        ])
        .arg(&file)
        .args(
            slipfront::app::verify::SMALL_SCENE
                .iter()
                .flat_map(|s| ["--set", s]),
        )
        .env("SLIPFRONT_CACHE_DIR", &dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("; auto chose "), "{err}");
    assert!(err.contains("one-step-lanes "), "{err}");
    // (Where the load phase took more than its budget to step, as on a
    // busy machine here, they were timed before any sample was due.)
    assert!(
        err.contains("recording the run's output on the device (")
            || err.contains("with the run's output cadences but no sample in the timed steps"),
        "{err}"
    );
    assert!(dir.join(CACHE_FILE).exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every part of a launch's name has a flag, so a launch `auto` chose can
/// be named again: `persistent/64/lanes-in-storage/bond-patches` is
/// `--gpu-path persistent --gpu-threads 64 --gpu-lanes-in-storage
/// --gpu-bond-patches` (and `…/one-lane-a-round` adds
/// `--gpu-one-lane-a-round`, `…/lane-run-4` `--gpu-lane-run 4`), and the
/// run's header (the description its file keeps) says what ran.
#[test]
fn a_launch_named_by_its_flags_is_the_one_described() {
    let header = |flags: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_slipfront"))
            .args([
                "run",
                "--backend",
                "gpu",
                "--precision",
                "f32",
                "--t-end",
                "1e-5",
            ])
            .args(["--gpu-path", "persistent", "--gpu-threads", "64"])
            .args(flags)
            .args(
                slipfront::app::verify::SMALL_SCENE
                    .iter()
                    .flat_map(|s| ["--set", s]),
            )
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{err}");
        err.lines()
            .find(|l| l.contains(" on gpu f32"))
            .unwrap_or_else(|| panic!("a header line: {err}"))
            .to_string()
    };
    let (merged, patches) = ("merged in subgroups", "bulk forces by 2x2 patches");
    let plain = header(&[]);
    assert!(
        plain.contains("persistent kernel") && plain.contains("64 threads"),
        "{plain}"
    );
    assert!(!plain.contains(patches), "{plain}");
    // lavapipe and NVIDIA have subgroups; the lanes merge there unless asked.
    let ctx = ctx();
    assert_eq!(plain.contains(merged), ctx.has_subgroups(), "{plain}");
    let named = header(&["--gpu-lanes-in-storage", "--gpu-bond-patches"]);
    assert!(!named.contains(merged), "{named}");
    assert!(named.contains(patches), "{named}");
    // Junction lanes a round are a choice on hardware only (software
    // adapters always step one), and the header says which ran there.
    let hardware = !ctx.is_software();
    let one = header(&["--gpu-one-lane-a-round"]);
    assert_eq!(one.contains("one junction lane a round"), hardware, "{one}");
    assert_eq!(
        plain.contains("two junction lanes a round"),
        hardware,
        "{plain}"
    );
    assert!(!one.contains("two junction lanes"), "{one}");
    // `…/lane-run-4` is `--gpu-lane-run 4`, on any adapter.
    let runs = header(&["--gpu-lane-run", "4"]);
    assert!(runs.contains("4 junction lanes a thread"), "{runs}");
    assert!(!plain.contains("junction lanes a thread"), "{plain}");
}

/// The kernels the driver statistics compile (`GpuEngine::kernel_sources_on`,
/// decided without a device) are the ones an engine built with the same
/// launch compiles: the same WGSL, entry points and override constants,
/// for every kernel (the tiled kernel's gather too) and in f64. The
/// control: another thread count gives other constants.
#[test]
fn kernel_sources_without_a_device_are_the_engines_own() {
    use slipfront::engines::gpu::AdapterTraits;
    let ctx = ctx();
    let traits = AdapterTraits::of(&ctx);
    let m = small(&[]);
    for name in [
        "one-step",
        "one-step/bond-patches",
        "one-step-lanes",
        "persistent/64",
        "persistent/128/lanes-in-storage",
        "resident/64/bond-patches",
        "tiled/64/8x4",
    ] {
        let opts = Launch::named(name).unwrap().options(GpuOptions::default());
        let engine = GpuEngine::with_context(&m, ctx.clone(), opts).unwrap();
        let planned = GpuEngine::<f32>::kernel_sources_on(&m, opts, &traits).unwrap();
        assert_eq!(engine.kernel_sources(), planned, "{name}");
        let entries: Vec<&str> = planned.iter().map(|k| k.entry.as_str()).collect();
        let tiled = name.starts_with("tiled");
        assert_eq!(
            entries.len(),
            if tiled { 2 } else { 1 },
            "{name}: {entries:?}"
        );
    }
    let opts = Launch::named("persistent/64")
        .unwrap()
        .options(GpuOptions::default());
    let engine = GpuEngine::<f64>::with_precision_and_context(&m, ctx.clone(), opts).unwrap();
    let planned = GpuEngine::<f64>::kernel_sources_on(&m, opts, &traits).unwrap();
    assert_eq!(engine.kernel_sources(), planned);
    assert_eq!(planned[0].precision, "f64");
    let other = Launch::named("persistent/128")
        .unwrap()
        .options(GpuOptions::default());
    let other = GpuEngine::<f64>::kernel_sources_on(&m, other, &traits).unwrap();
    assert_ne!(other, planned, "the thread count is in the constants");
    assert_eq!(other[0].constant("PERSISTENT_THREADS"), Some(128.0));
}
