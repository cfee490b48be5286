// The forces of block i at the start of a step, stored in `force`, and its
// friction: a per-block law (friction_law), or the junction lanes of an interface block
// one after the other, in lane order (the CPU twin's order). With `ready`
// the forces were computed already (by a snapshot's force pass): read them.
// Returns (force, friction). CPU twin: src/engines/cpu/mod.rs CpuEngine::force_pass.
// import: bulk_forces, junctions, friction_law, common, coordinates, scene, state

fn block_forces(i: u32, ld: Loads, ready: bool) -> vec3<real> {
    if ready {
        var friction: real = 0.0;
        if FRICTION_LAW != LAW_NONE && i < c.nx {
            friction = contact[interface_base() + i].x;
        }
        return vec3<real>(force[block_base() + i], friction);
    }
    let f = bulk_force(i, ld);
    force[block_base() + i] = f;
    var friction: real = 0.0;
    if is_block_law() && i < c.nx {
        let cn = block_law_friction(i, f.x, ld);
        contact[interface_base() + i] = cn;
        friction = cn.x;
    }
    if FRICTION_LAW == LAW_JUNCTIONS && i < c.nx {
        let lanes = min(JUNCTION_LANES, c.junction_count);
        let jb = junction_block(i, ld);
        var lane_sums = lane_sum_zero();
        for (var l = 0u; l < lanes; l++) {
            lane_sums = lane_sum_merge(lane_sums, junction_lane(i, l, jb, ld));
        }
        friction = junction_friction(i, jb, lane_sums, f.x);
        contact[interface_base() + i] = vec2<real>(friction, foundation_normal(coord_value(load_disp(i).z)));
    }
    return vec3<real>(f, friction);
}
