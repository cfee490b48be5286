//! The benches' scene of a given lattice size: the Table S1 scene's
//! spacing, a short normal-load phase, then driven hard enough that
//! junctions rupture. Shared by `throughput` and `stencil_ceiling`.

use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::Model;

pub fn scene(nx: u32, nz: u32) -> Model {
    Model::from_scenario(&scenario(nx, nz, &[]), false).expect("bench model")
}

/// The scenario of `scene`, with `extra` overrides after its own.
#[allow(dead_code)] // not every bench runs scenarios
pub fn scenario(nx: u32, nz: u32, extra: &[&str]) -> Scenario {
    let l = 0.14 / 56.0;
    let set = vec![
        format!("geometry.nx={nx}"),
        format!("geometry.nz={nz}"),
        format!("geometry.length={}", l * (nx - 1) as f64),
        format!("geometry.height={}", l * (nz - 1) as f64),
        // Short normal-load phase, then driving hard so junctions rupture.
        "loading.normal.ramp_time=2e-5".into(),
        "loading.normal.relax_time=2e-5".into(),
        "loading.drive.velocity=1.0".into(),
    ];
    let set: Vec<String> = set
        .into_iter()
        .chain(extra.iter().map(|s| s.to_string()))
        .collect();
    Scenario::parse(DEFAULT_SCENARIO, "bench", &set).expect("bench scene")
}
