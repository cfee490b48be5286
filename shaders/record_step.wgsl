// The one-step kernels' recording variant (STEP_RECORDS, set on its
// pipeline only; the engine dispatches it for the steps of a batch's output
// samples): the step dispatch of a sample also sums its workgroup's part
// of the sample, from the state it reads (u(s), v(s−½)) and the forces,
// friction and junction states of s it computes, into the sample's partial
// of that workgroup (record_batch.wgsl), and writes its blocks' interface
// row and bulk field where planned. So no output dispatch follows a
// sample's step: record_batch_finish adds the partials once a batch.
// Which planned samples are due the host decides as it reads the batch
// back (recorder.rs fast_rule), but a planned sample of the fast cadence
// alone, which in a stick phase is most of them, is computed only where
// the fast chain says it may be due (step_sample_computed): every
// workgroup of a sample's step reads what the sample before left, the
// same words, and so takes the same decision. Its rule is the host's, with
// each due sample's max slip speed compared as the order bits of its f32
// rounding (plan.fast_bits): exact in mixed precision, and in f64 letting
// through at most a few samples more than are due (their rows are written
// and not read). Partial 0 of a sample says whether it was computed.
// CPU twin: src/engines/sample.rs record_sample.
// import: common, patch_items, record_batch, record_buffers, record_common, scene, state

override STEP_RECORDS: bool = false;

// Thread 0's decision for its workgroup (step_sample_computed).
var<workgroup> wg_sample_computed: u32;

// The batch's sample at each step offset (an index into record_entries;
// only the recording variant's steps read it).
@group(0) @binding(26) var<storage, read> step_samples: array<u32>;

// The sample of this dispatch's step.
fn step_sample() -> RecordEntry {
    return record_entries[step_samples[step_offset]];
}

// Whether a sample whose max slip speed has the order bits `bits` (of its
// f32 rounding) may have slipped faster than the plan's threshold.
fn fast_chain_may_be_fast(bits: u32) -> bool {
    return plans[scene].every_fast != 0u && bits >= plans[scene].fast_bits;
}

// Whether sample e (its ordinal n mod 6: e.ring) may be due: its fixed
// cadences, or its fast one while the flag after sample n − 1 is on. That
// flag is sample n − 1's speed if it was computed (its step has finished:
// its max is whole), else the flag after sample n − 2, which sample
// n − 1's step wrote. `writer` (one thread of the scene's dispatch) writes
// the flag after n − 1 and n's decision, and clears the max of n + 1: no
// slot this step reads (the rings' sizes, layout.rs FAST_CHAIN_*).
fn fast_chain_due(e: RecordEntry, writer: bool) -> bool {
    let n = e.ring;
    let flag_before = atomicLoad(&plans[scene].fast_chain[FAST_CHAIN_FLAG + n % 2u]);
    let due_before = atomicLoad(&plans[scene].fast_chain[FAST_CHAIN_DUE + (n + 1u) % 2u]);
    let max_before = atomicLoad(&plans[scene].fast_chain[FAST_CHAIN_MAX + (n + 2u) % 3u]);
    var fast = flag_before != 0u;
    if due_before != 0u {
        fast = fast_chain_may_be_fast(max_before);
    }
    let due = (e.channels & RECORD_FIXED) != 0u || ((e.channels & RECORD_FAST) != 0u && fast);
    if writer {
        atomicStore(&plans[scene].fast_chain[FAST_CHAIN_FLAG + (n + 1u) % 2u], select(0u, 1u, fast));
        atomicStore(&plans[scene].fast_chain[FAST_CHAIN_DUE + n % 2u], select(0u, 1u, due));
        atomicStore(&plans[scene].fast_chain[FAST_CHAIN_MAX + (n + 1u) % 3u], 0u);
    }
    return due;
}

// Whether workgroup g computes this step's sample (fast_chain_due),
// uniform across it: thread 0 decides, the others wait for it.
// Uniform control flow only.
fn step_sample_computed(local: u32, g: u32) -> bool {
    if local == 0u {
        wg_sample_computed = select(0u, 1u, fast_chain_due(step_sample(), g == 0u));
    }
    return workgroupUniformLoad(&wg_sample_computed) != 0u;
}

// A sample this step does not compute: partial 0 says so, for
// record_batch_finish (workgroup 0's thread 0 writes it).
fn mark_step_skipped(local: u32, g: u32, e: RecordEntry) {
    if local == 0u && g == 0u {
        sums[batch_partial_slot(e, 0u)] = no_sums();
    }
}

// Block i's part of this step's sample, from the state the step read and
// its force `f` and friction at the step (its normal force, on the
// interface, from `contact`, which the step wrote or a snapshot did).
fn step_block_sample(i: u32, e: RecordEntry, f: vec2<real>, friction: real) -> SampleSums {
    var normal = real(0.0);
    if i < c.nx {
        normal = contact[interface_base() + i].y;
    }
    return block_sample(i, e, flags[i], load_disp(i), load_vel(i), f, friction, normal, interface_planned(e));
}

// Whether a workgroup whose threads hold items first .. first + WORKGROUP − 1
// (blocks, or with `patches` the items of patch_items.wgsl) may hold a
// block that adds more than its kinetic energy to a sample: an interface
// block, the driven block, or with a top drive a block of the top row
// (block_sample). Every thread computes the same answer; a
// workgroup past the lattice's last item may answer true, which costs only
// time.
fn items_add_more_than_kinetic(first: u32, patches: bool) -> bool {
    let last = first + (WORKGROUP - 1u);
    let driven = plans[scene].driven_block;
    var holds_driven = false;
    if driven < c.n_blocks {
        let item = item_of_block(driven, c.nx, patches);
        holds_driven = item >= first && item <= last;
    }
    let top = plans[scene].top_reaction != 0u && last >= item_of_block(c.n_blocks - c.nx, c.nx, patches);
    return first < c.nx || holds_driven || top;
}

// step_block_sample of interface block i whose junction tally is given
// (interface_tally's; one_step_lanes' lanes add it side by side).
fn step_block_sample_tallied(i: u32, e: RecordEntry, f: vec2<real>, friction: real, tally: vec2<u32>) -> SampleSums {
    let normal = contact[interface_base() + i].y;
    return block_sample_tallied(i, e, flags[i], load_disp(i), load_vel(i), f, friction, normal, interface_planned(e), tally);
}

// Workgroup g's partial of this step's sample: its threads' parts reduced
// in a fixed tree (the same bits every run); `whole` false (a workgroup of
// blocks that add only their kinetic energy): that alone, by the same
// tree. Marked computed (`recorded`), and its max slip speed added to the
// sample's in the fast chain. Uniform control flow only.
fn write_step_partial(local: u32, g: u32, e: RecordEntry, part: SampleSums, whole: bool) {
    reduce_threads(local, WORKGROUP, part, whole);
    if local == 0u && g < plans[scene].partials {
        var partial = wg_sums[0];
        partial.recorded = 1u;
        sums[batch_partial_slot(e, g)] = partial;
        if whole {
            let bits = bitcast<u32>(f32(partial.max_slip_speed));
            atomicMax(&plans[scene].fast_chain[FAST_CHAIN_MAX + e.ring % 3u], bits);
        }
    }
}
