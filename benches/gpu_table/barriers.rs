//! Section 10: the phase barriers at workgroup scope against naga's device
//! scope (`GpuOptions::workgroup_barriers`), each launch both ways in one
//! run.

use crate::common::{s1_scene, section_launches};
use crate::gpu_timing::{ensemble_step_seconds, solo_step_figures_in};
use slipfront::engines::gpu::context::GpuContext;
use slipfront::engines::gpu::kernel_choice::Launch;
use slipfront::engines::gpu::{GpuOptions, GpuReal};
use slipfront::Model;

/// Launches whose step has phase barriers, timed on Table S1 alone.
pub const SOLO: &[&str] = &[
    "persistent/256",
    "persistent/1024",
    "resident/1024",
    "tiled/512/8x4",
    "tiled/512/8x4/chained",
];

/// Launches timed on ensembles of Table S1 scenes.
const ENSEMBLE: &[&str] = &[
    "resident/1024",
    "persistent/1024/2-scenes",
    "persistent/256",
];

/// Quick (software adapters, 29 columns): tiles a scene no more than
/// lavapipe's cores, so the chained ones run at once.
const QUICK_SOLO: &[&str] = &["persistent/256", "tiled/256/16x4", "tiled/256/16x4/chained"];
const QUICK_ENSEMBLE: &[&str] = &["persistent/256"];

fn launch(name: &str) -> Launch {
    Launch::named(name).unwrap_or_else(|| panic!("`{name}` is not a launch name"))
}

fn options(name: &str, workgroup: bool) -> GpuOptions {
    GpuOptions {
        workgroup_barriers: workgroup,
        ..launch(name).options(GpuOptions::default())
    }
}

/// What a device-scope barrier between a step's phases costs: each launch
/// with its barriers at workgroup scope (the default where the engine
/// writes its own SPIR-V) and at device scope (the module wgpu writes),
/// timed in the order workgroup, device, device, workgroup, so that a
/// drift of the clocks falls on both alike. The device's busy time a step
/// beside the wall time.
pub fn scopes(ctx: &GpuContext, quick: bool, min_seconds: f64) {
    println!("\n## 10. Phase barriers: workgroup against device scope\n");
    if !ctx.has_own_spirv() {
        println!(
            "This adapter takes no SPIR-V from the engine (it needs Vulkan 1.3 and wgpu's \
             passthrough shaders): both columns time wgpu's module.\n"
        );
    }
    let scene = |seed: usize| s1_scene(seed, quick);
    let s1 = scene(1);
    println!("Table S1 alone (µs a step: wall, with the device's busy time in brackets):\n");
    println!("| launch | precision | workgroup scope | device scope | device / workgroup |");
    println!("| --- | --- | ---: | ---: | ---: |");
    let solo = section_launches(SOLO, QUICK_SOLO, quick);
    for name in &solo {
        solo_row::<f32>(&s1, name, min_seconds);
    }
    if !quick {
        for name in solo
            .iter()
            .filter(|n| n.starts_with("persistent/1024") || n.ends_with("chained"))
        {
            solo_row::<f64>(&s1, name, min_seconds);
        }
    }
    let counts: &[usize] = if quick { &[4] } else { &[132, 264] };
    println!("\nEnsembles of Table S1 scenes (µs an ensemble step, mixed f32):\n");
    println!("| launch | scenes | workgroup scope | device scope | device / workgroup |");
    println!("| --- | ---: | ---: | ---: | ---: |");
    for &n in counts {
        let models: Vec<Model> = (0..n).map(|k| scene(k + 1)).collect();
        for name in &section_launches(ENSEMBLE, QUICK_ENSEMBLE, quick) {
            let time = |workgroup| {
                ensemble_step_seconds(&models, options(name, workgroup), min_seconds)
                    .map(|(s, _)| s)
            };
            let row = (|| -> Result<(f64, f64), String> {
                let (w1, d1, d2, w2) = (time(true)?, time(false)?, time(false)?, time(true)?);
                Ok(((w1 + w2) / 2.0, (d1 + d2) / 2.0))
            })();
            match row {
                Ok((w, d)) => println!(
                    "| {name} | {n} | {:.2} | {:.2} | {:.3} |",
                    w * 1e6,
                    d * 1e6,
                    d / w
                ),
                Err(e) => println!("| {name} | {n} | not run: {e} | | |"),
            }
        }
    }
    println!();
}

/// One launch alone on `model` in precision `T`, both ways.
fn solo_row<T: GpuReal>(model: &Model, name: &str, min_seconds: f64) {
    let time = |workgroup| solo_step_figures_in::<T>(model, options(name, workgroup), min_seconds);
    let row = (|| {
        let (w1, d1, d2, w2) = (time(true)?, time(false)?, time(false)?, time(true)?);
        Ok::<_, String>(((w1, w2), (d1, d2)))
    })();
    let figure = |(a, b): (
        crate::gpu_timing::StepFigures,
        crate::gpu_timing::StepFigures,
    )| {
        let wall = (a.seconds + b.seconds) / 2.0;
        let busy = a.device.zip(b.device).map(|(x, y)| (x + y) / 2.0);
        let text = match busy {
            Some(b) => format!("{:.2} ({:.2})", wall * 1e6, b * 1e6),
            None => format!("{:.2}", wall * 1e6),
        };
        (wall, text)
    };
    match row {
        Ok((w, d)) => {
            let ((ws, wt), (ds, dt)) = (figure(w), figure(d));
            println!("| {name} | {} | {wt} | {dt} | {:.3} |", T::NAME, ds / ws);
        }
        Err(e) => println!("| {name} | {} | not run: {e} | | |", T::NAME),
    }
}
