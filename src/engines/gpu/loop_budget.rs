//! llvmpipe's loop budget: a software adapter (lavapipe) silently ends a
//! shader's loops after 65,535 iterations an invocation in all, so the
//! kernels that loop over many steps in one dispatch (persistent,
//! resident, tiled) size their dispatches by the iterations they count
//! here. Below `options` and `tiles`, which both count with it.

/// Loop iterations a software adapter may run in one dispatch per
/// invocation: half of llvmpipe's limit.
pub const SOFTWARE_LOOP_BUDGET: usize = 32_768;

/// The loop iterations (llvmpipe counts them: `persistent_steps_per_dispatch`)
/// that the busiest of `threads` invocations runs a step in a walk over the
/// junction lanes of `blocks` interface blocks with `lanes` lanes and `ns`
/// junctions each, `lane_run` lanes an item: an item's pass, and in a lane
/// run a pass a lane, plus each lane's junctions.
pub fn lane_loop_iterations(
    blocks: usize,
    lanes: usize,
    ns: usize,
    threads: usize,
    lane_run: u32,
) -> usize {
    let run = lane_run.max(1) as usize;
    let items = (blocks * lanes.div_ceil(run)).div_ceil(threads.max(1));
    let per_lane = ns.div_ceil(lanes.max(1));
    if run == 1 {
        items * (1 + per_lane)
    } else {
        items * (1 + run * (1 + per_lane))
    }
}
