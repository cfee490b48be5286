// Where a kernel keeps the junctions it steps (the `junction_store` slot):
// here, block ix's Ns junctions from junction_first(ix) on in the
// junction arrays (read and written through junction_state_at and its
// kin, common.wgsl). The tiled kernel keeps its halo's copies in the
// arrays' tail (junction_tiled.wgsl).
// CPU twin: src/engines/gpu/buffers.rs gpu_junction_springs (the host side of this layout).
// import: common, scene

fn junction_first(ix: u32) -> u32 {
    return junction_base() + ix * c.junction_count;
}

// Where block ix's kept junction sums are (junction_cache): its scene's
// record. The tiled kernel's halo copies keep theirs apart.
fn junction_sums_slot(ix: u32) -> u32 {
    return interface_base() + ix;
}
