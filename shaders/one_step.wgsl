// One step n → n+1 of every block in one dispatch, one thread per block:
// the forces and friction at step n (an interface block's thread walks its
// junction lanes in order), then the leapfrog update written to the other
// state buffer. Workgroup row z is scene z of an ensemble. No barrier, so software adapters run it without
// coroutines. CPU twin: src/engines/cpu/mod.rs CpuEngine::one_step.
// The recording variant (STEP_RECORDS, the step dispatch of an output
// sample) also sums its workgroup's part of the sample into the sample's
// partial g (record_step.wgsl), where the sample may be due (its fast
// chain); the workgroup barriers of that sum and of that decision are in
// that variant only.
// With BOND_PATCHES (GpuOptions::bond_patches) the threads step the
// interface row a block each and the rows above by 2×2 patches
// (step_patches.wgsl), and a workgroup's partial holds its threads' items.
// import: common, record_batch, record_common, record_step, scene, step_forces, step_patches, verlet

@compute @workgroup_size(WORKGROUP)
fn one_step(
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    enter_scene(wid.z);
    let g = wid.x + wid.y * groups.x;
    let i = g * WORKGROUP + local;
    var computed = false;
    if STEP_RECORDS {
        computed = step_sample_computed(local, g);
    }
    var part = no_sums();
    if BOND_PATCHES {
        part = step_by_patches(i, computed);
    } else if i < c.n_blocks && !scene_stopped() {
        let ld = loads_at(step_offset);
        let ready = batch.forces_ready != 0u && step_offset == 0u;
        let ff = block_forces(i, ld, ready);
        if computed {
            part = step_block_sample(i, step_sample(), ff.xy, ff.z);
        }
        if batch.forces_only == 0u {
            verlet(i, i % c.nx, i / c.nx, ff.xy, ff.z, ld, step_offset);
        }
    }
    if STEP_RECORDS {
        if computed {
            write_step_partial(local, g, step_sample(), part, items_add_more_than_kinetic(g * WORKGROUP, BOND_PATCHES));
        } else {
            mark_step_skipped(local, g, step_sample());
        }
    }
}
