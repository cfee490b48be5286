// Block state of the one-step kernel: two copies of u and v; step n reads
// one and writes step n+1 to the other (ping-pong), so no block waits for
// another. Which copy holds step n follows from the batch's starting copy
// and the step offset (one bind group for all dispatches, see common.wgsl).
// CPU twin: src/engines/gpu/buffers.rs state_group (the host side of these bindings).
// import: common, scene, state_by_index

@group(0) @binding(1) var<storage, read_write> disp_a: array<Disp>;
@group(0) @binding(2) var<storage, read_write> vel_a: array<vec2<real>>;
@group(0) @binding(3) var<storage, read_write> disp_b: array<Disp>;
@group(0) @binding(4) var<storage, read_write> vel_b: array<vec2<real>>;

fn reads_b() -> bool {
    return ((batch.parity + step_offset) & 1u) == 1u;
}

fn load_disp(i: u32) -> Disp {
    if reads_b() {
        return disp_b[block_base() + i];
    }
    return disp_a[block_base() + i];
}

fn load_vel(i: u32) -> vec2<real> {
    if reads_b() {
        return vel_b[block_base() + i];
    }
    return vel_a[block_base() + i];
}

fn store_block(i: u32, u: Disp, v: vec2<real>) {
    if reads_b() {
        disp_a[block_base() + i] = u;
        vel_a[block_base() + i] = v;
    } else {
        disp_b[block_base() + i] = u;
        vel_b[block_base() + i] = v;
    }
}
