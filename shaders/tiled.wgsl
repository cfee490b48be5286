// Temporal blocking: up to TILE_HALO steps of a small lattice per
// dispatch, spread over a workgroup per column tile (not one per scene as
// the persistent kernel). Workgroup (tile, scene) holds its columns and a
// halo of TILE_HALO columns each side (state_tiled.wgsl) and steps them
// all; the columns it can still step shrink by one each side a step
// (a block's update needs its neighbours' state at the step before), so
// after K ≤ TILE_HALO steps its own columns are exact, and only those are
// written back. No barrier crosses workgroups, so the tiles run on many
// SMs at once, and a dispatch costs per K steps, not per step.
// - A halo block's junctions are stepped from a private copy
//   (junction_tiled.wgsl): their updates depend only on the block's u_x
//   and their state, and the slip draws are keyed by (seed, block,
//   junction, count), so the copy evolves as its owner's original does.
// - tile_gather, the dispatch before each, copies every tile's halo
//   (blocks, and interface junctions) out of the state its neighbours are
//   about to overwrite.
// - Where a dispatch ends (tile_dispatch_end, the host's
//   tiles::dispatch_end): after TILE_HALO steps, at the batch's end, after
//   the batch's first step (whose forces may be the snapshot's, read from
//   `force` by every tile while no tile writes it), and after a sample's
//   step, which the output kernels then record as after a one-step dispatch.
// Each step runs the one-step kernels' phase functions in their order:
// bulk force and junction lanes, then (after a barrier) friction from
// the lanes merged in lane order, and the update. Junction friction laws
// only (the per-block laws keep state that a halo would race on).
// CPU twin: src/engines/cpu/mod.rs CpuEngine::one_step (each step of the loop).
// import: bulk_forces, common, coordinates, junction_store, junctions, lane_partials, scene, state, verlet

// The batch's record entries (RecordEntry) as words: the recorder lays
// them out RECORD_ENTRY_WORDS apart, the dynamic-offset alignment of the
// output kernels that read one each; a step offset is an entry's first word.
@group(0) @binding(16) var<storage, read> record_entry_words: array<u32>;

override TILE_THREADS: u32 = 64u;
override RECORD_ENTRY_WORDS: u32 = 64u;

// The forces of the held blocks at the step under way.
var<workgroup> tile_force: array<vec2<real>, TILE_BLOCKS>;
// First step, end step and whether the scene has stopped.
var<workgroup> tile_plan: vec4<u32>;

// The step after the last of the dispatch that starts at `first`.
fn tile_dispatch_end(first: u32) -> u32 {
    var end = min(first + TILE_HALO, batch.steps);
    if first == 0u {
        end = min(1u, batch.steps);
    }
    for (var k = 0u; k < batch.records; k++) {
        let offset = record_entry_words[k * RECORD_ENTRY_WORDS];
        if offset >= first {
            end = min(end, offset + 1u);
            break;
        }
    }
    return end;
}

// Copies this tile's halo columns (every row) and their interface blocks'
// junctions out of the state of the dispatch's first step.
@compute @workgroup_size(TILE_THREADS)
fn tile_gather(
    @builtin(local_invocation_index) t: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
) {
    enter_scene(wid.z);
    tile_enter(wid.x);
    if scene_stopped() {
        return;
    }
    let copy = copy_of(step_offset);
    let left = tile_x0 - tile_lo;
    let halo_cols = left + (tile_hi - tile_x1);
    for (var k = t; k < halo_cols * c.nz; k += TILE_THREADS) {
        let col = k % halo_cols;
        let iz = k / halo_cols;
        let ix = select(tile_x1 + (col - left), tile_lo + col, col < left);
        let i = iz * c.nx + ix;
        let at = halo_slot(ix, iz);
        tile_halo_disp[at] = stored_disp(i, copy);
        tile_halo_vel[at] = stored_vel(i, copy);
    }
    if FRICTION_LAW == LAW_JUNCTIONS {
        let ns = c.junction_count;
        for (var k = t; k < halo_cols * ns; k += TILE_THREADS) {
            let col = k / ns;
            let ix = select(tile_x1 + (col - left), tile_lo + col, col < left);
            let j = k % ns;
            let original = junction_base() + ix * ns + j;
            let to = halo_junction_first(ix) + j;
            halo_junction_state[to] = junction_state[original];
            halo_junction_spring[to] = junction_spring[original];
        }
    }
}

@compute @workgroup_size(TILE_THREADS)
fn tiled_steps(
    @builtin(local_invocation_index) t: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
) {
    enter_scene(wid.z);
    tile_enter(wid.x);
    if t == 0u {
        tile_plan = vec4<u32>(step_offset, tile_dispatch_end(step_offset), u32(scene_stopped()), 0u);
    }
    let plan = workgroupUniformLoad(&tile_plan);
    if plan.z != 0u {
        return;
    }
    let lanes = min(JUNCTION_LANES, c.junction_count);
    let update = batch.forces_only == 0u;
    // The held blocks: own columns from the state, the halo from the copy.
    let held = tile_hi - tile_lo;
    let copy = copy_of(plan.x);
    for (var k = t; k < held * c.nz; k += TILE_THREADS) {
        let ix = tile_lo + k % held;
        let iz = k / held;
        let i = iz * c.nx + ix;
        let at = tile_slot_at(ix, iz);
        if tile_owns(ix) {
            tile_disp[at] = stored_disp(i, copy);
            tile_vel[at] = stored_vel(i, copy);
        } else {
            tile_disp[at] = tile_halo_disp[halo_slot(ix, iz)];
            tile_vel[at] = tile_halo_vel[halo_slot(ix, iz)];
        }
    }
    workgroupBarrier();
    let lane_first = tile_index() * tile_span() * lanes;
    for (var s = plan.x; s < plan.y; s++) {
        // The columns this step updates: one fewer each side than the last
        // step, except at the lattice's edges.
        let done = s - plan.x + 1u;
        let a = select(tile_lo + done, 0u, tile_lo == 0u);
        let b = select(tile_hi - done, c.nx, tile_hi == c.nx);
        let cols = b - a;
        let ld = loads_at(s);
        let ready = batch.forces_ready != 0u && s == 0u;
        if !ready {
            for (var k = t; k < cols * c.nz; k += TILE_THREADS) {
                let ix = a + k % cols;
                let iz = k / cols;
                let i = iz * c.nx + ix;
                let f = bulk_force(i, ld);
                tile_force[tile_slot_at(ix, iz)] = f;
                if tile_owns(ix) {
                    force[block_base() + i] = f;
                }
            }
            if FRICTION_LAW == LAW_JUNCTIONS {
                for (var w = t; w < cols * lanes; w += TILE_THREADS) {
                    let ix = a + w / lanes;
                    let l = w % lanes;
                    let at = lane_first + (ix - tile_lo) * lanes + l;
                    lane_partial[at] = junction_lane(ix, l, junction_block(ix), ld);
                }
            }
        }
        storageBarrier();
        workgroupBarrier();
        for (var k = t; k < cols * c.nz; k += TILE_THREADS) {
            let ix = a + k % cols;
            let iz = k / cols;
            let i = iz * c.nx + ix;
            var f: vec2<real>;
            var friction: real = 0.0;
            if ready {
                f = force[block_base() + i];
                if FRICTION_LAW != LAW_NONE && iz == 0u {
                    friction = contact[interface_base() + ix].x;
                }
            } else {
                f = tile_force[tile_slot_at(ix, iz)];
                if FRICTION_LAW == LAW_JUNCTIONS && iz == 0u {
                    let sums = merged_lane_partials(lane_first + (ix - tile_lo) * lanes, lanes);
                    friction = junction_friction(ix, junction_block(ix), sums, f.x);
                    if tile_owns(ix) {
                        contact[interface_base() + ix] = vec2<real>(friction, foundation_normal(coord_value(load_disp(ix).z)));
                    }
                }
            }
            if update {
                // The last step's starting state stays in its copy, where a
                // run of one-step dispatches leaves it (output samples read it).
                if s + 1u == plan.y && tile_owns(ix) {
                    store_copy(i, copy_of(s), load_disp(i), load_vel(i));
                }
                verlet(i, f, friction, ld, s);
            }
        }
        storageBarrier();
        workgroupBarrier();
    }
    if update {
        let own = tile_x1 - tile_x0;
        let last = copy_of(plan.y);
        for (var k = t; k < own * c.nz; k += TILE_THREADS) {
            let ix = tile_x0 + k % own;
            let iz = k / own;
            let i = iz * c.nx + ix;
            store_copy(i, last, load_disp(i), load_vel(i));
        }
    }
}
