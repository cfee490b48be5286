//! The GPU launch flags `run` and `sweep` share (threads, tile shape,
//! run-ahead, run-time checks, patches, where the lanes merge, junction
//! lanes a round): one
//! declaration, so a new part of a launch gets its flag in both at once.

use slipfront::engines::gpu::tiles::TileShape;
use slipfront::engines::gpu::{GpuOptions, GpuOutput, GpuPath};

#[derive(clap::Args, Clone, Debug)]
pub struct GpuLaunchArgs {
    /// Threads of the persistent and resident kernels' workgroup
    /// (default: 256 persistent, 1024 resident; at most the adapter's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub gpu_threads: Option<u32>,
    /// The tiled kernel's tiles as WIDTHxHALO: columns each tile owns, and
    /// halo columns each side, the most steps a dispatch runs (default 8x4;
    /// `auto` on a hardware GPU searches a few shapes when this is not given).
    #[arg(long, value_name = "WIDTHxHALO", value_parser = TileShape::parse)]
    pub gpu_tile: Option<TileShape>,
    /// Batches the GPU may go on stepping while the samples it recorded
    /// are written (0: it waits for the output at every chunk; at most 64).
    #[arg(long, default_value_t = slipfront::engines::gpu::options::RUN_AHEAD_BATCHES,
          value_parser = run_ahead_batches)]
    pub gpu_run_ahead: usize,
    /// Let wgpu add its run-time checks to the GPU kernels (an index clamp
    /// at each fixed-size array access, a counter in every loop): the same
    /// results, slower; for checking a suspect kernel.
    #[arg(long)]
    pub gpu_shader_checks: bool,
    /// The GPU kernels compute the bulk forces by 2×2 patches of blocks,
    /// each bond inside a patch once: the same forces to their last bits,
    /// another split of the work (`auto` on a hardware GPU times both when
    /// this is not given).
    #[arg(long)]
    pub gpu_bond_patches: bool,
    /// Every junction lane's sum crosses threads through storage, none
    /// merged in subgroups first (persistent, resident and tiled kernels):
    /// the same tree of sums (`auto` on a hardware GPU times both when
    /// this is not given; its figures name such a launch
    /// `…/lanes-in-storage`).
    #[arg(long)]
    pub gpu_lanes_in_storage: bool,
    /// The persistent and resident kernels step one junction lane a round
    /// on a hardware GPU, not two: the same results, fewer registers a
    /// thread, longer chains of loads (`auto` on a hardware GPU times both
    /// when this is not given; its figures name such a launch
    /// `…/one-lane-a-round`; software adapters always step one).
    #[arg(long)]
    pub gpu_one_lane_a_round: bool,
    /// Junction lanes a thread steps in the persistent, resident and tiled
    /// kernels, 1, 2, 4 or 8: a thread works out its block's junction
    /// state once a run and merges the run's lane sums itself. The same
    /// results, fewer instructions, more registers a thread (`auto` on a
    /// hardware GPU times 4 beside 1 unless another run is given; its figures
    /// name such a launch `…/lane-run-4`).
    #[arg(long, value_name = "LANES", value_parser = slipfront::engines::gpu::options::lane_run)]
    pub gpu_lane_run: Option<u32>,
    /// The tiled kernel runs a batch's rounds (up to a halo's steps each)
    /// in one dispatch, each tile waiting for its neighbours' edges
    /// between them: the same results, fewer dispatches. It needs a
    /// scene's tiles on the GPU at once, and stops with an error where
    /// they are not (`auto` on a hardware GPU times both when this is not
    /// given; its figures name such a launch `tiled/…/chained`).
    #[arg(long)]
    pub gpu_chained_tiles: bool,
    /// Scenes the persistent kernel steps side by side in one workgroup
    /// (an ensemble or sweep; 1, 2 or 4), each on an equal share of its
    /// --gpu-threads: the same results; on GPUs that give a large
    /// workgroup fewer registers a thread, scenes share a multiprocessor
    /// (`auto` on a hardware GPU times 2 and 4 for an ensemble when this is
    /// not given; its figures name such a launch `persistent/1024/2-scenes`).
    #[arg(long, value_name = "SCENES", value_parser = slipfront::engines::gpu::options::group_scenes)]
    pub gpu_group_scenes: Option<u32>,
    /// How the kernels' arithmetic is compiled: `strict` forbids the
    /// driver to fuse or regroup any operation (each kernel then computes
    /// the CPU engine's operations as written: in f64 the CPU reference's
    /// numbers, to the bit where the GPU rounds division and square roots
    /// as IEEE does); `wgpu` leaves the modules as wgpu writes them;
    /// `leaner` (the default) is strict in mixed f32, where it costs fewer
    /// instructions, and wgpu's in f64, where strict costs more. Strict
    /// needs a Vulkan 1.3 adapter (elsewhere the run says it is not).
    #[arg(long, value_enum, default_value = "leaner")]
    pub gpu_arithmetic: slipfront::engines::gpu::Arithmetic,
}

impl Default for GpuLaunchArgs {
    /// The flags' defaults (none given).
    fn default() -> Self {
        GpuLaunchArgs {
            gpu_threads: None,
            gpu_tile: None,
            gpu_run_ahead: slipfront::engines::gpu::options::RUN_AHEAD_BATCHES,
            gpu_shader_checks: false,
            gpu_bond_patches: false,
            gpu_lanes_in_storage: false,
            gpu_one_lane_a_round: false,
            gpu_lane_run: None,
            gpu_chained_tiles: false,
            gpu_group_scenes: None,
            gpu_arithmetic: slipfront::engines::gpu::Arithmetic::Leaner,
        }
    }
}

impl GpuLaunchArgs {
    /// The engine's GPU options: these flags with the command's kernel
    /// and output.
    pub fn options(&self, path: GpuPath, output: GpuOutput) -> GpuOptions {
        GpuOptions {
            path,
            output,
            persistent_threads: self.gpu_threads,
            run_ahead: self.gpu_run_ahead,
            tile: self.gpu_tile,
            shader_checks: self.gpu_shader_checks,
            bond_patches: self.gpu_bond_patches,
            lane_shuffle: !self.gpu_lanes_in_storage,
            two_lanes_a_round: !self.gpu_one_lane_a_round,
            lane_run: self.gpu_lane_run.unwrap_or(1),
            chained_tiles: self.gpu_chained_tiles,
            group_scenes: self.gpu_group_scenes.unwrap_or(1),
            arithmetic: self.gpu_arithmetic,
            ..GpuOptions::default()
        }
    }
}

/// `--gpu-run-ahead`: a count of batches from 0 to
/// `MAX_RUN_AHEAD_BATCHES` (more would hold a long run's samples and
/// staging buffers back without bound).
pub fn run_ahead_batches(text: &str) -> Result<usize, String> {
    use slipfront::engines::gpu::options::{run_ahead_batches, MAX_RUN_AHEAD_BATCHES};
    match text.parse::<i64>() {
        Ok(n) => run_ahead_batches(n),
        Err(_) => Err(format!(
            "`{text}` is not a count of batches from 0 to {MAX_RUN_AHEAD_BATCHES}"
        )),
    }
}
