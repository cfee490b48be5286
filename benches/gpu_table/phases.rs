//! Section 11: where a step's time goes on the device, phase by phase
//! (`GpuOptions::phase_clocks`): thread 0 of each workgroup reads its
//! multiprocessor's cycle counter at the barriers between phases. Each
//! launch on Table S1 alone (and in f64 those that lead it there), and
//! resident/1024 and the two-scene persistent workgroup on 132 scenes (one
//! workgroup an SM of an H100 SXM or an H200), from the start of driving.

use crate::both_ways;
use crate::common::{s1_scene, section_launches};
use crate::gpu_timing::{solo_step_figures_in, timed_advance};
use slipfront::engines::gpu::context::GpuContext;
use slipfront::engines::gpu::ensemble::GpuEnsemble;
use slipfront::engines::gpu::kernel_choice::Launch;
use slipfront::engines::gpu::phase_clocks::{Phase, PhaseCycles};
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuReal};
use slipfront::{advance_to, Engine, Model};

/// Beside the launches section 10 times alone: chained tiles of 4
/// columns with halo 2, twice the rounds a step of 8x4 (what the rounds'
/// publication and waits cost against the halo's redundant work).
const SOLO_MORE: &[&str] = &["tiled/256/4x2/chained"];
const ENSEMBLE: &[&str] = &["resident/1024", "persistent/1024/2-scenes"];
const QUICK_SOLO: &[&str] = &["persistent/256", "resident/256", "tiled/256/16x4/chained"];
const QUICK_ENSEMBLE: &[&str] = &["persistent/256"];

fn options(name: &str, clocks: bool) -> GpuOptions {
    let launch = Launch::named(name).unwrap_or_else(|| panic!("`{name}` is not a launch name"));
    GpuOptions {
        phase_clocks: clocks,
        ..launch.options(GpuOptions::default())
    }
}

pub fn profile(ctx: &GpuContext, quick: bool, min_seconds: f64) {
    println!("\n## 11. Where a step's time goes on the device: phase clocks\n");
    if !ctx.has_shader_clock() {
        println!(
            "This adapter does not let the engine read the multiprocessor's clock \
             (VK_KHR_shader_clock's shaderSubgroupClock, with the engine's own SPIR-V): \
             nothing to show.\n"
        );
        return;
    }
    println!(
        "Cycles of a workgroup's step, each phase from the mark before to its own past \
         its barrier; in brackets, thread 0's own work (to its arrival at the barrier) \
         and the slowest warp's (to the latest arrival: the rest of the phase is the \
         barrier itself); phases run once a dispatch or a round are spread over its \
         steps. `in barriers`: the share of the step from the slowest warp's arrival \
         to the mark past the barrier, over every phase. `cycles/µs`: the workgroup's \
         cycles a step over the clocked run's wall µs a step (near the SM clock where \
         the device is busy throughout). `clocked / plain`: the wall time a step with the \
         clocks against without (what the marks cost).\n"
    );
    let scene = |seed: usize| s1_scene(seed, quick);
    header("launch");
    let s1 = scene(1);
    let alone: Vec<&str> = both_ways::BARRIERS
        .solo
        .iter()
        .chain(SOLO_MORE)
        .copied()
        .collect();
    let names = section_launches(&alone, QUICK_SOLO, quick);
    let mut tiled = Vec::new();
    for name in &names {
        tiled.extend(solo_row::<f32>(&s1, name, min_seconds));
    }
    // f64, what a default run computes in on a GPU with f64 shaders: the
    // launches that lead Table S1 in it.
    if !quick && ctx.device.features().contains(f64::FEATURES) {
        for name in names
            .iter()
            .filter(|n| n.starts_with("persistent/1024") || n.ends_with("chained"))
        {
            tiled.extend(solo_row::<f64>(&s1, name, min_seconds));
        }
    }
    tile_rows(&tiled);
    let count = if quick { 4 } else { 132 };
    println!("\n{count} Table S1 scenes in one dispatch (scene 0's workgroup):\n");
    header("launch");
    let models: Vec<Model> = (0..count).map(|k| scene(k + 1)).collect();
    for name in section_launches(ENSEMBLE, QUICK_ENSEMBLE, quick) {
        match ensemble(&models, &name, min_seconds) {
            Ok((clocks, wall)) => row(&name, &clocks, wall, None),
            Err(e) => println!("| {name} | not run: {e} |"),
        }
    }
    println!();
}

fn header(first: &str) {
    let phases: Vec<&str> = Phase::ALL.iter().map(|p| p.name()).collect();
    println!(
        "| {first} | µs a step | cycles a step | cycles/µs | in barriers | clocked / plain | {} |",
        phases.join(" | ")
    );
    println!(
        "| --- | ---: | ---: | ---: | ---: | ---: |{}",
        " ---: |".repeat(phases.len())
    );
}

/// One launch's row: cycles a workgroup-step of each phase.
fn row(name: &str, clocks: &PhaseCycles, wall: f64, plain: Option<f64>) {
    let steps = f64::from(clocks.get(Phase::Forces).marks.max(1));
    let per_step = clocks.total_cycles() as f64 / steps;
    let cells: Vec<String> = Phase::ALL
        .iter()
        .map(|&p| {
            let s = clocks.get(p);
            match s.marks {
                0 => "–".to_string(),
                _ => format!(
                    "{:.0} ({:.0}; {:.0})",
                    s.cycles as f64 / steps,
                    s.own_cycles as f64 / steps,
                    s.slowest_cycles as f64 / steps
                ),
            }
        })
        .collect();
    let ratio = plain.map_or("–".into(), |p| format!("{:.3}", wall / p));
    let share = barrier_share(clocks);
    println!(
        "| {name} | {:.2} | {per_step:.0} | {:.0} | {:.1} % | {ratio} | {} |",
        wall * 1e6,
        per_step / (wall * 1e6),
        100.0 * share,
        cells.join(" | ")
    );
}

/// One launch's row on Table S1 alone in precision `T`; its label and
/// tiles' sums where it has several tiles.
fn solo_row<T: GpuReal>(
    model: &Model,
    name: &str,
    min_seconds: f64,
) -> Option<(String, Vec<PhaseCycles>)> {
    let label = match T::NAME {
        "f32" => name.to_string(),
        other => format!("{name} ({other})"),
    };
    match solo::<T>(model, name, min_seconds) {
        Ok((tiles, wall, plain)) => {
            let clocks: PhaseCycles = tiles.iter().sum();
            row(&label, &clocks, wall, Some(plain));
            (tiles.len() > 1).then_some((label, tiles))
        }
        Err(e) => {
            println!("| {label} | not run: {e} |");
            None
        }
    }
}

/// `name` on `model` alone: its tiles' phase sums (one for a kernel
/// without tiles) over a timed stretch of driving, its wall seconds a step
/// clocked, and unclocked.
fn solo<T: GpuReal>(
    model: &Model,
    name: &str,
    min_seconds: f64,
) -> Result<(Vec<PhaseCycles>, f64, f64), String> {
    let mut e =
        GpuEngine::<T>::with_precision(model, options(name, true)).map_err(|e| e.to_string())?;
    advance_to(&mut e, model.prep_steps + 16).map_err(|e| e.to_string())?;
    let mut sums = Vec::new();
    let (dt, steps) = timed_advance(
        |n| {
            let before = e.phase_cycles_by_tile(0)?;
            e.advance(n)?;
            let after = e.phase_cycles_by_tile(0)?;
            sums = after.iter().zip(&before).map(|(a, b)| a.since(b)).collect();
            Ok(())
        },
        min_seconds,
    )
    .map_err(|e| e.to_string())?;
    let plain = solo_step_figures_in::<T>(model, options(name, false), min_seconds)?;
    Ok((sums, dt / steps as f64, plain.seconds))
}

/// The tiled launches' sums tile by tile, in column order: cycles a step
/// of the phases a round runs, and the share in barriers. A tile that
/// waits long on its neighbours is faster than they are.
fn tile_rows(launches: &[(String, Vec<PhaseCycles>)]) {
    if launches.is_empty() {
        return;
    }
    // Those a round runs: all but the dispatch's enter and leave.
    let phases = &Phase::ALL[Phase::Forces as usize..=Phase::Wait as usize];
    let names: Vec<&str> = phases.iter().map(|p| p.name()).collect();
    println!("\nThe tiled launches tile by tile (cycles a step; tiles in column order):\n");
    println!(
        "| launch | tile | cycles a step | in barriers | {} |",
        names.join(" | ")
    );
    println!(
        "| --- | ---: | ---: | ---: |{}",
        " ---: |".repeat(phases.len())
    );
    for (label, tiles) in launches {
        for (k, tile) in tiles.iter().enumerate() {
            let steps = f64::from(tile.get(Phase::Forces).marks.max(1));
            let cells: Vec<String> = phases
                .iter()
                .map(|&p| format!("{:.0}", tile.get(p).cycles as f64 / steps))
                .collect();
            println!(
                "| {label} | {k} | {:.0} | {:.1} % | {} |",
                tile.total_cycles() as f64 / steps,
                100.0 * barrier_share(tile),
                cells.join(" | ")
            );
        }
    }
}

/// The share of `clocks`' cycles the barriers themselves took.
fn barrier_share(clocks: &PhaseCycles) -> f64 {
    clocks.barrier_cycles() as f64 / clocks.total_cycles().max(1) as f64
}

/// `name` on the ensemble `models`: scene 0's phase sums over a stretch of
/// driving, and the wall seconds an ensemble step.
fn ensemble(models: &[Model], name: &str, min_seconds: f64) -> Result<(PhaseCycles, f64), String> {
    let mut e = GpuEnsemble::new(models, options(name, true)).map_err(|e| e.to_string())?;
    e.advance(models[0].prep_steps + 16)
        .map_err(|e| e.to_string())?;
    let mut sums = None;
    let (dt, steps) = timed_advance(
        |n| {
            let before = e.phase_cycles(0)?;
            e.advance(n)?;
            e.settle()?;
            sums = Some(e.phase_cycles(0)?.since(&before));
            Ok(())
        },
        min_seconds,
    )
    .map_err(|e| e.to_string())?;
    Ok((sums.expect("timed"), dt / steps as f64))
}
