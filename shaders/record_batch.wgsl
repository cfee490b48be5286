// A batch's output samples when the step kernels record them in their
// steps (the one-step kernels' recording variant, record_step.wgsl, and
// the tiled kernel): each workgroup of a sample's step writes a partial of
// its own, and no sample ends a dispatch. After the batch's steps,
// record_batch_finish adds each sample's partials. Which samples were due
// (the fast cadence's rule, a chain from sample to sample) the host
// decides as it reads them back (src/engines/gpu/recorder.rs fast_rule);
// the tiled kernel computes every planned sample, the one-step kernels
// those their fast chain says may be due (record_step.wgsl), and a sample's
// `recorded` says whether it was computed. The entries are the batch's
// samples in step order; sample k's partial g is
// sums[plans[scene].partials_offset + k · plans[scene].partials + g].
// CPU twin: src/engines/sample.rs record_sample.
// import: common, record_buffers, record_common, scene

@group(0) @binding(25) var<storage, read> record_entries: array<RecordEntry>;

const RECORD_BATCH_THREADS: u32 = 64u;

// Where sample `e`'s partial g goes.
fn batch_partial_slot(e: RecordEntry, g: u32) -> u32 {
    return plans[scene].partials_offset + e.sums_slot * plans[scene].partials + g;
}

// After a batch's step dispatches, a workgroup per sample and scene
// (workgroup (k, 0, z): sample k of scene z): each thread adds a fixed run
// of the sample's partials in order, eight loaded before their combines,
// and the workgroup reduces the threads' sums in a fixed tree (the same
// order every run: the same bits solo or in an ensemble). The samples run
// side by side, and a sample's partials are read by all its threads at
// once: a thread's chain of storage round trips is this dispatch's length.
@compute @workgroup_size(RECORD_BATCH_THREADS)
fn record_batch_finish(
    @builtin(local_invocation_index) t: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
) {
    enter_scene(wid.z);
    // The host dispatches a workgroup per sample of the batch.
    let k = min(wid.x, max(batch.records, 1u) - 1u);
    let e = record_entries[k];
    let partials = plans[scene].partials;
    let at = batch_partial_slot(e, 0u);
    // Partial 0 of a sample the one-step kernels skipped says so: the
    // others were not written.
    let computed = plans[scene].step_chain == 0u || sums[at].recorded != 0u;
    let first = t * partials / RECORD_BATCH_THREADS;
    var end = (t + 1u) * partials / RECORD_BATCH_THREADS;
    if !computed {
        end = first;
    }
    var total = no_sums();
    var g = first;
    for (; g + 8u <= end; g += 8u) {
        let p0 = sums[at + g];
        let p1 = sums[at + g + 1u];
        let p2 = sums[at + g + 2u];
        let p3 = sums[at + g + 3u];
        let p4 = sums[at + g + 4u];
        let p5 = sums[at + g + 5u];
        let p6 = sums[at + g + 6u];
        let p7 = sums[at + g + 7u];
        total = combine(combine(combine(combine(total, p0), p1), p2), p3);
        total = combine(combine(combine(combine(total, p4), p5), p6), p7);
    }
    for (; g < end; g++) {
        total = combine(total, sums[at + g]);
    }
    reduce_threads(t, RECORD_BATCH_THREADS, total, true);
    if t == 0u && wid.x < batch.records {
        var out = wg_sums[0];
        out.recorded = select(0u, 1u, computed);
        sums[sums_slot(e)] = out;
    }
}
