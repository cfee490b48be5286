// The lane sums of an interface block merged from storage (lane_partial,
// which the state slot declares): the persistent and tiled kernels write
// each lane's sum in one phase and merge them in the next. Where the
// workgroup merges lanes in subgroups (lane_shuffle.wgsl), its lanes wrote
// subtrees of 8 or more lanes, lane_subtree_stride apart, and only those
// are read and merged here: the same tree, its lower levels done.
// CPU twin: src/engines/kernels/junctions.rs merge_lanes.
// import: junctions, lane_merge, state

// Lane l of the block whose lanes start at `first`, or the zero sum past
// its last lane.
fn lane_partial_or_zero(first: u32, l: u32, lanes: u32) -> LaneSum {
    if l < lanes {
        return lane_partial[first + l];
    }
    return lane_sum_zero();
}

// The lane sums of one interface block, lanes first .. first + lanes of
// lane_partial, merged as the CPU twin's tree: eight subtrees of eight
// lanes. Each subtree's eight loads go out together ahead of its merges,
// and no merge waits on more than six before it.
fn merged_lane_partials(first: u32, lanes: u32) -> LaneSum {
    let k = lane_subtree_stride();
    if k >= 8u {
        // At most eight subtrees (JUNCTION_LANES / k), all loaded before
        // the first merge; past the block's lanes, the zero sum.
        return lane_tree8(
            lane_partial_or_zero(first, 0u, lanes),
            lane_partial_or_zero(first, k, lanes),
            lane_partial_or_zero(first, 2u * k, lanes),
            lane_partial_or_zero(first, 3u * k, lanes),
            lane_partial_or_zero(first, 4u * k, lanes),
            lane_partial_or_zero(first, 5u * k, lanes),
            lane_partial_or_zero(first, 6u * k, lanes),
            lane_partial_or_zero(first, 7u * k, lanes),
        );
    }
    var tree: LaneTree;
    var total = lane_sum_zero();
    for (var k = 0u; k < 8u; k++) {
        let l = 8u * k;
        total = lane_tree_add(&tree, k, lane_tree8(
            lane_partial_or_zero(first, l, lanes),
            lane_partial_or_zero(first, l + 1u, lanes),
            lane_partial_or_zero(first, l + 2u, lanes),
            lane_partial_or_zero(first, l + 3u, lanes),
            lane_partial_or_zero(first, l + 4u, lanes),
            lane_partial_or_zero(first, l + 5u, lanes),
            lane_partial_or_zero(first, l + 6u, lanes),
            lane_partial_or_zero(first, l + 7u, lanes),
        ));
    }
    // Leaf 7 completed the tree of the eight subtrees.
    return total;
}
