//! The MCAP output read back: every channel against the engine state, the
//! protobuf schema, and `info`/`plot` on a real run.

use slipfront::app::runner::{run_scene, RunOptions};
use slipfront::engines::backend::{cpu_engine, Precision};
use slipfront::io::output::reader::RunFile;
use slipfront::io::output::ChunkCompression;
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Model};

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

/// The default scene with `set` applied, its model, and a fresh folder
/// named `name` for its files.
fn scene(name: &str, set: &[&str]) -> (Scenario, Model, Scratch) {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let scenario = Scenario::parse(DEFAULT_SCENARIO, name, &set).unwrap();
    let model = Model::from_scenario(&scenario, false).unwrap();
    (scenario, model, Scratch::new("output", name))
}

#[test]
fn every_channel_reads_back_as_the_engine_state() {
    // 2.2e-4 s of fast driving (junctions break); every cadence divides the end, so the last
    // message of each channel is the final state.
    let (scenario, model, dir) = scene(
        "out",
        &[
            "time.end=2.237101e-4",
            "time.dt=2.237101e-7",
            "loading.drive.velocity=2.0",
            "output.global_interval=2.237101e-6",
            "output.interface_interval=4.474202e-6",
            "output.bulk_interval=1.1185505e-4",
            "output.fast_interval=0",
        ],
    );
    let path = dir.join("run.mcap");
    let mut engine = cpu_engine(&model, Precision::F64, 1).unwrap();
    run_scene(
        engine.as_mut(),
        &scenario,
        &RunOptions {
            fast_forward: None,
            output: Some(path.clone()),
            ..RunOptions::default()
        },
    )
    .unwrap();
    let run = RunFile::read(&path).unwrap();
    assert!(!run.truncated);
    assert_eq!(run.metadata["nx"], "57");
    assert_eq!(run.metadata["backend"], "cpu f64 (1 thread(s), sweep)");
    let attached = Scenario::parse(run.scenario.as_deref().unwrap(), "attachment", &[]).unwrap();
    assert_eq!(attached, scenario);
    assert_eq!(
        (run.global.len(), run.interface.len(), run.bulk.len()),
        (100, 50, 2)
    );

    // The same scene, stepped again, gives the reference state.
    let mut reference = cpu_engine(&model, Precision::F64, 1).unwrap();
    advance_to(reference.as_mut(), model.total_steps()).unwrap();
    let snap = reference.snapshot().unwrap();
    let area = model.spacing * model.width;
    let last = run.interface.last().unwrap();
    assert_eq!(last.step, snap.step);
    assert_eq!(last.pinned_fraction, snap.pinned_fraction(model.nx));
    for ix in 0..model.nx {
        assert_eq!(last.shear_stress[ix], -snap.friction[ix] / area);
        assert_eq!(last.normal_stress[ix], snap.normal[ix] / area);
        assert_eq!(last.slip_speed[ix], snap.vel[ix][0]);
    }
    let bulk = run.bulk.last().unwrap();
    assert_eq!((bulk.nx, bulk.nz), (57, 31));
    for i in 0..model.n_blocks() {
        assert_eq!(bulk.ux[i], snap.disp[i][0] as f32);
        assert_eq!(bulk.vz[i], snap.vel[i][1] as f32);
    }
    let g = run.global.last().unwrap();
    assert_eq!(g.ruptures, snap.total_ruptures());
    assert_eq!(g.friction_force, snap.total_friction());
    assert!(g.ruptures > 0);
    // The load at a time is that of the nearest global sample.
    let mid = &run.global[40];
    assert_eq!(run.drive_ratio_at(mid.time), mid.drive_ratio);
    let after = &run.global[41];
    let near_after = mid.time + 0.6 * (after.time - mid.time);
    assert_eq!(run.drive_ratio_at(near_after), after.drive_ratio);
    assert_eq!(run.drive_ratio_at(-1.0), run.global[0].drive_ratio);
    assert_eq!(run.drive_ratio_at(1e9), g.drive_ratio);
}

#[test]
fn a_file_cut_short_is_still_readable() {
    let (scenario, model, dir) = scene("cut", &["time.end=1e-4", "output.interface_interval=1e-6"]);
    let path = dir.join("run.mcap");
    let mut engine = cpu_engine(&model, Precision::F64, 1).unwrap();
    let opts = RunOptions {
        fast_forward: None,
        output: Some(path.clone()),
        ..RunOptions::default()
    };
    run_scene(engine.as_mut(), &scenario, &opts).unwrap();
    let whole = RunFile::read(&path).unwrap();
    // Drop the summary and the end of the data, as a kill would.
    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let part = RunFile::read(&cut).unwrap();
    assert!(part.truncated);
    assert!(!part.interface.is_empty());
    assert!(part.interface.len() <= whole.interface.len());
    assert_eq!(part.interface[0], whole.interface[0]);
}

#[test]
fn a_scratch_file_without_compression_reads_back_as_the_compressed_one() {
    // A sweep point that keeps no file writes it uncompressed: the same
    // messages, read back the same, in a larger file (the control: the
    // option is seen to change the file).
    let (scenario, model, dir) = scene(
        "scratch",
        &[
            "time.end=1e-4",
            "output.interface_interval=1e-6",
            "output.bulk_interval=2e-5",
        ],
    );
    let write = |name: &str, compression| {
        let path = dir.join(name);
        let mut engine = cpu_engine(&model, Precision::F64, 1).unwrap();
        let opts = RunOptions {
            output: Some(path.clone()),
            output_compression: compression,
            ..RunOptions::default()
        };
        run_scene(engine.as_mut(), &scenario, &opts).unwrap();
        let size = std::fs::metadata(&path).unwrap().len();
        (RunFile::read(&path).unwrap(), size)
    };
    let (kept, kept_size) = write("kept.mcap", ChunkCompression::Zstd);
    let (scratch, scratch_size) = write("scratch.mcap", ChunkCompression::None);
    assert!(!scratch.truncated && scratch.damage.is_none());
    assert!(!scratch.interface.is_empty() && !scratch.bulk.is_empty());
    assert_eq!(scratch.global, kept.global);
    assert_eq!(scratch.interface, kept.interface);
    assert_eq!(scratch.bulk, kept.bulk);
    assert!(
        scratch_size > kept_size,
        "uncompressed {scratch_size} B, zstd {kept_size} B"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
