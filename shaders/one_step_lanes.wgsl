// One step n → n+1 of every block in one dispatch, junction lanes in
// parallel (hardware GPUs, many junctions): workgroup w < nx (junction
// laws) is interface block w, its threads are the junction lanes and
// thread 0 adds the lane sums in lane order and updates the block. The
// other workgroups update WORKGROUP blocks each, one per thread. The
// workgroup barrier makes llvmpipe run the whole shader as coroutines, so
// software adapters take one_step (serial lanes) instead.
// CPU twin: src/engines/cpu/mod.rs CpuEngine::one_step (force pass and update).
// import: bulk_forces, common, coordinates, junctions, scene, state, step_forces, verlet

var<workgroup> lane_sum: array<LaneSum, JUNCTION_LANES>;

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
    if junction_group && !ready && local < lanes {
        lane_sum[local] = junction_lane(w, local, junction_block(w), ld);
    }
    // Outside the branch: every workgroup reaches it (an ensemble scene's
    // constants are not uniform to the uniformity analysis).
    workgroupBarrier();
    if junction_group {
        if local == 0u {
            var f: vec2<real>;
            var friction: real = 0.0;
            if ready {
                f = force[block_base() + w];
                friction = contact[interface_base() + w].x;
            } else {
                f = bulk_force(w, ld);
                var lane_sums = lane_sum_zero();
                for (var l = 0u; l < lanes; l++) {
                    lane_sums = lane_sum_merge(lane_sums, lane_sum[l]);
                }
                friction = junction_friction(w, junction_block(w), lane_sums, f.x);
                force[block_base() + w] = f;
                contact[interface_base() + w] = vec2<real>(friction, foundation_normal(coord_value(load_disp(w).z)));
            }
            if update {
                verlet(w, f, friction, ld, i_step);
            }
        }
        return;
    }
    var i = w * WORKGROUP + local;
    if FRICTION_LAW == LAW_JUNCTIONS {
        i = c.nx + (w - c.nx) * WORKGROUP + local;
    }
    if i >= c.n_blocks {
        return;
    }
    let ff = block_forces(i, ld, ready);
    if update {
        verlet(i, ff.xy, ff.z, ld, i_step);
    }
}
