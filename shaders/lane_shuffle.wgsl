// A block's junction lanes merged in registers before they cross threads
// through storage (adapters with subgroup operations): each aligned run of
// 2^levels lane runs (junctions.wgsl lane_run: LANE_RUN lanes a thread,
// already merged) of one block, consecutive invocations of one subgroup,
// joins its sums by a butterfly of shuffles. Each level merges the
// lower run's sum on the left, as the CPU twin's tree does, so the run's
// every invocation ends with the run's subtree, in the tree's order; its
// first lane writes it, and lane_partials.wgsl merges the subtrees that
// are left (lane_subtree_stride apart). Fewer sums through storage on the
// merging thread's path: 2 a block on a subgroup of 32 where there were 64.
// lane_no_shuffle.wgsl is the same interface with no subgroup operation.
// CPU twin: src/engines/kernels/junctions.rs merge_lanes.
// import: junctions

// Levels of the lane tree this workgroup merges in subgroups, above the
// lane runs' own (log2 LANE_RUN): together 3 to 6, or 0 (every lane run
// writes its own sum). Set by lane_shuffle_enter and lane_shuffle_ready,
// the same in every invocation of the workgroup.
var<private> lane_levels: u32;

// 6 − the fewest levels any invocation allows (zero-initialised: 6 allowed).
var<workgroup> lane_levels_short: atomic<u32>;

// At the kernel's start, every invocation active, before a workgroup
// barrier: the levels this invocation's subgroup allows. The subgroup's
// size and this invocation's place in it are counted from the active
// invocations, so no subgroup built-in is declared by the entry point
// (the module without shuffles shares it). The butterfly needs a block's
// lanes on consecutive invocations in subgroup order: where invocation t
// is not at t mod size of its subgroup, or a run would cross a block
// (2^levels must divide the lane runs a block has), the workgroup merges
// none in subgroups. Under 8 lanes a subtree, the storage path's tree is
// kept.
fn lane_shuffle_enter(t: u32, lanes: u32) {
    let size = subgroupAdd(1u);
    let place = subgroupExclusiveAdd(1u);
    let in_order = subgroupAll(place == t % size);
    let by_subgroup = countTrailingZeros(size);
    let by_block = countTrailingZeros(max(lane_runs(lanes), 1u));
    let run_levels = countTrailingZeros(LANE_RUN);
    var levels = min(min(by_subgroup, by_block), 6u - run_levels);
    if !in_order || levels + run_levels < 3u || (size & (size - 1u)) != 0u {
        levels = 0u;
    }
    atomicMax(&lane_levels_short, 6u - levels);
}

// After that barrier: the workgroup's levels.
fn lane_shuffle_ready() {
    lane_levels = 6u - atomicLoad(&lane_levels_short);
    if lane_levels + countTrailingZeros(LANE_RUN) < 3u {
        lane_levels = 0u;
    }
}

// The levels of the lane tree merged before storage where subgroups
// merged any, the lane runs' own included (GpuStatus::lane_levels).
fn lane_levels_used() -> u32 {
    return select(0u, lane_levels + countTrailingZeros(LANE_RUN), lane_levels > 0u);
}

// Lanes apart of the subtrees a block leaves in storage (LANE_RUN: every
// lane run; a power of two, so a lane tests it with a mask, not a
// division).
fn lane_subtree_stride() -> u32 {
    return LANE_RUN << lane_levels;
}

// The lane run from lane `lane` of a block (a multiple of LANE_RUN): its
// sum, or its subgroup run's subtree where the workgroup merges in
// subgroups. Called by every lane run of a block together (the block's
// kept decision is the same for all of them), so the invocation a shuffle
// reads is active.
fn lane_subtree(sum: LaneSum, lane: u32) -> LaneSum {
    if lane_levels == 0u {
        return sum;
    }
    let run = lane >> countTrailingZeros(LANE_RUN);
    var s = lane_level(sum, run, 1u);
    if lane_levels > 1u {
        s = lane_level(s, run, 2u);
    }
    if lane_levels > 2u {
        s = lane_level(s, run, 4u);
    }
    if lane_levels > 3u {
        s = lane_level(s, run, 8u);
    }
    if lane_levels > 4u {
        s = lane_level(s, run, 16u);
    }
    if lane_levels > 5u {
        s = lane_level(s, run, 32u);
    }
    return s;
}

// One level: the run of `mask` lane runs holding this one (`lane`: its
// index among its block's lane runs) joined with its sibling, the lower
// run's sum on the left in both (select, not a branch: the two halves do
// one merge together). The maxima and the count are the same in either
// order.
fn lane_level(s: LaneSum, lane: u32, mask: u32) -> LaneSum {
    let o = LaneSum(
        subgroupShuffleXor(s.anchored, mask),
        subgroupShuffleXor(s.stiffness, mask),
        subgroupShuffleXor(s.stretch_max, mask),
        subgroupShuffleXor(s.stiffness_max, mask),
        subgroupShuffleXor(s.slipping, mask),
        0u,
    );
    let upper = (lane & mask) != 0u;
    let low = LaneSum(select(s.anchored, o.anchored, upper), select(s.stiffness, o.stiffness, upper), s.stretch_max, s.stiffness_max, s.slipping, 0u);
    let high = LaneSum(select(o.anchored, s.anchored, upper), select(o.stiffness, s.stiffness, upper), o.stretch_max, o.stiffness_max, o.slipping, 0u);
    return lane_sum_merge(low, high);
}

// x as the compiler may take it: the same on every invocation of the
// subgroup (its first active invocation's), kept in uniform registers.
// Exact where x is the same on the whole subgroup.
fn subgroup_uniform(x: u32) -> u32 {
    return subgroupBroadcastFirst(x);
}
