// Phase 2 (Amontons–Coulomb friction) per interface block.
// CPU twin: src/cpu/coulomb.rs.

@compute @workgroup_size(64)
fn coulomb(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let ix = thread_index(gid, groups);
    if ix >= c.nx {
        return;
    }
    let u = disp[ix];
    let v = vel[ix];
    let other = force[ix].x;
    let normal = foundation_normal(u.z.x);
    var state = slide[ix];
    var dir = state.x;
    if dir != 0 && v.x * f32(dir) <= 0.0 {
        dir = 0;
    }
    var friction = 0.0;
    if dir == 0 {
        // Friction that brings the block to rest this step.
        let hold = -other - c.mass * v.x / c.dt;
        if sp.preparing != 0u || abs(hold) <= c.mu_s * normal {
            friction = hold;
        } else {
            dir = select(-1, 1, other > 0.0);
            state.y = state.y + 1;
            friction = -c.mu_d * normal * f32(dir);
        }
    } else {
        friction = -c.mu_d * normal * f32(dir);
    }
    slide[ix] = vec2<i32>(dir, state.y);
    contact[ix] = vec2<f32>(friction, normal);
}
