// The lane sums of an interface block merged from storage (lane_partial,
// which the state slot declares): the persistent and tiled kernels write
// each lane's sum in one phase and merge them in the next.
// CPU twin: src/engines/kernels/junctions.rs junction_friction (its lane sums merged in lane order).
// import: junctions, state

// The lane sums of one interface block, lanes first .. first + lanes of
// lane_partial, merged in lane order (the CPU twin's order). The loads go
// out eight at a time ahead of their merges: this thread's chain of
// storage round trips, one per lane, was the step's critical path.
fn merged_lane_partials(first: u32, lanes: u32) -> LaneSum {
    var total = lane_sum_zero();
    var l = 0u;
    for (; l + 8u <= lanes; l += 8u) {
        let p0 = lane_partial[first + l];
        let p1 = lane_partial[first + l + 1u];
        let p2 = lane_partial[first + l + 2u];
        let p3 = lane_partial[first + l + 3u];
        let p4 = lane_partial[first + l + 4u];
        let p5 = lane_partial[first + l + 5u];
        let p6 = lane_partial[first + l + 6u];
        let p7 = lane_partial[first + l + 7u];
        total = lane_sum_merge(lane_sum_merge(lane_sum_merge(lane_sum_merge(total, p0), p1), p2), p3);
        total = lane_sum_merge(lane_sum_merge(lane_sum_merge(lane_sum_merge(total, p4), p5), p6), p7);
    }
    for (; l < lanes; l++) {
        total = lane_sum_merge(total, lane_partial[first + l]);
    }
    return total;
}
