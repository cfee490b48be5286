// One step n → n+1 of every block in one dispatch, junction lanes in
// parallel (hardware GPUs, many junctions): workgroup w < nx (junction
// laws) is interface block w, its threads are the junction lanes; every
// eighth thread merges eight lanes' sums, thread 0 merges those eight
// (the CPU twin's tree, lane_tree8) and updates the block. The block's
// bulk force is computed beside the lanes, by the last lane (the one with
// the fewest junctions, or none), not after the merges on thread 0's
// chain; the same function of the same state, so the same bits. The
// other workgroups update WORKGROUP blocks each, one per thread. The
// workgroup barrier makes llvmpipe run the whole shader as coroutines, so
// software adapters take one_step (serial lanes) instead. With junctions,
// the other workgroups start at block WORKGROUP·⌊nx/WORKGROUP⌋ (the
// interface blocks among them are the junction workgroups'). With
// BOND_PATCHES the other workgroups step the items of step_patches.wgsl
// from the same run of WORKGROUP (without junctions, from the first: the
// interface row a block a thread).
// The recording variant (STEP_RECORDS, the step dispatch of an output
// sample; record_step.wgsl) writes a partial of the sample per workgroup,
// where the sample may be due (its fast chain, which one thread reads
// while the lanes step, CHAIN_THREAD; the step's first barrier hands the
// decision to the workgroup): a junction workgroup's holds its block (thread 0 sums it,
// with the junction tally its lanes add: lane_tally), the others' their
// blocks or items.
// CPU twin: src/engines/cpu/mod.rs CpuEngine::one_step (force pass and update).
// import: bulk_forces, common, coordinates, junctions, record_batch, record_common, record_step, scene, state, step_forces, step_patches, verlet

var<workgroup> lane_sum: array<LaneSum, JUNCTION_LANES>;
// The interface block's bulk force, from the last lane to thread 0.
var<workgroup> interface_bulk: vec2<real>;
// A sample's junction tally (pinned junctions, their ruptures), added by
// the lanes side by side (integer sums: any order, the same counts) for
// thread 0, whose own walk through the block's Ns states was a chain of
// rounds of loads on the step's critical path.
var<workgroup> sample_tally: array<atomic<u32>, 2>;
// The thread that reads the fast chain in a sample's step: not thread 0,
// whose merge ends the step, nor the last lane, which computes the bulk
// force; a lane with the fewest junctions, or none.
const CHAIN_THREAD: u32 = JUNCTION_LANES - 2u;

// (pinned, ruptures) of the junctions of interface block i that lane
// `lane` holds (junctions lane, lane + JUNCTION_LANES, …), from their
// states in storage after the step's updates.
fn lane_tally(i: u32, lane: u32) -> vec2<u32> {
    let first = junction_first(i);
    var tally = vec2<u32>(0u);
    for (var j = lane; j < c.junction_count; j += JUNCTION_LANES) {
        let state = junction_state_at(first + j);
        tally += vec2<u32>(select(0u, 1u, state.x == PINNED), state.y);
    }
    return tally;
}

@compute @workgroup_size(WORKGROUP)
fn one_step_lanes(
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    enter_scene(wid.z);
    let w = wid.x + wid.y * groups.x;
    let i_step = step_offset;
    let ld = loads_at(i_step);
    let ready = batch.forces_ready != 0u && i_step == 0u;
    let update = batch.forces_only == 0u;
    let lanes = min(JUNCTION_LANES, c.junction_count);
    let junction_group = FRICTION_LAW == LAW_JUNCTIONS && w < c.nx;
    // A kept block's lane sums are not merged: not made. Slots past the
    // last lane hold the zero sum.
    var kept = true;
    // Thread 0 keeps its block's jb (as lane 0) for the merge after the
    // barrier: the lanes' updates cannot change it (junction 0's re-pin
    // anchors at u_x, the reference it had while slipping).
    var jb: JunctionBlock;
    if STEP_RECORDS && junction_group && local == 0u {
        atomicStore(&sample_tally[0], 0u);
        atomicStore(&sample_tally[1], 0u);
    }
    if STEP_RECORDS && local == CHAIN_THREAD {
        wg_sample_computed = select(0u, 1u, fast_chain_due(step_sample(), w == 0u));
    }
    if junction_group && !ready && local < JUNCTION_LANES {
        // The lane's first pair is loaded beside the junction block, not
        // once the block is known to be summed: two round trips to storage
        // on the lanes' path before the first update where there were three
        // (u and junction 0, then the kept sums, then the pair), for loads a kept
        // block's lanes make for nothing (its junctions' states and
        // springs, 2 KB a block and step at Ns = 100 in mixed f32).
        // The same values: lane_pair clamps a lane past the last junction
        // to the last.
        let first_pair = lane_pair(w, local);
        jb = junction_block(w, ld);
        kept = jb.kept;
        if !kept {
            var sum = lane_sum_zero();
            if local < lanes {
                sum = lane_from(w, local, jb, ld, first_pair);
            }
            lane_sum[local] = sum;
        }
        if local == JUNCTION_LANES - 1u {
            interface_bulk = bulk_force(w, w, 0u, ld);
        }
    }
    // Outside the branch: every workgroup reaches it (an ensemble scene's
    // constants are not uniform to the uniformity analysis). In the
    // recording variant the barrier is the load of thread 0's decision,
    // uniform from here on. A sample's junction tally (the lanes, below)
    // reads from storage only the states each lane has just written itself:
    // no storage barrier.
    var computed = false;
    if STEP_RECORDS {
        computed = workgroupUniformLoad(&wg_sample_computed) != 0u;
    } else {
        workgroupBarrier();
    }
    if computed && junction_group && local < JUNCTION_LANES {
        let tally = lane_tally(w, local);
        atomicAdd(&sample_tally[0], tally.x);
        atomicAdd(&sample_tally[1], tally.y);
    }
    if !kept && local % 8u == 0u {
        let l = local;
        lane_sum[l] = lane_tree8(
            lane_sum[l],
            lane_sum[l + 1u],
            lane_sum[l + 2u],
            lane_sum[l + 3u],
            lane_sum[l + 4u],
            lane_sum[l + 5u],
            lane_sum[l + 6u],
            lane_sum[l + 7u],
        );
    }
    workgroupBarrier();
    var part = no_sums();
    if junction_group {
        if local == 0u {
            var f: vec2<real>;
            var friction: real = 0.0;
            if ready {
                f = force[block_base() + w];
                friction = contact[interface_base() + w].x;
            } else {
                f = interface_bulk;
                var lane_sums: LaneSum;
                if jb.kept {
                    lane_sums = kept_lane_sum(jb);
                } else {
                    lane_sums = lane_tree8(lane_sum[0], lane_sum[8], lane_sum[16], lane_sum[24], lane_sum[32], lane_sum[40], lane_sum[48], lane_sum[56]);
                }
                friction = junction_friction(w, jb, lane_sums, f.x);
                force[block_base() + w] = f;
                contact[interface_base() + w] = vec2<real>(friction, foundation_normal(coord_value(load_disp(w).z)));
            }
            if computed {
                let tally = vec2<u32>(atomicLoad(&sample_tally[0]), atomicLoad(&sample_tally[1]));
                part = step_block_sample_tallied(w, step_sample(), f, friction, tally);
            }
            if update {
                verlet(w, w, 0u, f, friction, ld, i_step);
            }
        }
    }
    // The bulk workgroups: partial g's blocks (with patches, its items),
    // less the interface's.
    var g = w;
    if FRICTION_LAW == LAW_JUNCTIONS {
        g = c.nx / WORKGROUP + (w - c.nx);
    }
    let i = g * WORKGROUP + local;
    let not_interface = FRICTION_LAW != LAW_JUNCTIONS || i >= c.nx;
    if BOND_PATCHES {
        if !junction_group && not_interface {
            part = step_by_patches(i, computed);
        }
    } else if !junction_group && i < c.n_blocks && not_interface {
        let ff = block_forces(i, ld, ready);
        if computed {
            part = step_block_sample(i, step_sample(), ff.xy, ff.z);
        }
        if update {
            verlet(i, i % c.nx, i / c.nx, ff.xy, ff.z, ld, i_step);
        }
    }
    // Workgroup w's partial (the host counts every workgroup's).
    if STEP_RECORDS {
        if computed {
            let whole = junction_group || items_add_more_than_kinetic(g * WORKGROUP, BOND_PATCHES);
            write_step_partial(local, w, step_sample(), part, whole);
        } else {
            mark_step_skipped(local, w, step_sample());
        }
    }
}
