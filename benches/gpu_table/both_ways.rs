//! Sections 10 and 12: one option of the kernels' build both ways, each
//! launch timed both ways in one run. Section 10: the phase barriers at
//! workgroup scope against naga's device scope
//! (`GpuOptions::workgroup_barriers`). Section 12: mixed f32's strict
//! arithmetic against wgpu's guarded modules
//! (`GpuOptions::arithmetic`, strict against wgpu's).

use crate::common::{s1_scene, section_launches};
use crate::gpu_timing::{ensemble_step_seconds, solo_step_figures_in};
use slipfront::engines::gpu::context::GpuContext;
use slipfront::engines::gpu::kernel_choice::Launch;
use slipfront::engines::gpu::{Arithmetic, GpuOptions, GpuReal};
use slipfront::Model;

/// An option timed both ways: on (the default) and off.
pub struct BothWays {
    pub section: u32,
    pub title: &'static str,
    /// What the two columns are.
    pub on: &'static str,
    pub off: &'static str,
    /// Launches timed on Table S1 alone, and those on ensembles (quick:
    /// software adapters, 29 columns, tiling a scene no more than
    /// lavapipe's cores so the chained ones run at once).
    pub solo: &'static [&'static str],
    pub quick_solo: &'static [&'static str],
    pub ensemble: &'static [&'static str],
    pub quick_ensemble: &'static [&'static str],
    /// Launches timed alone in f64 too, where f64 builds the option
    /// (quick: on software adapters).
    pub f64_solo: &'static [&'static str],
    pub quick_f64_solo: &'static [&'static str],
    /// The launch's options with the option on or off.
    pub set: fn(GpuOptions, bool) -> GpuOptions,
}

/// Section 10: launches whose step has phase barriers.
pub const BARRIERS: BothWays = BothWays {
    section: 10,
    title: "Phase barriers: workgroup against device scope",
    on: "workgroup scope",
    off: "device scope",
    solo: &[
        "persistent/256",
        "persistent/1024",
        "resident/1024",
        "tiled/512/8x4",
        "tiled/512/8x4/chained",
    ],
    quick_solo: &["persistent/256", "tiled/256/16x4", "tiled/256/16x4/chained"],
    ensemble: &[
        "resident/1024",
        "persistent/1024/2-scenes",
        "persistent/256",
    ],
    quick_ensemble: &["persistent/256"],
    f64_solo: &["persistent/1024", "tiled/512/8x4/chained"],
    quick_f64_solo: &[],
    set: |o, on| GpuOptions {
        workgroup_barriers: on,
        ..o
    },
};

/// Section 12: every kernel, the one-step kernels included (strict
/// arithmetic is the engine's own SPIR-V for them too). On AMD's compiler
/// strict issues 2.5-5 % fewer instructions in mixed f32 (session 67) and
/// 4-7 % more in f64 (session 68); what NVIDIA's makes of a kernel without
/// fused multiply-adds only this times.
pub const ARITHMETIC: BothWays = BothWays {
    section: 12,
    title: "Strict arithmetic against wgpu's modules (mixed f32: guarded; f64: plain)",
    on: "strict",
    off: "wgpu's",
    solo: &[
        "one-step",
        "one-step-lanes",
        "persistent/1024",
        "resident/1024",
        "tiled/512/8x4",
        "tiled/512/8x4/chained",
    ],
    quick_solo: &["one-step-lanes", "persistent/256", "tiled/256/16x4/chained"],
    ensemble: &["resident/1024", "resident/512", "persistent/256"],
    quick_ensemble: &["persistent/256"],
    f64_solo: &["one-step-lanes", "persistent/1024", "tiled/512/8x4/chained"],
    quick_f64_solo: &["one-step-lanes", "persistent/256"],
    set: |o, on| GpuOptions {
        arithmetic: match on {
            true => Arithmetic::Strict,
            false => Arithmetic::Wgpu,
        },
        ..o
    },
};

fn launch(name: &str) -> Launch {
    Launch::named(name).unwrap_or_else(|| panic!("`{name}` is not a launch name"))
}

impl BothWays {
    fn options(&self, name: &str, on: bool) -> GpuOptions {
        (self.set)(launch(name).options(GpuOptions::default()), on)
    }

    /// Each launch with the option on (the default) and off, timed in the
    /// order on, off, off, on, so that a drift of the clocks falls on both
    /// alike. The device's busy time a step beside the wall time.
    pub fn compare(&self, ctx: &GpuContext, quick: bool, min_seconds: f64) {
        println!("\n## {}. {}\n", self.section, self.title);
        if !ctx.has_own_spirv() {
            println!(
                "This adapter takes no SPIR-V from the engine (it needs Vulkan 1.3 and wgpu's \
                 passthrough shaders): both columns time wgpu's module.\n"
            );
        }
        let (on, off) = (self.on, self.off);
        let scene = |seed: usize| s1_scene(seed, quick);
        let s1 = scene(1);
        println!("Table S1 alone (µs a step: wall, with the device's busy time in brackets):\n");
        println!("| launch | precision | {on} | {off} | {off} / {on} |");
        println!("| --- | --- | ---: | ---: | ---: |");
        let solo = section_launches(self.solo, self.quick_solo, quick);
        for name in &solo {
            self.solo_row::<f32>(&s1, name, min_seconds);
        }
        for name in &section_launches(self.f64_solo, self.quick_f64_solo, quick) {
            self.solo_row::<f64>(&s1, name, min_seconds);
        }
        let counts: &[usize] = if quick { &[4] } else { &[132, 264] };
        println!("\nEnsembles of Table S1 scenes (µs an ensemble step, mixed f32):\n");
        println!("| launch | scenes | {on} | {off} | {off} / {on} |");
        println!("| --- | ---: | ---: | ---: | ---: |");
        for &n in counts {
            let models: Vec<Model> = (0..n).map(|k| scene(k + 1)).collect();
            for name in &section_launches(self.ensemble, self.quick_ensemble, quick) {
                let time = |on| {
                    ensemble_step_seconds(&models, self.options(name, on), min_seconds)
                        .map(|(s, _)| s)
                };
                let row = (|| -> Result<(f64, f64), String> {
                    let (a1, b1, b2, a2) = (time(true)?, time(false)?, time(false)?, time(true)?);
                    Ok(((a1 + a2) / 2.0, (b1 + b2) / 2.0))
                })();
                match row {
                    Ok((a, b)) => println!(
                        "| {name} | {n} | {:.2} | {:.2} | {:.3} |",
                        a * 1e6,
                        b * 1e6,
                        b / a
                    ),
                    Err(e) => println!("| {name} | {n} | not run: {e} | | |"),
                }
            }
        }
        println!();
    }

    /// One launch alone on `model` in precision `T`, both ways.
    fn solo_row<T: GpuReal>(&self, model: &Model, name: &str, min_seconds: f64) {
        let time = |on| solo_step_figures_in::<T>(model, self.options(name, on), min_seconds);
        let row = (|| {
            let (a1, b1, b2, a2) = (time(true)?, time(false)?, time(false)?, time(true)?);
            Ok::<_, String>(((a1, a2), (b1, b2)))
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
            Ok((a, b)) => {
                let ((a_s, a_t), (b_s, b_t)) = (figure(a), figure(b));
                println!(
                    "| {name} | {} | {a_t} | {b_t} | {:.3} |",
                    T::NAME,
                    b_s / a_s
                );
            }
            Err(e) => println!("| {name} | {} | not run: {e} | | |", T::NAME),
        }
    }
}
