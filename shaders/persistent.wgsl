// batch.steps_per_dispatch steps of the whole lattice in one dispatch of
// one workgroup per scene (small lattices): dispatch d of a batch (its step offset)
// runs steps d·K .. (d+1)·K. Each step computes the forces and junction lanes,
// then (after a barrier) adds the lane sums and updates every block in
// place, then waits at a barrier again. The thread that updates block ix
// is the one that adds its lane sums, so no third barrier is needed.
// Same phase functions, in the same order, as the one-step kernel.

override PERSISTENT_THREADS: u32 = 256u;

var<workgroup> stop: u32;
var<workgroup> span: vec2<u32>;

@compute @workgroup_size(PERSISTENT_THREADS)
fn persistent_steps(
    @builtin(local_invocation_index) t: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
) {
    enter_scene(wid.z);
    let lanes = min(JUNCTION_LANES, c.junction_count);
    // The steps of this dispatch, made uniform for the barriers of the loop.
    if t == 0u {
        let begin = step_offset * batch.steps_per_dispatch;
        span = vec2<u32>(begin, min(begin + batch.steps_per_dispatch, batch.steps));
        stop = atomicLoad(&status[status_base()]);
    }
    let steps = workgroupUniformLoad(&span);
    var ran = 0u;
    if workgroupUniformLoad(&stop) != 0u {
        return;
    }
    for (var s = steps.x; s < steps.y; s++) {
        let ld = loads_at(s);
        let ready = batch.forces_ready != 0u && s == 0u;
        if !ready {
            for (var i = t; i < c.n_blocks; i += PERSISTENT_THREADS) {
                let f = bulk_force(i, ld);
                force[block_base() + i] = f;
                if FRICTION_LAW == LAW_COULOMB && i < c.nx {
                    contact[interface_base() + i] = coulomb(i, f.x, ld);
                }
            }
            if FRICTION_LAW == LAW_JUNCTIONS {
                for (var w = t; w < c.nx * lanes; w += PERSISTENT_THREADS) {
                    let ix = w / lanes;
                    lane_partial[lane_base() + w] = junction_lane(ix, w % lanes, junction_block(ix), ld);
                }
            }
        }
        storageBarrier();
        for (var i = t; i < c.n_blocks; i += PERSISTENT_THREADS) {
            var friction = 0.0;
            if FRICTION_LAW != LAW_NONE && i < c.nx {
                if FRICTION_LAW == LAW_JUNCTIONS && !ready {
                    for (var l = 0u; l < lanes; l++) {
                        friction = friction + lane_partial[lane_base() + i * lanes + l];
                    }
                    contact[interface_base() + i] = vec2<f32>(friction, foundation_normal(load_disp(i).z.x));
                } else {
                    friction = contact[interface_base() + i].x;
                }
            }
            if batch.forces_only == 0u {
                verlet(i, force[block_base() + i], friction, ld, s);
            }
        }
        ran = ran + 1u;
        storageBarrier();
        // Stop at a blow-up (checked every 16 steps: each check costs a barrier).
        if (s & 15u) == 15u {
            if t == 0u {
                stop = atomicLoad(&status[status_base()]);
            }
            if workgroupUniformLoad(&stop) != 0u {
                break;
            }
        }
    }
    // Steps run, summed over dispatches: the host checks that no driver
    // cut a dispatch short (llvmpipe ends a shader's loops after 65535
    // iterations in all, silently).
    if t == 0u {
        atomicAdd(&status[status_base() + 7u], ran);
    }
}
