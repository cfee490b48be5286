// Shared by every phase: the run constants, the loads of the current step,
// and the state buffers. Layout mirrors src/gpu/layout.rs and the CPU twins.

struct Consts {
    nx: u32,
    nz: u32,
    junction_count: u32,
    seed: u32,
    spacing: f32,
    k: f32,
    eta: f32,
    k_foundation: f32,
    mass: f32,
    inv_mass: f32,
    dt: f32,
    mu_s: f32,
    mu_d: f32,
    junction_stiffness_value: f32,
    slip_mean_steps: f32,
    slip_std_steps: f32,
    drive_stiffness: f32,
    speed_limit: f32,
    top_share_full: f32,
    top_share_edge: f32,
    stiffness_normal_load: u32,
    n_blocks: u32,
    // Runtime 1.0: see double_single.wgsl.
    one: f32,
    _pad1: u32,
}

// The loads of one step: src/step_params.rs computes them on the host.
// drive_target_hi/lo: where the side spring's far end is (drive origin +
// V t), a double-single coordinate. No step count: junctions count their
// own slip steps down, so nothing on the device wraps in long runs.
struct StepLoads {
    preparing: u32,
    normal_total: f32,
    top_tangential_total: f32,
    relax_eta: f32,
    top_velocity: f32,
    drive_target_hi: f32,
    drive_target_lo: f32,
    _pad: u32,
}

// Per block: (hi, lo) of u_x and of u_z.
struct Disp {
    x: vec2<f32>,
    z: vec2<f32>,
}

// Per junction: the anchor as a double-single coordinate, and the
// stiffness taken when it pinned (src/cpu/junctions.rs JunctionSpring).
struct JunctionSpring {
    anchor_hi: f32,
    anchor_lo: f32,
    stiffness: f32,
}

const PINNED: u32 = 0xffffffffu;
const FLAG_FIX_X: u32 = 1u;
const FLAG_FIX_Z: u32 = 2u;
const FLAG_TOP: u32 = 4u;
const FLAG_INTERFACE: u32 = 8u;
const FLAG_DRIVEN: u32 = 16u;
const FLAG_PRESCRIBED_X: u32 = 32u;
const WORKGROUP: u32 = 64u;

@group(0) @binding(0) var<uniform> c: Consts;
@group(0) @binding(1) var<storage, read_write> disp: array<Disp>;
@group(0) @binding(2) var<storage, read_write> vel: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> force: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read_write> flags: array<u32>;
// (friction along x, normal force) per interface block.
@group(0) @binding(5) var<storage, read_write> contact: array<vec2<f32>>;
// Index ix * Ns + j.
@group(0) @binding(6) var<storage, read_write> junction_spring: array<JunctionSpring>;
// (slip steps left or PINNED, rupture count) per junction.
@group(0) @binding(7) var<storage, read_write> junction_state: array<vec2<u32>>;
// (sliding direction 0/±1, stick → slip count) per interface block.
@group(0) @binding(8) var<storage, read_write> slide: array<vec2<i32>>;
// A storage binding, not a uniform: lavapipe specialises shaders on uniform
// contents and would recompile (and keep) a variant for every step.
@group(1) @binding(0) var<storage, read> sp: StepLoads;

// Linear thread index over a 2D grid of workgroups (large lattices need
// more than 65535 workgroups along x).
fn thread_index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * WORKGROUP;
}

fn foundation_normal(uz: f32) -> f32 {
    return c.k_foundation * max(-uz, 0.0);
}
