// Many scenes of one lattice shape per dispatch (an ensemble): workgroup
// row z of the dispatch steps scene z. Each scene has its own constants
// and batch (its loads, seed, friction, prestress) and its own slice of
// every state buffer, scene-major: scene s's block i is at s·n_blocks + i.
// The block flags are shared (one lattice). Private copies of the scene's
// constants and batch keep the phase functions the same as for one scene;
// they are not uniform to the uniformity analysis, so the kernels with
// barriers take their loop bounds through workgroupUniformLoad.
// CPU twin: src/engines/gpu/layout.rs GpuConsts, GpuBatch (one of each per scene).
// import: common

@group(0) @binding(0) var<storage, read> scene_consts: array<Consts>;
@group(1) @binding(1) var<storage, read> scene_batches: array<Batch>;

var<private> c: Consts;
var<private> batch: Batch;
var<private> scene: u32;

fn enter_scene(s: u32) {
    scene = s;
    c = scene_consts[s];
    batch = scene_batches[s];
}

// A scene that blew up is left as it is (its status keeps the first
// blow-up) while the others go on.
fn scene_stopped() -> bool {
    return atomicLoad(&status[status_base()]) != 0u;
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

fn status_base() -> u32 {
    return scene * 8u;
}
