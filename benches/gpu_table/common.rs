//! What the sections share: the kernels' options as the environment sets
//! them, the precursors scene with keys changed, and counts from the
//! environment.

use slipfront::engines::gpu::shaders::Kernel;
use slipfront::engines::gpu::{GpuOptions, GpuPath};
use slipfront::{Model, Scenario};

pub fn options(kernel: Kernel) -> GpuOptions {
    GpuOptions {
        path: GpuPath::of(kernel),
        keep_junction_sums: keep_sums(),
        lane_shuffle: lane_shuffle(),
        ..GpuOptions::default()
    }
}

/// `SLIPFRONT_GPU_TABLE_LANE_SHUFFLE`: 1 (the default) merges runs of
/// junction lanes in subgroups before storage, 0 sends every lane's sum
/// through storage.
fn lane_shuffle() -> bool {
    match std::env::var("SLIPFRONT_GPU_TABLE_LANE_SHUFFLE").as_deref() {
        Err(_) | Ok("1") => true,
        Ok("0") => false,
        Ok(v) => panic!("SLIPFRONT_GPU_TABLE_LANE_SHUFFLE: `{v}` is neither 0 nor 1"),
    }
}

/// `SLIPFRONT_GPU_TABLE_KEEP_SUMS`: 1 (the default) keeps quiet blocks'
/// junction sums, 0 sums every junction every step.
fn keep_sums() -> bool {
    match std::env::var("SLIPFRONT_GPU_TABLE_KEEP_SUMS").as_deref() {
        Err(_) | Ok("1") => true,
        Ok("0") => false,
        Ok(v) => panic!("SLIPFRONT_GPU_TABLE_KEEP_SUMS: `{v}` is neither 0 nor 1"),
    }
}

pub fn with_threads(kernel: Kernel, threads: Option<u32>) -> GpuOptions {
    GpuOptions {
        persistent_threads: threads,
        ..options(kernel)
    }
}

pub fn path_name(kernel: Kernel) -> String {
    GpuPath::of(kernel).name()
}

/// The precursors scene from `text`, with `set`'s keys changed.
pub fn s1_model(text: &str, set: &[&str]) -> Model {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let scenario = Scenario::parse(text, "table S1", &set).expect("the scene");
    Model::from_scenario(&scenario, false).expect("the scene")
}

/// The counts listed in environment variable `name` (`1,64,256`), else
/// `default`.
pub fn counts_from_env(name: &str, default: &[usize]) -> Vec<usize> {
    match std::env::var(name) {
        Ok(list) => list
            .split(',')
            .map(|n| {
                n.trim()
                    .parse()
                    .unwrap_or_else(|_| panic!("{name}: `{n}` is not a count"))
            })
            .collect(),
        Err(_) => default.to_vec(),
    }
}

/// A section's launch names: `SLIPFRONT_GPU_TABLE_LAUNCHES` where set,
/// else `full`, or `quick_list` in the quick form.
pub fn section_launches(full: &[&str], quick_list: &[&str], quick: bool) -> Vec<String> {
    match std::env::var("SLIPFRONT_GPU_TABLE_LAUNCHES") {
        Ok(list) => list.split(',').map(|s| s.trim().to_string()).collect(),
        Err(_) => match quick {
            true => quick_list,
            false => full,
        }
        .iter()
        .map(|s| s.to_string())
        .collect(),
    }
}

/// Table S1 with seed `seed`; in the quick form (software adapters), its
/// keys on 29 columns.
pub fn s1_scene(seed: usize, quick: bool) -> Model {
    match quick {
        false => crate::gpu_timing::table_s1(seed),
        true => s1_model(
            slipfront::model::scenario::built_in("tromborg2014_precursors").expect("shipped scene"),
            &[
                "geometry.nx=29",
                "geometry.length=0.07",
                &format!("time.seed={seed}"),
            ],
        ),
    }
}
