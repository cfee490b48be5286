// Loads and stores by column and row for the state slots indexed by block
// (one-step, persistent, resident): the block's index is all they need. The tiled
// kernel's slot finds its local slot from the column and row instead of
// dividing the index by nx (state_tiled.wgsl).
// CPU twin: src/engines/kernels/bulk_forces.rs bulk_force (its neighbours, by index).
// import: state

// Block j at column jx and row jz (j = jz·nx + jx): the bulk force's
// neighbours, the update's block and an interface block (row 0), whose
// column and row the caller has at hand.
fn load_disp_at(j: u32, jx: u32, jz: u32) -> Disp {
    return load_disp(j);
}

fn load_vel_at(j: u32, jx: u32, jz: u32) -> vec2<real> {
    return load_vel(j);
}

fn store_block_at(i: u32, ix: u32, iz: u32, u: Disp, v: vec2<real>) {
    store_block(i, u, v);
}
