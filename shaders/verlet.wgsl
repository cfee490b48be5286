// The leapfrog update of one block, v += dt F/m, u += dt v, with
// constraints and prescribed motion; u is a coordinate (double-single in mixed
// precision), so the increment dt v keeps its low bits. CPU twin: src/engines/kernels/verlet.rs verlet.
// import: common, coordinates, scene, state

// Block i at column ix and row iz (the tiled kernel's slot needs them).
fn verlet(i: u32, ix: u32, iz: u32, f: vec2<real>, friction: real, ld: Loads, step: u32) {
    let v = load_vel_at(i, ix, iz);
    var vx = v.x + c.dt * ((f.x + friction) * c.inv_mass);
    var vz = v.y + c.dt * (f.y * c.inv_mass);
    let fl = flags[i];
    if (fl & FLAG_FIX_X) != 0u {
        vx = 0.0;
    }
    if (fl & FLAG_FIX_Z) != 0u {
        vz = 0.0;
    }
    if (fl & FLAG_PRESCRIBED_X) != 0u {
        vx = ld.top_velocity;
    }
    let u = load_disp_at(i, ix, iz);
    let next = Disp(coord_add(u.x, c.dt * vx), coord_add(u.z, c.dt * vz));
    store_block_at(i, ix, iz, next, vec2<real>(vx, vz));
    // NaN fails both comparisons.
    if !(abs(vx) <= c.speed_limit && abs(vz) <= c.speed_limit) {
        report_blow_up(i, step, next, vec2<real>(vx, vz));
    }
}
