// Block state of the one-step kernel: two copies of u and v; step n reads
// one and writes step n+1 to the other (ping-pong), so no block waits for
// another. Which copy holds step n follows from the batch's starting copy
// and the step offset (one bind group for all dispatches, see common.wgsl).
// CPU twin: src/engines/gpu/buffers.rs state_group (the host side of these bindings).
// import: common, scene, state_by_index

// Both copies of u (and of v) in one array each, the second half way
// along (the host pads each to its storage offset alignment): the copy a
// step reads is an index, not a branch between two bindings, so a block's
// neighbours' loads are not split by it (bulk_forces.wgsl,
// NEIGHBOURS_WITHOUT_BRANCHES).
@group(0) @binding(1) var<storage, read_write> disp_copies: array<Disp>;
@group(0) @binding(2) var<storage, read_write> vel_copies: array<vec2<real>>;

fn reads_b() -> bool {
    return ((batch.parity + step_offset) & 1u) == 1u;
}

// Block i of this scene in the disp copy (b: the second) and the vel copy.
fn disp_slot(b: bool, i: u32) -> u32 {
    return select(0u, arrayLength(&disp_copies) / 2u, b) + block_base() + i;
}

fn vel_slot(b: bool, i: u32) -> u32 {
    return select(0u, arrayLength(&vel_copies) / 2u, b) + block_base() + i;
}

fn load_disp(i: u32) -> Disp {
    return disp_copies[disp_slot(reads_b(), i)];
}

fn load_vel(i: u32) -> vec2<real> {
    return vel_copies[vel_slot(reads_b(), i)];
}

fn store_block(i: u32, u: Disp, v: vec2<real>) {
    let b = !reads_b();
    disp_copies[disp_slot(b, i)] = u;
    vel_copies[vel_slot(b, i)] = v;
}
