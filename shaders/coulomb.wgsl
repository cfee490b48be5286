// Amontons–Coulomb friction on interface block ix, given the other forces
// along x; returns (friction, normal force). CPU twin: src/cpu/coulomb.rs.

fn coulomb(ix: u32, other: f32, ld: Loads) -> vec2<f32> {
    let u = load_disp(ix);
    let v = load_vel(ix);
    let normal = foundation_normal(u.z.x);
    var state = slide[interface_base() + ix];
    var dir = state.x;
    if dir != 0 && v.x * f32(dir) <= 0.0 {
        dir = 0;
    }
    var friction = 0.0;
    if dir == 0 {
        // Friction that brings the block to rest this step.
        let hold = -other - c.mass * v.x / c.dt;
        if ld.preparing || abs(hold) <= c.mu_s * normal {
            friction = hold;
        } else {
            dir = select(-1, 1, other > 0.0);
            state.y = state.y + 1;
            friction = -c.mu_d * normal * f32(dir);
        }
    } else {
        friction = -c.mu_d * normal * f32(dir);
    }
    slide[interface_base() + ix] = vec2<i32>(dir, state.y);
    return vec2<f32>(friction, normal);
}
