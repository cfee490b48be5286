// The lane sums of an interface block merged from storage (lane_partial,
// which the state slot declares): the persistent and tiled kernels write
// each lane's sum in one phase and merge them in the next. Where the
// workgroup merges lanes in subgroups (lane_shuffle.wgsl), its lanes wrote
// subtrees of 8 or more lanes, lane_subtree_stride apart, and only those
// are read and merged here: the same tree, its lower levels done.
// CPU twin: src/engines/kernels/junctions.rs merge_lanes.
// import: junctions, lane_merge, state

// The lane sums of one interface block, lanes first .. first + lanes of
// lane_partial, merged as the CPU twin's tree. Its subtrees (lanes, or
// runs merged in subgroups, lane_subtree_stride apart) are added to a
// tree of at most eight one at a time, two loaded together a round
// (merged_run), and the tree is closed over the subtrees there are, as if
// the missing ones were zero. Where no subgroup merged the lanes (64
// single lanes), runs of eight are merged first and each written over its
// first slot, then those merged: the same tree of 64, with three pending
// subtrees on the merging thread, not six. A register is allocated for
// the deepest tree the code allows, whether or not it runs, and six
// levels cost the single-workgroup kernels 8 VGPRs a thread
// (benches/gpu_registers.rs). Eight sums loaded at once had cost 64
// values (session 34). The maxima go beside the tree (lane_maxima).
fn merged_lane_partials(first: u32, lanes: u32) -> LaneSum {
    var stride = lane_subtree_stride();
    // A power of two: a shift, not a division on the merging thread's path.
    var count = (lanes + stride - 1u) >> countTrailingZeros(stride);
    // One pass where there are at most eight subtrees; else runs of eight,
    // each written over its first slot, and then a pass over those. One
    // copy of merged_run for every pass: llvmpipe steps a larger kernel
    // slower (BENCHMARKS.md, session 35).
    var total = lane_sum_zero();
    loop {
        let runs = (count + 7u) >> 3u;
        for (var r = 0u; r < runs; r++) {
            let at = first + r * 8u * stride;
            total = merged_run(at, stride, min(count - 8u * r, 8u));
            if runs > 1u {
                lane_partial[at] = total;
            }
        }
        if runs == 1u {
            break;
        }
        stride *= 8u;
        count = runs;
    }
    return total;
}

// The n (1 to 8) lane sums at first, first + stride, ... merged as the
// tree of eight, with their maxima.
fn merged_run(first: u32, stride: u32, n: u32) -> LaneSum {
    var tree: LaneTree8;
    var last = lane_sum_zero();
    var maxima = vec2<real>(0.0, 0.0);
    var i = 0u;
    for (; i + 1u < n; i += 2u) {
        let a = lane_partial[first + i * stride];
        let b = lane_partial[first + (i + 1u) * stride];
        maxima = max(maxima, max(lane_maxima(a), lane_maxima(b)));
        last = lane_tree8_add(&tree, i, lane_sum_unbounded(a));
        last = lane_tree8_add(&tree, i + 1u, lane_sum_unbounded(b));
    }
    if i < n {
        let a = lane_partial[first + i * stride];
        maxima = max(maxima, lane_maxima(a));
        last = lane_tree8_add(&tree, i, lane_sum_unbounded(a));
    }
    return lane_sum_bounded(lane_tree8_close(&tree, n, last), maxima);
}
