// One scene per dispatch. The constants are a uniform block, bound once per
// submit: lavapipe inlines its contents (constant folding). Switching the
// bound group between dispatches made it compile and keep a variant per
// submit (2.7 MB each), so the one-step kernel keeps one group and picks
// its state copy from the step parity. Every buffer holds this one scene:
// its offsets are 0 (folded away).
// CPU twin: src/engines/gpu/layout.rs GpuConsts, GpuBatch (the host's layout).
// import: (none)

@group(0) @binding(0) var<uniform> c: Consts;
@group(1) @binding(1) var<storage, read> batch: Batch;

fn enter_scene(scene: u32) {}

// A blown-up scene stops the whole run on the host: nothing to skip here.
fn scene_stopped() -> bool {
    return false;
}

fn block_base() -> u32 {
    return 0u;
}

fn interface_base() -> u32 {
    return 0u;
}

fn junction_base() -> u32 {
    return 0u;
}

fn lane_base() -> u32 {
    return 0u;
}

fn status_base() -> u32 {
    return 0u;
}
