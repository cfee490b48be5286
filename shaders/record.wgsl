// Output samples written on the device, so that a run with an output file
// reads back only the channels that are due. Dispatched in the steps'
// compute pass right after the step dispatch that started from the sample's
// instant s: that dispatch left u(s) and v(s−½) in its input copy, and the
// forces, friction, normal forces and junction states of s in `force`,
// `contact` and `junction_state` (or after a forces-only pass at the end of
// an advance). One workgroup does a small lattice's sample
// (record_small); larger ones take two dispatches: record_sample, one
// thread per block, writes the interface row and the bulk field if due and
// reduces each workgroup's sums to a partial, then record_finish adds the
// partials. The sample's sums also decide the fast interface cadence for
// the next samples.
// CPU twin: src/engine/sample.rs record_sample.

@group(0) @binding(1) var<storage, read> disp_a: array<Disp>;
@group(0) @binding(2) var<storage, read> vel_a: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read> disp_b: array<Disp>;
@group(0) @binding(4) var<storage, read> vel_b: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read> force: array<vec2<f32>>;
@group(0) @binding(6) var<storage, read> flags: array<u32>;
@group(0) @binding(7) var<storage, read> contact: array<vec2<f32>>;
@group(0) @binding(9) var<storage, read> junction_state: array<vec2<u32>>;
@group(0) @binding(10) var<storage, read> slide: array<vec2<i32>>;
@group(0) @binding(13) var<storage, read_write> plan: RecordPlan;
// Each sample's sums (slot entry.sums_slot), then from plan.partials_offset
// one partial per workgroup of record_sample.
@group(0) @binding(14) var<storage, read_write> sums: array<SampleSums>;
// Interface rows (RECORD_INTERFACE_WORDS per block) from
// plan.interface_offset, bulk fields (RECORD_BULK_WORDS per block) from
// plan.bulk_offset, in the slots the entry names. One scene: block i is
// element i of every buffer.
@group(0) @binding(15) var<storage, read_write> rows: array<f32>;
@group(1) @binding(0) var<storage, read> entry: RecordEntry;

// The fixed cadences make the sample due, or the fast one does and is on.
fn sample_due() -> bool {
    return (entry.channels & RECORD_FIXED) != 0u
        || ((entry.channels & RECORD_FAST) != 0u && plan.fast != 0u);
}

fn interface_due() -> bool {
    return (entry.channels & RECORD_INTERFACE) != 0u
        || ((entry.channels & RECORD_FAST) != 0u && plan.fast != 0u);
}

fn no_sums() -> SampleSums {
    var s: SampleSums;
    s.min_pinned = 3.0e38;
    return s;
}

fn combine(a: SampleSums, b: SampleSums) -> SampleSums {
    var s = a;
    let lo = a.ruptures_lo + b.ruptures_lo;
    s.ruptures_hi = a.ruptures_hi + b.ruptures_hi + select(0u, 1u, lo < a.ruptures_lo);
    s.ruptures_lo = lo;
    s.kinetic = a.kinetic + b.kinetic;
    s.friction = a.friction + b.friction;
    s.pinned = a.pinned + b.pinned;
    s.min_pinned = min(a.min_pinned, b.min_pinned);
    s.max_slip_speed = max(a.max_slip_speed, b.max_slip_speed);
    s.top_reaction = a.top_reaction + b.top_reaction;
    // Only the driven block's are not zero.
    s.driven_ux_hi = a.driven_ux_hi + b.driven_ux_hi;
    s.driven_ux_lo = a.driven_ux_lo + b.driven_ux_lo;
    return s;
}

// Block i's sums at the instant, and its rows if due.
fn block_sample(i: u32) -> SampleSums {
    var u: Disp;
    var v_half: vec2<f32>;
    if entry.copy == 1u {
        u = disp_b[i];
        v_half = vel_b[i];
    } else {
        u = disp_a[i];
        v_half = vel_a[i];
    }
    let f = force[i];
    var friction = 0.0;
    var normal = 0.0;
    if i < c.nx {
        friction = contact[i].x;
        normal = contact[i].y;
    }
    // The velocity at the instant of u (CPU twin:
    // engine::synchronised_velocity); samples are taken while driving.
    let half_dt_over_m = 0.5 * c.dt * c.inv_mass;
    var v = vec2<f32>(v_half.x + half_dt_over_m * (f.x + friction), v_half.y + half_dt_over_m * f.y);
    let fl = flags[i];
    if (fl & FLAG_FIX_X) != 0u {
        v.x = 0.0;
    }
    if (fl & FLAG_FIX_Z) != 0u {
        v.y = 0.0;
    }
    if (fl & FLAG_PRESCRIBED_X) != 0u {
        v.x = c.drive_velocity;
    }
    var s = no_sums();
    s.kinetic = v.x * v.x + v.y * v.y;
    if i < c.nx {
        var pinned = 0u;
        var ruptures = u32(slide[i].y);
        let ns = plan.junctions_per_block;
        for (var j = 0u; j < ns; j++) {
            let state = junction_state[i * ns + j];
            pinned += select(0u, 1u, state.x == PINNED);
            ruptures += state.y;
        }
        var fraction = f32(pinned) / f32(max(ns, 1u));
        if ns == 0u {
            fraction = select(0.0, 1.0, slide[i].x == 0);
        }
        s.friction = friction;
        s.pinned = fraction;
        s.min_pinned = fraction;
        s.max_slip_speed = abs(v.x);
        s.ruptures_lo = ruptures;
        if interface_due() {
            let at = plan.interface_offset + (entry.interface_slot * c.nx + i) * RECORD_INTERFACE_WORDS;
            rows[at] = u.x.x;
            rows[at + 1u] = u.x.y;
            rows[at + 2u] = friction;
            rows[at + 3u] = normal;
            rows[at + 4u] = fraction;
            rows[at + 5u] = v.x;
        }
    }
    if i == plan.driven_block {
        s.driven_ux_hi = u.x.x;
        s.driven_ux_lo = u.x.y;
    }
    if plan.top_reaction != 0u && i >= c.n_blocks - c.nx {
        s.top_reaction = c.mass * (c.drive_velocity - v_half.x) / c.dt - f.x - friction;
    }
    if (entry.channels & RECORD_BULK) != 0u {
        let at = plan.bulk_offset + (entry.bulk_slot * c.n_blocks + i) * RECORD_BULK_WORDS;
        // hi + lo rounded once: the f32 of the f64 displacement.
        rows[at] = u.x.x + u.x.y;
        rows[at + 1u] = u.z.x + u.z.y;
        rows[at + 2u] = v.x;
        rows[at + 3u] = v.y;
    }
    return s;
}

// Threads of the one-workgroup entry points: a power of two, at most 256
// (software adapters run a workgroup on one core, where fewer threads,
// with fewer barrier switches, are faster).
override RECORD_THREADS: u32 = 256u;

var<workgroup> wg_sums: array<SampleSums, 256>;
var<workgroup> wg_go: u32;

// Reduces wg_sums[0..width] to wg_sums[0] (a fixed tree: the same bits
// every run).
fn reduce_workgroup(local: u32, width: u32) {
    for (var half = width / 2u; half > 0u; half = half / 2u) {
        workgroupBarrier();
        if local < half {
            wg_sums[local] = combine(wg_sums[local], wg_sums[local + half]);
        }
    }
    workgroupBarrier();
}

// Thread 0 of a workgroup whose wg_sums[0] holds the sample's sums: writes
// them and decides the fast interface cadence for the samples after this
// one (the host's rule, runner::outputs::Outputs::emit_sample).
fn finish_sample() {
    var out = wg_sums[0];
    out.recorded = 1u;
    out.interface_row = select(0u, 1u, interface_due());
    let fast = plan.every_fast != 0u && out.max_slip_speed > plan.fast_slip_speed;
    out.fast = select(0u, 1u, fast);
    sums[entry.sums_slot] = out;
    plan.fast = out.fast;
}

// Whether the sample is due, made uniform across the workgroup (thread 0
// reads the fast flag); a sample not due is marked so in its slot.
fn begin_sample(local: u32) -> bool {
    if local == 0u {
        wg_go = select(0u, 1u, sample_due());
    }
    return workgroupUniformLoad(&wg_go) != 0u;
}

// Lattices of up to RECORD_SMALL_BLOCKS blocks: the whole sample in one
// dispatch of one workgroup.
@compute @workgroup_size(RECORD_THREADS)
fn record_small(@builtin(local_invocation_index) local: u32) {
    if !begin_sample(local) {
        if local == 0u {
            sums[entry.sums_slot].recorded = 0u;
        }
        return;
    }
    var s = no_sums();
    for (var i = local; i < c.n_blocks; i += RECORD_THREADS) {
        s = combine(s, block_sample(i));
    }
    wg_sums[local] = s;
    reduce_workgroup(local, RECORD_THREADS);
    if local == 0u {
        finish_sample();
    }
}

// Larger lattices, first dispatch: a thread per block, a partial per
// workgroup.
@compute @workgroup_size(WORKGROUP)
fn record_sample(
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    if !begin_sample(local) {
        return;
    }
    let g = wid.x + wid.y * groups.x;
    let i = g * WORKGROUP + local;
    var s = no_sums();
    if i < c.n_blocks {
        s = block_sample(i);
    }
    wg_sums[local] = s;
    reduce_workgroup(local, WORKGROUP);
    if local == 0u {
        sums[plan.partials_offset + g] = wg_sums[0];
    }
}

// Larger lattices, second dispatch: one workgroup adds the partials.
@compute @workgroup_size(RECORD_THREADS)
fn record_finish(@builtin(local_invocation_index) local: u32) {
    if !begin_sample(local) {
        if local == 0u {
            sums[entry.sums_slot].recorded = 0u;
        }
        return;
    }
    var s = no_sums();
    for (var g = local; g < plan.partials; g += RECORD_THREADS) {
        s = combine(s, sums[plan.partials_offset + g]);
    }
    wg_sums[local] = s;
    reduce_workgroup(local, RECORD_THREADS);
    if local == 0u {
        finish_sample();
    }
}
