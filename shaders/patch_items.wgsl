// The one-step kernels' patched layout of threads (step_patches.wgsl),
// whose workgroups' sample partials follow it (record_step.wgsl): item t
// below nx is interface block t; item nx + p is the 2×2 patch p of the
// rows above the interface, ⌈nx/2⌉ patches a row from row 1 up (an even
// row count leaves the top row in half patches).
// CPU twin: src/engines/gpu/step_kernel.rs patch_item_origin, item_of_block.
// import: (none)

// The first block (column, row) of patch item t ≥ nx of a lattice nx wide;
// its row is nz or more past the last patch.
fn patch_item_origin(t: u32, nx: u32) -> vec2<u32> {
    let columns = (nx + 1u) / 2u;
    let p = t - nx;
    return vec2<u32>(2u * (p % columns), 1u + 2u * (p / columns));
}

// The item that holds block i (column i mod nx, row i / nx): the block
// itself, or with `patches` its interface item or its patch's.
fn item_of_block(i: u32, nx: u32, patches: bool) -> u32 {
    if !patches || i < nx {
        return i;
    }
    let columns = (nx + 1u) / 2u;
    return nx + ((i / nx - 1u) / 2u) * columns + (i % nx) / 2u;
}
