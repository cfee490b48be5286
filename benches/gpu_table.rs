//! The GPU table in one command, for anyone with a GPU:
//!
//!     cargo bench --bench gpu_table
//!
//! (on the lent GPU machine: the packed `gpu_table` binary). It prints, as
//! Markdown, in mixed f32:
//!
//! 1. every kernel against lattice size (Table S1 to 8192×4096): µs per
//!    step and block-steps/s, each kernel on the scene alone, the one-step
//!    kernels also with their bulk forces by 2×2 patches;
//! 2. what `auto` chooses on Table S1 (timed now, as `--gpu-path measure`,
//!    from the start of driving; and, for comparison, from the initial
//!    state, as builds before 2026-11-27 timed it), and the persistent and resident kernels there with 256, 512 and 1024
//!    threads (`--gpu-threads`: more threads, fewer registers each); and the
//!    tiled kernel by tile width, halo and threads;
//! 3. ensembles of 1 to 1024 Table S1 scenes (the precursors scene, a seed
//!    each) in one dispatch, per kernel (the persistent and resident ones
//!    at 256, 512 and 1024 threads): aggregate block-steps/s and the
//!    speed-up over running the scenes one at a time;
//! 4. what an output file at the default cadences costs (device records),
//!    against the same steps without one;
//! 5. the CPU engine on all cores of the same machine, and the GPU's best
//!    over it;
//! 6. the issue's own figure: 64 and 256 Table S1 points (a seed each,
//!    0.01 s of driving) as one `sweep --backend gpu` (its kernel timed on
//!    the sweep's ensemble, as `auto` does), and the 64 one at a time;
//! 7. what the junctions cost on Table S1: Ns = 100 with every junction
//!    summed every step (with runs of lanes merged in subgroups first, the
//!    default, and with every lane's sum through storage) and with quiet
//!    blocks' sums kept (the default), Ns = 16, Coulomb friction, and no
//!    friction (the bulk alone, the tiled kernel included); the resident
//!    and tiled kernels also with each junction lane calling
//!    `junction_block` for its block's kept flag, as before session 33
//!    (`GpuOptions::lanes_read_kept`), and the tiled kernel with its
//!    rounds chained in one dispatch (`GpuOptions::chained_tiles`);
//! 8. what limits an ensemble: the single-workgroup kernels on one Table S1
//!    scene and on 132, 264 and 528 (one, two and four an SM of an H200 or
//!    an H100 SXM, 132 SMs), at 256 threads (and 1024 on the
//!    shipped scene), with Ns = 100 (as shipped), Ns = 16 and Coulomb
//!    friction in mixed f32, and as shipped in f64 (each launch also with
//!    one junction lane a round, which needs fewer registers in f64, so
//!    may fit more scenes an SM). Where the step doubles
//!    between the counts says how many scenes an SM holds at once; how much
//!    longer than one scene's it is where they share, against the
//!    junctions' share of the work and the precision, says whether they
//!    overlap or contend, and for what (docs/gpu-kernels.md, "What limits
//!    an ensemble"). SLIPFRONT_GPU_TABLE_LIMIT_SCENES=1,132,264 sets its
//!    scene counts;
//! 9. the tiled kernel with its rounds chained in one dispatch on Table S1
//!    by tile width (2 to 16 columns), halo (1, 2, 4) and threads (256,
//!    512, 1024), with the device's busy time a step: `auto` times
//!    chained tiles only at the width its unchained search found.
//!
//! Sections 1–3 also print the host's CPU time per wall second of each
//! timed span: it says whether the host (encoding dispatches, waiting) or
//! the device is what a figure measures.
//!
//! Every figure is timed after a warm-up, over at least `SECONDS` of wall
//! time (doubling the steps until then); the device is waited for at the
//! end of each advance, and nothing is read back in the timed span.
//! SLIPFRONT_GPU_TABLE_QUICK=1 keeps to small lattices and ensembles of up
//! to 16 (software adapters: lavapipe runs the full table for hours).
//! SLIPFRONT_GPU_TABLE_SECTIONS=1,3,6 runs only those sections (a short
//! loan of a GPU can take the table in parts); each prints its wall time.
//! SLIPFRONT_GPU_TABLE_SCENES=1,256 runs section 3 at those scene counts
//! only, SLIPFRONT_GPU_TABLE_LAUNCHES=resident/1024,persistent/512 those
//! kernels only (two builds compared in one loan; a name such as
//! `resident/1024/bond-patches` adds that launch's rows);
//! SLIPFRONT_GPU_TABLE_SWEEPS=256 runs section 6 at those point counts.
//! SLIPFRONT_GPU_TABLE_KEEP_SUMS=0 sums every junction every step in
//! sections 1–3 (`GpuOptions::keep_junction_sums` off): the same bits,
//! the cost of the junction phase without skipping quiet blocks.
//! SLIPFRONT_GPU_TABLE_LANE_SHUFFLE=0 sends every junction lane's sum
//! through storage in sections 1–3 (`GpuOptions::lane_shuffle` off; the
//! default merges runs of lanes in subgroups first where the adapter has
//! them): the same bits. Section 7 prints both on Table S1, and the
//! shipped Table S1 scene with and without wgpu's run-time checks in the
//! kernels (`GpuOptions::shader_checks`), and the persistent, resident
//! and tiled kernels there with their bulk forces by patches of blocks
//! (`GpuOptions::bond_patches`).

use gpu_timing::{
    ensemble_step_seconds, ensemble_step_seconds_in, output_run, solo_step_figures_in,
    solo_step_seconds, table_s1, timed_advance, Timed,
};
use slipfront::app::sweeps::{run_sweep, KeepMcap, Sweep, SweepOptions};
use slipfront::engines::backend::{make_engine, Backend, Precision};
use slipfront::engines::gpu::kernel_choice::{candidates, launches, measure_within, Launch};
use slipfront::engines::gpu::shaders::Kernel;
use slipfront::engines::gpu::tiles::TileShape;
use slipfront::engines::gpu::{context, GpuOptions, GpuPath, GpuReal};
use slipfront::model::scenario::built_in;
use slipfront::{advance_to, Model, Scenario};
use std::time::Instant;

#[path = "support/bench_scene.rs"]
mod bench_scene;
#[path = "support/gpu_timing.rs"]
mod gpu_timing;
#[path = "support/thread_cpu.rs"]
mod thread_cpu;

/// Section 2's budget for stepping the normal-load phase before timing
/// (`auto`'s is 3 s): the bench always times from the start of driving.
const PREPARE_WITHOUT_BUDGET: f64 = 1e6;

fn options(kernel: Kernel) -> GpuOptions {
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

fn with_threads(kernel: Kernel, threads: Option<u32>) -> GpuOptions {
    GpuOptions {
        persistent_threads: threads,
        ..options(kernel)
    }
}

fn path_name(kernel: Kernel) -> String {
    GpuPath::of(kernel).name()
}

/// The tiled kernel on `model` by tile width, halo (the most steps per
/// dispatch) and threads: which tiles fill the GPU's SMs and how many
/// steps a dispatch should take (`shaders/tiled.wgsl`).
fn tiled_grid(model: &Model, quick: bool, min_seconds: f64) {
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

/// What a Table S1 step costs with fewer junction lanes and with none:
/// the same lattice with Ns = 100 (64 lanes per interface block, as
/// shipped) with every junction summed every step and with quiet blocks'
/// sums kept (the default; the timed span is after the normal-load phase,
/// where the precursors scene is quiet), Ns = 16 (16 lanes), Coulomb
/// friction (no junctions) and no friction (the bulk alone), per kernel at
/// its default threads; the
/// shipped scene also with wgpu's run-time checks in the kernels. Where the junctions' share is large, the
/// lane sums (one thread adds a block's lanes, in order) are the step's
/// critical path; where it is small, the stencil and the barriers are.
fn junction_cost(min_seconds: f64) {
    println!("What the junctions cost (Table S1 lattice, each kernel at its default threads):\n");
    println!("| friction | kernel | µs/step | host CPU / wall |");
    println!("| --- | --- | ---: | ---: |");
    let text = built_in("tromborg2014_precursors").expect("shipped scene");
    // The same scene with every junction summed every step: what keeping a
    // quiet block's sums (`GpuOptions::keep_junction_sums`) saves.
    // And with every lane's sum through storage: what merging runs of
    // lanes in subgroups first saves where every block is summed.
    for kernel in candidates(&s1_model(text, &[])) {
        let shuffles: &[bool] = if kernel.merges_lanes_through_storage() {
            &[true, false]
        } else {
            &[true]
        };
        for &shuffle in shuffles {
            let opts = GpuOptions {
                keep_junction_sums: false,
                lane_shuffle: shuffle,
                ..options(kernel)
            };
            let figure = match solo_step_seconds(&s1_model(text, &[]), opts, min_seconds) {
                Ok((s, host)) => format!("{:.2} | {host:.2}", s * 1e6),
                Err(e) => format!("not run: {e} |"),
            };
            let lanes = match (kernel.merges_lanes_through_storage(), shuffle) {
                (false, _) => "",
                (true, true) => ", lanes merged in subgroups first",
                (true, false) => ", every lane's sum through storage",
            };
            println!(
                "| junctions, Ns = 100, every junction summed every step{lanes} | {} | {figure} |",
                path_name(kernel)
            );
        }
    }
    for (name, set) in [
        (
            "junctions, Ns = 100 (64 lanes), quiet blocks' sums kept",
            None,
        ),
        (
            "junctions, Ns = 16 (16 lanes)",
            Some("friction.junctions.count=16"),
        ),
        ("Coulomb (no junctions)", Some("friction.law=coulomb")),
        // No friction at all: the bulk, the update and the step's overhead
        // alone, on every kernel the tiled one included (it refuses
        // Coulomb, a per-block law).
        ("no friction (the bulk alone)", Some("friction.law=none")),
    ] {
        let set: Vec<String> = set.map(String::from).into_iter().collect();
        let scenario = Scenario::parse(text, "table S1", &set).expect("a Table S1 variant");
        let model = Model::from_scenario(&scenario, false).expect("a Table S1 variant");
        // The scene as shipped also with wgpu's run-time checks in the
        // kernels (`GpuOptions::shader_checks`): what leaving them out saves;
        // and with their bulk forces by patches of blocks
        // (`GpuOptions::bond_patches`).
        for kernel in candidates(&model) {
            // (shader checks, bond patches, lanes read the kept bit,
            // chained tiles)
            let mut variants = vec![(false, false, true, false)];
            if set.is_empty() {
                variants.push((true, false, true, false));
                variants.push((false, true, true, false));
                if matches!(kernel, Kernel::Resident | Kernel::Tiled) {
                    variants.push((false, false, false, false));
                }
            }
            // The tiled kernel's rounds chained in one dispatch, on every
            // scene (the bulk alone too): what a dispatch a round costs.
            if kernel == Kernel::Tiled {
                variants.push((false, false, true, true));
            }
            for (shader_checks, bond_patches, lanes_read_kept, chained_tiles) in variants {
                let kept = GpuOptions {
                    keep_junction_sums: true,
                    shader_checks,
                    bond_patches,
                    lanes_read_kept,
                    chained_tiles,
                    ..options(kernel)
                };
                let figure = match solo_step_seconds(&model, kept, min_seconds) {
                    Ok((s, host)) => format!("{:.2} | {host:.2}", s * 1e6),
                    Err(e) => format!("not run: {e} |"),
                };
                let how = match (shader_checks, bond_patches, lanes_read_kept) {
                    _ if chained_tiles => ", rounds chained in one dispatch",
                    (true, _, _) => ", wgpu's run-time checks in the kernels",
                    (_, true, _) => ", bulk forces by 2×2 patches of blocks",
                    (_, _, false) => {
                        ", each lane calling junction_block for its block's kept flag \
                         (before session 33)"
                    }
                    _ => "",
                };
                println!("| {name}{how} | {} | {figure} |", path_name(kernel));
            }
        }
    }
    println!();
}

/// Section 8: the single-workgroup kernels on one Table S1 scene and on a
/// staircase of scene counts (1, 128, 192, 256 by default), for scenes with
/// less and less junction work (Ns = 100 as shipped, Ns = 16, Coulomb) in
/// mixed f32, and as shipped in f64. More scenes than fit the GPU at once
/// run in waves, so the step grows in stairs: from 128 to 192 scenes it
/// doubles where one workgroup fills an SM (an H200 has 132), and stays
/// where two fit. Where they fit, how much longer the step is than one
/// scene's says whether scenes that share an SM overlap or contend, and the
/// scene variants say in which phase (docs/gpu-kernels.md, "What limits an
/// ensemble").
fn ensemble_limits(quick: bool, min_seconds: f64) {
    let counts = counts_from_env(
        "SLIPFRONT_GPU_TABLE_LIMIT_SCENES",
        if quick { &[1, 4] } else { &[1, 132, 264, 528] },
    );
    let most = counts.iter().copied().max().unwrap_or(1);
    // Half a second a figure: a step of tens of µs is then thousands of
    // steps, and the section fits one step of gpu_call.sh.
    let min_seconds = min_seconds.min(0.5);
    let text = built_in("tromborg2014_precursors").expect("shipped scene");
    println!(
        "Each row: µs per ensemble step at each scene count, then each count's step over \
         one scene's (1.0: the scenes ran at once without slowing each other; 2.0: in two \
         waves, or side by side at half speed).\n"
    );
    let header: String = counts
        .iter()
        .map(|&n| format!(" {n} scene{} |", if n == 1 { "" } else { "s" }))
        .collect();
    let ratios: String = counts[1..].iter().map(|n| format!(" {n} / 1 |")).collect();
    let last = counts[counts.len() - 1];
    println!("| scene | precision | launch |{header}{ratios} block-steps/s at {last} |");
    let rule = " ---: |".repeat(2 * counts.len());
    println!("| --- | --- | --- |{rule}");
    // Why a launch did not run ("–" in the table), each reason once.
    let mut not_run: Vec<String> = Vec::new();
    // (scene, its settings, precision, threads): 1024 threads (a scene a
    // workgroup that fills its SM) as the control on the shipped scene,
    // 256 threads (room for several scenes an SM) on every variant.
    let both: &[u32] = &[256, 1024];
    let few: &[u32] = &[256];
    let variants: [(&str, Option<&str>, bool, &[u32]); 4] = [
        ("Ns = 100 (as shipped)", None, false, both),
        ("Ns = 100 (as shipped)", None, true, both),
        ("Ns = 16", Some("friction.junctions.count=16"), false, few),
        (
            "Coulomb (no junctions)",
            Some("friction.law=coulomb"),
            false,
            few,
        ),
    ];
    for (name, set, f64_run, threads) in variants {
        let models: Vec<Model> = (1..=most)
            .map(|seed| {
                let mut sets = vec![format!("time.seed={seed}")];
                sets.extend(set.map(String::from));
                let scenario =
                    Scenario::parse(text, "table S1", &sets).expect("a Table S1 variant");
                Model::from_scenario(&scenario, false).expect("a Table S1 variant")
            })
            .collect();
        let rows = LimitRows {
            name,
            models: &models,
            counts: &counts,
            threads,
            min_seconds,
            // In f64 one lane a round needs fewer registers (AMD: 72–80
            // VGPRs against 88), so it may fit more scenes an SM.
            one_lane_too: f64_run,
        };
        if f64_run {
            rows.print::<f64>("f64", &mut not_run);
        } else {
            rows.print::<f32>("mixed f32", &mut not_run);
        }
    }
    println!();
    for line in &not_run {
        println!("{line}");
    }
}

/// Section 8's rows of one scene variant.
struct LimitRows<'a> {
    name: &'a str,
    models: &'a [Model],
    counts: &'a [usize],
    threads: &'a [u32],
    min_seconds: f64,
    /// Each launch again with one junction lane a round.
    one_lane_too: bool,
}

impl LimitRows<'_> {
    /// The rows in precision `T`: the resident and persistent kernels at
    /// each of the threads (and each with one junction lane a round, where
    /// asked), each on the first `n` scenes for each count. A
    /// launch that does not run (resident in f64 at Table S1 does not fit)
    /// adds its reason to `not_run`.
    fn print<T: GpuReal>(&self, precision: &str, not_run: &mut Vec<String>) {
        let blocks = self.models[0].n_blocks() as f64;
        let launches = [Kernel::Resident, Kernel::Persistent]
            .into_iter()
            .flat_map(|kernel| {
                self.threads
                    .iter()
                    .map(move |&t| Launch::with_threads(kernel, t))
            })
            .flat_map(|launch| {
                let one = self.one_lane_too.then(|| launch.with_one_lane_a_round());
                std::iter::once(launch).chain(one)
            });
        for launch in launches {
            let steps: Vec<Result<f64, String>> = self
                .counts
                .iter()
                .map(|&n| {
                    ensemble_step_seconds_in::<T>(
                        &self.models[..n],
                        launch.options(GpuOptions::default()),
                        self.min_seconds,
                    )
                    .map(|(s, _)| s)
                })
                .collect();
            let cells: String = steps
                .iter()
                .map(|r| match r {
                    Ok(s) => format!(" {:.2} |", s * 1e6),
                    Err(_) => " – |".to_string(),
                })
                .collect();
            for e in steps.iter().filter_map(|r| r.as_ref().err()) {
                let line = format!("- {}, {precision}: not run: {e}", launch.name());
                if !not_run.contains(&line) {
                    not_run.push(line);
                }
            }
            let ratios: String = steps[1..]
                .iter()
                .map(|r| match (r, &steps[0]) {
                    (Ok(s), Ok(one)) => format!(" {:.2} |", s / one),
                    _ => " |".to_string(),
                })
                .collect();
            let last = self.counts[self.counts.len() - 1] as f64;
            let rate = match steps.last() {
                Some(Ok(s)) => format!("{:.3e}", last * blocks / s),
                _ => String::new(),
            };
            println!(
                "| {} | {precision} | {} |{cells}{ratios} {rate} |",
                self.name,
                launch.name()
            );
        }
    }
}

/// The precursors scene from `text`, with `set`'s keys changed.
fn s1_model(text: &str, set: &[&str]) -> Model {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let scenario = Scenario::parse(text, "table S1", &set).expect("the scene");
    Model::from_scenario(&scenario, false).expect("the scene")
}

/// `points` seeds of the precursors scene, 0.01 s of driving each, as a
/// sweep file in `dir`.
fn table_s1_sweep(dir: &std::path::Path, points: usize) -> Sweep {
    let base = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/tromborg2014_precursors.toml"
    );
    let text = format!(
        "base = \"{base}\"\nseeds = {points}\n[set]\n\"time.end\" = 0.01\n\
         \"output.bulk_interval\" = 0.0\n"
    );
    let file = dir.join(format!("table_s1_{points}.toml"));
    std::fs::write(&file, text).expect("sweep file");
    Sweep::load(&file).expect("sweep")
}

/// Wall seconds of `sweep` on the GPU in mixed f32, `ensemble` scenes per
/// dispatch at most (1: one point at a time), the device running ahead of
/// the runners by `run_ahead` batches (0: it waits for them every chunk);
/// and the CPU its threads used per wall second.
fn sweep_wall(
    dir: &std::path::Path,
    sweep: &Sweep,
    ensemble: usize,
    run_ahead: usize,
) -> Result<(f64, String), String> {
    let out = dir.join(format!("sweep-{}-{ensemble}", sweep.points.len()));
    let _ = std::fs::remove_dir_all(&out);
    let threads = thread_cpu::ThreadCpu::start();
    let t0 = Instant::now();
    let report = run_sweep(
        sweep,
        &SweepOptions {
            out_dir: out.clone(),
            backend: Backend::Gpu,
            precision: Precision::F32,
            threads: 1,
            shard: None,
            keep_mcap: KeepMcap::None,
            progress: false,
            share_loading: true,
            ensemble,
            gpu: GpuOptions {
                run_ahead,
                ..slipfront::app::sweeps::default_gpu()
            },
            on_point: None,
        },
    )?;
    let wall = t0.elapsed().as_secs_f64();
    let threads = thread_cpu::per_wall(&threads.finish(), wall);
    let _ = std::fs::remove_dir_all(&out);
    if report.not_ok > 0 {
        return Err(format!("{} points not ok", report.not_ok));
    }
    Ok((wall, threads))
}

/// The counts listed in environment variable `name` (`1,64,256`), else
/// `default`.
fn counts_from_env(name: &str, default: &[usize]) -> Vec<usize> {
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

/// Which sections to run (`SLIPFRONT_GPU_TABLE_SECTIONS=1,3,6`; all by
/// default), so that a short loan of a GPU can run the table in parts;
/// each section's own wall time is printed after it.
struct Sections(Vec<u32>);

/// Prints a section's wall time when dropped.
struct SectionTimer(u32, Instant);

impl Drop for SectionTimer {
    fn drop(&mut self) {
        println!(
            "\n(section {} took {:.1} s of wall time)\n",
            self.0,
            self.1.elapsed().as_secs_f64()
        );
    }
}

impl Sections {
    fn from_env() -> Self {
        let all = (1..=9).collect();
        match std::env::var("SLIPFRONT_GPU_TABLE_SECTIONS") {
            Ok(list) => Sections(
                list.split(',')
                    .map(|s| match s.trim().parse() {
                        Ok(n @ 1..=9) => n,
                        _ => {
                            panic!("SLIPFRONT_GPU_TABLE_SECTIONS: `{s}` is not a section (1 to 9)")
                        }
                    })
                    .collect(),
            ),
            Err(_) => Sections(all),
        }
    }

    fn start(&self, n: u32) -> Option<SectionTimer> {
        self.0.contains(&n).then(|| SectionTimer(n, Instant::now()))
    }
}

fn main() {
    let quick = std::env::var("SLIPFRONT_GPU_TABLE_QUICK").is_ok();
    let min_seconds = if quick { 0.3 } else { 1.0 };
    let ctx = context::shared().expect("a GPU adapter (lavapipe counts)");
    println!("# GPU table: {}\n", ctx.describe());
    // The limits the kernels' choices rest on (the resident kernel's fit,
    // the ensembles' binding cap, the threads of a workgroup).
    println!(
        "Limits: workgroup memory {} bytes, {} threads per workgroup, storage binding {} bytes.\n",
        ctx.limits.max_compute_workgroup_storage_size,
        ctx.limits.max_compute_invocations_per_workgroup,
        ctx.limits.max_storage_buffer_binding_size
    );
    println!("Mixed f32; each figure timed over at least {min_seconds} s of wall time.\n");

    let dir = std::env::temp_dir().join(format!("slipfront-gpu-table-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let sections = Sections::from_env();
    let sizes: &[(u32, u32)] = if quick {
        &[(57, 31), (256, 64)]
    } else {
        &[
            (57, 31),
            (256, 64),
            (1024, 256),
            (2048, 1024),
            (4096, 2048),
            (8192, 4096),
        ]
    };
    let s1 = table_s1(1);
    let mut best_gpu = Vec::new();
    if let Some(_timer) = sections.start(1) {
        // 1. Kernels against lattice size.
        println!("## 1. Kernels against lattice size (each scene alone)\n");
        println!(
            "Host CPU / wall: CPU seconds of every thread of the process per wall second of the \
             timed span (near 1 or above: the host is the limit; near 0 on a hardware GPU: the \
             device).\n"
        );
        println!("| lattice | kernel | µs/step | block-steps/s | host CPU / wall |");
        println!("| --- | --- | ---: | ---: | ---: |");
        for &(nx, nz) in sizes {
            let model = bench_scene::scene(nx, nz);
            let mut best = f64::INFINITY;
            // The one-step kernels also with their bulk forces by 2×2
            // patches (a quarter of the threads: the large lattices' variant).
            let runs = candidates(&model).into_iter().flat_map(|kernel| {
                let one_step = matches!(kernel, Kernel::OneStep | Kernel::OneStepLanes);
                let patched = one_step.then_some((kernel, true));
                [(kernel, false)].into_iter().chain(patched)
            });
            for (kernel, bond_patches) in runs {
                let opts = GpuOptions {
                    bond_patches,
                    ..options(kernel)
                };
                let name = format!(
                    "{}{}",
                    path_name(kernel),
                    if bond_patches { "/bond-patches" } else { "" }
                );
                match solo_step_seconds(&model, opts, min_seconds) {
                    Ok((s, host)) => {
                        best = best.min(s);
                        println!(
                            "| {nx}×{nz} | {name} | {:.2} | {:.3e} | {host:.2} |",
                            s * 1e6,
                            model.n_blocks() as f64 / s
                        );
                    }
                    Err(e) => println!("| {nx}×{nz} | {name} | not run: {e} | | |"),
                }
            }
            best_gpu.push(((nx, nz), model.n_blocks() as f64 / best));
        }
    }
    if let Some(_timer) = sections.start(2) {
        // 2. The auto choice on Table S1.
        println!("\n## 2. What `auto` chooses on Table S1 (the precursors scene)\n");
        // As `auto` times (from the start of driving; here with no budget
        // for the load phase, which lavapipe takes 9 s to step), and as
        // builds before 2026-11-27 did (from the initial state, in the
        // normal-load phase, where no block keeps its junction sums):
        // whether the phase changes the choice on this GPU.
        for (how, budget) in [
            ("from the start of driving", PREPARE_WITHOUT_BUDGET),
            ("from the initial state", 0.0),
        ] {
            match measure_within::<f32>(
                std::slice::from_ref(&s1),
                &ctx,
                GpuOptions::default(),
                budget,
            ) {
                Ok(choice) => println!("Timed {how}: {}\n", choice.describe()),
                Err(e) => println!("Timed {how}: not measured: {e}\n"),
            }
        }
        println!("| kernel | threads | µs/step | host CPU / wall |");
        println!("| --- | ---: | ---: | ---: |");
        for kernel in [Kernel::Persistent, Kernel::Resident] {
            for threads in [256, 512, 1024] {
                let figure = match solo_step_seconds(
                    &s1,
                    with_threads(kernel, Some(threads)),
                    min_seconds,
                ) {
                    Ok((s, host)) => format!("{:.2} | {host:.2}", s * 1e6),
                    Err(e) => format!("not run: {e} |"),
                };
                println!("| {} | {threads} | {figure} |", path_name(kernel));
            }
        }
        println!();
        tiled_grid(&s1, quick, min_seconds);
    }
    if let Some(_timer) = sections.start(3) {
        // 3. Ensembles of Table S1 scenes.
        let counts = counts_from_env(
            "SLIPFRONT_GPU_TABLE_SCENES",
            if quick {
                &[1, 4, 16]
            } else {
                &[1, 4, 16, 64, 256, 1024]
            },
        );
        println!("## 3. Ensembles of Table S1 scenes in one dispatch\n");
        println!(
            "Speed-up: the ensemble's aggregate rate over the same kernel's rate for one scene \
         alone (what running the scenes one at a time gets).\n"
        );
        println!("Host CPU / wall: as in section 1.\n");
        println!(
            "| scenes | kernel | µs per ensemble step | aggregate block-steps/s | speed-up | \
             host CPU / wall |"
        );
        println!("| ---: | --- | ---: | ---: | ---: | ---: |");
        let blocks = s1.n_blocks() as f64;
        // Scene counts outermost, so that a loan cut short has every
        // kernel's row at the smaller counts before any at the largest. The
        // single-workgroup kernels at each of ENSEMBLE_THREADS, as a
        // sweep's measurement times them (how many scenes share an SM
        // depends on their threads).
        let mut tried = launches(&s1, 2, GpuOptions::default(), &ctx.limits);
        // The launches with their bulk forces by patches too, but only
        // where SLIPFRONT_GPU_TABLE_LAUNCHES names them
        // (`resident/1024/bond-patches`).
        let patched: Vec<_> = tried.iter().map(|l| l.with_bond_patches()).collect();
        tried.extend(patched);
        // SLIPFRONT_GPU_TABLE_LAUNCHES=resident/1024,one-step-lanes: only those.
        let launches_wanted: Option<Vec<String>> = std::env::var("SLIPFRONT_GPU_TABLE_LAUNCHES")
            .ok()
            .map(|list| list.split(',').map(|n| n.trim().to_string()).collect());
        let mut alone = vec![None; tried.len()];
        for &n in &counts {
            let models: Vec<Model> = (1..=n).map(table_s1).collect();
            for (&launch, alone) in tried.iter().zip(alone.iter_mut()) {
                let wanted = match &launches_wanted {
                    Some(w) => w.contains(&launch.name()),
                    None => !launch.bond_patches,
                };
                if !wanted {
                    continue;
                }
                let result = ensemble_step_seconds(
                    &models,
                    launch.options(GpuOptions::default()),
                    min_seconds,
                );
                match result {
                    Ok((per_step, host)) => {
                        let rate = n as f64 * blocks / per_step;
                        let one = *alone.get_or_insert(blocks / per_step);
                        println!(
                            "| {n} | {} | {:.2} | {rate:.3e} | {:.1}× | {:.2} |",
                            launch.name(),
                            per_step * 1e6,
                            rate / one,
                            host
                        );
                    }
                    Err(e) => println!("| {n} | {} | not run: {e} | | | |", launch.name()),
                }
            }
        }
    }
    if let Some(_timer) = sections.start(4) {
        // 4. Output cost at the default cadences.
        println!("\n## 4. An output file at the default cadences (device records) against none\n");
        println!(
            "| lattice | kernel | steps | wall without | wall with -o | ratio | \
             host CPU / wall with -o | with -o, not running ahead | ratio | \
             device busy without | device busy with -o |"
        );
        println!("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
        let output_sizes: &[(u32, u32, u64)] = if quick {
            &[(57, 31, 2000)]
        } else {
            &[(57, 31, 40_000), (1024, 512, 20_000)]
        };
        let mut threads_seen = Vec::new();
        // Each lattice at `steps` and twice as many: what the longer run
        // adds is the output's cost per step, without what a run pays once
        // (the file's creation, the checkpoint at the end: 37 MB at
        // 1024×512), which a run of a second or less weighs heavily.
        let mut marginal = Vec::new();
        let mut split = Vec::new();
        let (mut marginal_f64, mut split_f64) = (Vec::new(), Vec::new());
        for &(nx, nz, first) in output_sizes {
            let mut walls = Vec::new();
            for steps in [first, 2 * first] {
                let model = bench_scene::scene(nx, nz);
                let t_end = steps as f64 * model.dt;
                let scenario = bench_scene::scenario(nx, nz, &[&format!("time.end={t_end:e}")]);
                let file = dir.join("run.mcap");
                let ahead = GpuOptions::default().run_ahead;
                let wall = |output: Option<&std::path::Path>, run_ahead: usize, time: bool| {
                    output_run::<f32>(&scenario, output, run_ahead, time)
                };
                // An untimed run with output first: the first one in a process
                // builds the record pipelines, which cost the first timed
                // column 0.22–0.28 s at 57×31 on an H200 (session 15).
                if steps == first {
                    let _ = wall(Some(&file), ahead, false);
                }
                match (
                    wall(None, ahead, false),
                    wall(Some(&file), ahead, false),
                    wall(Some(&file), 0, false),
                ) {
                    (Ok(quiet_run), Ok(output_run), Ok(waiting_run)) => {
                        let (without, device_without) = (quiet_run.wall, quiet_run.device);
                        let (with, host, device_with) =
                            (output_run.wall, output_run.cpu, output_run.device);
                        let samples = output_run.samples_text();
                        let (how, quiet, busy) =
                            (quiet_run.how, quiet_run.threads, output_run.threads);
                        let waiting = waiting_run.wall;
                        let kernel = how.split(", ").nth(1).unwrap_or(&how).to_string();
                        let device =
                            |d: Option<f64>| d.map_or("–".to_string(), |d| format!("{d:.3} s"));
                        println!(
                            "| {nx}×{nz} | {kernel} | {steps} | {without:.3} s | {with:.3} s | {:.2} | \
                             {host:.2} | {waiting:.3} s | {:.2} | {} | {} |",
                            with / without,
                            waiting / without,
                            device(device_without),
                            device(device_with),
                        );
                        threads_seen.push(format!(
                            "- {nx}×{nz}, {steps} steps, CPU seconds per wall second by thread: \
                             without output {quiet}; with -o {busy}; device samples {samples}"
                        ));
                        walls.push((without, with, waiting, device_without, device_with));
                    }
                    (a, b, c) => {
                        println!("| {nx}×{nz} | not run: {a:?} {b:?} {c:?} | | | | | | | | | |")
                    }
                }
                // Where the output's device time goes: the shorter run again,
                // its dispatches timed.
                if steps == first {
                    split.push(match wall(Some(&file), ahead, true) {
                        Ok(Timed {
                            dispatches: Some(t),
                            wall,
                            ..
                        }) => format!("- {nx}×{nz}, {steps} steps with -o ({wall:.3} s): {t}"),
                        Ok(_) => format!("- {nx}×{nz}: the dispatches were not timed"),
                        Err(e) => format!("- {nx}×{nz}: not run: {e}"),
                    });
                }
            }
            // f64, the default precision where the adapter has it (its
            // samples recorded on the device since session 17): the same
            // two lengths, without and with -o, and the split.
            let file = dir.join("run.mcap");
            let ahead = GpuOptions::default().run_ahead;
            let scenario_of = |steps: u64| {
                let t_end = steps as f64 * bench_scene::scene(nx, nz).dt;
                bench_scene::scenario(nx, nz, &[&format!("time.end={t_end:e}")])
            };
            let _ = output_run::<f64>(&scenario_of(first), Some(&file), ahead, false);
            let mut f64_walls = Vec::new();
            for steps in [first, 2 * first] {
                let scenario = scenario_of(steps);
                match (
                    output_run::<f64>(&scenario, None, ahead, false),
                    output_run::<f64>(&scenario, Some(&file), ahead, false),
                ) {
                    (Ok(a), Ok(b)) => f64_walls.push((a.wall, b.wall, a.device, b.device)),
                    (a, b) => marginal_f64.push(format!(
                        "- {nx}×{nz} in f64, {steps} steps: not run: {:?} {:?}",
                        a.err(),
                        b.err()
                    )),
                }
            }
            if let [short, long] = f64_walls[..] {
                let device = match (short.2.zip(long.2), short.3.zip(long.3)) {
                    (Some((a, b)), Some((c, d))) => format!(
                        "; the device was busy {:.3} s of them without output, {:.3} s with -o",
                        b - a,
                        d - c
                    ),
                    _ => String::new(),
                };
                marginal_f64.push(format!(
                    "- {nx}×{nz} in f64: the second {first} steps cost {:.3} s without output, \
                     {:.3} s with -o ({:.2}×){device}",
                    long.0 - short.0,
                    long.1 - short.1,
                    (long.1 - short.1) / (long.0 - short.0),
                ));
            }
            split_f64.push(
                match output_run::<f64>(&scenario_of(first), Some(&file), ahead, true) {
                    Ok(Timed {
                        dispatches: Some(t),
                        wall,
                        ..
                    }) => format!("- {nx}×{nz} in f64, {first} steps with -o ({wall:.3} s): {t}"),
                    Ok(_) => format!("- {nx}×{nz} in f64: the dispatches were not timed"),
                    Err(e) => format!("- {nx}×{nz} in f64: not run: {e}"),
                },
            );
            if let [short, long] = walls[..] {
                let device = match (short.3.zip(long.3), short.4.zip(long.4)) {
                    (Some((a, b)), Some((c, d))) => format!(
                        "; the device was busy {:.3} s of them without output, {:.3} s with -o",
                        b - a,
                        d - c
                    ),
                    _ => String::new(),
                };
                marginal.push(format!(
                    "- {nx}×{nz}: the second {first} steps cost {:.3} s without output, {:.3} s with \
                     -o ({:.2}×), {:.3} s with -o not running ahead ({:.2}×){device}",
                    long.0 - short.0,
                    long.1 - short.1,
                    (long.1 - short.1) / (long.0 - short.0),
                    long.2 - short.2,
                    (long.2 - short.2) / (long.0 - short.0),
                ));
            }
        }
        println!("\nPer step, without what a run pays once (the longer run less the shorter):\n");
        for line in marginal.iter().chain(&marginal_f64) {
            println!("{line}");
        }
        println!("\nThe device time of a run with -o by dispatch (timestamps inside the pass):\n");
        for line in split.iter().chain(&split_f64) {
            println!("{line}");
        }
        // Which host thread the output keeps busy: the runner ("main"),
        // the file's writing thread (slipfront-mcap) or the driver's.
        println!();
        for line in threads_seen {
            println!("{line}");
        }
    }
    if let Some(_timer) = sections.start(5) {
        // 5. The CPU on all cores, and the GPU's best over it.
        println!("\n## 5. The CPU engine on all cores of this machine (mixed f32)\n");
        println!("| lattice | CPU block-steps/s | GPU best block-steps/s | GPU/CPU |");
        println!("| --- | ---: | ---: | ---: |");
        for &(nx, nz) in sizes {
            if nx as usize * nz as usize > 1024 * 256 {
                continue;
            }
            // Section 1's best kernel at this size, when it ran.
            let gpu_rate = best_gpu
                .iter()
                .find(|(size, _)| *size == (nx, nz))
                .map(|&(_, rate)| rate);
            let model = bench_scene::scene(nx, nz);
            let result = make_engine(&model, Backend::Cpu, Precision::F32, 0).and_then(|mut e| {
                advance_to(e.as_mut(), model.prep_steps + 16)?;
                timed_advance(|n| e.advance(n), min_seconds)
            });
            match result {
                Ok((dt, steps)) => {
                    let cpu = model.n_blocks() as f64 * steps as f64 / dt;
                    match gpu_rate {
                        Some(gpu) => {
                            println!("| {nx}×{nz} | {cpu:.3e} | {gpu:.3e} | {:.1}× |", gpu / cpu)
                        }
                        None => println!("| {nx}×{nz} | {cpu:.3e} | (section 1 not run) | |"),
                    }
                }
                Err(e) => println!("| {nx}×{nz} | not run: {e} | | |"),
            }
        }
    }
    if let Some(_timer) = sections.start(6) {
        // 6. Table S1 points as one sweep.
        println!("\n## 6. Table S1 points as one sweep, 0.01 s of driving each\n");
        println!(
            "Block-steps/s of the runs count each point's normal-load phase; the sweep steps \
             that phase once for all of them, so block-steps/s stepped counts it once. Host \
             threads: CPU seconds per wall second by thread.\n"
        );
        println!(
            "| points | how | wall (s) | block-steps/s of the runs | block-steps/s stepped | \
             against one at a time | host threads |"
        );
        println!("| ---: | --- | ---: | ---: | ---: | ---: | --- |");
        let sweeps = counts_from_env(
            "SLIPFRONT_GPU_TABLE_SWEEPS",
            if quick { &[4] } else { &[64, 256] },
        );
        for &n in &sweeps {
            let sweep = table_s1_sweep(&dir, n);
            let model = Model::from_scenario(&sweep.points[0].scenario, false).expect("model");
            // Each point's run has its normal-load phase, but the sweep
            // steps that phase once for all (`share_loading`): block-steps
            // of the runs, and block-steps the device stepped.
            let block_steps = n as f64 * model.total_steps() as f64 * model.n_blocks() as f64;
            let stepped = (n as f64 * model.drive_steps as f64 + model.prep_steps as f64)
                * model.n_blocks() as f64;
            let ahead = GpuOptions::default().run_ahead;
            // Untimed first: it times the kernels on this ensemble and
            // caches the choice, which the timed sweeps then share.
            let _ = sweep_wall(&dir, &sweep, n, ahead);
            let together = sweep_wall(&dir, &sweep, n, ahead);
            // The same without running ahead: what the device's wait for
            // the runners costs.
            let waiting = sweep_wall(&dir, &sweep, n, 0);
            // One at a time only for the smaller sweep (64 points take
            // 75 s so on an H200).
            let alone = if n == sweeps[0] && n <= 64 {
                Some(sweep_wall(&dir, &sweep, 1, ahead))
            } else {
                None
            };
            for (how, wall) in [
                ("one ensemble", Some(&together)),
                ("one ensemble, not running ahead", Some(&waiting)),
                ("one at a time", alone.as_ref()),
            ] {
                match wall {
                    Some(Ok((w, threads))) => {
                        let against = match alone.as_ref() {
                            Some(Ok((a, _))) => format!("{:.1}×", a / w),
                            _ => String::new(),
                        };
                        println!(
                            "| {n} | {how} | {w:.1} | {:.3e} | {:.3e} | {against} | {threads} |",
                            block_steps / w,
                            stepped / w
                        );
                    }
                    Some(Err(e)) => println!("| {n} | {how} | not run: {e} | | | | |"),
                    None => {}
                }
            }
        }
    }
    if let Some(_timer) = sections.start(7) {
        // 7. What the junctions cost on Table S1.
        println!("\n## 7. What the junctions cost on Table S1\n");
        junction_cost(min_seconds);
    }
    if let Some(_timer) = sections.start(8) {
        // 8. What limits an ensemble.
        println!("\n## 8. What limits an ensemble of Table S1 scenes\n");
        ensemble_limits(quick, min_seconds);
    }
    if let Some(_timer) = sections.start(9) {
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
    let _ = std::fs::remove_dir_all(&dir);
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
