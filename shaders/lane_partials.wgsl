// The lane sums of an interface block merged from storage (lane_partial,
// which the state slot declares): the persistent and tiled kernels write
// each lane's sum in one phase and merge them in the next.
// CPU twin: src/engines/kernels/junctions.rs merge_lanes.
// import: junctions, state

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
