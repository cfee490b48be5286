//! Timing the launches on the scene: from the end of its normal-load
//! phase where that is reached within a budget, a warm-up (on hardware,
//! sustained, so that the GPU's clocks are those of a run), then what a
//! step costs in a run: the time a long span of steps takes beyond a
//! short one (`step_timing::marginal_step_seconds`), recording the run's output samples
//! on the device where the run will (`GpuOptions::samples`).

use super::{launches, ChoiceSource, KernelChoice, Launch, TimedPhase};
use crate::engines::gpu::context::GpuContext;
use crate::engines::gpu::options::{fitting_lane_run, persistent_threads, GpuOptions};
use crate::engines::gpu::precision::GpuReal;
use crate::engines::gpu::shaders::Kernel;
use crate::engines::gpu::tiles::{
    TileGeometry, TileShape, CHAINED_HALOS_SEARCHED, CHAINED_WIDTHS_SEARCHED, HALOS_SEARCHED,
    WIDTHS_SEARCHED,
};
use crate::engines::gpu::GpuEngine;
use crate::engines::step_timing::{step_seconds, SUSTAINED_WARM_UP_SECONDS, WARM_UP_STEPS};
use crate::engines::{EngineError, EngineState};
use crate::model::Model;
use std::cell::Cell;
use std::time::Instant;

/// How a step is timed, in the cache key: choices timed another way are
/// measured again.
pub(super) const TIMING: &str = "marginal steps after a sustained warm-up";
/// The most wall time spent stepping the normal-load phase before timing
/// (once for all candidates). A lattice whose load phase takes longer (a
/// large one: more blocks, a shorter time step, more steps) is timed from
/// its initial state, and the choice says so.
pub const PREPARE_BUDGET_SECONDS: f64 = 3.0;
/// Steps timed after the warm-up to estimate the load phase's wall time.
const ESTIMATE_STEPS: u64 = 32;

/// Wall time per step of `launch` on the scenes `models` (one, or an
/// ensemble stepped in one dispatch), from `start` (one state per scene)
/// or else from their initial state: a warm-up, then
/// `marginal_step_seconds` over spans of `advance`s, each of which
/// returns when its steps have run on the device.
pub fn time_kernel<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
    launch: Launch,
    start: Option<&[EngineState]>,
) -> Result<f64, EngineError> {
    time_launch::<T>(models, ctx, opts, launch, start).map(|t| t.seconds)
}

/// What timing a launch found: its wall time a step, the levels of the
/// junction lane tree its workgroups merged in subgroups
/// (`GpuEngine::lane_shuffle_levels`; 0: every lane's sum through
/// storage), and the output samples it recorded on the device while
/// timed (`GpuOptions::samples`; 0 without).
#[derive(Debug, Clone, Copy)]
struct Timed {
    seconds: f64,
    lane_levels: u32,
    samples: u64,
}

/// `time_kernel`, with the lane levels the engine used and the samples it
/// recorded (where `opts.samples` asks it to record, as the run will).
fn time_launch<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
    launch: Launch,
    start: Option<&[EngineState]>,
) -> Result<Timed, EngineError> {
    let opts = launch.options(opts);
    let mut engine = GpuEngine::<T>::build(models, ctx.clone(), opts, models.len() > 1)?;
    if let Some(states) = start {
        engine.start_scenes_from(&states.iter().collect::<Vec<_>>())?;
    }
    if let Some(plan) = opts.samples.as_ref() {
        record_while_timed(&mut engine, plan)?;
    }
    let batch = engine.batch_steps();
    let sustain = if ctx.is_software() {
        0.0
    } else {
        SUSTAINED_WARM_UP_SECONDS
    };
    let mut samples = 0;
    // A span: `steps` steps, waited for, and their wall seconds; the
    // samples they recorded are counted and dropped outside the time.
    let mut span = |steps: u64| -> Result<f64, EngineError> {
        let t = Instant::now();
        engine.advance_steps(steps)?;
        let seconds = t.elapsed().as_secs_f64();
        for k in 0..models.len() {
            samples += engine.take_samples_of(k).len() as u64;
        }
        Ok(seconds)
    };
    let rough = span(WARM_UP_STEPS)? / WARM_UP_STEPS as f64;
    let seconds = step_seconds(&mut span, rough, batch, sustain)?;
    Ok(Timed {
        seconds,
        lane_levels: engine.lane_shuffle_levels(),
        samples,
    })
}

/// Every scene of `engine` records its samples on the device at `plan`'s
/// cadences, as the run will; a launch that cannot is not one the run
/// could take at this speed (its samples would be host snapshots), so
/// that is an error (the launch is skipped, with it as the reason).
fn record_while_timed<T: GpuReal>(
    engine: &mut GpuEngine<T>,
    plan: &crate::engines::SamplePlan,
) -> Result<(), EngineError> {
    for k in 0..engine.scenes.len() {
        if !engine.record_samples_of(k, plan)? {
            return Err(EngineError::Gpu(
                "cannot record the run's output samples on the device (they would be host \
                 snapshots)"
                    .into(),
            ));
        }
    }
    Ok(())
}

/// The states the candidates are timed from: the scenes stepped by
/// `launch` to the last step of their normal-load phase, if that takes at
/// most `budget` seconds (estimated from a few steps after a warm-up);
/// else none, and why.
pub fn driving_start<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
    launch: Launch,
    budget: f64,
) -> (Option<Vec<EngineState>>, TimedPhase) {
    let end = models[0].prep_steps.saturating_sub(1);
    if models.iter().any(|m| m.prep_steps != models[0].prep_steps) {
        let why = "the scenes' normal-load phases differ in length".to_string();
        return (None, TimedPhase::NormalLoad { why });
    }
    if end == 0 {
        return (None, TimedPhase::Driving { from_step: 0 });
    }
    let stepped = || -> Result<Result<Vec<EngineState>, String>, EngineError> {
        let mut engine =
            GpuEngine::<T>::build(models, ctx.clone(), launch.options(opts), models.len() > 1)?;
        engine.advance_steps(WARM_UP_STEPS.min(end))?;
        let estimate = ESTIMATE_STEPS.min(end - engine.step);
        let t = Instant::now();
        engine.advance_steps(estimate)?;
        let per_step = t.elapsed().as_secs_f64() / estimate.max(1) as f64;
        let left = end - engine.step;
        let reach = per_step * left as f64;
        if reach > budget {
            return Ok(Err(format!(
                "reaching driving would take {reach:.1} s ({left} steps at {:.1} µs/step on {}), \
                 over the {budget} s budget",
                per_step * 1e6,
                launch.name()
            )));
        }
        engine.advance_steps(left)?;
        (0..models.len())
            .map(|k| engine.save_state_of(k))
            .collect::<Result<Vec<_>, _>>()
            .map(Ok)
    };
    match stepped() {
        Ok(Ok(states)) => (Some(states), TimedPhase::Driving { from_step: end }),
        Ok(Err(why)) => (None, TimedPhase::NormalLoad { why }),
        Err(e) => {
            let why = format!(
                "{} could not step the normal-load phase: {e}",
                launch.name()
            );
            (None, TimedPhase::NormalLoad { why })
        }
    }
}

/// The tiled kernel's shape, searched from `best`, its fastest launch at
/// the default shape (and the threads it ran at), with `time` (seconds a
/// step, or None where the launch could not run): first the widths of
/// `tiles::WIDTHS_SEARCHED` at the default halo, then the halos of
/// `HALOS_SEARCHED` at the fastest width. Two rounds of two, not the whole
/// grid: each shape is a pipeline to compile, and the width (how many
/// multiprocessors a scene spreads over) and the halo (dispatches a step
/// against redundant work) pull mostly apart. Returns the fastest launch
/// and its time, `best` if no shape beat it.
pub fn search_tile_shapes(
    best: (Launch, f64),
    mut time: impl FnMut(Launch) -> Option<f64>,
) -> (Launch, f64) {
    let mut fastest = best;
    let base = best.0;
    for width in WIDTHS_SEARCHED {
        let launch = base.with_tile(TileShape {
            width,
            ..TileShape::DEFAULT
        });
        if let Some(s) = time(launch).filter(|&s| s < fastest.1) {
            fastest = (launch, s);
        }
    }
    let width = fastest.0.tile.unwrap_or(TileShape::DEFAULT).width;
    for halo in HALOS_SEARCHED {
        let launch = base.with_tile(TileShape { width, halo });
        if let Some(s) = time(launch).filter(|&s| s < fastest.1) {
            fastest = (launch, s);
        }
    }
    fastest
}

/// Times every launch (`launches`) on the scenes `models` (one, or an
/// ensemble of one lattice shape) from the start of driving
/// (`driving_start`, within `PREPARE_BUDGET_SECONDS`), then the tiled
/// kernel's other tile shapes (`search_tile_shapes`, unless the options
/// fix the shape), then the fastest tiled launch chained and, where that
/// wins, its smaller halos and (on hardware) narrower widths chained
/// (`chained_halo_search`, `chained_width_search`), then the fastest launch whose lanes merged in subgroups
/// with every lane's sum through storage instead (unless the options fix
/// that), then the fastest launch so far with its bulk forces by patches
/// (unless the options fix them on), and takes the fastest. A launch that cannot be built
/// (a buffer too large, a lattice beyond workgroup memory, a device error)
/// is skipped with its reason; if none can, the first error is returned.
pub fn measure<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
) -> Result<KernelChoice, EngineError> {
    measure_within::<T>(models, ctx, opts, PREPARE_BUDGET_SECONDS)
}

/// `measure` with `budget` seconds to step the normal-load phase.
pub fn measure_within<T: GpuReal>(
    models: &[Model],
    ctx: &GpuContext,
    opts: GpuOptions,
    budget: f64,
) -> Result<KernelChoice, EngineError> {
    let mut timings = Vec::new();
    let mut skipped = Vec::new();
    let mut first_error = None;
    let launches = launches(&models[0], models.len(), opts, &ctx.limits);
    // One-step (always a candidate, first) steps the load phase.
    let (start, phase) = driving_start::<T>(models, ctx, opts, launches[0], budget);
    // Every launch is timed here: a failure is listed as skipped, and the
    // first one is the error if none runs. The fastest so far is kept
    // apart (the closure holds `timings`).
    let fastest = Cell::new(None);
    // The fewest samples a launch recorded while timed.
    let mut recorded: Option<u64> = None;
    let mut time =
        |launch: Launch| match time_launch::<T>(models, ctx, opts, launch, start.as_deref()) {
            Ok(timed) => {
                timings.push((launch, timed.seconds));
                recorded = Some(recorded.map_or(timed.samples, |r| r.min(timed.samples)));
                let mut best = fastest.get();
                keep_faster(&mut best, launch, timed.seconds);
                fastest.set(best);
                Some(timed)
            }
            Err(e) => {
                skipped.push((launch, e.to_string()));
                first_error.get_or_insert(e);
                None
            }
        };
    // The launches whose lanes merged in subgroups, with their times.
    let mut shuffled = Vec::new();
    let mut time_noting_merges = |launch: Launch| {
        let timed = time(launch)?;
        if timed.lane_levels > 0 {
            shuffled.push((launch, timed.seconds));
        }
        Some(timed.seconds)
    };
    let mut tiled_best: Option<(Launch, f64)> = None;
    for launch in launches {
        if let Some(s) = time_noting_merges(launch) {
            if launch.kernel == Kernel::Tiled {
                keep_faster(&mut tiled_best, launch, s);
            }
        }
    }
    // The tile's shape is searched unless the options fix it.
    if let Some(best) = tiled_best.filter(|_| opts.tile.is_none()) {
        tiled_best = Some(search_tile_shapes(best, &mut time_noting_merges));
    }
    // The fastest tiled launch with its rounds chained in one dispatch
    // (unless the options fix that): the same bits, a dispatch where
    // there were many, for tiles that wait on their neighbours instead.
    // Where chaining wins, smaller halos are timed chained too.
    if let Some((launch, unchained)) = tiled_best.filter(|_| !opts.chained_tiles) {
        let chained = time_noting_merges(launch.with_chained_tiles());
        if let Some(seconds) = chained.filter(|&s| s < unchained && opts.tile.is_none()) {
            let mut chained_best = Some((launch.with_chained_tiles(), seconds));
            for smaller in chained_halo_search(launch) {
                if let Some(s) = time_noting_merges(smaller) {
                    keep_faster(&mut chained_best, smaller, s);
                }
            }
            // Then narrower tiles at the fastest chained halo (hardware).
            if let Some((fastest_chained, _)) = chained_best.filter(|_| !ctx.is_software()) {
                for narrower in chained_width_search(fastest_chained) {
                    time_noting_merges(narrower);
                }
            }
        }
    }
    // Where the lanes merge: the same tree of sums either way, and
    // subgroup merges have no hardware figure yet. Only the fastest launch
    // that used them is timed without (another pipeline to compile).
    let fastest_shuffled = shuffled.iter().min_by(|a, b| a.1.total_cmp(&b.1));
    if let Some(&(launch, _)) = fastest_shuffled {
        time(launch.with_lanes_in_storage());
    }
    // The bulk forces by patches, on the fastest launch so far (unless
    // the options fix them on): the same forces to their last bits, and
    // no hardware figure yet says whether a quarter of the threads doing
    // 26 bonds' work each beats all of them doing 8.
    if let Some((launch, _)) = fastest.get().filter(|_| !opts.bond_patches) {
        time(launch.with_bond_patches());
    }
    // One junction lane a round, on the fastest launch so far: the same
    // bits, and registers a thread against chains of round trips, which
    // no hardware figure has weighed yet.
    if let Some((launch, _)) = fastest.get() {
        if times_one_lane_a_round(launch, opts, ctx.is_software()) {
            time(launch.with_one_lane_a_round());
        }
    }
    // Lane runs, on the fastest launch so far: the same bits, fewer
    // instructions a block's lanes for more registers a thread, which no
    // hardware figure has weighed yet. The run that fills its threads once.
    let junctions = models[0].law == crate::model::scenario::FrictionLaw::Junctions
        && models[0].junctions.is_some_and(|j| j.count > 1);
    if let Some((launch, _)) = fastest.get() {
        let run = launch_lane_run(launch, opts, &models[0], &ctx.limits, ctx.is_software());
        if times_lane_run(launch, opts, ctx.is_software(), junctions) && run > 1 {
            time(launch.with_lane_run(run));
        }
    }
    let Some(&(launch, _)) = timings.iter().min_by(|a, b| a.1.total_cmp(&b.1)) else {
        return Err(first_error.expect("at least one candidate (one-step always is)"));
    };
    Ok(KernelChoice {
        launch,
        timings,
        source: ChoiceSource::Measured,
        skipped,
        scenes: models.len(),
        phase,
        recorded: opts.samples.and(recorded),
    })
}

/// Whether `measure` times `launch` (the fastest so far) again with one
/// junction lane a round: a persistent kernel on hardware, unless the
/// options fix one lane a round already. Software adapters always step
/// one (`TWO_LANES_A_ROUND`), so there both would be the same pipeline.
fn times_one_lane_a_round(launch: Launch, opts: GpuOptions, software: bool) -> bool {
    launch.kernel.is_persistent() && !launch.one_lane_a_round && opts.two_lanes_a_round && !software
}

/// The lane run `measure` times `launch` with (`fitting_lane_run`): its
/// junction phase steps every interface block's lanes at once (the tiled
/// kernel: the columns a tile holds) on its workgroup's threads.
pub fn launch_lane_run(
    launch: Launch,
    opts: GpuOptions,
    model: &Model,
    limits: &wgpu::Limits,
    software: bool,
) -> u32 {
    let opts = launch.options(opts);
    let threads = persistent_threads(launch.kernel, opts.persistent_threads, limits, software);
    let lanes = crate::model::junction::JUNCTION_LANES.min(model.junctions.map_or(0, |j| j.count));
    let mut blocks = model.nx as u32;
    if launch.kernel == Kernel::Tiled {
        let shape = opts.tile.unwrap_or(TileShape::DEFAULT);
        if let Ok(tiles) = TileGeometry::new(model, shape) {
            blocks = blocks.min(tiles.span);
        }
    }
    fitting_lane_run(blocks, lanes as u32, threads)
}

/// Whether `measure` times `launch` (the fastest so far) again with
/// more than one lane a thread (`launch_lane_run`): a kernel with lane runs on hardware,
/// on a scene whose blocks have junction lanes to run, unless the options
/// or the launch fix the run. On software adapters each lane of a run is
/// a loop pass llvmpipe counts (fewer steps a dispatch), so `auto` keeps a
/// lane a thread there.
fn times_lane_run(launch: Launch, opts: GpuOptions, software: bool, junctions: bool) -> bool {
    launch.has_lane_runs()
        && launch.lane_run.is_none()
        && opts.lane_run == 1
        && junctions
        && !software
}

/// The chained launches `measure` times after chaining `launch` (the
/// fastest tiled launch) beat it unchained: its width and threads with
/// each of `CHAINED_HALOS_SEARCHED` smaller than its halo.
pub fn chained_halo_search(launch: Launch) -> Vec<Launch> {
    let shape = launch.tile.unwrap_or(TileShape::DEFAULT);
    let halos = CHAINED_HALOS_SEARCHED
        .into_iter()
        .filter(|&h| h < shape.halo);
    chained_shapes(launch, halos.map(|halo| TileShape { halo, ..shape }))
}

/// The chained launches `measure` times last, on hardware, after the
/// chained halos (`chained_halo_search`): `launch` (the fastest chained
/// launch) at each of `CHAINED_WIDTHS_SEARCHED` narrower than its width,
/// with its halo and threads.
pub fn chained_width_search(launch: Launch) -> Vec<Launch> {
    let shape = launch.tile.unwrap_or(TileShape::DEFAULT);
    let widths = CHAINED_WIDTHS_SEARCHED
        .into_iter()
        .filter(|&w| w < shape.width);
    chained_shapes(launch, widths.map(|width| TileShape { width, ..shape }))
}

/// `launch` chained at each of `shapes`.
fn chained_shapes(launch: Launch, shapes: impl Iterator<Item = TileShape>) -> Vec<Launch> {
    shapes
        .map(|shape| launch.with_tile(shape).with_chained_tiles())
        .collect()
}

/// `best` becomes (`launch`, `seconds`) if that is faster or it was empty.
fn keep_faster(best: &mut Option<(Launch, f64)>, launch: Launch, seconds: f64) {
    if best.is_none_or(|(_, b)| seconds < b) {
        *best = Some((launch, seconds));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Chained, the halos below the launch's own are searched at its width
    /// and threads: 1 and 2 below the default 4, 1 below 2, none below 1.
    #[test]
    fn a_winning_chain_searches_the_smaller_halos_at_its_width() {
        let base =
            Launch::with_threads(Kernel::Tiled, 256).with_tile(TileShape { width: 16, halo: 4 });
        let names: Vec<String> = chained_halo_search(base).iter().map(|l| l.name()).collect();
        assert_eq!(names, ["tiled/256/16x1/chained", "tiled/256/16x2/chained"]);
        let two = base.with_tile(TileShape { width: 16, halo: 2 });
        assert_eq!(chained_halo_search(two).len(), 1);
        let one = base.with_tile(TileShape { width: 16, halo: 1 });
        assert!(chained_halo_search(one).is_empty());
        let default = Launch::with_threads(Kernel::Tiled, 512);
        assert_eq!(
            chained_halo_search(default)[0].name(),
            "tiled/512/8x1/chained"
        );
    }

    /// The narrower chained widths are searched at the fastest chained
    /// launch's halo and threads: 2 and 4 below the default 8, 2 below 4,
    /// none below 2.
    #[test]
    fn a_winning_chain_searches_narrower_tiles_at_its_halo() {
        let base = Launch::with_threads(Kernel::Tiled, 512)
            .with_tile(TileShape { width: 8, halo: 2 })
            .with_chained_tiles();
        let names: Vec<String> = chained_width_search(base)
            .iter()
            .map(|l| l.name())
            .collect();
        assert_eq!(names, ["tiled/512/2x2/chained", "tiled/512/4x2/chained"]);
        let four = base.with_tile(TileShape { width: 4, halo: 1 });
        let names: Vec<String> = chained_width_search(four)
            .iter()
            .map(|l| l.name())
            .collect();
        assert_eq!(names, ["tiled/512/2x1/chained"]);
        let two = base.with_tile(TileShape { width: 2, halo: 1 });
        assert!(chained_width_search(two).is_empty());
    }

    /// A made-up landscape of step times by shape: the search times the
    /// widths at the default halo, then the halos at the fastest width,
    /// and returns the fastest it timed; a shape that cannot run is passed
    /// over.
    #[test]
    fn the_tile_search_walks_widths_then_halos_at_the_fastest_width() {
        let base = Launch::with_threads(Kernel::Tiled, 1024);
        let landscape = |shape: TileShape| -> Option<f64> {
            match (shape.width, shape.halo) {
                (8, 4) => Some(10.0),
                (4, 4) => Some(11.0),
                (16, 4) => Some(9.0),
                (16, 2) => None,
                (16, 8) => Some(7.0),
                _ => Some(100.0),
            }
        };
        let mut timed = Vec::new();
        let (launch, s) = search_tile_shapes((base, 10.0), |l| {
            timed.push(l.tile.unwrap().name());
            landscape(l.tile.unwrap())
        });
        assert_eq!(timed, ["4x4", "16x4", "16x2", "16x8"]);
        assert_eq!(launch, base.with_tile(TileShape { width: 16, halo: 8 }));
        assert_eq!(launch.threads, Some(1024));
        assert_eq!(s, 7.0);

        // Nothing beats the default: it stays, without a shape; the halo
        // round runs at the default width.
        let mut timed = Vec::new();
        let kept = search_tile_shapes((base, 1.0), |l| {
            timed.push(l.tile.unwrap().name());
            Some(2.0)
        });
        assert_eq!(kept, (base, 1.0));
        assert_eq!(timed, ["4x4", "16x4", "8x2", "8x8"]);
    }

    /// One lane a round is timed on a persistent kernel's launch on
    /// hardware only, and sets the option off in the launch's options.
    #[test]
    fn one_lane_a_round_is_timed_on_hardware_persistent_launches_only() {
        let plain = GpuOptions::default();
        for kernel in [Kernel::Persistent, Kernel::Resident] {
            let launch = Launch::with_threads(kernel, 256);
            assert!(times_one_lane_a_round(launch, plain, false), "{kernel:?}");
            assert!(
                !times_one_lane_a_round(launch, plain, true),
                "software: {kernel:?}"
            );
            let one = launch.with_one_lane_a_round();
            assert!(
                !times_one_lane_a_round(one, plain, false),
                "twice: {kernel:?}"
            );
            assert!(!one.options(plain).two_lanes_a_round);
            assert!(launch.options(plain).two_lanes_a_round);
        }
        for kernel in [Kernel::OneStep, Kernel::OneStepLanes, Kernel::Tiled] {
            assert!(
                !times_one_lane_a_round(Launch::of(kernel), plain, false),
                "{kernel:?}"
            );
        }
        let fixed = GpuOptions {
            two_lanes_a_round: false,
            ..plain
        };
        assert!(!times_one_lane_a_round(
            Launch::of(Kernel::Resident),
            fixed,
            false
        ));
    }

    /// Lane runs are timed on hardware, on the persistent, resident and
    /// tiled kernels of a scene with junction lanes, unless fixed; the
    /// launch sets the run in its options.
    #[test]
    fn lane_runs_are_timed_on_hardware_junction_launches_only() {
        let plain = GpuOptions::default();
        for kernel in [Kernel::Persistent, Kernel::Resident, Kernel::Tiled] {
            let launch = Launch::with_threads(kernel, 256);
            assert!(times_lane_run(launch, plain, false, true), "{kernel:?}");
            assert!(
                !times_lane_run(launch, plain, true, true),
                "software: {kernel:?}"
            );
            assert!(
                !times_lane_run(launch, plain, false, false),
                "Coulomb: {kernel:?}"
            );
            let run = launch.with_lane_run(4);
            assert!(
                !times_lane_run(run, plain, false, true),
                "twice: {kernel:?}"
            );
            assert_eq!(run.options(plain).lane_run, 4);
            assert_eq!(launch.options(plain).lane_run, 1);
            assert_eq!(Launch::named(&run.name()), Some(run), "{}", run.name());
        }
        for kernel in [Kernel::OneStep, Kernel::OneStepLanes] {
            assert!(
                !times_lane_run(Launch::of(kernel), plain, false, true),
                "{kernel:?}"
            );
            let name = format!("{}/lane-run-4", super::super::path_name(kernel));
            assert_eq!(Launch::named(&name), None);
        }
        let fixed = GpuOptions {
            lane_run: 2,
            ..plain
        };
        assert!(!times_lane_run(
            Launch::of(Kernel::Resident),
            fixed,
            false,
            true
        ));
        assert_eq!(Launch::named("resident/1024/lane-run-3"), None);
        assert_eq!(
            Launch::named("tiled/512/8x4/chained/lane-run-8").map(|l| l.lane_run),
            Some(Some(8))
        );
    }

    /// The run timed on Table S1 gives each thread of the junction phase at
    /// most one run: 57 blocks of 64 lanes on the resident kernel's 1024
    /// threads in runs of 4, on 256 threads in runs of 8 (the longest,
    /// though 57 × 8 do not fit); a tiled launch counts the columns a tile
    /// holds (8x4: 16 columns on 512 threads, runs of 2).
    #[test]
    fn the_lane_run_timed_fills_the_launchs_threads_once() {
        let s = crate::model::scenario::Scenario::parse(
            crate::model::scenario::built_in("tromborg2014_precursors").unwrap(),
            "s1",
            &[] as &[String],
        )
        .unwrap();
        let model = Model::from_scenario(&s, false).unwrap();
        let limits = wgpu::Limits {
            max_compute_invocations_per_workgroup: 1024,
            max_compute_workgroup_size_x: 1024,
            ..wgpu::Limits::default()
        };
        let plain = GpuOptions::default();
        let run = |name: &str| {
            let launch = Launch::named(name).unwrap();
            launch_lane_run(launch, plain, &model, &limits, false)
        };
        assert_eq!(run("resident/1024"), 4);
        assert_eq!(run("persistent/256"), 8);
        assert_eq!(run("tiled/512"), 2);
        assert_eq!(run("tiled/512/8x4/chained"), 2);
        assert_eq!(run("tiled/256/16x2/chained"), 8);
        assert_eq!(run("tiled/256/4x2/chained"), 2);
        // A lane a thread that fits already: no run is timed.
        assert_eq!(run("tiled/1024/4x2"), 1);
        assert_eq!(fitting_lane_run(57, 16, 1024), 1);
        assert_eq!(fitting_lane_run(57, 64, 0), 8);
    }

    /// A launch with patches turns them on in the options it builds; one
    /// without keeps what the options asked for.
    #[test]
    fn a_launch_with_bond_patches_sets_them_in_the_options() {
        let plain = GpuOptions::default();
        let patched = Launch::of(Kernel::Resident).with_bond_patches();
        assert!(patched.options(plain).bond_patches);
        assert!(!Launch::of(Kernel::Resident).options(plain).bond_patches);
        let asked = GpuOptions {
            bond_patches: true,
            ..plain
        };
        assert!(Launch::of(Kernel::Resident).options(asked).bond_patches);
    }

    /// A searched shape reaches the options the engine is built with.
    #[test]
    fn a_launch_with_a_tile_shape_sets_the_tile_options() {
        let shaped =
            Launch::with_threads(Kernel::Tiled, 256).with_tile(TileShape { width: 16, halo: 2 });
        let opts = shaped.options(GpuOptions::default());
        assert_eq!(opts.tile, Some(TileShape { width: 16, halo: 2 }));
        assert_eq!(opts.persistent_threads, Some(256));
        let plain = Launch::of(Kernel::Tiled).options(GpuOptions::default());
        assert_eq!(plain.tile, None);
    }
}
