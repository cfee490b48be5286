// Block state of the persistent kernel: one workgroup owns the whole
// lattice and separates the phases of a step with barriers, so it updates
// the state in place. lane_partial holds the junction lane sums between
// the force and the update phases.
// CPU twin: src/engines/gpu/buffers.rs state_group (the host side of these bindings).
// import: barriers, scene, state_by_index

@group(0) @binding(1) var<storage, read_write> disp: array<Disp>;
@group(0) @binding(2) var<storage, read_write> vel: array<vec2<real>>;
@group(0) @binding(12) var<storage, read_write> lane_partial: array<LaneSum>;

// The force phase walks the lattice in order, every block through the
// bounds-checked bulk_force: walking the inner blocks apart, the compiler
// hoists a block's eight neighbour loads from storage, and on RADV the
// kernel holds 72 registers a thread where it held 64 (112 for 88 in
// f64), which on NVIDIA may cost persistent/256 its second workgroup an
// SM. In workgroup memory (resident, tiled) the registers stay as they were.
const INNER_BLOCKS_FIRST: bool = false;

fn load_disp(i: u32) -> Disp {
    return disp[block_base() + i];
}

fn load_vel(i: u32) -> vec2<real> {
    return vel[block_base() + i];
}

fn store_block(i: u32, u: Disp, v: vec2<real>) {
    disp[block_base() + i] = u;
    vel[block_base() + i] = v;
}

// The state stays in storage: nothing to load or write back, and the
// phases of a step meet at a storage barrier.
fn state_enter(t: u32, threads: u32) {}

fn state_leave(t: u32, threads: u32) {}

fn state_barrier() {
    workgroup_storage_barrier();
}
