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
//!    and tiled kernels also with each junction lane and each update
//!    calling `junction_block` for its block, as before session 33
//!    (`GpuOptions::noted_junction_blocks`), and the tiled kernel with its
//!    rounds chained in one dispatch (`GpuOptions::chained_tiles`), and
//!    (both ways) with each round's halo sums made anew, as before session
//!    60 (`GpuOptions::published_halo_sums`); the persistent, resident and
//!    tiled kernels (chained too) on every scene also with their phase
//!    barriers at naga's device scope, as before session 62
//!    (`GpuOptions::workgroup_barriers`);
//! 8. what limits an ensemble: the single-workgroup kernels on one Table S1
//!    scene and on 132, 264 and 528 (one, two and four an SM of an H200 or
//!    an H100 SXM, 132 SMs), at 256 threads (and 1024 on the
//!    shipped scene), with Ns = 100 (as shipped), Ns = 16 and Coulomb
//!    friction in mixed f32, and as shipped in f64 (each launch also with
//!    one junction lane a round, which needs fewer registers in f64, so
//!    may fit more scenes an SM; as shipped in mixed f32 also with 4
//!    junction lanes a thread, `GpuOptions::lane_run`). Where the step doubles
//!    between the counts says how many scenes an SM holds at once; how much
//!    longer than one scene's it is where they share, against the
//!    junctions' share of the work and the precision, says whether they
//!    overlap or contend, and for what (docs/gpu-kernels.md, "What limits
//!    an ensemble"). SLIPFRONT_GPU_TABLE_LIMIT_SCENES=1,132,264 sets its
//!    scene counts;
//! 9. the tiled kernel with its rounds chained in one dispatch on Table S1
//!    by tile width (2 to 16 columns), halo (1, 2, 4) and threads (256,
//!    512, 1024), with the device's busy time a step: `auto` times
//!    chained tiles only at the width its unchained search found;
//! 10. the phase barriers of the persistent, resident and tiled kernels at
//!     workgroup scope (the default where the engine writes its own SPIR-V)
//!     against naga's device scope (`GpuOptions::workgroup_barriers`), each
//!     launch both ways in one run: Table S1 alone in mixed f32 and f64, and
//!     ensembles of 132 and 264 scenes (SLIPFRONT_GPU_TABLE_LAUNCHES: those
//!     launches instead);
//! 11. where a step's time goes on the device (`GpuOptions::phase_clocks`,
//!     on adapters with VK_KHR_shader_clock): each phase's cycles a
//!     workgroup-step (forces, updates, a tiled round's load, publication
//!     and wait, the dispatch's enter and leave), thread 0's own share, and
//!     what the marks cost the wall time, for the persistent, resident and
//!     tiled kernels on Table S1 alone (mixed f32, and f64 for persistent/1024
//!     and the chained tiles) and on 132 scenes
//!     (SLIPFRONT_GPU_TABLE_LAUNCHES: those launches instead);
//! 12. strict arithmetic (every operation NoContraction, where the engine
//!     writes its own SPIR-V: mixed f32's default) against wgpu's modules
//!     (mixed f32 with its fusion guards, f64 plain: f64's default)
//!     (`GpuOptions::arithmetic`), each launch both ways in one run: Table
//!     S1 alone, the one-step kernels included, three launches in f64 too,
//!     and ensembles of 132 and 264 scenes
//!     (SLIPFRONT_GPU_TABLE_LAUNCHES: those launches instead).
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

use gpu_timing::table_s1;
use slipfront::engines::gpu::context;

#[path = "../support/bench_scene.rs"]
mod bench_scene;
#[path = "../support/gpu_timing.rs"]
mod gpu_timing;
#[path = "../support/thread_cpu.rs"]
mod thread_cpu;

mod auto_choice;
mod both_ways;
mod common;
mod cpu;
mod ensembles;
mod junctions;
mod kernels;
mod limits;
mod output;
mod phases;
mod sections;
mod sweeps;
mod tiles;

use sections::Sections;

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
        best_gpu = kernels::against_size(sizes, min_seconds);
    }
    if let Some(_timer) = sections.start(2) {
        auto_choice::on_table_s1(&s1, &ctx, quick, min_seconds);
    }
    if let Some(_timer) = sections.start(3) {
        ensembles::of_table_s1(&s1, &ctx, quick, min_seconds);
    }
    if let Some(_timer) = sections.start(4) {
        output::cost(&dir, quick);
    }
    if let Some(_timer) = sections.start(5) {
        cpu::against_gpu(sizes, &best_gpu, min_seconds);
    }
    if let Some(_timer) = sections.start(6) {
        sweeps::table_s1_points(&dir, quick);
    }
    if let Some(_timer) = sections.start(7) {
        junctions::cost(min_seconds);
    }
    if let Some(_timer) = sections.start(8) {
        limits::ensemble_limits(quick, min_seconds);
    }
    if let Some(_timer) = sections.start(9) {
        tiles::chained_on_table_s1(quick, min_seconds);
    }
    if let Some(_timer) = sections.start(10) {
        both_ways::BARRIERS.compare(&ctx, quick, min_seconds);
    }
    if let Some(_timer) = sections.start(11) {
        phases::profile(&ctx, quick, min_seconds);
    }
    if let Some(_timer) = sections.start(12) {
        both_ways::ARITHMETIC.compare(&ctx, quick, min_seconds);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
