//! The tiled kernel by tile shape: unchained (section 2's grid) and with
//! its rounds chained in one dispatch (section 9).

use crate::common::{s1_model, with_threads};
use crate::gpu_timing::{solo_step_figures_in, solo_step_seconds, table_s1};
use slipfront::engines::gpu::shaders::Kernel;
use slipfront::engines::gpu::tiles::TileShape;
use slipfront::engines::gpu::GpuOptions;
use slipfront::model::scenario::built_in;
use slipfront::Model;

/// The tiled kernel on `model` by tile width, halo (the most steps per
/// dispatch) and threads: which tiles fill the GPU's SMs and how many
/// steps a dispatch should take (`shaders/tiled.wgsl`).
pub fn tiled_grid(model: &Model, quick: bool, min_seconds: f64) {
    println!("The tiled kernel by tile width, halo (steps per dispatch) and threads:\n");
    println!("| tile width | halo | threads | µs/step | host CPU / wall |");
    println!("| ---: | ---: | ---: | ---: | ---: |");
    let (widths, halos, threads): (&[u32], &[u32], &[u32]) = if quick {
        (&[8, 16], &[2, 4], &[256])
    } else {
        (&[2, 4, 8, 16], &[2, 4, 8], &[256, 1024])
    };
    for &width in widths {
        for &halo in halos {
            for &t in threads {
                let opts = GpuOptions {
                    tile: Some(TileShape { width, halo }),
                    ..with_threads(Kernel::Tiled, Some(t))
                };
                let figure = match solo_step_seconds(model, opts, min_seconds) {
                    Ok((s, host)) => format!("{:.2} | {host:.2}", s * 1e6),
                    Err(e) => format!("not run: {e} |"),
                };
                println!("| {width} | {halo} | {t} | {figure} |");
            }
        }
    }
    println!();
}

/// Section 9: the chained tiles by shape on Table S1 (quick: on a
/// narrower scene).
pub fn chained_on_table_s1(quick: bool, min_seconds: f64) {
    // 9. The chained tiles by shape on Table S1.
    println!("\n## 9. Chained tiles on Table S1 by width, halo and threads\n");
    // Quick (software adapters): 29 columns, two tiles of 16 and 13.
    let model = if quick {
        let text = built_in("tromborg2014_precursors").expect("shipped scene");
        s1_model(text, &["geometry.nx=29", "geometry.length=0.07"])
    } else {
        table_s1(1)
    };
    chained_grid(&model, quick, min_seconds);
}

/// The tiled kernel with its rounds chained in one dispatch on `model`,
/// by tile width, halo and threads, with the device's busy time a step.
/// `auto` times chained tiles only at the width the unchained search
/// found (halos 1, 2 and its own), so narrower tiles, which spread a
/// Table S1 step over more SMs, are timed here: the launch nearest the
/// 3 µs target (6.84 µs on the H200 at 8 columns, halo 4, in session
/// 50), and bound by the device, not the host. A software adapter runs
/// only scenes of two tiles (quick: 16 columns of a 29-column scene).
fn chained_grid(model: &Model, quick: bool, min_seconds: f64) {
    println!(
        "µs a step; device: the passes' busy time a step (timestamps, where the adapter has \
         them); tiles: the scene's tiles, each a workgroup on its own SM where they fit.\n"
    );
    println!(
        "| tile width | halo | threads | tiles | µs/step | device µs/step | host CPU / wall |"
    );
    println!("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    let (widths, halos, threads): (&[u32], &[u32], &[u32]) = if quick {
        (&[16], &[2], &[256])
    } else {
        (&[2, 4, 8, 16], &[1, 2, 4], &[256, 512, 1024])
    };
    for &width in widths {
        for &halo in halos {
            for &t in threads {
                let opts = GpuOptions {
                    tile: Some(TileShape { width, halo }),
                    chained_tiles: true,
                    ..with_threads(Kernel::Tiled, Some(t))
                };
                let figure = match solo_step_figures_in::<f32>(model, opts, min_seconds) {
                    Ok(f) => format!(
                        "{:.2} | {} | {:.2}",
                        f.seconds * 1e6,
                        f.device.map_or("–".into(), |d| format!("{:.2}", d * 1e6)),
                        f.host
                    ),
                    Err(e) => format!("not run: {e} | | "),
                };
                println!(
                    "| {width} | {halo} | {t} | {} | {figure} |",
                    model.nx.div_ceil(width as usize)
                );
            }
        }
    }
    println!();
}
