// One step n → n+1 of every block in one dispatch, junction lanes in
// parallel (hardware GPUs, many junctions): workgroup w < nx (junction
// laws) is interface block w, its threads are the junction lanes and
// thread 0 adds the lane sums in lane order and updates the block. The
// other workgroups update WORKGROUP blocks each, one per thread. The
// workgroup barrier makes llvmpipe run the whole shader as coroutines, so
// software adapters take one_step (serial lanes) instead. With junctions,
// the other workgroups start at block WORKGROUP·⌊nx/WORKGROUP⌋, so that
// each covers the blocks of one output partial (record_kinetic.wgsl),
// whose kinetic energy the recording variant (RECORD_KINETIC) sums as in
// one_step.
// CPU twin: src/engines/cpu/mod.rs CpuEngine::one_step (force pass and update).
// import: bulk_forces, common, coordinates, junctions, record_kinetic, scene, state, step_forces, verlet

var<workgroup> lane_sum: array<LaneSum, JUNCTION_LANES>;

override RECORD_KINETIC: bool = false;

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
        lane_sum[local] = junction_lane(w, local, junction_block(w, ld), ld);
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
                let jb = junction_block(w, ld);
                var lane_sums = lane_sum_zero();
                for (var l = 0u; !jb.kept && l < lanes; l++) {
                    lane_sums = lane_sum_merge(lane_sums, lane_sum[l]);
                }
                friction = junction_friction(w, jb, lane_sums, f.x);
                force[block_base() + w] = f;
                contact[interface_base() + w] = vec2<real>(friction, foundation_normal(coord_value(load_disp(w).z)));
            }
            if update {
                verlet(w, f, friction, ld, i_step);
            }
        }
    }
    // The bulk workgroups: partial g's blocks, less the interface's.
    var g = w;
    if FRICTION_LAW == LAW_JUNCTIONS {
        g = c.nx / WORKGROUP + (w - c.nx);
    }
    let i = g * WORKGROUP + local;
    var kinetic = real(0.0);
    let bulk = !junction_group && i < c.n_blocks && (FRICTION_LAW != LAW_JUNCTIONS || i >= c.nx);
    if bulk {
        let ff = block_forces(i, ld, ready);
        if RECORD_KINETIC {
            kinetic = bulk_kinetic(i, load_vel(i), ff.xy);
        }
        if update {
            verlet(i, ff.xy, ff.z, ld, i_step);
        }
    }
    // Partials that hold interface blocks are the output kernels' to
    // write (record.wgsl, after this dispatch).
    if RECORD_KINETIC {
        let total = sum_kinetic(local, kinetic);
        if local == 0u && !junction_group && g < plans[scene].partials {
            write_kinetic_partial(g, total);
        }
    }
}
