// One step n → n+1 of every block in one dispatch, one thread per block:
// the forces and friction at step n (an interface block's thread walks its
// junction lanes in order), then the leapfrog update written to the other
// state buffer. Workgroup row z is scene z of an ensemble. No barrier, so software adapters run it without
// coroutines. CPU twin: src/engines/cpu/mod.rs CpuEngine::one_step.
// import: common, scene, step_forces, verlet

@compute @workgroup_size(WORKGROUP)
fn one_step(
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    enter_scene(wid.z);
    let i = (wid.x + wid.y * groups.x) * WORKGROUP + local;
    if i >= c.n_blocks || scene_stopped() {
        return;
    }
    let ld = loads_at(step_offset);
    let ready = batch.forces_ready != 0u && step_offset == 0u;
    let ff = block_forces(i, ld, ready);
    if batch.forces_only == 0u {
        verlet(i, ff.xy, ff.z, ld, step_offset);
    }
}
