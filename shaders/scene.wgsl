// The scenes a dispatch steps: workgroup row z steps scene z. One scene is
// an ensemble of one: a solo run and an ensemble run the same module and
// the same code, so a scene's bits never depend on how many scenes ran
// beside it (a separate solo module with uniform constants compiled to
// other bits on NVIDIA). Each scene has its own constants
// and batch (its loads, seed, friction, prestress) and its own slice of
// every state buffer, scene-major: scene s's block i is at s·n_blocks + i.
// The block flags are shared (one lattice). Private copies of the scene's
// constants and batch keep the phase functions the same as for one scene;
// they are not uniform to the uniformity analysis, so the kernels with
// barriers take their loop bounds through workgroupUniformLoad.
// CPU twin: src/engines/gpu/layout.rs GpuConsts, GpuBatch (one of each per scene).
// import: (none)

@group(0) @binding(0) var<storage, read> scene_consts: array<Consts>;
@group(1) @binding(1) var<storage, read> scene_batches: array<Batch>;

var<private> c: Consts;
var<private> batch: Batch;
var<private> scene: u32;

fn enter_scene(s: u32) {
    enter_scene_consts(s);
    batch = scene_batches[s];
}

// The output kernels read a scene's constants and state, not its batch.
fn enter_scene_consts(s: u32) {
    scene = s;
    c = scene_consts[s];
}

fn block_base() -> u32 {
    return scene * c.n_blocks;
}

fn interface_base() -> u32 {
    return scene * c.nx;
}

fn junction_base() -> u32 {
    return scene * c.nx * c.junction_count;
}

fn lane_base() -> u32 {
    return scene * c.nx * min(JUNCTION_LANES, c.junction_count);
}

// A scene's status words start here; STATUS_WORDS and each word's
// STATUS_<FIELD> come from GpuStatus (layout.rs wgsl_prelude).
fn status_base() -> u32 {
    return scene * STATUS_WORDS;
}
