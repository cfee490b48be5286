// Output samples written on the device: what a block contributes to a
// sample, the sums and their reduction, and the fast cadence's rule. Shared
// by every step kernel, each of which records in its steps: the persistent
// kernel in its loop, the tiled kernel and the one-step kernels' recording
// variant (record_step.wgsl) a partial per workgroup (record_batch.wgsl).
// CPU twin: src/engines/sample.rs record_sample.
// import: common, coordinates, record_buffers, scene

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

// The fixed cadences make the sample due, or the fast one does and is on.
fn sample_due(e: RecordEntry) -> bool {
    return (e.channels & RECORD_FIXED) != 0u
        || ((e.channels & RECORD_FAST) != 0u && plans[scene].fast != 0u);
}

fn interface_due(e: RecordEntry) -> bool {
    return (e.channels & RECORD_INTERFACE) != 0u
        || ((e.channels & RECORD_FAST) != 0u && plans[scene].fast != 0u);
}

// The fixed cadence makes the interface row due, or the fast one plans it
// whether it turns out on or not: the tiled and one-step kernels write
// such a row before the samples before it have decided the fast flag (the
// host decides it afterwards, in order: recorder.rs fast_rule).
fn interface_planned(e: RecordEntry) -> bool {
    return (e.channels & (RECORD_INTERFACE | RECORD_FAST)) != 0u;
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

// The slot of a sample's sums in the current scene's region.
fn sums_slot(e: RecordEntry) -> u32 {
    return plans[scene].sums_offset + e.sums_slot;
}

// (pinned junctions, ruptures) of junctions first .. first + 8, their
// eight states loaded before any is used.
fn tally_eight(first: u32) -> vec2<u32> {
    let s0 = junction_state[first];
    let s1 = junction_state[first + 1u];
    let s2 = junction_state[first + 2u];
    let s3 = junction_state[first + 3u];
    let s4 = junction_state[first + 4u];
    let s5 = junction_state[first + 5u];
    let s6 = junction_state[first + 6u];
    let s7 = junction_state[first + 7u];
    let x0 = vec4<u32>(s0.x, s1.x, s2.x, s3.x);
    let x1 = vec4<u32>(s4.x, s5.x, s6.x, s7.x);
    let one = vec4<u32>(1u);
    let none = vec4<u32>(0u);
    let held = select(none, one, x0 == vec4<u32>(PINNED)) + select(none, one, x1 == vec4<u32>(PINNED));
    let ruptures = (s0.y + s1.y + s2.y + s3.y) + (s4.y + s5.y + s6.y + s7.y);
    return vec2<u32>(held.x + held.y + held.z + held.w, ruptures);
}

// tally_eight of the first `count` (0 to 8) of junctions first ..
// first + 8 only: every index is kept at or below first + count - 1 (the
// block's last state; first, where count is 0), and the states past
// count add nothing. No loop: llvmpipe counts every loop iteration of a
// persistent dispatch against its limit.
fn tally_eight_of(first: u32, count: u32) -> vec2<u32> {
    let last = first + max(count, 1u) - 1u;
    let s0 = junction_state[min(first, last)];
    let s1 = junction_state[min(first + 1u, last)];
    let s2 = junction_state[min(first + 2u, last)];
    let s3 = junction_state[min(first + 3u, last)];
    let s4 = junction_state[min(first + 4u, last)];
    let s5 = junction_state[min(first + 5u, last)];
    let s6 = junction_state[min(first + 6u, last)];
    let s7 = junction_state[min(first + 7u, last)];
    let n = vec4<u32>(count);
    let in0 = vec4<u32>(0u, 1u, 2u, 3u) < n;
    let in1 = vec4<u32>(4u, 5u, 6u, 7u) < n;
    let one = vec4<u32>(1u);
    let none = vec4<u32>(0u);
    let held0 = (vec4<u32>(s0.x, s1.x, s2.x, s3.x) == vec4<u32>(PINNED)) & in0;
    let held1 = (vec4<u32>(s4.x, s5.x, s6.x, s7.x) == vec4<u32>(PINNED)) & in1;
    let held = select(none, one, held0) + select(none, one, held1);
    let ruptures = select(none, vec4<u32>(s0.y, s1.y, s2.y, s3.y), in0)
        + select(none, vec4<u32>(s4.y, s5.y, s6.y, s7.y), in1);
    return vec2<u32>(
        held.x + held.y + held.z + held.w,
        ruptures.x + ruptures.y + ruptures.z + ruptures.w,
    );
}

// (pinned junctions, ruptures of its junctions) of interface block i, its
// Ns junction states tallied by one thread. Sixteen states are loaded
// before any is used: a load at a time made that a chain of Ns memory
// round trips on hardware (integer sums: any order, the same result).
fn interface_tally(i: u32) -> vec2<u32> {
    var pinned = 0u;
    var ruptures = 0u;
    let ns = plans[scene].junctions_per_block;
    let first = junction_base() + i * ns;
    var j = 0u;
    for (; j + 16u <= ns; j += 16u) {
        let a = tally_eight(first + j);
        let b = tally_eight(first + j + 8u);
        pinned += a.x + b.x;
        ruptures += a.y + b.y;
    }
    // The last ns mod 16 in one more round, the states past the block's
    // masked out.
    if j < ns {
        let a = tally_eight_of(first + j, ns - j);
        let b = tally_eight_of(first + j + 8u, ns - min(ns, j + 8u));
        pinned += a.x + b.x;
        ruptures += a.y + b.y;
    }
    return vec2<u32>(pinned, ruptures);
}

// Block i's sums at the instant of sample e (u(s), v(s−½), the forces,
// friction and normal force of s), its interface row where `row` says
// (interface_due, or interface_planned), and its bulk field if due.
fn block_sample(
    i: u32,
    e: RecordEntry,
    fl: u32,
    u: Disp,
    v_half: vec2<real>,
    f: vec2<real>,
    friction: real,
    normal: real,
    row: bool,
) -> SampleSums {
    let v = sampled_velocity(fl, v_half, f, friction);
    var s = block_sample_besides_interface(i, e, u, v_half, v, f, friction);
    if i < c.nx {
        s = with_interface_part(s, i, e, u, v, friction, normal, row, false, vec2<u32>(0u));
    }
    return s;
}

// block_sample of interface block i with its junction tally given
// (`tally`, interface_tally's: one_step_lanes has its lanes tally the
// block's junctions side by side).
fn block_sample_tallied(
    i: u32,
    e: RecordEntry,
    fl: u32,
    u: Disp,
    v_half: vec2<real>,
    f: vec2<real>,
    friction: real,
    normal: real,
    row: bool,
    tally: vec2<u32>,
) -> SampleSums {
    let v = sampled_velocity(fl, v_half, f, friction);
    let s = block_sample_besides_interface(i, e, u, v_half, v, f, friction);
    return with_interface_part(s, i, e, u, v, friction, normal, row, true, tally);
}

// Interface block i's part of sample e added to `sums`, the rest of its
// sums (v: its velocity at the sample's instant), and its interface row
// written where `row` says. Its junctions' (pinned, ruptures): `given`
// where `tallied`, else interface_tally's, taken after the block's slide
// state as block_sample always took them (the drivers' register
// allocation follows the order).
fn with_interface_part(
    sums: SampleSums,
    i: u32,
    e: RecordEntry,
    u: Disp,
    v: vec2<real>,
    friction: real,
    normal: real,
    row: bool,
    tallied: bool,
    given: vec2<u32>,
) -> SampleSums {
    var s = sums;
    let slide_i = slide[interface_base() + i];
    let ns = plans[scene].junctions_per_block;
    var tally = given;
    if !tallied {
        tally = interface_tally(i);
    }
    var fraction = real(tally.x) / real(max(ns, 1u));
    if ns == 0u {
        fraction = select(real(0.0), real(1.0), slide_i.x == 0);
    }
    s.friction = friction;
    s.pinned = fraction;
    s.min_pinned = fraction;
    s.max_slip_speed = abs(v.x);
    s.ruptures_lo = u32(slide_i.y) + tally.y;
    if row {
        let at = plans[scene].interface_offset + (e.interface_slot * c.nx + i) * RECORD_INTERFACE_WORDS;
        rows[at] = coord_hi(u.x);
        rows[at + 1u] = coord_lo(u.x);
        rows[at + 2u] = friction;
        rows[at + 3u] = normal;
        rows[at + 4u] = fraction;
        rows[at + 5u] = v.x;
    }
    return s;
}

// What block i adds to sample e besides its interface part (block_sample):
// its kinetic energy (from v, its velocity at the sample's instant), the
// driven block's displacement, the top row's reaction, its bulk field if
// due. All a block off the interface adds: the tiled kernel sums those
// blocks with this alone, which holds fewer registers than block_sample's
// junction tally.
fn block_sample_besides_interface(
    i: u32,
    e: RecordEntry,
    u: Disp,
    v_half: vec2<real>,
    v: vec2<real>,
    f: vec2<real>,
    friction: real,
) -> SampleSums {
    var s = no_sums();
    s.kinetic = v.x * v.x + v.y * v.y;
    if i == plans[scene].driven_block {
        s.driven_ux_hi = coord_hi(u.x);
        s.driven_ux_lo = coord_lo(u.x);
    }
    if plans[scene].top_reaction != 0u && i >= c.n_blocks - c.nx {
        s.top_reaction = c.mass * (c.drive_velocity - v_half.x) / c.dt - f.x - friction;
    }
    if (e.channels & RECORD_BULK) != 0u {
        let at = plans[scene].bulk_offset + (e.bulk_slot * c.n_blocks + i) * RECORD_BULK_WORDS;
        // hi + lo rounded once: the displacement in the kernels' precision.
        rows[at] = coord_rounded(u.x);
        rows[at + 1u] = coord_rounded(u.z);
        rows[at + 2u] = v.x;
        rows[at + 3u] = v.y;
    }
    return s;
}

// REDUCTION_SLOTS (prelude): 256 in mixed precision, fewer in f64, whose
// sums are larger (layout::reduction_slots). The resident and tiled
// kernels, whose workgroup memory holds the lattice, take fewer
// (REDUCTION_WIDTH).
override REDUCTION_WIDTH: u32 = REDUCTION_SLOTS;
var<workgroup> wg_sums: array<SampleSums, REDUCTION_WIDTH>;
// Scenes that reduce their samples side by side in one workgroup (the
// persistent kernel's GROUP_SCENES), each in REDUCTION_WIDTH /
// REDUCTION_GROUPS slots from its reduction_base.
override REDUCTION_GROUPS: u32 = 1u;
var<private> reduction_base: u32 = 0u;

// Reduces wg_sums[0..width] to wg_sums[0] (a fixed tree: the same bits
// every run). With `whole` false only the kinetic energy is reduced, by
// the same tree, and wg_sums[0] is no_sums with that kinetic energy: the
// sums of threads whose blocks add nothing else (off the interface and the
// top row, not the driven block), bit for bit what the whole tree gives
// them, for a fourteenth of the workgroup memory traffic. `whole` must be
// the same on every thread, but need not be uniform to the analysis: the
// barriers are outside its branches.
fn reduce_workgroup(local: u32, width: u32, whole: bool) {
    let at = reduction_base + local;
    for (var half = width / 2u; half > 0u; half = half / 2u) {
        workgroupBarrier();
        if local < half {
            if whole {
                wg_sums[at] = combine(wg_sums[at], wg_sums[at + half]);
            } else {
                wg_sums[at].kinetic = wg_sums[at].kinetic + wg_sums[at + half].kinetic;
            }
        }
    }
    // Thread 0 wrote slot 0 last (or alone, with one slot): no barrier
    // before it fills in the rest.
    if !whole && local == 0u {
        var s = no_sums();
        s.kinetic = wg_sums[at].kinetic;
        wg_sums[at] = s;
    }
    workgroupBarrier();
}

// Reduces the sums `acc` of `width` threads (a power of two) to
// wg_sums[0]. Threads beyond REDUCTION_WIDTH first fold into the slots, one
// block of them per round, in a fixed order (the same bits every run); with
// width ≤ REDUCTION_WIDTH this is the tree alone. With `whole` false, the
// kinetic energy alone (reduce_workgroup).
fn reduce_threads(local: u32, width: u32, acc: SampleSums, whole: bool) {
    let slots = min(width, REDUCTION_WIDTH / REDUCTION_GROUPS);
    if local < slots {
        if whole {
            wg_sums[reduction_base + local] = acc;
        } else {
            wg_sums[reduction_base + local].kinetic = acc.kinetic;
        }
    }
    for (var base = slots; base < width; base += slots) {
        workgroupBarrier();
        if local >= base && local < base + slots {
            let at = reduction_base + local - base;
            if whole {
                wg_sums[at] = combine(wg_sums[at], acc);
            } else {
                wg_sums[at].kinetic = wg_sums[at].kinetic + acc.kinetic;
            }
        }
    }
    reduce_workgroup(local, slots, whole);
}

// Thread 0 of a workgroup whose wg_sums[0] holds due sample e's sums (the
// persistent kernel's): writes them, and decides the fast interface
// cadence for the samples after it (the host's rule,
// runner::outputs::Outputs::emit_sample).
fn finish_sample(e: RecordEntry) {
    var out = wg_sums[reduction_base];
    out.recorded = 1u;
    out.interface_row = select(0u, 1u, interface_due(e));
    let fast = plans[scene].every_fast != 0u && out.max_slip_speed > plans[scene].fast_slip_speed;
    out.fast = select(0u, 1u, fast);
    sums[sums_slot(e)] = out;
    plans[scene].fast = out.fast;
}
