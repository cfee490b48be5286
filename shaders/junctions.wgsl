// Junction friction: the Ns micro-junctions of each interface block pin,
// break at mu_s f_N, slip at mu_d f_N for a drawn time and re-pin. A
// slipping junction counts its slip steps down (no global step count).
// Lane l of block ix handles junctions l, l + JUNCTION_LANES, ...: it sums
// the pinned junctions' forces and counts the slipping ones (a LaneSum);
// the caller merges the lane sums as a tree (lane_tree8) and junction_friction adds
// the slipping junctions' force, which can hold the block at rest.
// CPU twin: src/engines/kernels/junctions.rs junction_lane, junction_friction.
// import: common, coordinates, junction_store, rng, scene, state

fn junction_stiffness(f_n: real) -> real {
    if c.stiffness_normal_load != 0u {
        return sqrt(c.junction_stiffness_value * f_n);
    }
    return c.junction_stiffness_value;
}

// What every junction of interface block ix needs this step: u_x, the
// reference r of the pinned sums (junction_reference), the normal force
// per junction, the break threshold and one slipping junction's force
// mu_d f_N.
//
// `kept`: the block's junctions are all pinned and none can break this
// step, so none changes, and its sums are those of junction_cache: the
// lanes skip it (no junction is loaded) and junction_friction takes the
// kept sums. `keeps`: junction_friction stores the sums it made.
struct JunctionBlock {
    ux: coord,
    reference: coord,
    f_n: real,
    threshold: real,
    slipping_force: real,
    kept: bool,
    keeps: bool,
    sums: JunctionCache,
}

// How far under the threshold the kept bound must stay: it covers the
// rounding of the bound and of each junction's force (a few ulps).
const KEPT_MARGIN: real = 1.0 + 1.0 / 65536.0;

// GpuOptions::keep_junction_sums: false sums every junction every step.
override KEEP_JUNCTION_SUMS: bool = true;

// GpuOptions::count_summed_junction_blocks: junction_friction counts the
// blocks whose lanes summed their junctions (GpuStatus::summed_junction_blocks),
// one atomic each; off, the count is compiled out.
override COUNT_SUMMED_BLOCKS: bool = false;

fn junction_block(ix: u32, ld: Loads) -> JunctionBlock {
    let u = load_disp_at(ix, ix, 0u);
    let f_n = foundation_normal(coord_value(u.z)) / real(c.junction_count);
    let threshold = c.mu_s * f_n;
    let keeps = KEEP_JUNCTION_SUMS && !ld.preparing;
    // Junction 0 is loaded with the kept sums, not after them: a block
    // that must be summed then waits one round trip for both.
    let first = junction_first(ix);
    let state0 = junction_state_at(first);
    let spring0 = junction_spring_at(first);
    var sums = JunctionCache();
    var kept = false;
    if keeps && f_n > 0.0 {
        sums = junction_cache[junction_sums_slot(ix)];
        // |k_j (u_x - a_j)| <= k_max |u_x - r| + max |k_j (a_j - r)|.
        let reach = sums.stiffness_max * abs(coord_diff(u.x, sums.reference)) + sums.stretch_max;
        kept = sums.stiffness_max > 0.0 && reach * KEPT_MARGIN <= threshold;
    }
    var reference = sums.reference;
    if !kept {
        reference = junction_reference(u.x, threshold, ld, state0, spring0);
    }
    return JunctionBlock(u.x, reference, f_n, threshold, c.mu_d * f_n, kept, keeps, sums);
}

// The coordinate r the block's pinned forces are summed about this step:
// junction 0's anchor if it is pinned after the step (pinned now and not
// breaking), else u_x. A pure function of the state, so sums kept from an
// earlier step of an unchanged block have the bits of sums made anew.
fn junction_reference(ux: coord, threshold: real, ld: Loads, state: vec2<u32>, spring: JunctionSpring) -> coord {
    if state.x != PINNED {
        return ux;
    }
    let f = -spring.stiffness * coord_diff(ux, coord_unpack(spring.anchor));
    if !ld.preparing && abs(f) > threshold {
        return ux;
    }
    return coord_unpack(spring.anchor);
}

fn lane_sum_zero() -> LaneSum {
    return LaneSum(force_sum_zero(), force_sum_zero(), 0.0, 0.0, 0u, 0u);
}

// Eight lane sums, or eight subtrees, merged as a complete binary tree.
// A block's 64 lane slots merge as eight subtrees of eight lanes, absent
// lanes (past the junction count) as the zero sum, which a merge leaves
// as it is: six merges deep, where a running sum was sixty-four (CPU twin:
// kernels/junctions.rs merge_lanes).
fn lane_tree8(a0: LaneSum, a1: LaneSum, a2: LaneSum, a3: LaneSum, a4: LaneSum, a5: LaneSum, a6: LaneSum, a7: LaneSum) -> LaneSum {
    let low = lane_sum_merge(lane_sum_merge(a0, a1), lane_sum_merge(a2, a3));
    let high = lane_sum_merge(lane_sum_merge(a4, a5), lane_sum_merge(a6, a7));
    return lane_sum_merge(low, high);
}

// The same tree built one leaf at a time, leaves 0, 1, 2, ... in order
// (a binary counter: l_n holds the finished subtree of 2^n leaves that
// waits for its right sibling). No array, so no private memory indexed at
// run time, which llvmpipe keeps in memory rather than registers.
struct LaneTree {
    l0: LaneSum,
    l1: LaneSum,
    l2: LaneSum,
    l3: LaneSum,
    l4: LaneSum,
    l5: LaneSum,
}

// Adds leaf k; returns the subtree that leaf completes: after leaf 2^n − 1,
// the tree of the first 2^n leaves (leaf 63: all 64 lanes).
fn lane_tree_add(t: ptr<function, LaneTree>, k: u32, leaf: LaneSum) -> LaneSum {
    var s = leaf;
    if (k & 1u) == 0u {
        (*t).l0 = s;
        return s;
    }
    s = lane_sum_merge((*t).l0, s);
    if (k & 2u) == 0u {
        (*t).l1 = s;
        return s;
    }
    s = lane_sum_merge((*t).l1, s);
    if (k & 4u) == 0u {
        (*t).l2 = s;
        return s;
    }
    s = lane_sum_merge((*t).l2, s);
    if (k & 8u) == 0u {
        (*t).l3 = s;
        return s;
    }
    s = lane_sum_merge((*t).l3, s);
    if (k & 16u) == 0u {
        (*t).l4 = s;
        return s;
    }
    s = lane_sum_merge((*t).l4, s);
    if (k & 32u) == 0u {
        (*t).l5 = s;
        return s;
    }
    return lane_sum_merge((*t).l5, s);
}

// The tree of at most eight leaves, built one leaf at a time as
// lane_tree_add builds its first three levels: what a thread holds while
// it merges lane partials from storage (lane_partials.wgsl), three
// pending subtrees where the tree of 64 holds six. Not the tree of 64
// rebuilt from two of these: the same merges, but llvmpipe then compiles
// the one-step kernel to other bits at a rounding tie (session 35).
struct LaneTree8 {
    l0: LaneSum,
    l1: LaneSum,
    l2: LaneSum,
}

// Adds leaf k (k < 8); returns the subtree that leaf completes.
fn lane_tree8_add(t: ptr<function, LaneTree8>, k: u32, leaf: LaneSum) -> LaneSum {
    var s = leaf;
    if (k & 1u) == 0u {
        (*t).l0 = s;
        return s;
    }
    s = lane_sum_merge((*t).l0, s);
    if (k & 2u) == 0u {
        (*t).l1 = s;
        return s;
    }
    s = lane_sum_merge((*t).l1, s);
    if (k & 4u) == 0u {
        (*t).l2 = s;
        return s;
    }
    return lane_sum_merge((*t).l2, s);
}

// The whole tree of the n leaves added (1 ≤ n ≤ 8; `last`: what the last
// lane_tree8_add returned), as the complete tree of eight with the
// missing leaves zero, which a merge leaves as they are: the subtrees
// still waiting for a sibling, merged from the lowest up, each on the left.
fn lane_tree8_close(t: ptr<function, LaneTree8>, n: u32, last: LaneSum) -> LaneSum {
    var total = last;
    let low = countTrailingZeros(n);
    if low < 1u && (n & 2u) != 0u {
        total = lane_sum_merge((*t).l1, total);
    }
    if low < 2u && (n & 4u) != 0u {
        total = lane_sum_merge((*t).l2, total);
    }
    return total;
}

// A lane sum's two maxima (stretch, stiffness) are the same in whatever
// order they are taken, so a tree of lane sums carries them beside it as
// one running max (lane_maxima), its levels holding the sums alone
// (lane_sum_unbounded): in every level they cost the junction kernels 16
// registers a thread (benches/gpu_registers.rs). The same bits.
fn lane_maxima(a: LaneSum) -> vec2<real> {
    return vec2<real>(a.stretch_max, a.stiffness_max);
}

// The sums and the count of a, its maxima zero (what a tree level holds).
fn lane_sum_unbounded(a: LaneSum) -> LaneSum {
    return LaneSum(a.anchored, a.stiffness, 0.0, 0.0, a.slipping, 0u);
}

// A tree's sums with the maxima taken beside it.
fn lane_sum_bounded(a: LaneSum, maxima: vec2<real>) -> LaneSum {
    return LaneSum(a.anchored, a.stiffness, maxima.x, maxima.y, a.slipping, 0u);
}

fn lane_sum_merge(a: LaneSum, b: LaneSum) -> LaneSum {
    return LaneSum(
        force_sum_merge(a.anchored, b.anchored),
        force_sum_merge(a.stiffness, b.stiffness),
        max(a.stretch_max, b.stretch_max),
        max(a.stiffness_max, b.stiffness_max),
        a.slipping + b.slipping,
        0u,
    );
}

// A junction pinned after the step, its stiffness k_j and its term
// k_j (a_j - r), added to a lane's sums.
fn lane_sum_add(a: LaneSum, stiffness: real, term: real) -> LaneSum {
    return LaneSum(
        force_sum_add(a.anchored, term),
        force_sum_add(a.stiffness, stiffness),
        max(a.stretch_max, abs(term)),
        max(a.stiffness_max, stiffness),
        a.slipping,
        0u,
    );
}

// The pinned junctions' force on the block: sum k_j (a_j - r) minus
// (sum k_j)(u_x - r). Where r is u_x, the term by term sum.
fn pinned_friction(jb: JunctionBlock, total: LaneSum) -> real {
    let moved = force_sum_value(total.stiffness) * coord_diff(jb.ux, jb.reference);
    return force_sum_value(force_sum_add(total.anchored, -moved));
}

// What a kept block's friction is made from, in place of its merged lane
// sums: its kept sums. Taken before a block's lane sums would be merged,
// and only for a kept block, so the kept sums are not held through the
// merge of a block that is summed (a thread's registers: benches/gpu_registers.rs).
fn kept_lane_sum(jb: JunctionBlock) -> LaneSum {
    return LaneSum(jb.sums.anchored, force_sum_add(force_sum_zero(), jb.sums.stiffness), 0.0, 0.0, 0u, 0u);
}

// The friction on interface block ix from its merged lane sums (a kept
// block's: kept_lane_sum), its other
// force along x and its velocity v(n-1/2): the pinned junctions' force plus
// the slipping junctions' n mu_d f_N, which under the at-rest rule `hold`
// (c.law0 != 0) stops the block this step when that bound allows, and
// under `sign` pushes against v (the thesis's rule).
fn junction_friction(ix: u32, jb: JunctionBlock, lanes: LaneSum, other: real) -> real {
    let total = lanes;
    if COUNT_SUMMED_BLOCKS && !jb.kept {
        atomicAdd(&status[status_base() + STATUS_SUMMED_JUNCTION_BLOCKS], 1u);
    }
    if !jb.kept && jb.keeps {
        // Kept only while every junction is pinned (stiffness_max 0: empty).
        let k_max = select(0.0, total.stiffness_max, total.slipping == 0u);
        let sums = JunctionCache(total.anchored, jb.reference, force_sum_value(total.stiffness), total.stretch_max, k_max, 0.0);
        junction_cache[junction_sums_slot(ix)] = sums;
    }
    let pinned = pinned_friction(jb, total);
    if total.slipping == 0u {
        return pinned;
    }
    let capacity = real(total.slipping) * jb.slipping_force;
    let vx = load_vel_at(ix, ix, 0u).x;
    if c.law0 != 0.0 {
        // The friction that brings the block to rest this step.
        let stop = -(other + pinned) - c.mass * vx / c.dt;
        return pinned + min(max(stop, -capacity), capacity);
    }
    return pinned + -capacity * sign(vx);
}

// The lane's sum is a force_sum: compensated in mixed precision, since an
// f32 running sum of a block's alike junction forces rounded the friction
// coherently across the interface (CPU twin's doc says more).
// A junction's spring is loaded with its state, not after it, and a lane's
// junctions two at a time (junctions j and j + JUNCTION_LANES, both loaded
// before either is used): each pair costs one round trip to storage on the
// lane's path, not four. The persistent kernels load two lanes' first
// pairs at once (lane_pair, lane_from). A slipping junction's spring is
// then loaded for nothing; between events nearly every junction is pinned.
// Spring and state are written back only where they changed, so a step
// between events writes none of them (the same bits, less storage traffic).
fn junction_lane(ix: u32, lane: u32, jb: JunctionBlock, ld: Loads) -> LaneSum {
    if jb.kept {
        return lane_sum_zero();
    }
    return lane_from(ix, lane, jb, ld, lane_pair(ix, lane));
}

// Consecutive junction lanes a thread steps in the persistent, resident
// and tiled kernels (1, 2, 4 or 8; GpuOptions::lane_run): where a thread
// steps a lane run, it works out its block's JunctionBlock once for the
// run, not once a lane, and merges the run's lane sums itself as the lane
// tree's lowest levels, so fewer levels are left to subgroup shuffles or
// storage. The same lanes by the same tree: the same bits.
override LANE_RUN: u32 = 1u;

// Lane runs of a block with `lanes` lanes.
fn lane_runs(lanes: u32) -> u32 {
    return (lanes + LANE_RUN - 1u) / LANE_RUN;
}

// A lane run loads its next lane's first pair before it steps this one
// (the persistent and resident kernels unless one lane a round is asked,
// GpuOptions::two_lanes_a_round): the round trip to storage off the
// thread's path, for the pair's registers (on AMD's compiler 8 a thread
// more at Table S1, BENCHMARKS.md session 57). false (the tiled kernel):
// each lane loads its own as it starts.
override LANE_RUN_AHEAD: bool = false;

// Lanes first .. first + LANE_RUN of block ix (first a multiple of
// LANE_RUN), each stepped as junction_lane steps it, merged as the subtree
// of the lane tree they make (lanes past the block's last make the zero
// sum).
fn lane_run(ix: u32, first: u32, jb: JunctionBlock, ld: Loads) -> LaneSum {
    if LANE_RUN == 1u || jb.kept {
        return junction_lane(ix, first, jb, ld);
    }
    var tree: LaneTree8;
    var last = lane_sum_zero();
    var maxima = vec2<real>(0.0, 0.0);
    var pair = lane_pair(ix, first);
    for (var q = 0u; q < LANE_RUN; q++) {
        var sum: LaneSum;
        if LANE_RUN_AHEAD {
            let next = lane_pair(ix, first + min(q + 1u, LANE_RUN - 1u));
            sum = lane_from(ix, first + q, jb, ld, pair);
            pair = next;
        } else {
            sum = lane_from(ix, first + q, jb, ld, lane_pair(ix, first + q));
        }
        maxima = max(maxima, lane_maxima(sum));
        last = lane_tree8_add(&tree, q, lane_sum_unbounded(sum));
    }
    return lane_sum_bounded(last, maxima);
}

// Two junctions of a lane (j and j + JUNCTION_LANES) as loaded, so that
// both loads go out before either is used, and the kernels can send two
// lanes' first pairs out together. A junction past the block's last is
// loaded as the last (in bounds) and not used.
struct LanePair {
    state_a: vec2<u32>,
    spring_a: JunctionSpring,
    state_b: vec2<u32>,
    spring_b: JunctionSpring,
}

// Block ix's pair for lane j, or nothing loaded where its sums are kept.
fn lane_pair_of(ix: u32, j: u32, jb: JunctionBlock) -> LanePair {
    if jb.kept {
        let none = JunctionSpring(coord_pack(jb.ux), 0.0);
        return LanePair(vec2<u32>(PINNED, 0u), none, vec2<u32>(PINNED, 0u), none);
    }
    return lane_pair(ix, j);
}

fn lane_pair(ix: u32, j: u32) -> LanePair {
    let first = junction_first(ix);
    let last = first + max(c.junction_count, 1u) - 1u;
    let a = min(first + j, last);
    let b = min(first + j + JUNCTION_LANES, last);
    return LanePair(junction_state_at(a), junction_spring_at(a), junction_state_at(b), junction_spring_at(b));
}

// The lane's sum, its first pair from `loaded` and each later pair loaded
// as it starts. One call of junction_update in one loop: llvmpipe counts
// every loop iteration of every inlined copy against its limit
// (options::persistent_steps_per_dispatch), and the f64 draws loop.
fn lane_from(ix: u32, lane: u32, jb: JunctionBlock, ld: Loads, loaded: LanePair) -> LaneSum {
    var total = lane_sum_zero();
    if jb.kept {
        return total;
    }
    let first = junction_first(ix);
    var pair = loaded;
    var second = false;
    for (var j = lane; j < c.junction_count; j += JUNCTION_LANES) {
        if !second && j != lane {
            pair = lane_pair(ix, j);
        }
        var state = pair.state_a;
        var spring = pair.spring_a;
        if second {
            state = pair.state_b;
            spring = pair.spring_b;
        }
        total = junction_update(ix, j, first + j, state, spring, jb, ld, total);
        second = !second;
    }
    return total;
}

// Junction j of block ix (at idx) by one step from its loaded state and
// spring, added to the lane's sum `total`.
fn junction_update(
    ix: u32,
    j: u32,
    idx: u32,
    loaded_state: vec2<u32>,
    loaded_spring: JunctionSpring,
    jb: JunctionBlock,
    ld: Loads,
    sum: LaneSum,
) -> LaneSum {
    let f_n = jb.f_n;
    let threshold = jb.threshold;
    var total = sum;
    var state = loaded_state;
    var spring = loaded_spring;
    let was_slipping = state.x != PINNED;
    var spring_changed = false;
    if was_slipping {
        // A lifted block (f_N = 0) keeps its junctions waiting at 0.
        state.x = max(state.x, 1u) - 1u;
        if state.x == 0u && f_n > 0.0 {
            spring = JunctionSpring(coord_pack(jb.ux), junction_stiffness(f_n));
            spring_changed = true;
            state.x = PINNED;
        }
    }
    var pinned = state.x == PINNED;
    var broke = false;
    if pinned {
        if ld.preparing {
            // While the normal load is applied, attachment is continuous.
            spring.stiffness = junction_stiffness(f_n);
            spring_changed = true;
        }
        let f = -spring.stiffness * coord_diff(jb.ux, coord_unpack(spring.anchor));
        if !ld.preparing && abs(f) > threshold {
            let count = state.y + 1u;
            state.y = count;
            let n = slip_steps(c.seed, ix, j, count, c.slip_mean_steps, c.slip_std_steps);
            // PINNED - 1 at most: a countdown never reads as pinned.
            state.x = min(n, PINNED - 1u);
            pinned = false;
            broke = true;
        } else {
            total = lane_sum_add(total, spring.stiffness, spring.stiffness * coord_diff(coord_unpack(spring.anchor), jb.reference));
        }
    }
    if !pinned {
        total.slipping += 1u;
    }
    if spring_changed {
        set_junction_spring(idx, spring);
    }
    if was_slipping || broke {
        set_junction_state(idx, state);
    }
    return total;
}
