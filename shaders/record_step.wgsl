// The one-step kernels' recording variant (STEP_RECORDS, set on its
// pipeline only; the engine dispatches it for the steps of a batch's output
// samples): the step dispatch of a sample also sums its workgroup's part
// of the sample, from the state it reads (u(s), v(s−½)) and the forces,
// friction and junction states of s it computes, into the sample's partial
// of that workgroup (record_batch.wgsl), and writes its blocks' interface
// row and bulk field where planned. So no output dispatch follows a
// sample's step: record_batch_finish adds the partials once a batch.
// A planned fast-cadence row is written whether the cadence turns out on
// or not (interface_planned): the samples before it decide that, and the
// host applies the rule as it reads the batch back.
// CPU twin: src/engines/sample.rs record_sample.
// import: common, patch_items, record_batch, record_buffers, record_common, scene, state

override STEP_RECORDS: bool = false;

// The batch's sample at each step offset (an index into record_entries;
// only the recording variant's steps read it).
@group(0) @binding(26) var<storage, read> step_samples: array<u32>;

// The sample of this dispatch's step.
fn step_sample() -> RecordEntry {
    return record_entries[step_samples[step_offset]];
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
// tree. Uniform control flow only.
fn write_step_partial(local: u32, g: u32, e: RecordEntry, part: SampleSums, whole: bool) {
    reduce_threads(local, WORKGROUP, part, whole);
    if local == 0u && g < plans[scene].partials {
        sums[batch_partial_slot(e, g)] = wg_sums[0];
    }
}
