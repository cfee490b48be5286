// The lane sums of an interface block merged from storage (lane_partial,
// which the state slot declares): the persistent and tiled kernels write
// each lane's sum in one phase and merge them in the next. Where the
// workgroup merges lanes in subgroups (lane_shuffle.wgsl), its lanes wrote
// subtrees of 8 or more lanes, lane_subtree_stride apart, and only those
// are read and merged here: the same tree, its lower levels done.
// CPU twin: src/engines/kernels/junctions.rs merge_lanes.
// import: junctions, lane_merge, state

// The lane sums of one interface block, lanes first .. first + lanes of
// lane_partial, merged as the CPU twin's tree: its subtrees (lanes, or
// runs merged in subgroups, lane_subtree_stride apart) added to the tree
// one at a time (lane_tree_add), two loaded together a round, and the
// tree closed over the subtrees there are (lane_tree_close), as if the
// missing ones were zero. Two lane sums live at a time, not eight: eight
// held sixty-four values a thread through the merge, the kernel's most
// (benches/gpu_registers.rs), on a path that on NVIDIA loads two. Where a
// subgroup merges 32 lanes, a block's two subtrees take one round trip.
// The maxima go beside the tree (lane_maxima).
fn merged_lane_partials(first: u32, lanes: u32) -> LaneSum {
    let k = lane_subtree_stride();
    // k is a power of two: a shift, not a division on the merging thread's path.
    let n = (lanes + k - 1u) >> countTrailingZeros(k);
    var tree: LaneTree;
    var last = lane_sum_zero();
    var maxima = vec2<real>(0.0, 0.0);
    var i = 0u;
    for (; i + 1u < n; i += 2u) {
        let a = lane_partial[first + i * k];
        let b = lane_partial[first + (i + 1u) * k];
        maxima = max(maxima, max(lane_maxima(a), lane_maxima(b)));
        last = lane_tree_add(&tree, i, lane_sum_unbounded(a));
        last = lane_tree_add(&tree, i + 1u, lane_sum_unbounded(b));
    }
    if i < n {
        let a = lane_partial[first + i * k];
        maxima = max(maxima, lane_maxima(a));
        last = lane_tree_add(&tree, i, lane_sum_unbounded(a));
    }
    return lane_sum_bounded(lane_tree_close(&tree, n, last), maxima);
}
