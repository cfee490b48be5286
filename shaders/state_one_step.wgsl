// Block state of the one-step kernel: read step n from one buffer pair,
// write step n+1 to the other (ping-pong), so no block waits for another.

@group(0) @binding(1) var<storage, read> disp_in: array<Disp>;
@group(0) @binding(2) var<storage, read> vel_in: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> disp_out: array<Disp>;
@group(0) @binding(4) var<storage, read_write> vel_out: array<vec2<f32>>;

fn load_disp(i: u32) -> Disp {
    return disp_in[i];
}

fn load_vel(i: u32) -> vec2<f32> {
    return vel_in[i];
}

fn store_block(i: u32, u: Disp, v: vec2<f32>) {
    disp_out[i] = u;
    vel_out[i] = v;
}
