// Where a kernel keeps the junctions it steps (the `junction_store` slot):
// here, in the storage buffers, block ix's Ns junctions from
// junction_first(ix) on. The tiled kernel keeps its halo's copies apart
// (junction_tiled.wgsl); the junction phase (junctions.wgsl) reads and
// writes only through these functions.
// CPU twin: src/engines/gpu/buffers.rs gpu_junction_springs (the host side of this layout).
// import: common, scene

fn junction_first(ix: u32) -> u32 {
    return junction_base() + ix * c.junction_count;
}

fn junction_state_at(k: u32) -> vec2<u32> {
    return junction_state[k];
}

fn junction_spring_at(k: u32) -> JunctionSpring {
    return junction_spring[k];
}

fn set_junction_state(k: u32, state: vec2<u32>) {
    junction_state[k] = state;
}

fn set_junction_spring(k: u32, spring: JunctionSpring) {
    junction_spring[k] = spring;
}

// Where block ix's kept junction sums are (junction_cache): its scene's
// record. The tiled kernel's halo copies keep theirs apart.
fn junction_sums_slot(ix: u32) -> u32 {
    return interface_base() + ix;
}
