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
// partials. Where the step dispatch summed the partials' kinetic energy
// (record_kinetic.wgsl), record_special replaces record_sample and writes
// only the partials with other sums. The sample's sums also decide the fast interface cadence for
// the next samples. Workgroup row z of every dispatch records scene z (all
// scenes of an ensemble at once, in their own regions of the buffers).
// The shared part is record_common.wgsl. CPU twin: src/engines/sample.rs record_sample.
// import: coordinates, patch_items, record_buffers, record_common, scene

@group(0) @binding(1) var<storage, read> disp_a: array<Disp>;
@group(0) @binding(2) var<storage, read> vel_a: array<vec2<real>>;
@group(0) @binding(3) var<storage, read> disp_b: array<Disp>;
@group(0) @binding(4) var<storage, read> vel_b: array<vec2<real>>;
@group(0) @binding(5) var<storage, read> force: array<vec2<real>>;
@group(0) @binding(6) var<storage, read> flags: array<u32>;
@group(0) @binding(7) var<storage, read> contact: array<vec2<real>>;
@group(0) @binding(9) var<storage, read> junction_state: array<vec2<u32>>;
@group(0) @binding(10) var<storage, read> slide: array<vec2<i32>>;
@group(1) @binding(0) var<storage, read> entry: RecordEntry;

// Threads of the one-workgroup entry points: a power of two, at most 256
// (software adapters run a workgroup on one core, where fewer threads,
// with fewer barrier switches, are faster).
override RECORD_THREADS: u32 = 256u;

// What block_sample reads of a block's state, forces and flags.
struct BlockInputs {
    u: Disp,
    v_half: vec2<real>,
    f: vec2<real>,
    contact: vec2<real>,
    fl: u32,
}

// Block i's inputs at the sample the entry names, from the copy it names.
fn inputs_of_entry(i: u32) -> BlockInputs {
    var x: BlockInputs;
    let b = block_base() + i;
    if entry.copy == 1u {
        x.u = disp_b[b];
        x.v_half = vel_b[b];
    } else {
        x.u = disp_a[b];
        x.v_half = vel_a[b];
    }
    x.f = force[b];
    x.fl = flags[i];
    if i < c.nx {
        x.contact = contact[interface_base() + i];
    }
    return x;
}

fn sample_of(i: u32, x: BlockInputs) -> SampleSums {
    return block_sample(i, entry, x.fl, x.u, x.v_half, x.f, x.contact.x, x.contact.y, interface_due(entry));
}

// Block i of the sample the entry names.
fn block_of_entry(i: u32) -> SampleSums {
    return sample_of(i, inputs_of_entry(i));
}

// Whether the sample is due, made uniform across the workgroup (thread 0
// reads the fast flag).
fn begin_sample(local: u32) -> bool {
    if local == 0u {
        wg_go = select(0u, 1u, sample_due(entry));
    }
    return workgroupUniformLoad(&wg_go) != 0u;
}

// The one-workgroup entry points (record_small, record_finish) begin
// alike: a sample that is not due is marked unrecorded.
fn begin_whole_sample(local: u32) -> bool {
    if !begin_sample(local) {
        if local == 0u {
            sums[sums_slot(entry)].recorded = 0u;
        }
        return false;
    }
    return true;
}

// ... and end alike: each thread's sums reduced across the workgroup,
// then the sample written.
fn end_whole_sample(local: u32, s: SampleSums) {
    wg_sums[local] = s;
    reduce_workgroup(local, RECORD_THREADS);
    if local == 0u {
        finish_sample(entry);
    }
}

// Lattices of up to RECORD_SMALL_BLOCKS blocks: the whole sample in one
// dispatch of one workgroup.
@compute @workgroup_size(RECORD_THREADS)
fn record_small(
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
) {
    enter_scene_consts(wid.z);
    if !begin_whole_sample(local) {
        return;
    }
    // Four blocks' inputs loaded before any is used, then added in the
    // same order as one at a time: each thread walks n/RECORD_THREADS
    // blocks, and a block at a time made that a chain of memory round
    // trips (seven at 57×31), this dispatch's length on hardware.
    var s = no_sums();
    let stride = RECORD_THREADS;
    var i = local;
    for (; i + 3u * stride < c.n_blocks; i += 4u * stride) {
        let x0 = inputs_of_entry(i);
        let x1 = inputs_of_entry(i + stride);
        let x2 = inputs_of_entry(i + 2u * stride);
        let x3 = inputs_of_entry(i + 3u * stride);
        s = combine(s, sample_of(i, x0));
        s = combine(s, sample_of(i + stride, x1));
        s = combine(s, sample_of(i + 2u * stride, x2));
        s = combine(s, sample_of(i + 3u * stride, x3));
    }
    for (; i < c.n_blocks; i += stride) {
        s = combine(s, block_of_entry(i));
    }
    end_whole_sample(local, s);
}

// Whether workgroup g of record_sample has a part in the sample: it is
// due and g holds blocks (a lattice past 65535 partials dispatches a few
// workgroups more), made uniform across the workgroup.
fn in_sample(local: u32, g: u32) -> bool {
    if local == 0u {
        wg_go = select(0u, 1u, sample_due(entry) && g < plans[scene].partials);
    }
    return workgroupUniformLoad(&wg_go) != 0u;
}

// Larger lattices, first dispatch (where the step did not sum the kinetic
// energy, or a bulk field is due): a thread per block, a partial per
// workgroup.
@compute @workgroup_size(WORKGROUP)
fn record_sample(
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let g = wid.x + wid.y * groups.x;
    enter_scene_consts(wid.z);
    if !in_sample(local, g) {
        return;
    }
    write_partial(local, g);
}

// Partial g of the sample: every sum of its blocks, reduced across the
// workgroup (a thread per block; where the one-step kernels step by
// patches, a thread per item of theirs, as their partials hold).
fn write_partial(local: u32, g: u32) {
    let t = g * WORKGROUP + local;
    var s = no_sums();
    if plans[scene].partials_by_patches != 0u {
        s = item_of_entry(t);
    } else if t < c.n_blocks {
        s = block_of_entry(t);
    }
    wg_sums[local] = s;
    reduce_workgroup(local, WORKGROUP);
    if local == 0u {
        sums[plans[scene].partials_offset + g] = wg_sums[0];
    }
}

// Item t of patch_items.wgsl: interface block t, or the blocks of a 2×2
// patch in patch order (a, b, c, d), as step_by_patches sums their
// kinetic energy.
fn item_of_entry(t: u32) -> SampleSums {
    if t < c.nx {
        return block_of_entry(t);
    }
    let origin = patch_item_origin(t, c.nx);
    if origin.y >= c.nz {
        return no_sums();
    }
    let i = origin.y * c.nx + origin.x;
    let has_b = origin.x + 1u < c.nx;
    var s = block_of_entry(i);
    if has_b {
        s = combine(s, block_of_entry(i + 1u));
    }
    if origin.y + 1u < c.nz {
        s = combine(s, block_of_entry(i + c.nx));
        if has_b {
            s = combine(s, block_of_entry(i + c.nx + 1u));
        }
    }
    return s;
}

// The partials that hold blocks adding more than kinetic energy (the
// interface, the top row where the top reaction is summed, the driven
// block), in increasing order (src/engines/gpu/recorder.rs).
@group(0) @binding(18) var<storage, read> special_groups: array<u32>;

// Larger lattices whose sample's step dispatch summed each partial's
// kinetic energy (the one-step kernels' RECORD_KINETIC variant), when no
// bulk field is due, first dispatch: only the partials of special_groups,
// a workgroup each, with all their sums. The others are the step's.
@compute @workgroup_size(WORKGROUP)
fn record_special(
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
) {
    enter_scene_consts(wid.z);
    if !begin_sample(local) {
        return;
    }
    write_partial(local, special_groups[wid.x]);
}

// Larger lattices, second dispatch: one workgroup adds the partials.
@compute @workgroup_size(RECORD_THREADS)
fn record_finish(
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
) {
    enter_scene_consts(wid.z);
    if !begin_whole_sample(local) {
        return;
    }
    var s = no_sums();
    let partials = plans[scene].partials;
    let at = plans[scene].partials_offset;
    // Eight partials loaded before their combines (in the same order):
    // one thread's chain of storage round trips was this dispatch's length.
    let stride = RECORD_THREADS;
    var g = local;
    for (; g + 7u * stride < partials; g += 8u * stride) {
        let p0 = sums[at + g];
        let p1 = sums[at + g + stride];
        let p2 = sums[at + g + 2u * stride];
        let p3 = sums[at + g + 3u * stride];
        let p4 = sums[at + g + 4u * stride];
        let p5 = sums[at + g + 5u * stride];
        let p6 = sums[at + g + 6u * stride];
        let p7 = sums[at + g + 7u * stride];
        s = combine(combine(combine(combine(s, p0), p1), p2), p3);
        s = combine(combine(combine(combine(s, p4), p5), p6), p7);
    }
    for (; g < partials; g += stride) {
        s = combine(s, sums[at + g]);
    }
    end_whole_sample(local, s);
}
