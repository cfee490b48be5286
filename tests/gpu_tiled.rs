//! The tiled kernel (temporal blocking, `shaders/tiled.wgsl`) against the
//! one-step kernel, on whatever adapter is present (lavapipe in CI): the
//! same phase functions in the same order, so the same bits, whatever the
//! tiles, the halo, where batches begin and where samples fall. These tests
//! fail, never skip, when no adapter exists.

use slipfront::engines::gpu::tiles::TileShape;
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuOutput, GpuPath};
use slipfront::engines::Sample;
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Engine, Model, Snapshot};

#[path = "support/record_twins.rs"]
mod record_twins;
use record_twins::{large_lattice, plan, twins, worst_error};

fn model(set: &[&str]) -> Model {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let s = Scenario::parse(DEFAULT_SCENARIO, "test", &set).unwrap();
    Model::from_scenario(&s, false).unwrap()
}

/// The small side-driven scene of the cross-checks (29 × 16 blocks),
/// driven fast enough that junctions break within the run.
fn driven() -> Model {
    let small: &[&str] = &slipfront::app::verify::SMALL_SCENE;
    model(&[small, &["loading.drive.velocity=0.4"]].concat())
}

fn tiled(m: &Model, width: u32, halo: u32) -> GpuEngine {
    tiled_with(m, width, halo, |_| {})
}

/// The tiled kernel with tiles of `width` and `halo`, its other options
/// as `set` leaves the defaults.
fn tiled_with(m: &Model, width: u32, halo: u32, set: impl Fn(&mut GpuOptions)) -> GpuEngine {
    let mut opts = GpuOptions {
        path: GpuPath::Tiled,
        tile: Some(TileShape { width, halo }),
        ..GpuOptions::default()
    };
    set(&mut opts);
    GpuEngine::with_options(m, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

fn one_step(m: &Model) -> GpuEngine {
    on_path(m, GpuPath::OneStep)
}

fn on_path(m: &Model, path: GpuPath) -> GpuEngine {
    let opts = GpuOptions {
        path,
        ..GpuOptions::default()
    };
    GpuEngine::with_options(m, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

/// `m` driven 1e-9 faster: the negative control of the bit-for-bit tests.
fn drive_faster(m: &Model) -> Model {
    let mut faster = m.clone();
    if let slipfront::model::Driver::SideSpring { velocity, .. } = &mut faster.driver {
        *velocity *= 1.0 + 1e-9;
    }
    faster
}

fn run_to(e: &mut GpuEngine, end: u64) -> Snapshot {
    advance_to(e, end).unwrap();
    e.snapshot().unwrap()
}

/// Through the normal-load phase and into ruptures, the tiled kernel ends
/// where the one-step kernel ends, bit for bit: tiles of 8 columns with
/// the default halo (29 columns: a last tile of 5), a halo wider than the
/// tiles (it reaches past the neighbour), one tile holding the whole
/// lattice, and one column a tile. Negative control: a drive 1e-9 faster
/// is flagged.
#[test]
fn the_tiled_kernel_is_the_one_step_kernel_bit_for_bit() {
    let m = driven();
    let end = m.prep_steps + 2500;
    let reference = run_to(&mut one_step(&m), end);
    println!("{} ruptures by step {end}", reference.total_ruptures());
    assert!(reference.total_ruptures() > 100, "junctions broke");
    for (width, halo) in [(8, 4), (3, 7), (32, 2), (1, 1)] {
        let mut e = tiled(&m, width, halo);
        let how = e.describe();
        assert!(how.contains("tiled kernel"), "{how}");
        let got = run_to(&mut e, end);
        assert!(
            got == reference,
            "tiles of {width}, halo {halo}: {} ruptures against {}",
            got.total_ruptures(),
            reference.total_ruptures()
        );
        // Up to `halo` steps a dispatch (and one at each batch's start).
        let dispatches = e.dispatches().unwrap();
        assert!(
            dispatches * u64::from(halo) >= end,
            "{dispatches} dispatches"
        );
        if halo > 1 {
            assert!(dispatches < end, "{dispatches} dispatches for {end} steps");
        }
    }
    let faster = drive_faster(&m);
    let other = run_to(&mut tiled(&faster, 8, 4), end);
    assert_ne!(other.disp, reference.disp, "control");
}

/// Every kernel merges a block's lane sums as the same tree from its own
/// source (one-step: one thread walking the lanes; one-step-lanes:
/// subtrees in workgroup memory; persistent and resident: partials in
/// storage), so through the normal-load phase (every block summed every
/// step) and ruptures they end in the bits of the one-step kernel (and
/// through the whole stick-slip window since the two-sums' terms are
/// `opaque`: gpu_engine.rs). Negative control: a drive 1e-9 faster is
/// flagged.
#[test]
fn every_kernel_is_the_one_step_kernel_bit_for_bit() {
    let m = driven();
    let end = m.prep_steps + 2500;
    let reference = run_to(&mut one_step(&m), end);
    assert!(reference.total_ruptures() > 100, "junctions broke");
    for path in [
        GpuPath::OneStepLanes,
        GpuPath::Persistent,
        GpuPath::Resident,
    ] {
        let got = run_to(&mut on_path(&m, path), end);
        assert!(
            got == reference,
            "{path:?}: {} ruptures against {}",
            got.total_ruptures(),
            reference.total_ruptures()
        );
    }
    let faster = drive_faster(&m);
    let other = run_to(&mut on_path(&faster, GpuPath::OneStepLanes), end);
    assert_ne!(other.disp, reference.disp, "control");
}

/// A block's lane subtrees merge as the complete tree of 64 lanes, the
/// missing ones zero, whatever their count (`merged_lane_partials`, which
/// adds them to the tree one at a time and closes it). Junction counts of
/// 24 and 56 leave 3 and 7 subtrees of 8 lanes where lanes merge in
/// subgroups of 8 (lavapipe), and 24 and 56 single lanes where every
/// lane's sum goes through storage; 7 and 56 leave three subtrees waiting
/// to be closed. On the kernels that merge partials from storage
/// (persistent, resident, tiled) they end in the one-step kernel's bits,
/// whose one thread adds all 64 lane slots. A close that drops a waiting
/// subtree fails here (tried); one that closes the same subtrees in
/// another association gave the same bits over this run (the compensated
/// merge rounds alike there), so the association rests on the tree's
/// definition (`lane_tree_close`). Negative control: a drive 1e-9 faster
/// is flagged.
#[test]
fn lane_subtrees_of_any_count_merge_as_the_one_step_kernels_tree() {
    let small: &[&str] = &slipfront::app::verify::SMALL_SCENE;
    for count in [24, 56] {
        let ns = format!("friction.junctions.count={count}");
        let m = model(&[small, &["loading.drive.velocity=0.4", ns.as_str()]].concat());
        let end = m.prep_steps + 2500;
        let reference = run_to(&mut one_step(&m), end);
        println!(
            "Ns = {count}: {} ruptures by step {end}",
            reference.total_ruptures()
        );
        assert!(
            reference.total_ruptures() > 100,
            "Ns = {count}: junctions broke"
        );
        for path in [GpuPath::Persistent, GpuPath::Resident, GpuPath::Tiled] {
            for lane_shuffle in [true, false] {
                let opts = GpuOptions {
                    path,
                    lane_shuffle,
                    ..GpuOptions::default()
                };
                let mut e = GpuEngine::with_options(&m, opts).unwrap();
                let got = run_to(&mut e, end);
                let levels = e.lane_shuffle_levels();
                // Runs of 8 (lavapipe) or more: 3 or more levels merged in
                // subgroups; none through storage.
                assert!(
                    if lane_shuffle {
                        levels >= 3
                    } else {
                        levels == 0
                    },
                    "Ns = {count}, {path:?}, shuffle {lane_shuffle}: {levels} levels"
                );
                assert!(
                    got == reference,
                    "Ns = {count}, {path:?}, shuffle {lane_shuffle}: {} ruptures against {}",
                    got.total_ruptures(),
                    reference.total_ruptures()
                );
            }
        }
        let faster = drive_faster(&m);
        let other = run_to(&mut on_path(&faster, GpuPath::Persistent), end);
        assert_ne!(other.disp, reference.disp, "control");
    }
}

/// Lane runs (`GpuOptions::lane_run`: a thread steps 2, 4 or 8
/// consecutive junction lanes and merges their sums as the lane tree's
/// lowest levels) end in the one-step kernel's bits through ruptures, on
/// the persistent, resident and tiled kernels. Ns = 56 leaves runs of 2 and
/// 4 lanes with subgroup levels above them (28 and 14 runs a block) and
/// runs of 8 with none (7 runs: each run's subtree goes through storage);
/// Ns = 100 fills all 64 lanes; runs of 4 with every run's sum through
/// storage too; runs of 4 with and without the next lane's pair loaded
/// ahead (`LANE_RUN_AHEAD`). Each engine says it compiled the run asked
/// for, so a run is not compared with a lane a thread. Negative control:
/// a drive 1e-9 faster on runs of 4 is flagged.
#[test]
fn lane_runs_merge_as_the_one_step_kernels_tree() {
    let small: &[&str] = &slipfront::app::verify::SMALL_SCENE;
    for (count, runs) in [(56, &[2u32, 4, 8][..]), (100, &[4][..])] {
        let ns = format!("friction.junctions.count={count}");
        let m = model(&[small, &["loading.drive.velocity=0.4", ns.as_str()]].concat());
        let end = m.prep_steps + 2500;
        let reference = run_to(&mut one_step(&m), end);
        assert!(
            reference.total_ruptures() > 100,
            "Ns = {count}: junctions broke"
        );
        for path in [GpuPath::Persistent, GpuPath::Resident, GpuPath::Tiled] {
            for &lane_run in runs {
                // (shuffle, loads ahead): the persistent kernels load a
                // run's next lane ahead unless one lane a round is asked.
                for (lane_shuffle, ahead) in [(true, true), (false, true), (true, false)] {
                    let persistent = path != GpuPath::Tiled;
                    if (!lane_shuffle || !ahead) && (lane_run != 4 || !persistent) {
                        continue;
                    }
                    let opts = GpuOptions {
                        path,
                        lane_shuffle,
                        lane_run,
                        two_lanes_a_round: ahead,
                        ..GpuOptions::default()
                    };
                    let mut e = GpuEngine::with_options(&m, opts).unwrap();
                    let how = e.describe();
                    assert!(
                        how.contains(&format!("{lane_run} junction lanes a thread")),
                        "{how}"
                    );
                    let got = run_to(&mut e, end);
                    let levels = e.lane_shuffle_levels();
                    let what =
                        format!("Ns = {count}, {path:?}, run {lane_run}, shuffle {lane_shuffle}");
                    // Subgroups merge 3 or more of the tree's levels (the
                    // run's own included), or none.
                    assert!(levels == 0 || levels >= 3, "{what}: {levels} levels");
                    assert_eq!(
                        levels > 0,
                        lane_shuffle && lane_run < 8,
                        "{what}: {levels} levels"
                    );
                    assert!(
                        got == reference,
                        "{what}: {} ruptures against {}",
                        got.total_ruptures(),
                        reference.total_ruptures()
                    );
                }
            }
        }
    }
    let m = model(&[small, &["loading.drive.velocity=0.4"]].concat());
    let end = m.prep_steps + 2500;
    let reference = run_to(&mut one_step(&m), end);
    let opts = GpuOptions {
        path: GpuPath::Resident,
        lane_run: 4,
        ..GpuOptions::default()
    };
    let faster = run_to(
        &mut GpuEngine::with_options(&drive_faster(&m), opts).unwrap(),
        end,
    );
    assert_ne!(faster.disp, reference.disp, "control");
    // A run that is no power of two up to 8 is refused, named.
    let odd = GpuOptions {
        lane_run: 3,
        ..opts
    };
    let err = GpuEngine::with_options(&m, odd)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        err.contains("lane_run = 3") && err.contains("[1, 2, 4, 8]"),
        "{err}"
    );
}

/// The tiled kernel's lane runs start on the first thread after the bulk
/// forces' items (`first_run_item`), at a multiple of 64 so that a block's
/// runs keep their places in their subgroup. On 15 rows a step's bulk items
/// are no multiple of 8 (lavapipe's subgroup), so a start that is not
/// rounded up misplaces the butterfly's partners. At 256 threads, lane
/// runs of 1 and 2 merged in subgroups end in the one-step kernel's bits
/// through ruptures.
#[test]
fn lane_runs_take_the_threads_the_bulk_forces_leave() {
    let small: &[&str] = &slipfront::app::verify::SMALL_SCENE;
    let fifteen_rows = ["geometry.nz=15", "geometry.height=0.035"];
    let m = model(&[small, &fifteen_rows, &["loading.drive.velocity=0.4"]].concat());
    assert_eq!(m.nz, 15);
    let end = m.prep_steps + 2500;
    let reference = run_to(&mut one_step(&m), end);
    assert!(reference.total_ruptures() > 100, "junctions broke");
    for lane_run in [1, 2] {
        let opts = GpuOptions {
            path: GpuPath::Tiled,
            tile: Some(TileShape { width: 8, halo: 4 }),
            persistent_threads: Some(256),
            lane_run,
            ..GpuOptions::default()
        };
        let mut e = GpuEngine::with_options(&m, opts).unwrap();
        let got = run_to(&mut e, end);
        assert!(
            e.lane_shuffle_levels() >= 3,
            "run {lane_run}: merged in subgroups"
        );
        assert!(
            got == reference,
            "run {lane_run}: {} ruptures against {}",
            got.total_ruptures(),
            reference.total_ruptures()
        );
    }
}

/// Batches cut every 37 steps, each followed by a snapshot (whose forces
/// the next batch's first step reads from storage), give the bits of one
/// long run.
#[test]
fn tiled_bits_do_not_depend_on_where_batches_begin() {
    let m = driven();
    let end = m.prep_steps + 2500;
    let whole = run_to(&mut tiled(&m, 8, 4), end);
    let mut cut = tiled(&m, 8, 4);
    while cut.steps_done() < end {
        let next = (cut.steps_done() + 37).min(end);
        advance_to(&mut cut, next).unwrap();
        cut.snapshot().unwrap();
    }
    let b = cut.snapshot().unwrap();
    assert!(whole.total_ruptures() > 0, "junctions broke");
    assert!(whole == b, "chunks changed the bits");
}

/// A per-block friction law keeps state a halo would race on, and a tile
/// that does not fit workgroup memory cannot run: both are refused with
/// the reason and what to use instead; so is a halo of 0 steps.
#[test]
fn the_tiled_kernel_refuses_what_it_cannot_step() {
    let coulomb = model(&["friction.law=\"coulomb\""]);
    let err = match GpuEngine::with_options(
        &coulomb,
        GpuOptions {
            path: GpuPath::Tiled,
            ..GpuOptions::default()
        },
    ) {
        Ok(_) => panic!("a per-block law must be refused"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("coulomb keeps per-block state"), "{err}");
    let m = driven();
    let wide = GpuOptions {
        path: GpuPath::Tiled,
        tile: Some(TileShape {
            width: 4000,
            ..TileShape::DEFAULT
        }),
        ..GpuOptions::default()
    };
    let err = GpuEngine::with_options(&m, wide).err().unwrap().to_string();
    assert!(err.contains("workgroup memory"), "{err}");
    assert!(err.contains("the adapter allows"), "{err}");
    let none = GpuOptions {
        path: GpuPath::Tiled,
        tile: Some(TileShape {
            halo: 0,
            ..TileShape::DEFAULT
        }),
        ..GpuOptions::default()
    };
    let err = GpuEngine::with_options(&m, none).err().unwrap().to_string();
    assert!(err.contains("tile halo 0"), "{err}");
}

/// A large lattice (257 × 65, 65 tiles of 4
/// columns, bulk fields among the samples) records its samples in the
/// tiled kernel's steps as a small one does: the samples equal the CPU
/// twin on host snapshots of the same kernel, and the twin a step later is
/// flagged.
#[test]
fn a_large_lattice_on_the_tiled_kernel_records_its_samples_on_the_device() {
    let s = large_lattice();
    let m = Model::from_scenario(&s, false).unwrap();
    let plan = plan(&m, &s);
    // 8 columns of 65 rows fit lavapipe's 32 KB of workgroup memory.
    let engine = |output| tiled_recording(&m, TileShape { width: 4, halo: 2 }, output);
    let mut dev = engine(GpuOutput::Device);
    assert!(dev.record_samples(&plan).unwrap());
    advance_to(&mut dev, m.total_steps()).unwrap();
    let samples = dev.take_samples();
    assert!(samples.len() >= 8, "{} samples", samples.len());
    assert!(samples.iter().any(|x| x.bulk.is_some()));
    assert_samples_match_the_twin(&m, &mut engine(GpuOutput::Host), &samples);
}

/// The halo copies keep their junction sums apart from their owner's
/// (`junction_sums_slot` in `junction_tiled.wgsl`). A round starts each
/// halo block from the sums its owner published with its junctions
/// (`GpuOptions::published_halo_sums`), or, the other way, from none:
/// summed at the round's first step, kept from the second. In a quiet
/// stretch of driving (before the first rupture) both the scene's records
/// and the halos' private ones hold kept sums; the one-step kernel keeps
/// none apart. The bits are those of summing every step (`gpu_engine.rs`,
/// `kept_junction_sums_give_the_bits_of_summing_every_step`).
#[test]
fn halo_copies_keep_their_junction_sums_apart() {
    let m = driven();
    let end = m.prep_steps + 200;
    // 29 columns in tiles of 8: 4 tiles, 6 halo sides of 4 columns. The
    // columns a step updates shrink by one each side, so a side's
    // outermost column is never stepped: it gets no junctions and no sums
    // (`tile_steps`). The other three keep theirs.
    for published in [true, false] {
        let mut e = tiled_with(&m, 8, 4, |o| o.published_halo_sums = published);
        advance_to(&mut e, end).unwrap();
        assert_eq!(e.snapshot().unwrap().total_ruptures(), 0, "a quiet stretch");
        let owned = e.kept_junction_blocks(0).unwrap();
        let halos = e.kept_halo_junction_records().unwrap();
        assert_eq!(owned, m.nx, "every block's sums kept");
        assert_eq!(halos, 6 * 3, "published: {published}");
    }
    let mut other = one_step(&m);
    advance_to(&mut other, end).unwrap();
    assert_eq!(other.kept_halo_junction_records().unwrap(), 0);
    assert_eq!(other.kept_junction_blocks(0).unwrap(), m.nx);
}

/// With the sums published beside the junctions, a quiet halo block keeps
/// its sums from a round's first step: in a stretch before the first
/// rupture no interface block, own or halo, sums its junctions
/// (`GpuStatus::summed_junction_blocks`), where starting each round from
/// no sums makes every stepped halo column sum once a round: three a halo
/// side (halo 4, the outermost column never stepped). Rounds a dispatch
/// each (tiles of 8: 6 halo sides) and chained in one dispatch (tiles of
/// 16: 2 sides, two tiles, which lavapipe runs at once). Through ruptures
/// both ways end in the same bits, the one-step kernel's.
#[test]
fn halo_blocks_keep_their_published_sums_from_a_rounds_first_step() {
    let m = driven();
    let quiet = (m.prep_steps + 20, m.prep_steps + 220);
    let end = m.prep_steps + 2500;
    // The count itself, on the one-step kernel: every interface block
    // summed at every step of the normal-load phase (nothing is kept
    // while the stiffnesses follow the load), and at most every block of
    // the 20 steps after it.
    let counted = GpuOptions {
        path: GpuPath::OneStep,
        count_summed_junction_blocks: true,
        ..GpuOptions::default()
    };
    let mut e = GpuEngine::with_options(&m, counted).unwrap();
    advance_to(&mut e, quiet.0).unwrap();
    let loaded = u64::from(e.summed_junction_blocks(0).unwrap());
    let nx = m.nx as u64;
    assert!(
        loaded >= nx * m.prep_steps && loaded <= nx * quiet.0,
        "{loaded} summed in {} steps of {nx} blocks",
        quiet.0
    );
    let reference = run_to(&mut one_step(&m), end);
    assert!(reference.total_ruptures() > 100, "junctions broke");
    for (chained, width, halo_sides) in [(false, 8, 6), (true, 16, 2)] {
        let mut summed = Vec::new();
        for published in [true, false] {
            let mut e = tiled_with(&m, width, 4, |o| {
                o.published_halo_sums = published;
                o.count_summed_junction_blocks = true;
                o.chained_tiles = chained;
            });
            advance_to(&mut e, quiet.0).unwrap();
            let before = e.summed_junction_blocks(0).unwrap();
            advance_to(&mut e, quiet.1).unwrap();
            assert_eq!(e.snapshot().unwrap().total_ruptures(), 0, "a quiet stretch");
            summed.push(e.summed_junction_blocks(0).unwrap() - before);
            let state = run_to(&mut e, end);
            assert!(
                state == reference,
                "chained {chained}, published {published}: not the one-step kernel's bits"
            );
        }
        println!("chained {chained}: summed in the quiet stretch, published and not: {summed:?}");
        assert_eq!(summed[0], 0, "chained {chained}: a halo block summed");
        let rounds = (quiet.1 - quiet.0) as u32 / 4;
        assert!(
            summed[1] >= 3 * halo_sides * rounds,
            "chained {chained}: {summed:?}"
        );
    }
}

/// A sample every step (the global cadence at dt): more samples than a
/// tiled batch keeps partials for (`TILED_SAMPLES_A_BATCH`, 256), so the
/// batches are cut short, through 600 steps of ruptures. Every step's
/// sample equals the CPU twin on host snapshots of the same kernel, and
/// the twin a step later is flagged.
#[test]
fn a_sample_every_step_cuts_the_tiled_batches_and_records_every_one() {
    let small: &[&str] = &slipfront::app::verify::SMALL_SCENE;
    let set: Vec<String> = [small, &["loading.drive.velocity=0.4"]]
        .concat()
        .iter()
        .map(|s| s.to_string())
        .collect();
    let mut s = Scenario::parse(DEFAULT_SCENARIO, "test", &set).unwrap();
    let m0 = Model::from_scenario(&s, false).unwrap();
    s.output.global_interval = m0.dt;
    let m = Model::from_scenario(&s, false).unwrap();
    let plan = plan(&m, &s);
    assert_eq!(plan.every_global, 1);
    let engine = |output| tiled_recording(&m, TileShape { width: 8, halo: 4 }, output);
    let mut dev = engine(GpuOutput::Device);
    assert!(dev.record_samples(&plan).unwrap());
    let start = m.prep_steps + 2000;
    advance_to(&mut dev, start).unwrap();
    dev.take_samples();
    advance_to(&mut dev, start + 600).unwrap();
    let samples = dev.take_samples();
    let steps: Vec<u64> = samples.iter().map(|x| x.step).collect();
    let expected: Vec<u64> = (start + 1..=start + 600).collect();
    assert_eq!(steps, expected, "a sample every step");
    assert!(
        samples.last().unwrap().sums.ruptures > samples[0].sums.ruptures,
        "junctions broke while sampled"
    );
    // Three batches of 256 samples at most, each with its finish.
    assert!(dev.output_dispatches().unwrap() >= 3);
    assert_samples_match_the_twin(&m, &mut engine(GpuOutput::Host), &samples);
}

/// The tiled kernel of `shape` on `m`, its samples taken as `output` says.
fn tiled_recording(m: &Model, shape: TileShape, output: GpuOutput) -> GpuEngine {
    let opts = GpuOptions {
        path: GpuPath::Tiled,
        output,
        tile: Some(shape),
        ..GpuOptions::default()
    };
    GpuEngine::with_options(m, opts).expect("a GPU adapter (lavapipe in CI)")
}

/// Device samples equal the CPU twin on host snapshots of `host` (the
/// same kernel) to f32 round-off, and the twin a step later is flagged.
fn assert_samples_match_the_twin(m: &Model, host: &mut GpuEngine, samples: &[Sample]) {
    let (twin, later) = twins(m, host, samples);
    let (err, field) = worst_error(&twin, samples);
    println!(
        "{} samples: device against twin {err:.2e} ({field})",
        samples.len()
    );
    assert!(err < 1e-5, "{field} off by {err:.2e} of its scale");
    let (shifted, field) = worst_error(&later, samples);
    assert!(shifted > 1e-4, "a one-step shift must be flagged ({field})");
}
