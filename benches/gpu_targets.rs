//! The GPU engine's targets, each with its figure and whether it is met, in
//! one command for a short loan of a GPU:
//!
//!     cargo bench --bench gpu_targets
//!
//! (on the lent GPU machine: the packed `gpu_targets` binary). The
//! precursors scene (Table S1: 57×31, Ns = 100), every figure timed past
//! the normal-load phase, in f64 and then in mixed f32: f64 is what `run`
//! and `sweep` compute in by default on an adapter with f64 shaders
//! (`Backend::default_precision`), so `auto`'s pick for a default job is
//! the f64 one; mixed f32 is what every earlier GPU figure measured. Each
//! precision's table is printed when its targets are done, so a call cut
//! short still brings back the first.
//!
//! 1. `auto` picks the fastest kernel: its measurement as a run makes it,
//!    then every launch it timed, timed again alone over at least `SECONDS`
//!    (with the host's CPU share and the device's busy time of that span:
//!    which of the two sets the pace).
//!    Met when the chosen launch is within `PICK_TOLERANCE` of the fastest.
//! 2. Table S1 in at most 3 µs a step: the fastest of those figures.
//!    2b. `--backend auto` runs the faster of the GPU and the CPU engine:
//!    its timing (`backend_choice::measure`: `auto`'s launch against the
//!    CPU on all cores), then the CPU timed again over at least `SECONDS`
//!    of driving. Met when the engine it runs is within `PICK_TOLERANCE`
//!    of the faster, timed again.
//! 3. 256 scenes (a seed each) in one dispatch at 2e10 block-steps/s or
//!    more in aggregate: the launch a sweep takes (timed on that ensemble,
//!    as `sweep --backend gpu` does), then the ensemble stepped. Beside it,
//!    whether that pick is the fastest (within `PICK_TOLERANCE`) of the
//!    persistent and resident launches `auto` timed, each timed again on
//!    the ensemble (`ensemble_figures`).
//! 4. 64 scenes at 20× or more the rate of one at a time: the 64-scene
//!    ensemble's aggregate (its own measured launch, timed again with the
//!    same contenders) over the fastest solo figure of 2. This is the
//!    ensemble's step; a sweep's wall time with its files is `gpu_table`
//!    section 6.
//! 5. An output file at the default cadences at 1024×512 costs at most 1.3×
//!    no output: the second N steps of a run with `-o` against the same
//!    without (what a run pays once, the file's creation and its final
//!    checkpoint, left out). Beside it, the device's busy time of the same
//!    steps with and without the file, and each thread's CPU: whether what
//!    the file adds is the device's time or the host's.
//!
//! SLIPFRONT_GPU_TARGETS_PRECISIONS=f32 (or f64, or f64,f32, the default)
//! runs those precisions only, in that order; f64 on an adapter without
//! f64 shaders is listed as not measured, with the reason.
//!
//! SLIPFRONT_GPU_TARGETS_SOLO=1 measures targets 1 and 2 only (a scene
//! alone: `auto`'s figures against each launch timed again).
//!
//! SLIPFRONT_GPU_TARGETS_WITH_OUTPUT=1 adds target 1 with an output file
//! (after 2): `auto` timed recording Table S1's samples at its cadences,
//! as a run with `-o` is, against each launch timed again recording them.
//! SLIPFRONT_GPU_TARGETS_WITH_OUTPUT=only measures that target alone.
//!
//! The ensemble-against-solo bits are `tests/gpu_ensemble.rs`: run its
//! binary on the same machine. SLIPFRONT_GPU_TARGETS_QUICK=1 (a software
//! adapter) runs 16 and 4 scenes and the output at 57×31, over shorter
//! spans: not the targets' sizes, and the table says so.

use slipfront::engines::backend_choice;
use slipfront::engines::cpu::SweepEngine;
use slipfront::engines::gpu::context::{self, GpuContext};
use slipfront::engines::gpu::kernel_choice::{measure, KernelChoice, Launch};
use slipfront::engines::gpu::{GpuOptions, GpuReal};
use slipfront::Model;
use std::time::Instant;

#[path = "support/bench_scene.rs"]
mod bench_scene;
#[path = "support/gpu_timing.rs"]
mod gpu_timing;
#[path = "support/thread_cpu.rs"]
mod thread_cpu;

use gpu_timing::{
    ensemble_step_seconds_in, output_run, solo_step_figures_in, table_s1, table_s1_scenario,
    StepFigures, Timed,
};
use slipfront::app::runner::sample_plan;

/// How much slower than the fastest launch `auto`'s pick may be, timed
/// again, and still count as the fastest: two launches this close swap
/// places between timings.
const PICK_TOLERANCE: f64 = 0.05;
const TABLE_S1_STEP_SECONDS: f64 = 3e-6;
const ENSEMBLE_RATE: f64 = 2e10;
const ENSEMBLE_SPEED_UP: f64 = 20.0;
const OUTPUT_RATIO: f64 = 1.3;

/// One target's line of the summary.
struct Target {
    what: String,
    figure: String,
    met: Option<bool>,
}

impl Target {
    fn new(what: String, figure: String, met: bool) -> Target {
        Target {
            what,
            figure,
            met: Some(met),
        }
    }

    fn not_measured(what: String, why: String) -> Target {
        Target {
            what,
            figure: format!("not measured: {why}"),
            met: None,
        }
    }
}

/// `auto`'s choice on `s1` and each launch it timed, timed again alone:
/// (choice, [(launch, seconds per step)]).
/// With `opts.samples`, both timings record the samples of a run with an
/// output file at those cadences.
fn solo_figures<T: GpuReal>(
    ctx: &GpuContext,
    s1: &Model,
    opts: GpuOptions,
    min_seconds: f64,
) -> Result<(KernelChoice, Vec<(Launch, f64)>), String> {
    let choice = measure::<T>(std::slice::from_ref(s1), ctx, opts).map_err(|e| e.to_string())?;
    let with = if opts.samples.is_some() {
        " with -o"
    } else {
        ""
    };
    println!("`auto` on Table S1{with}: {}\n", choice.describe());
    let again = timed_again(&choice.timings, "µs/step", |launch| {
        solo_step_figures_in::<T>(s1, launch.options(opts), min_seconds)
    });
    Ok((choice, again))
}

/// Each of `timings` (a launch and `auto`'s seconds a step for it) timed
/// again by `time`, printed as a table beside `auto`'s figure in `unit`,
/// with the host's CPU share and the device's busy time of the same span
/// where `time` has it: the launches that ran, with their seconds.
fn timed_again(
    timings: &[(Launch, f64)],
    unit: &str,
    mut time: impl FnMut(Launch) -> Result<StepFigures, String>,
) -> Vec<(Launch, f64)> {
    println!(
        "| launch | auto's figure ({unit}) | timed again ({unit}) | host CPU / wall | \
         device busy ({unit}) |"
    );
    println!("| --- | ---: | ---: | ---: | ---: |");
    let mut again = Vec::new();
    for &(launch, seconds) in timings {
        match time(launch) {
            Ok(f) => {
                let busy = f.device.map_or("–".into(), |d| format!("{:.2}", d * 1e6));
                println!(
                    "| {} | {:.2} | {:.2} | {:.2} | {busy} |",
                    launch.name(),
                    seconds * 1e6,
                    f.seconds * 1e6,
                    f.host
                );
                again.push((launch, f.seconds));
            }
            Err(e) => println!(
                "| {} | {:.2} | not run: {e} | | |",
                launch.name(),
                seconds * 1e6
            ),
        }
    }
    println!();
    again
}

/// The launch a sweep of `models` takes (timed on that ensemble), and
/// it with the ensemble's contenders timed again: the persistent and
/// resident launches `auto` timed at each thread count without other
/// options. With more scenes than SMs they run in waves or share SMs
/// (`gpu_table` section 8), and on the H200 `auto`'s figures ranked them
/// 5–6× off what they ran at (BENCHMARKS.md, session 50): whether the
/// pick is the fastest of them. (choice, [(launch, seconds an ensemble
/// step)]).
fn ensemble_figures<T: GpuReal>(
    ctx: &GpuContext,
    models: &[Model],
    min_seconds: f64,
) -> Result<(KernelChoice, Vec<(Launch, f64)>), String> {
    let opts = slipfront::app::sweeps::default_gpu();
    let choice = measure::<T>(models, ctx, opts).map_err(|e| e.to_string())?;
    println!("{} scenes: {}\n", models.len(), choice.describe());
    let contenders: Vec<(Launch, f64)> = choice
        .timings
        .iter()
        .copied()
        .filter(|(l, _)| {
            *l == choice.launch
                || (l.kernel.is_persistent()
                    && !l.lanes_in_storage
                    && !l.bond_patches
                    && !l.one_lane_a_round)
        })
        .collect();
    let again = timed_again(&contenders, "µs an ensemble step", |launch| {
        ensemble_step_seconds_in::<T>(models, launch.options(opts), min_seconds).map(
            |(seconds, host)| StepFigures {
                seconds,
                host,
                device: None,
            },
        )
    });
    Ok((choice, again))
}

/// The chosen launch of `ensemble_figures` with its seconds an ensemble
/// step timed again.
fn chosen_again(choice: &KernelChoice, again: &[(Launch, f64)]) -> Result<(Launch, f64), String> {
    again
        .iter()
        .find(|(l, _)| *l == choice.launch)
        .copied()
        .ok_or_else(|| NOT_AGAIN.to_string())
}

/// The output's cost at `nx`×`nz`, the second `steps` steps of a run
/// with an output file (`-o`) against the same without.
struct OutputCost {
    /// Wall seconds of those steps without and with the file.
    without: f64,
    with: f64,
    /// The device's busy seconds of the same steps, without and with
    /// (None where the adapter has no timestamp queries): whether what the
    /// file adds is device time or the host's.
    device: Option<(f64, f64)>,
    /// The longer run with the file: its device samples and each
    /// thread's CPU seconds per wall second.
    samples: String,
    threads: String,
}

impl OutputCost {
    /// The figure of the target row.
    fn describe(&self, steps: u64) -> String {
        let device = self.device.map_or(String::new(), |(without, with)| {
            format!(
                "; device busy {without:.3} s without, {with:.3} s with: the file adds \
                 {:.3} s of device time of its {:.3} s",
                with - without,
                self.with - self.without
            )
        });
        format!(
            "{:.2}× (the second {steps} steps: {:.3} s with -o, {:.3} s without{device}; \
             the longer run with -o: device samples {}, CPU a wall second {})",
            self.with / self.without,
            self.with,
            self.without,
            self.samples,
            self.threads
        )
    }
}

/// The output's cost at `nx`×`nz` over the second `steps` steps of a run
/// (what a run pays once, the file's creation and its final checkpoint,
/// drops out of the difference).
fn output_cost<T: GpuReal>(
    nx: u32,
    nz: u32,
    steps: u64,
    dir: &std::path::Path,
) -> Result<OutputCost, String> {
    let file = dir.join("run.mcap");
    let ahead = GpuOptions::default().run_ahead;
    let scenario_of = |n: u64| {
        let t_end = n as f64 * bench_scene::scene(nx, nz).dt;
        bench_scene::scenario(nx, nz, &[&format!("time.end={t_end:e}")])
    };
    // Untimed first: the first run with output builds the record pipelines.
    output_run::<T>(&scenario_of(steps), Some(&file), ahead, false)?;
    let mut runs = Vec::new();
    for n in [steps, 2 * steps] {
        let scenario = scenario_of(n);
        let without = output_run::<T>(&scenario, None, ahead, false)?;
        let with = output_run::<T>(&scenario, Some(&file), ahead, false)?;
        runs.push((without, with));
    }
    let (short, long) = (&runs[0], &runs[1]);
    let busy = |a: &Timed, b: &Timed| a.device.zip(b.device).map(|(a, b)| b - a);
    Ok(OutputCost {
        without: long.0.wall - short.0.wall,
        with: long.1.wall - short.1.wall,
        device: busy(&short.0, &long.0).zip(busy(&short.1, &long.1)),
        samples: long.1.samples_text(),
        threads: long.1.threads.clone(),
    })
}

const NOT_AGAIN: &str = "the chosen launch did not run again";

/// Whether `choice` is within `PICK_TOLERANCE` of the fastest launch
/// timed `again`, and that launch with its seconds a step (None where the
/// chosen launch did not run again).
fn pick_target(
    what: String,
    choice: &KernelChoice,
    again: &[(Launch, f64)],
) -> (Target, Option<(Launch, f64)>) {
    let fastest = again.iter().copied().min_by(|a, b| a.1.total_cmp(&b.1));
    let chosen = again.iter().find(|(l, _)| *l == choice.launch).map(|t| t.1);
    match (fastest, chosen) {
        (Some((best, best_s)), Some(chosen_s)) => (
            Target::new(
                what,
                format!(
                    "chose {} ({:.2} µs/step timed again); fastest {} ({:.2})",
                    choice.launch.name(),
                    chosen_s * 1e6,
                    best.name(),
                    best_s * 1e6
                ),
                chosen_s <= best_s * (1.0 + PICK_TOLERANCE),
            ),
            fastest,
        ),
        _ => (Target::not_measured(what, NOT_AGAIN.into()), None),
    }
}

/// 2b: `--backend auto` on Table S1 (the GPU's launch `choice` against the
/// CPU engine on all cores, `backend_choice::measure`), against the GPU's
/// fastest launch timed again (`fastest`) and the CPU engine timed again
/// over at least `min_seconds` of driving: met when the engine it runs is
/// within `PICK_TOLERANCE` of the faster of the two.
fn backend_target<T: GpuReal>(
    ctx: &GpuContext,
    s1: &Model,
    choice: &KernelChoice,
    fastest: Option<(Launch, f64)>,
    min_seconds: f64,
) -> Target {
    let what = format!(
        "`--backend auto` runs the faster of the GPU and the CPU (within {:.0} %)",
        PICK_TOLERANCE * 100.0
    );
    let Some((best, gpu_again)) = fastest else {
        return Target::not_measured(what, NOT_AGAIN.into());
    };
    let picked =
        match backend_choice::measure::<T>(s1, ctx, GpuOptions::default(), choice.launch, 0) {
            Ok(c) => c,
            Err(e) => return Target::not_measured(what, e.to_string()),
        };
    println!("`--backend auto` on Table S1: {}\n", picked.describe());
    let (cpu_again, threads) = match cpu_timed_again::<T>(s1, min_seconds) {
        Ok(t) => t,
        Err(e) => return Target::not_measured(what, e.to_string()),
    };
    let (chosen, chosen_again) = if picked.cpu_is_faster() {
        (format!("the CPU ({threads} thread(s))"), cpu_again)
    } else {
        (format!("the GPU ({})", picked.gpu_launch), gpu_again)
    };
    Target::new(
        what,
        format!(
            "chose {chosen}: GPU {} {:.2} µs/step, CPU {threads} thread(s) {:.2} µs/step \
             timed again",
            best.name(),
            gpu_again * 1e6,
            cpu_again * 1e6
        ),
        chosen_again <= gpu_again.min(cpu_again) * (1.0 + PICK_TOLERANCE),
    )
}

/// The CPU engine on all cores (`--threads 0`) on `s1`: its seconds a step
/// over at least `min_seconds` of driving after its trial of thread
/// counts, and the threads it kept.
fn cpu_timed_again<T: GpuReal>(s1: &Model, min_seconds: f64) -> Result<(f64, usize), String> {
    use slipfront::Engine;
    let mut cpu = SweepEngine::<T>::new(s1, 0).map_err(|e| e.to_string())?;
    let err = |e: slipfront::engines::EngineError| e.to_string();
    cpu.advance(s1.prep_steps).map_err(err)?;
    let trial = Instant::now();
    while cpu.timing_threads() && trial.elapsed().as_secs_f64() < 10.0 {
        cpu.advance(64).map_err(err)?;
    }
    let (t, mut steps) = (Instant::now(), 0u64);
    while t.elapsed().as_secs_f64() < min_seconds {
        cpu.advance(256).map_err(err)?;
        steps += 256;
    }
    Ok((t.elapsed().as_secs_f64() / steps as f64, cpu.threads()))
}

/// Every target in precision `T`, in the summary's order.
fn targets_in<T: GpuReal>(ctx: &GpuContext, quick: bool, min_seconds: f64) -> Vec<Target> {
    let s1 = table_s1(1);
    let blocks = s1.n_blocks() as f64;
    let mut targets = Vec::new();

    // 1 and 2: the solo kernels.
    let pick = format!(
        "`auto` picks the fastest launch (within {:.0} %)",
        PICK_TOLERANCE * 100.0
    );
    let speed = format!("Table S1 ≤ {:.0} µs/step", TABLE_S1_STEP_SECONDS * 1e6);
    let mut fastest_solo = None;
    let with_output = std::env::var("SLIPFRONT_GPU_TARGETS_WITH_OUTPUT").ok();
    let output_only = with_output.as_deref() == Some("only");
    let solo =
        (!output_only).then(|| solo_figures::<T>(ctx, &s1, GpuOptions::default(), min_seconds));
    match solo {
        None => {}
        Some(Ok((choice, again))) => {
            let (target, fastest) = pick_target(pick, &choice, &again);
            targets.push(target);
            targets.push(match fastest {
                Some((best, best_s)) => {
                    fastest_solo = Some(best_s);
                    Target::new(
                        speed,
                        format!("{:.2} µs/step ({})", best_s * 1e6, best.name()),
                        best_s <= TABLE_S1_STEP_SECONDS,
                    )
                }
                None => Target::not_measured(speed, NOT_AGAIN.into()),
            });
            targets.push(backend_target::<T>(ctx, &s1, &choice, fastest, min_seconds));
        }
        Some(Err(e)) => {
            targets.push(Target::not_measured(pick, e.clone()));
            targets.push(Target::not_measured(speed, e));
        }
    }

    // 1b: `auto` with an output file, timed recording (`GpuOptions::samples`).
    if with_output.is_some() {
        let what = format!(
            "with -o, `auto` picks the fastest launch with -o (within {:.0} %)",
            PICK_TOLERANCE * 100.0
        );
        let recording = GpuOptions {
            samples: Some(sample_plan(&s1, &table_s1_scenario(1))),
            ..GpuOptions::default()
        };
        targets.push(match solo_figures::<T>(ctx, &s1, recording, min_seconds) {
            Ok((choice, again)) => pick_target(what, &choice, &again).0,
            Err(e) => Target::not_measured(what, e),
        });
    }

    if output_only || std::env::var("SLIPFRONT_GPU_TARGETS_SOLO").is_ok() {
        return targets;
    }

    // 3 and 4: ensembles.
    let (many, some) = if quick { (16, 4) } else { (256, 64) };
    let what = format!("{many} scenes ≥ {ENSEMBLE_RATE:.0e} block-steps/s");
    let models: Vec<Model> = (1..=many).map(table_s1).collect();
    let figures = ensemble_figures::<T>(ctx, &models, min_seconds);
    let pick = format!(
        "{many} scenes: `auto`'s pick is the fastest of it and the persistent and resident \
         launches (within {:.0} %)",
        PICK_TOLERANCE * 100.0
    );
    targets.push(match &figures {
        Ok((choice, again)) => pick_target(pick, choice, again).0,
        Err(e) => Target::not_measured(pick, e.clone()),
    });
    let chosen = figures.and_then(|(choice, again)| chosen_again(&choice, &again));
    targets.push(match chosen {
        Ok((launch, s)) => {
            let rate = many as f64 * blocks / s;
            Target::new(
                what,
                format!(
                    "{rate:.3e} ({}, {:.2} µs per ensemble step)",
                    launch.name(),
                    s * 1e6
                ),
                rate >= ENSEMBLE_RATE,
            )
        }
        Err(e) => Target::not_measured(what, e),
    });
    let what = format!("{some} scenes ≥ {ENSEMBLE_SPEED_UP:.0}× one at a time");
    let models: Vec<Model> = (1..=some).map(table_s1).collect();
    targets.push(
        match (
            ensemble_figures::<T>(ctx, &models, min_seconds)
                .and_then(|(choice, again)| chosen_again(&choice, &again)),
            fastest_solo,
        ) {
            (Ok((launch, s)), Some(solo)) => {
                let speed_up = some as f64 * solo / s;
                Target::new(
                    what,
                    format!(
                        "{speed_up:.1}× ({}: {:.3e} block-steps/s against {:.3e} alone)",
                        launch.name(),
                        some as f64 * blocks / s,
                        blocks / solo
                    ),
                    speed_up >= ENSEMBLE_SPEED_UP,
                )
            }
            (Err(e), _) => Target::not_measured(what, e),
            (_, None) => Target::not_measured(what, "no solo figure".into()),
        },
    );

    // 5: output.
    let (nx, nz, steps) = if quick {
        (57, 31, 2000)
    } else {
        (1024, 512, 20_000)
    };
    let what = format!("output at {nx}×{nz} ≤ {OUTPUT_RATIO}× none");
    let dir = std::env::temp_dir().join(format!("slipfront-gpu-targets-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    targets.push(match output_cost::<T>(nx, nz, steps, &dir) {
        Ok(cost) => Target::new(
            what,
            cost.describe(steps),
            cost.with <= OUTPUT_RATIO * cost.without,
        ),
        Err(e) => Target::not_measured(what, e),
    });
    let _ = std::fs::remove_dir_all(&dir);
    targets
}

/// The precisions asked (SLIPFRONT_GPU_TARGETS_PRECISIONS), in order.
fn precisions() -> Vec<&'static str> {
    const NAME: &str = "SLIPFRONT_GPU_TARGETS_PRECISIONS";
    let Ok(text) = std::env::var(NAME) else {
        return vec!["f64", "f32"];
    };
    text.split(',')
        .map(|p| match p.trim() {
            "f64" => "f64",
            "f32" => "f32",
            other => {
                eprintln!("{NAME}: {other:?} is not a precision (allowed: f64, f32)");
                std::process::exit(2);
            }
        })
        .collect()
}

/// A table of targets, a row each, under `title`.
fn print_targets(title: &str, rows: &[(&str, &Target)]) {
    println!("## {title}\n");
    println!("| precision | target | measured | met |");
    println!("| --- | --- | --- | --- |");
    for (precision, t) in rows {
        let met = match t.met {
            Some(true) => "yes",
            Some(false) => "no",
            None => "–",
        };
        println!("| {precision} | {} | {} | {met} |", t.what, t.figure);
    }
    println!();
}

fn main() {
    let quick = std::env::var("SLIPFRONT_GPU_TARGETS_QUICK").is_ok();
    let min_seconds = if quick { 0.3 } else { 1.0 };
    let asked = precisions();
    let started = Instant::now();
    let ctx = context::shared().expect("a GPU adapter (lavapipe counts)");
    println!("# GPU targets: {}\n", ctx.describe());
    if quick {
        println!("Quick: 16 and 4 scenes, output at 57×31: not the targets' sizes.\n");
    }
    let mut all = Vec::new();
    for precision in asked {
        let label = if precision == "f32" {
            "mixed f32"
        } else {
            "f64"
        };
        println!("# {label}\n");
        let targets = match precision {
            "f64" => match ctx.check_precision::<f64>() {
                Ok(()) => targets_in::<f64>(&ctx, quick, min_seconds),
                Err(e) => vec![Target::not_measured("every target".into(), e.to_string())],
            },
            _ => targets_in::<f32>(&ctx, quick, min_seconds),
        };
        let rows: Vec<_> = targets.iter().map(|t| (label, t)).collect();
        print_targets(&format!("Targets, {label}"), &rows);
        all.push((label, targets));
    }
    let rows: Vec<_> = all
        .iter()
        .flat_map(|(label, targets)| targets.iter().map(move |t| (*label, t)))
        .collect();
    print_targets("Targets", &rows);
    println!(
        "({:.1} s of wall time; the ensemble-against-solo bits: tests/gpu_ensemble.rs)",
        started.elapsed().as_secs_f64()
    );
}
