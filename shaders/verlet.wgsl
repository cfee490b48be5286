// Phase 3: the leapfrog update v += dt F/m, u += dt v, with constraints and
// prescribed motion. CPU twin: src/cpu/verlet.rs. u is double-single, so
// the increment dt v keeps its low bits.

override USE_FRICTION: bool = true;

@compute @workgroup_size(64)
fn verlet(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = thread_index(gid, groups);
    if i >= c.n_blocks {
        return;
    }
    let f = force[i];
    var friction = 0.0;
    if USE_FRICTION && i < c.nx {
        friction = contact[i].x;
    }
    let v = vel[i];
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
        vx = sp.top_velocity;
    }
    vel[i] = vec2<f32>(vx, vz);
    let u = disp[i];
    disp[i] = Disp(ds_add(u.x, c.dt * vx), ds_add(u.z, c.dt * vz));
}
