// A sample's kinetic energy summed per workgroup of WORKGROUP consecutive
// blocks, in the fixed tree of reduce_workgroup (record_common.wgsl), and
// what a block contributes to it. Shared by the output kernels
// (record.wgsl: a workgroup of blocks that add nothing else) and by the
// one-step kernels' recording variant (RECORD_KINETIC), which sums it in
// the step dispatch of a sample: that dispatch has the block's velocity
// and force at hand, so the output kernels need not read the lattice
// again.
// CPU twin: src/engines/sample.rs record_sample (kinetic_energy).
// import: bindings, record_buffers, scene

var<workgroup> wg_kinetic: array<real, WORKGROUP>;

// The one-step kernels' recording variant (set on its pipeline only).
override RECORD_KINETIC: bool = false;

fn no_sums() -> SampleSums {
    var s: SampleSums;
    s.min_pinned = 3.0e38;
    return s;
}

// A block's velocity at the instant of u (CPU twin:
// engine::synchronised_velocity), from its flags `fl`; samples are taken
// while driving.
fn sampled_velocity(fl: u32, v_half: vec2<real>, f: vec2<real>, friction: real) -> vec2<real> {
    let half_dt_over_m = 0.5 * c.dt * c.inv_mass;
    var v = vec2<real>(v_half.x + half_dt_over_m * (f.x + friction), v_half.y + half_dt_over_m * f.y);
    if (fl & FLAG_FIX_X) != 0u {
        v.x = 0.0;
    }
    if (fl & FLAG_FIX_Z) != 0u {
        v.y = 0.0;
    }
    if (fl & FLAG_PRESCRIBED_X) != 0u {
        v.x = c.drive_velocity;
    }
    return v;
}

// |v|² of a block away from the interface (no friction) at the sample's
// instant, from v(s−½) and the force of s.
fn bulk_kinetic(i: u32, v_half: vec2<real>, f: vec2<real>) -> real {
    let v = sampled_velocity(flags[i], v_half, f, 0.0);
    return v.x * v.x + v.y * v.y;
}

// The workgroup's kinetic energies (each thread's `k`) summed, in
// wg_kinetic[0] for every thread afterwards. Uniform control flow only.
fn sum_kinetic(local: u32, k: real) -> real {
    wg_kinetic[local] = k;
    for (var half = WORKGROUP / 2u; half > 0u; half = half / 2u) {
        workgroupBarrier();
        if local < half {
            wg_kinetic[local] = wg_kinetic[local] + wg_kinetic[local + half];
        }
    }
    workgroupBarrier();
    return wg_kinetic[0];
}

// Partial g of the current scene's sample: the sums of a workgroup whose
// blocks add only kinetic energy (the others stay no_sums's).
fn write_kinetic_partial(g: u32, kinetic: real) {
    var s = no_sums();
    s.kinetic = kinetic;
    sums[plans[scene].partials_offset + g] = s;
}
