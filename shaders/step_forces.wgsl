// The forces of block i at the start of a step, stored in `force`, and its
// friction: a per-block law (friction_law), or the junction lanes of an interface block
// one after the other, merged as the CPU twin's tree (merge_lanes). With `ready`
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
    let f = bulk_force(i, i % c.nx, i / c.nx, ld);
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
        // Every lane slot into the tree in order (the CPU twin's
        // merge_lanes), the slots past the last lane as the zero sum.
        // The maxima beside the tree (lane_maxima).
        var tree: LaneTree;
        var lane_sums: LaneSum;
        if jb.kept {
            lane_sums = kept_lane_sum(jb);
        } else {
            var maxima = vec2<real>(0.0, 0.0);
            for (var l = 0u; l < JUNCTION_LANES; l++) {
                var leaf = lane_sum_zero();
                if l < lanes {
                    leaf = junction_lane(i, l, jb, ld);
                }
                maxima = max(maxima, lane_maxima(leaf));
                lane_sums = lane_tree_add(&tree, l, lane_sum_unbounded(leaf));
            }
            lane_sums = lane_sum_bounded(lane_sums, maxima);
        }
        friction = junction_friction(i, jb, lane_sums, f.x);
        contact[interface_base() + i] = vec2<real>(friction, foundation_normal(coord_value(load_disp(i).z)));
    }
    return vec3<real>(f, friction);
}
