// Block state of the resident kernel: the persistent kernel's loop with
// the scene's u and v held in workgroup memory for the whole dispatch. The
// stencil of every step then reads on-chip memory, not storage (whose
// loads on one workgroup set the persistent kernel's pace). The state is
// loaded from the storage buffers at the dispatch's start and written back
// at its end, so between dispatches it is where the persistent kernel
// keeps it. RESIDENT_BLOCKS ≥ c.n_blocks: the host compiles it to the
// lattice, and takes this kernel only where the lattice fits the
// adapter's workgroup memory (options::resident_fit). Where u fits and u
// and v do not (f64 Table S1 on NVIDIA's 48 KB), v stays in storage as
// the persistent kernel keeps it (RESIDENT_VELOCITIES false): the same
// values, so the same bits.
// CPU twin: src/engines/gpu/buffers.rs state_group (the host side of these bindings).
// import: barriers, scene, state_by_index

@group(0) @binding(1) var<storage, read_write> disp: array<Disp>;
@group(0) @binding(2) var<storage, read_write> vel: array<vec2<real>>;
@group(0) @binding(12) var<storage, read_write> lane_partial: array<LaneSum>;

override RESIDENT_BLOCKS: u32 = 1u;
override RESIDENT_VELOCITIES: bool = true;
// RESIDENT_BLOCKS where v is held here, else 1 (unused).
override RESIDENT_VEL_BLOCKS: u32 = 1u;
var<workgroup> resident_disp: array<Disp, RESIDENT_BLOCKS>;
var<workgroup> resident_vel: array<vec2<real>, RESIDENT_VEL_BLOCKS>;

// The force phase walks the inner blocks first, without bounds
// (persistent.wgsl; state_persistent.wgsl says why not there).
const INNER_BLOCKS_FIRST: bool = true;

fn load_disp(i: u32) -> Disp {
    return resident_disp[i];
}

fn load_vel(i: u32) -> vec2<real> {
    if RESIDENT_VELOCITIES {
        return resident_vel[i];
    }
    return vel[block_base() + i];
}

fn store_block(i: u32, u: Disp, v: vec2<real>) {
    resident_disp[i] = u;
    if RESIDENT_VELOCITIES {
        resident_vel[i] = v;
    } else {
        vel[block_base() + i] = v;
    }
}

// Thread t of `threads` loads blocks t, t + threads, ...
fn state_enter(t: u32, threads: u32) {
    for (var i = t; i < c.n_blocks; i += threads) {
        resident_disp[i] = disp[block_base() + i];
        if RESIDENT_VELOCITIES {
            resident_vel[i] = vel[block_base() + i];
        }
    }
    workgroupBarrier();
}

fn state_leave(t: u32, threads: u32) {
    workgroupBarrier();
    for (var i = t; i < c.n_blocks; i += threads) {
        disp[block_base() + i] = resident_disp[i];
        if RESIDENT_VELOCITIES {
            vel[block_base() + i] = resident_vel[i];
        }
    }
}

// The lane sums and forces cross threads through storage, the blocks
// through workgroup memory.
fn state_barrier() {
    workgroup_storage_barrier();
    workgroupBarrier();
}
