// Amontons–Coulomb friction on interface block ix, given the other forces
// along x; returns (friction, normal force). Its constants c.law0, c.law1
// are (μs, μd). CPU twin: src/model/friction/coulomb/mod.rs coulomb.
// import: common, coordinates, scene, state

fn coulomb(ix: u32, other: real, ld: Loads) -> vec2<real> {
    let u = load_disp(ix);
    let v = load_vel(ix);
    let normal = foundation_normal(coord_value(u.z));
    var state = slide[interface_base() + ix];
    var dir = state.x;
    if dir != 0 && v.x * real(dir) <= 0.0 {
        dir = 0;
    }
    var friction: real = 0.0;
    if dir == 0 {
        // Friction that brings the block to rest this step.
        let hold = -other - c.mass * v.x / c.dt;
        if ld.preparing || abs(hold) <= c.law0 * normal {
            friction = hold;
        } else {
            dir = select(-1, 1, other > 0.0);
            state.y = state.y + 1;
            friction = -c.law1 * normal * real(dir);
        }
    } else {
        friction = -c.law1 * normal * real(dir);
    }
    slide[interface_base() + ix] = vec2<i32>(dir, state.y);
    return vec2<real>(friction, normal);
}
