// lane_shuffle.wgsl's interface without subgroup operations (adapters
// without them, and GpuOptions::lane_shuffle false): every lane run
// (junctions.wgsl lane_run; a lane where LANE_RUN is 1) writes its own
// sum, and lane_partials.wgsl merges all of a block's runs.
// CPU twin: src/engines/kernels/junctions.rs merge_lanes.
// import: junctions

fn lane_shuffle_enter(t: u32, lanes: u32) {}

fn lane_shuffle_ready() {}

fn lane_levels_used() -> u32 {
    return 0u;
}

fn lane_subtree_stride() -> u32 {
    return LANE_RUN;
}

fn lane_subtree(sum: LaneSum, lane: u32) -> LaneSum {
    return sum;
}

fn subgroup_uniform(x: u32) -> u32 {
    return x;
}
