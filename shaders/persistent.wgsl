// batch.steps_per_dispatch steps of the whole lattice in one dispatch of
// one workgroup per scene (small lattices): dispatch d of a batch (its step offset)
// runs steps d·K .. (d+1)·K. Each step computes the forces and junction lanes,
// then (after a barrier) adds the lane sums and updates every block in
// place, then waits at a barrier again. The thread that updates block ix
// is the one that adds its lane sums, so no third barrier is needed.
// Same phase functions, in the same order, as the one-step kernel.
// Where u and v live during the dispatch is the state slot's: storage
// (state_persistent.wgsl), or workgroup memory, loaded at the dispatch's
// start and written back at its end (state_resident.wgsl: the resident
// kernel, for lattices that fit). Both run this same loop.
// CPU twin: src/engines/cpu/mod.rs CpuEngine::one_step (one step of its loop).
// import: bulk_forces, bulk_patch, common, coordinates, friction_law, junctions, lane_merge, noted_blocks, lane_partials, phase_clocks, record_buffers, record_common, scene, state, verlet

// With an output file, the samples of the batch (batch.records of them,
// in step order; src/engines/gpu/recorder.rs): a sample of step s is recorded in
// step s's update phase, from the state before the update
// (record_common.wgsl), then reduced across the workgroup.
// SCENE_THREADS is then a power of two (reduce_threads).
@group(0) @binding(16) var<storage, read> record_entries: array<RecordEntry>;

// Threads of the workgroup: GROUP_SCENES scenes of SCENE_THREADS each.
override PERSISTENT_THREADS: u32 = 256u;
// Scenes a workgroup steps, side by side (1, 2 or 4; the persistent kernel
// only: the resident one holds its scene in workgroup memory), each on its
// own SCENE_THREADS threads. On NVIDIA a 1024-thread workgroup is held to
// 64 registers a thread, the only way to have two scenes' threads share a
// multiprocessor where a smaller workgroup takes more registers.
override GROUP_SCENES: u32 = 1u;
override SCENE_THREADS: u32 = 256u;
// Junction lanes two at a time in phase 1 (hardware; see there).
override TWO_LANES_A_ROUND: bool = true;
// Software adapters: check llvmpipe's loop budget at the dispatch's end
// (loop_budget_left). Off on hardware, which has no such budget, where the
// probe cost the f64 one-lane persistent/256 launch 16 VGPRs on RADV.
override LOOP_PROBE: bool = false;

// Bulk forces by 2×2 patches of blocks, each inner bond computed once
// (bulk_patch.wgsl; GpuOptions::bond_patches): the same bits, fewer
// bonds and loads a block, a quarter of the threads busy.
override BOND_PATCHES: bool = false;

// Per member scene (GROUP_SCENES ≤ 4): stopped (a blow-up, or no scene:
// past the ensemble's last), and its sample's state at this step.
var<workgroup> stop: vec4<u32>;
// First and end step of this dispatch, samples in the batch, the first
// sample at or after the first step: the same for every scene (the host's
// batches differ only in their scene's loads, submit_batch).
var<workgroup> span: vec4<u32>;
var<workgroup> wg_sample: vec4<u32>;
// The fewest steps any thread of each member ran (llvmpipe cuts each
// invocation's loops on its own, so thread 0's count alone may miss a cut).
var<workgroup> fewest_run: array<atomic<u32>, 4>;

// Whether this invocation's loops all ran whole. Once llvmpipe has spent
// an invocation's loop budget it ends every loop after one pass, and the
// budget never comes back, so a loop of batch.probe_passes (2) passes then
// stops short of its end. The loop's bound varies by thread, as the kernel's loops do:
// llvmpipe neither counts nor cuts a loop whose bound is the same for the
// whole workgroup (measured: such a probe ran 70,000 passes after a cut).
fn loop_budget_left(t: u32) -> bool {
    var k = t;
    let end = t + batch.probe_passes * SCENE_THREADS;
    loop {
        k += SCENE_THREADS;
        if k >= end {
            break;
        }
    }
    return k >= end;
}

// Block i's bulk force, and a per-block friction law's friction from it.
fn store_bulk_force(i: u32, f: vec2<real>, ld: Loads) {
    force[block_base() + i] = f;
    if is_block_law() && i < c.nx {
        contact[interface_base() + i] = block_law_friction(i, f.x, ld);
    }
}

@compute @workgroup_size(PERSISTENT_THREADS)
fn persistent_steps(
    @builtin(local_invocation_index) wt: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
) {
    phase_start(wt);
    // This thread's member scene, and its place among the scene's threads.
    // One scene a workgroup: member 0, a value the compiler sees is the
    // same on every thread (its scene's constants then stay in uniform
    // registers).
    // Several: the member as the subgroup's first thread has it, which the
    // compiler may keep in uniform registers (with a thread's own, the
    // scene's constants took twice the registers on RADV). Exact where no
    // subgroup holds two members' threads; one that does voids the run.
    let own_member = wt / SCENE_THREADS;
    let member = select(subgroup_uniform(own_member), 0u, GROUP_SCENES == 1u);
    let t = select(wt % SCENE_THREADS, wt, GROUP_SCENES == 1u);
    let first_scene = wid.z * GROUP_SCENES;
    let scenes = arrayLength(&scene_consts);
    // A member past the ensemble's last scene steps nothing and writes
    // nothing; it enters a scene only to keep its loops' bounds in range.
    let present = first_scene + member < scenes;
    enter_scene(min(first_scene + member, scenes - 1u));
    if GROUP_SCENES > 1u && member != own_member {
        atomicStore(&status[status_base() + STATUS_STRADDLED_SUBGROUP], 1u);
    }
    reduction_base = member * (REDUCTION_WIDTH / REDUCTION_GROUPS);
    let lanes = min(JUNCTION_LANES, c.junction_count);
    // Before the barrier of workgroupUniformLoad below. Every invocation,
    // whatever its scene: the levels are the workgroup's (the same tree of
    // sums at any level).
    lane_shuffle_enter(wt, lanes);
    if t == 0u {
        // A member absent or stopped before the dispatch starts stopped.
        var stopped = 1u;
        if present {
            stopped = atomicLoad(&status[status_base() + STATUS_FLAG]);
        }
        stop[member] = stopped;
        atomicStore(&fewest_run[member], 0xffffffffu);
    }
    // The steps of this dispatch, made uniform for the barriers of the loop.
    if wt == 0u {
        let begin = step_offset * batch.steps_per_dispatch;
        var first_sample = 0u;
        while first_sample < batch.records && record_entries[first_sample].offset < begin {
            first_sample++;
        }
        span = vec4<u32>(
            begin,
            min(begin + batch.steps_per_dispatch, batch.steps),
            batch.records,
            first_sample,
        );
    }
    let steps = workgroupUniformLoad(&span);
    lane_shuffle_ready();
    let stride = lane_subtree_stride();
    if t == 0u && present {
        atomicMax(&status[status_base() + STATUS_LANE_LEVELS], lane_levels_used());
    }
    var next_sample = steps.w;
    var ran = 0u;
    var stops = workgroupUniformLoad(&stop);
    if all_stopped(stops) {
        return;
    }
    var stepping = stops[member] == 0u;
    state_enter(t, SCENE_THREADS);
    // The first step's junction blocks (noted_blocks.wgsl; resident only).
    if NOTED_JUNCTION_BLOCKS && FRICTION_LAW == LAW_JUNCTIONS {
        let first = loads_at(steps.x);
        for (var ix = t; ix < c.nx; ix += SCENE_THREADS) {
            note_junction_block(ix, ix, first);
        }
        workgroupBarrier();
    }
    phase_mark(wt, PHASE_ENTER);
    for (var s = steps.x; s < steps.y; s++) {
        let ld = loads_at(s);
        let ready = batch.forces_ready != 0u && s == 0u;
        // A stopped member's threads skip the phases, not the barriers.
        if member_steps(stepping) && !ready {
            if BOND_PATCHES {
                let columns = (c.nx + 1u) / 2u;
                for (var p = grid_walk(t, SCENE_THREADS, columns); 2u * p.row < c.nz; grid_walk_next(&p)) {
                    let x0 = 2u * p.column;
                    let z0 = 2u * p.row;
                    let f = bulk_force_patch(x0, z0, c.nx, ld);
                    let i = z0 * c.nx + x0;
                    store_bulk_force(i, f.a, ld);
                    if x0 + 1u < c.nx {
                        store_bulk_force(i + 1u, f.b, ld);
                    }
                    if z0 + 1u < c.nz {
                        store_bulk_force(i + c.nx, f.c, ld);
                        if x0 + 1u < c.nx {
                            store_bulk_force(i + c.nx + 1u, f.d, ld);
                        }
                    }
                }
            } else if INNER_BLOCKS_FIRST {
                // Inner blocks first, without bounds, then the rim: item
                // k = t, t + threads, … of inner then rim blocks.
                let span = block_span(0u, c.nx);
                var k = t;
                for (var b = grid_walk(t, SCENE_THREADS, max(span.inner_columns, 1u)); k < span.inner_count; grid_walk_next(&b)) {
                    let column = span.inner_first + b.column;
                    let i = (b.row + 1u) * c.nx + column;
                    store_bulk_force(i, inner_bulk_force(i, column, b.row + 1u, ld), ld);
                    k += SCENE_THREADS;
                }
                for (; k < c.n_blocks; k += SCENE_THREADS) {
                    let b = span_rim_block(span, k - span.inner_count);
                    let i = b.y * c.nx + b.x;
                    store_bulk_force(i, bulk_force(i, b.x, b.y, ld), ld);
                }
            } else {
                for (var b = grid_walk(t, SCENE_THREADS, c.nx); b.row < c.nz; grid_walk_next(&b)) {
                    let i = b.row * c.nx + b.column;
                    store_bulk_force(i, bulk_force(i, b.column, b.row, ld), ld);
                }
            }
            if FRICTION_LAW == LAW_JUNCTIONS {
                // Two lanes a round on hardware, both lanes' first
                // junctions loaded before either is stepped: half the chains
                // of storage round trips on a thread's path. One on software
                // adapters (TWO_LANES_A_ROUND false), where a second inlined
                // lane doubles the loop iterations llvmpipe counts.
                // Item w is lane run w mod runs of block w / runs (row and
                // column of the walk): a lane where LANE_RUN is 1; longer
                // runs load their lanes ahead themselves (lane_run).
                let runs = lane_runs(lanes);
                let items = c.nx * runs;
                var w = t;
                var lane = grid_walk(t, SCENE_THREADS, runs);
                for (; TWO_LANES_A_ROUND && LANE_RUN == 1u && w + SCENE_THREADS < items; w += 2u * SCENE_THREADS) {
                    let w2 = w + SCENE_THREADS;
                    var lane2 = lane;
                    grid_walk_next(&lane2);
                    let ix = lane.row;
                    let ix2 = lane2.row;
                    let jb = lanes_junction_block(ix, ix, ld);
                    let jb2 = lanes_junction_block(ix2, ix2, ld);
                    let first = lane_pair_of(ix, lane.column, jb);
                    let first2 = lane_pair_of(ix2, lane2.column, jb2);
                    // A kept block's partials are not merged: not written.
                    // Where lanes merge in subgroups, a run's first lane
                    // writes its subtree.
                    if !jb.kept {
                        let sum = lane_subtree(lane_from(ix, lane.column, jb, ld, first), lane.column);
                        if (lane.column & (stride - 1u)) == 0u {
                            lane_partial[lane_base() + w] = sum;
                        }
                    }
                    if !jb2.kept {
                        let sum = lane_subtree(lane_from(ix2, lane2.column, jb2, ld, first2), lane2.column);
                        if (lane2.column & (stride - 1u)) == 0u {
                            lane_partial[lane_base() + w2] = sum;
                        }
                    }
                    lane = lane2;
                    grid_walk_next(&lane);
                }
                for (; w < items; w += SCENE_THREADS) {
                    let jb = lanes_junction_block(lane.row, lane.row, ld);
                    if !jb.kept {
                        let l = lane.column * LANE_RUN;
                        let sum = lane_subtree(lane_run(lane.row, l, jb, ld), l);
                        if (l & (stride - 1u)) == 0u {
                            lane_partial[lane_base() + lane.row * lanes + l] = sum;
                        }
                    }
                    grid_walk_next(&lane);
                }
            }
        }
        phase_arrive(wt, PHASE_FORCES);
        state_barrier();
        phase_mark(wt, PHASE_FORCES);
        // Is step s a sample (1), and is it due (2), for each member? The
        // samples' steps are the same for every scene; whether one is due
        // is each scene's (its fast cadence).
        var sampling = false;
        var any_due = false;
        var e: RecordEntry;
        var acc = no_sums();
        if steps.z > 0u {
            if t == 0u {
                var state = 0u;
                if member_steps(stepping) && next_sample < steps.z && record_entries[next_sample].offset == s {
                    state = 1u + select(0u, 1u, sample_due(record_entries[next_sample]));
                }
                wg_sample[member] = state;
            }
            let states = workgroupUniformLoad(&wg_sample);
            let state = states[member];
            any_due = states.x == 2u || (GROUP_SCENES > 1u && any(states.yzw == vec3<u32>(2u)));
            if state != 0u {
                e = record_entries[next_sample];
                next_sample++;
                sampling = state == 2u;
                if !sampling && t == 0u {
                    sums[sums_slot(e)].recorded = 0u;
                }
            }
        }
        for (var b = grid_walk(t, SCENE_THREADS, c.nx); member_steps(stepping) && b.row < c.nz; grid_walk_next(&b)) {
            let i = b.row * c.nx + b.column;
            var friction: real = 0.0;
            if FRICTION_LAW != LAW_NONE && i < c.nx {
                if FRICTION_LAW == LAW_JUNCTIONS && !ready {
                    let jb = update_junction_block(i, i, ld);
                    var lane_sums: LaneSum;
                    if jb.kept {
                        lane_sums = kept_lane_sum(jb);
                    } else {
                        lane_sums = merged_lane_partials(lane_base() + i * lanes, lanes);
                    }
                    friction = junction_friction(i, jb, lane_sums, force[block_base() + i].x);
                    contact[interface_base() + i] = vec2<real>(friction, foundation_normal(coord_value(load_disp(i).z)));
                } else {
                    friction = contact[interface_base() + i].x;
                }
            }
            if sampling {
                var normal: real = 0.0;
                if i < c.nx {
                    normal = contact[interface_base() + i].y;
                }
                let f = force[block_base() + i];
                acc = combine(acc, block_sample(i, e, flags[i], load_disp(i), load_vel(i), f, friction, normal, interface_due(e)));
            }
            if batch.forces_only == 0u {
                verlet(i, b.column, b.row, force[block_base() + i], friction, ld, s);
            }
            // Its junction block for step s + 1.
            if NOTED_JUNCTION_BLOCKS && FRICTION_LAW == LAW_JUNCTIONS && i < c.nx {
                note_junction_block(i, i, ld);
            }
        }
        // Every member reduces where any one's sample is due (the
        // reduction's barriers are the workgroup's), each in its own slots;
        // only a due member's sums are written.
        if any_due {
            reduce_threads(t, SCENE_THREADS, acc, true);
            if t == 0u && sampling {
                finish_sample(e);
            }
        }
        if member_steps(stepping) {
            ran = ran + 1u;
        }
        phase_arrive(wt, PHASE_UPDATES);
        state_barrier();
        phase_mark(wt, PHASE_UPDATES);
        // Stop at a blow-up (checked every 16 steps: each check costs a
        // barrier). A stopped member's threads wait at the barriers of the
        // others' steps; the workgroup ends when every member has stopped.
        if (s & 15u) == 15u {
            if t == 0u && member_steps(stepping) {
                stop[member] = atomicLoad(&status[status_base() + STATUS_FLAG]);
            }
            stops = workgroupUniformLoad(&stop);
            phase_mark(wt, PHASE_CHECKS);
            if all_stopped(stops) {
                break;
            }
            stepping = stops[member] == 0u;
        }
    }
    state_leave(t, SCENE_THREADS);
    // Steps run, summed over dispatches: the host checks that no driver
    // cut a dispatch short (llvmpipe ends a shader's loops after 65535
    // iterations in all, silently, each invocation's apart: a thread with
    // more junction draws than thread 0 may be cut while thread 0 is not).
    // A loop cut inside a step leaves the step counted, so a thread whose
    // budget ran out anywhere in the dispatch reports no steps at all.
    if LOOP_PROBE && !loop_budget_left(t) {
        ran = 0u;
    }
    atomicMin(&fewest_run[member], ran);
    workgroupBarrier();
    if t == 0u && present {
        atomicAdd(&status[status_base() + STATUS_PERSISTENT_STEPS], atomicLoad(&fewest_run[member]));
    }
    phase_mark(wt, PHASE_LEAVE);
    phase_flush(wt, PERSISTENT_THREADS, scene);
}

// Whether this thread's member scene steps: always with one scene a
// workgroup, which ends at its stop (so the compiler drops the checks).
fn member_steps(stepping: bool) -> bool {
    return GROUP_SCENES == 1u || stepping;
}

// Whether every member scene of the workgroup has stopped (members past
// GROUP_SCENES do not exist).
fn all_stopped(stops: vec4<u32>) -> bool {
    let members = vec4<u32>(0u, 1u, 2u, 3u) < vec4<u32>(GROUP_SCENES);
    return all(!members | stops != vec4<u32>(0u));
}
