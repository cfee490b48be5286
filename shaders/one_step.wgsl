// One step n → n+1 of every block in one dispatch, one thread per block:
// the forces and friction at step n (an interface block's thread walks its
// junction lanes in order), then the leapfrog update written to the other
// state buffer. Workgroup row z is scene z of an ensemble. No barrier, so software adapters run it without
// coroutines. CPU twin: src/engines/cpu/mod.rs CpuEngine::one_step.
// The recording variant (RECORD_KINETIC, the step dispatch of an output
// sample on a lattice recorded in two dispatches) also sums its
// workgroup's kinetic energy at the sample's instant into the sample's
// partial g (record_kinetic.wgsl); the workgroup barriers of that sum
// are in that variant only.
// With BOND_PATCHES (GpuOptions::bond_patches) the threads step the
// interface row a block each and the rows above by 2×2 patches
// (step_patches.wgsl), and a workgroup's partial holds its threads' items.
// import: common, record_kinetic, scene, step_forces, step_patches, verlet

@compute @workgroup_size(WORKGROUP)
fn one_step(
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    enter_scene(wid.z);
    let g = wid.x + wid.y * groups.x;
    let i = g * WORKGROUP + local;
    var kinetic = real(0.0);
    if BOND_PATCHES {
        kinetic = step_by_patches(i);
    } else if i < c.n_blocks && !scene_stopped() {
        let ld = loads_at(step_offset);
        let ready = batch.forces_ready != 0u && step_offset == 0u;
        let ff = block_forces(i, ld, ready);
        if RECORD_KINETIC {
            kinetic = bulk_kinetic(i, load_vel(i), ff.xy);
        }
        if batch.forces_only == 0u {
            verlet(i, i % c.nx, i / c.nx, ff.xy, ff.z, ld, step_offset);
        }
    }
    if RECORD_KINETIC {
        let total = sum_kinetic(local, kinetic);
        if local == 0u && g < plans[scene].partials {
            write_kinetic_partial(g, total);
        }
    }
}
