//! What the tests of the kernels with phase barriers share: the small
//! side-driven scene, and those kernels' launches.

use slipfront::engines::gpu::tiles::TileShape;
use slipfront::engines::gpu::{GpuOptions, GpuPath};
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::Model;

/// The small side-driven scene of the cross-checks (29 × 16 blocks),
/// driven at `velocity`: at 0.4, fast enough that junctions break within
/// a test's run.
pub fn driven(velocity: f64) -> Model {
    let small: &[&str] = &slipfront::app::verify::SMALL_SCENE;
    let drive = format!("loading.drive.velocity={velocity}");
    let set: Vec<String> = [small, &[drive.as_str()]]
        .concat()
        .iter()
        .map(|s| s.to_string())
        .collect();
    let s = Scenario::parse(DEFAULT_SCENARIO, "test", &set).unwrap();
    Model::from_scenario(&s, false).unwrap()
}

/// The kernels with phase barriers: persistent, resident, tiled (tiles of
/// 16 columns, halo 4: two on the small scene) and chained tiles.
pub fn launches() -> Vec<(&'static str, GpuOptions)> {
    let with = |path, chained| GpuOptions {
        path,
        tile: (path == GpuPath::Tiled).then_some(TileShape { width: 16, halo: 4 }),
        chained_tiles: chained,
        ..GpuOptions::default()
    };
    vec![
        ("persistent", with(GpuPath::Persistent, false)),
        ("resident", with(GpuPath::Resident, false)),
        ("tiled", with(GpuPath::Tiled, false)),
        ("tiled, chained", with(GpuPath::Tiled, true)),
    ]
}
