//! What writing an output file costs a GPU run, with the output samples
//! made on the device (`--gpu-output device`, `shaders/record.wgsl`) and
//! from whole-state snapshots read back at every sample (`host`), against
//! the same run without output, at the scenario's default cadences
//! (global 10 µs, interface 20 µs and 1 µs while slipping, bulk 10 ms).
//! `cargo bench --bench gpu_output [-- STEPS]`; prints a Markdown table
//! (BENCHMARKS.md). The three runs of a scene are timed in rounds, one of
//! each per round, so a noisy machine affects them alike.

use slipfront::app::runner::{run_scene, ProgressMode, RunOptions};
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuOutput, GpuPath};
use slipfront::io::output::reader::RunFile;
use slipfront::{Engine, Model, Scenario};
use std::path::PathBuf;
use std::time::Instant;

#[path = "support/bench_scene.rs"]
mod bench_scene;

/// Wall seconds of the driving phase (the normal-load phase is run before
/// the clock starts, by a run without output to the loaded state).
fn timed(s: &Scenario, path: GpuPath, output: Option<(GpuOutput, &PathBuf)>) -> (f64, u64, String) {
    let m = Model::from_scenario(s, false).expect("bench model");
    let opts = GpuOptions {
        path,
        output: output.map_or(GpuOutput::Device, |o| o.0),
        ..GpuOptions::default()
    };
    let mut e = GpuEngine::with_options(&m, opts).expect("a GPU adapter");
    slipfront::advance_to(&mut e, m.prep_steps).expect("normal load");
    let run = RunOptions {
        output: output.map(|o| o.1.clone()),
        progress: ProgressMode::None,
        ..RunOptions::default()
    };
    if let Some((_, p)) = output {
        let _ = std::fs::remove_file(p);
        let _ = std::fs::remove_file(slipfront::io::checkpoint::path_for(p));
    }
    let t0 = Instant::now();
    run_scene(&mut e, s, &run).expect("run");
    let wall = t0.elapsed().as_secs_f64();
    (wall, m.total_steps() - m.prep_steps, e.describe())
}

fn main() {
    let steps: f64 = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .and_then(|a| a.parse().ok())
        .unwrap_or(4000.0);
    let dir = std::env::temp_dir().join(format!("slipfront-gpu-output-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scenes: [(&str, GpuPath, u32, u32, &[&str]); 3] = [
        (
            "57×31, V = 1 m/s (junctions slipping throughout)",
            GpuPath::Auto,
            57,
            31,
            &[],
        ),
        (
            "57×31, V = 0.4 mm/s (stick phase)",
            GpuPath::Auto,
            57,
            31,
            &["loading.drive.velocity=4e-4"],
        ),
        (
            "57×31, V = 1 m/s, persistent kernel",
            GpuPath::Persistent,
            57,
            31,
            &[],
        ),
    ];
    println!("| scene | output | driving steps | wall (s) | µs/step | against no output | records (global / interface / bulk) |");
    println!("| --- | --- | ---: | ---: | ---: | ---: | --- |");
    let mut adapter = String::new();
    for (name, path, nx, nz, extra) in scenes {
        let m = bench_scene::scene(nx, nz);
        let t_end = format!("time.end={}", steps * m.dt);
        let mut set: Vec<&str> = vec![t_end.as_str()];
        set.extend(extra);
        let s = bench_scene::scenario(nx, nz, &set);
        let (host_file, device_file) = (dir.join("host.mcap"), dir.join("device.mcap"));
        let mut best = [f64::INFINITY; 3];
        let mut driving = 0;
        for _round in 0..3 {
            let runs = [
                None,
                Some((GpuOutput::Host, &host_file)),
                Some((GpuOutput::Device, &device_file)),
            ];
            for (k, out) in runs.into_iter().enumerate() {
                let (wall, n, describe) = timed(&s, path, out);
                best[k] = best[k].min(wall);
                driving = n;
                if path == GpuPath::Auto {
                    adapter = describe;
                }
            }
        }
        for (k, label) in ["none", "`-o`, host snapshots", "`-o`, device records"]
            .iter()
            .enumerate()
        {
            let records = match k {
                1 => Some(&host_file),
                2 => Some(&device_file),
                _ => None,
            }
            .map_or("".to_string(), |p| {
                let r = RunFile::read(p).expect("run file");
                format!(
                    "{} / {} / {}",
                    r.global.len(),
                    r.interface.len(),
                    r.bulk.len()
                )
            });
            println!(
                "| {name} | {label} | {driving} | {:.2} | {:.0} | {:.2}× | {records} |",
                best[k],
                1e6 * best[k] / driving as f64,
                best[k] / best[0],
            );
        }
    }
    println!("\n{adapter}; best of 3 rounds");
    let _ = std::fs::remove_dir_all(&dir);
}
