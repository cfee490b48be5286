// Temporal blocking: up to TILE_HALO steps of a small lattice per
// dispatch, spread over a workgroup per column tile (not one per scene as
// the persistent kernel). Workgroup (tile, scene) holds its columns and a
// halo of TILE_HALO columns each side (state_tiled.wgsl) and steps them
// all; the columns it can still step shrink by one each side a step
// (a block's update needs its neighbours' state at the step before), so
// after K ≤ TILE_HALO steps its own columns are exact, and only those are
// written back. No barrier crosses workgroups, so the tiles run on many
// SMs at once, and a dispatch costs per K steps, not per step.
// - The halo comes from a published copy, not from the state its owner
//   overwrites meanwhile: each dispatch publishes its edge columns' end
//   state (and their interface junctions) in the copy the next dispatch
//   reads; tile_gather publishes them once before a batch's first.
// - A halo block's junctions are stepped from a private copy
//   (junction_tiled.wgsl): their updates depend only on the block's u_x
//   and their state, and the slip draws are keyed by (seed, block,
//   junction, count), so the copy evolves as its owner's original does.
//   Its kept sums are published with them (PUBLISHED_HALO_SUMS), so a
//   quiet halo block skips its junctions from a round's first step.
// - Dispatch d of a batch (its step offset) runs the steps from
//   tile_ends[d − 1] (0 for the first) to tile_ends[d], which the host
//   cuts after TILE_HALO steps and after the batch's first step (whose
//   forces may be a snapshot's, read from `force` by every tile while no
//   tile writes it) (`tiles::dispatch_ends`).
// - Output samples are recorded here, in the step of the sample, so that
//   no sample ends a dispatch: each tile sums its own columns' part of the
//   sample (record_common.wgsl block_sample) into a partial of its own,
//   and writes their rows. A planned fast-cadence row is written whether
//   the fast cadence turns out on or not: that is decided by the samples
//   before it, which other tiles may not have finished. After the batch,
//   record_batch_finish (record_batch.wgsl; the host counts a partial per
//   tile) adds each sample's partials in a fixed order, and the host decides
//   as it reads them back which were due.
// - Chained tiles (TILE_CHAINED; GpuOptions::chained_tiles): one dispatch
//   runs several of those dispatches' rounds in turn, up to the round
//   whose end carries ROUND_ENDS_DISPATCH (the batch's end). Before its
//   round k > 0, a tile waits until every tile whose
//   columns reach into its halo has finished round k − 1 (their counters
//   in tile_progress), so it reads what the next dispatch would have read;
//   its neighbours wait on it in turn before they overwrite the copy it
//   reads. The same rounds, so the same bits as a dispatch a round; one
//   dispatch where there were many. It needs a scene's tiles on the GPU at
//   once: a tile that has polled CHAIN_POLLS times in a dispatch gives up
//   and reports itself (GpuStatus::stalled_tile) instead of hanging.
// Each step runs the one-step kernels' phase functions in their order:
// bulk force and junction lanes, then (after a barrier) friction from
// the lanes merged as a tree (lane_tree8), and the update. Junction friction laws
// only (the per-block laws keep state that a halo would race on).
// CPU twin: src/engines/cpu/mod.rs CpuEngine::one_step (each step of the loop).
// import: barriers, bulk_forces, bulk_patch, common, coordinates, junction_store, junctions, lane_merge, lane_partials, noted_blocks, phase_clocks, record_batch, record_buffers, record_common, scene, state, verlet

override TILE_THREADS: u32 = 64u;
// Bulk forces by 2×2 patches of blocks (bulk_patch.wgsl;
// GpuOptions::bond_patches), as in the persistent kernel.
override BOND_PATCHES: bool = false;

// Chained tiles (above): rounds a dispatch, and the most polls a tile makes
// for its neighbours in one dispatch (a software adapter's loop budget).
override TILE_CHAINED: bool = false;
override CHAIN_POLLS: u32 = 16777216u;
// Each poll first waits at 256 workgroup barriers: on a software adapter
// they take time and no loop iteration, so the budget of polls lasts
// (on lavapipe about 0.37 ms a poll: 32,648 polls took 12 s).
override CHAIN_POLL_PAUSE: bool = false;
// A round's end step is its tile_ends entry without this bit; the bit
// marks the round that ends its dispatch (chained tiles).
const ROUND_ENDS_DISPATCH: u32 = 0x80000000u;

// Rounds each tile of each scene has finished, all dispatches (mod 2³²):
// equal for a scene's tiles between dispatches.
@group(0) @binding(24) var<storage, read_write> tile_progress: array<atomic<u32>>;
// A step offset no sample has.
const NO_SAMPLE: u32 = 0xffffffffu;
// The recording variant (the engine builds it for a run that records its
// samples on the device): without it the sample code is compiled out, and
// a run without output steps as fast as a kernel without it (llvmpipe
// steps a kernel with the sample's barriers in its loop at about half the
// speed, samples or not).
override TILE_RECORDS: bool = false;

// The forces of the held blocks at the step under way.
var<workgroup> tile_force: array<vec2<real>, TILE_BLOCKS>;
// First step, end step and whether the scene has stopped.
var<workgroup> tile_plan: vec4<u32>;
// The dispatch's rounds and this tile's counter at its start.
var<workgroup> tile_chain: vec2<u32>;
// Whether every neighbour has finished the round awaited.
var<workgroup> tile_neighbours_done: u32;
// The next sample of the round: its index among the batch's and its step
// (NO_SAMPLE: none).
var<workgroup> tile_next_sample: vec2<u32>;
// What a sample reads of each own interface block, kept from the update
// phase (which computes its friction, then overwrites its u and v), and
// the block's part of the sample, column by column.
struct InterfaceInputs {
    u: Disp,
    v_half: vec2<real>,
    f: vec2<real>,
    friction: real,
    normal: real,
}
var<workgroup> tile_interface_inputs: array<InterfaceInputs, TILE_WIDTH>;
var<workgroup> tile_interface_sums: array<SampleSums, TILE_WIDTH>;

// Publishes this tile's edge columns (every row: those in a neighbour's
// halo) in published copy `copy`: u and v from the tile's state, the
// interface junctions from storage. After a barrier.
fn publish_edges(t: u32, copy: u32) {
    for (var b = grid_walk(t, TILE_THREADS, tile_x1 - tile_x0); b.row < c.nz; grid_walk_next(&b)) {
        let ix = tile_x0 + b.column;
        if tile_edge(ix) {
            let i = b.row * c.nx + ix;
            pub_disp[pub_slot(copy, i)] = load_disp_at(i, ix, b.row);
            pub_vel[pub_slot(copy, i)] = load_vel_at(i, ix, b.row);
        }
    }
    publish_edge_junctions(t, copy);
}

// The interface junctions of this tile's edge columns that a neighbour
// steps, and their blocks' kept sums, from storage into published copy
// `copy`.
fn publish_edge_junctions(t: u32, copy: u32) {
    if FRICTION_LAW != LAW_JUNCTIONS {
        return;
    }
    if PUBLISHED_HALO_SUMS {
        for (var ix = tile_x0 + t; ix < tile_x1; ix += TILE_THREADS) {
            if tile_edge_stepped(ix) {
                tile_junction_cache[pub_sums_slot(copy, ix)] = junction_cache[junction_sums_slot(ix)];
            }
        }
    }
    let ns = c.junction_count;
    for (var b = grid_walk(t, TILE_THREADS, ns); b.row < tile_x1 - tile_x0; grid_walk_next(&b)) {
        let ix = tile_x0 + b.row;
        if tile_edge_stepped(ix) {
            let j = b.column;
            let at = pub_junction_first(copy, ix) + j;
            tile_junction_state[at] = junction_state[junction_base() + ix * ns + j];
            tile_junction_spring[at] = junction_spring[junction_base() + ix * ns + j];
        }
    }
}

// Loads this tile's own columns from the state copy of step `first`
// (unless `own` is false: a chained round finds them where the round
// before left them), its halo from published copy `copy`, and its halo's
// junctions into its private copy. Before a barrier.
fn load_tile(t: u32, first: u32, copy: u32, own: bool) {
    let held = tile_hi - tile_lo;
    let state = copy_of(first);
    for (var b = grid_walk(t, TILE_THREADS, held); b.row < c.nz; grid_walk_next(&b)) {
        let ix = tile_lo + b.column;
        let i = b.row * c.nx + ix;
        let at = tile_slot_at(ix, b.row);
        if tile_owns(ix) {
            if own {
                tile_disp[at] = stored_disp(i, state);
                tile_vel[at] = stored_vel(i, state);
            }
        } else {
            tile_disp[at] = pub_disp[pub_slot(copy, i)];
            tile_vel[at] = pub_vel[pub_slot(copy, i)];
        }
    }
    if FRICTION_LAW == LAW_JUNCTIONS {
        // The halo's kept sums: those published with its junctions, or
        // none (the private records hold an earlier round's). Only for the
        // columns the round steps: the outermost halo columns' junctions
        // are never stepped, nor their sums or notes read.
        for (var ix = tile_lo + t; ix < tile_hi; ix += TILE_THREADS) {
            if !tile_owns(ix) && tile_steps(ix) {
                var sums = JunctionCache();
                if PUBLISHED_HALO_SUMS {
                    sums = tile_junction_cache[pub_sums_slot(copy, ix)];
                }
                junction_cache[junction_sums_slot(ix)] = sums;
            }
        }
        let ns = c.junction_count;
        for (var b = grid_walk(t, TILE_THREADS, ns); b.row < held; grid_walk_next(&b)) {
            let ix = tile_lo + b.row;
            if !tile_owns(ix) && tile_steps(ix) {
                let j = b.column;
                let published = pub_junction_first(copy, ix) + j;
                let to = halo_junction_first(ix) + j;
                junction_state[to] = tile_junction_state[published];
                junction_spring[to] = tile_junction_spring[published];
            }
        }
    }
}

// Before a batch's first dispatch: every tile publishes its edge columns
// from the state of the batch's first step, in published copy 0.
@compute @workgroup_size(TILE_THREADS)
fn tile_gather(
    @builtin(local_invocation_index) t: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
) {
    enter_scene(wid.z);
    tile_enter(wid.x);
    let state = copy_of(0u);
    for (var b = grid_walk(t, TILE_THREADS, tile_x1 - tile_x0); b.row < c.nz; grid_walk_next(&b)) {
        let ix = tile_x0 + b.column;
        if tile_edge(ix) {
            let i = b.row * c.nx + ix;
            pub_disp[pub_slot(0u, i)] = stored_disp(i, state);
            pub_vel[pub_slot(0u, i)] = stored_vel(i, state);
        }
    }
    publish_edge_junctions(t, 0u);
}

// Block (ix, iz)'s bulk force, in the tile, and in `force` where the tile
// owns it.
fn store_tile_force(ix: u32, iz: u32, f: vec2<real>) {
    tile_force[tile_slot_at(ix, iz)] = f;
    if tile_owns(ix) {
        force[block_base() + iz * c.nx + ix] = f;
    }
}

// Whether every tile whose columns reach into this tile's halo has
// finished `rounds` rounds of this dispatch (its counter was `base` at the
// start, as was theirs). Thread 0's.
fn neighbours_finished(base: u32, rounds: u32) -> bool {
    if TILE_HALO <= TILE_WIDTH {
        // Only the tiles either side (no loop: a software adapter counts
        // every loop round against its budget).
        let row = scene * tile_count();
        let left = tile == 0u || atomicLoad(&tile_progress[row + tile - 1u]) - base >= rounds;
        let right = tile + 1u == tile_count() || atomicLoad(&tile_progress[row + tile + 1u]) - base >= rounds;
        return left && right;
    }
    let first = tile_lo / TILE_WIDTH;
    let last = (tile_hi - 1u) / TILE_WIDTH;
    for (var n = first; n <= last; n++) {
        let done = atomicLoad(&tile_progress[scene * tile_count() + n]) - base;
        if n != tile && done < rounds {
            return false;
        }
    }
    return true;
}

// 256 workgroup barriers in a row, no loop (CHAIN_POLL_PAUSE).
fn poll_pause() {
    sixty_four_barriers();
    sixty_four_barriers();
    sixty_four_barriers();
    sixty_four_barriers();
}

fn sixty_four_barriers() {
    eight_barriers();
    eight_barriers();
    eight_barriers();
    eight_barriers();
    eight_barriers();
    eight_barriers();
    eight_barriers();
    eight_barriers();
}

fn eight_barriers() {
    workgroupBarrier();
    workgroupBarrier();
    workgroupBarrier();
    workgroupBarrier();
    workgroupBarrier();
    workgroupBarrier();
    workgroupBarrier();
    workgroupBarrier();
}

@compute @workgroup_size(TILE_THREADS)
fn tiled_steps(
    @builtin(local_invocation_index) t: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
) {
    phase_start(t);
    enter_scene(wid.z);
    tile_enter(wid.x);
    let lanes = min(JUNCTION_LANES, c.junction_count);
    // Before the barrier of workgroupUniformLoad below.
    lane_shuffle_enter(t, lanes);
    // This dispatch runs rounds d0 .. d0 + rounds of the batch: one, or
    // with chained tiles up to the one that ends the dispatch.
    let d0 = step_offset;
    if t == 0u {
        var last = d0;
        if TILE_CHAINED {
            while (tile_ends[last] & ROUND_ENDS_DISPATCH) == 0u {
                last++;
            }
        }
        tile_chain = vec2<u32>(last + 1u - d0, atomicLoad(&tile_progress[tile_index()]));
    }
    let chain = workgroupUniformLoad(&tile_chain);
    lane_shuffle_ready();
    let stride = lane_subtree_stride();
    if t == 0u && wid.x == 0u {
        atomicMax(&status[status_base() + STATUS_LANE_LEVELS], lane_levels_used());
    }
    var polls = 0u;
    phase_mark(t, PHASE_ENTER);
    for (var k = 0u; k < chain.x; k++) {
        if k > 0u {
            // Its neighbours' round k − 1 published what round k reads.
            loop {
                if t == 0u {
                    tile_neighbours_done = u32(neighbours_finished(chain.y, k));
                }
                if workgroupUniformLoad(&tile_neighbours_done) != 0u {
                    break;
                }
                polls++;
                if CHAIN_POLL_PAUSE {
                    poll_pause();
                }
                if polls >= CHAIN_POLLS {
                    // They never came: this adapter does not run the scene's
                    // tiles at once. The scene stops, its neighbours go on.
                    if t == 0u {
                        atomicMax(&status[status_base() + STATUS_STALLED_TILE], tile + 1u);
                    }
                    break;
                }
            }
            // What they published, visible to every thread here.
            storageBarrier();
            phase_mark(t, PHASE_WAIT);
        }
        // Chained, a round's own columns stay in workgroup memory for the
        // next: loaded at the dispatch's first round, stored at its last.
        let update = batch.forces_only == 0u;
        let first = k == 0u || !update;
        let last = k + 1u == chain.x;
        let end = tile_round(t, d0 + k, lanes, stride, first, last);
        if end == 0u {
            break;
        }
        // This round's publication before its counter, and its counter
        // before its own columns' store, which no neighbour reads.
        phase_arrive(t, PHASE_PUBLISH);
        storageBarrier();
        if t == 0u {
            atomicStore(&tile_progress[tile_index()], chain.y + k + 1u);
        }
        phase_mark(t, PHASE_PUBLISH);
        if update && last {
            store_tile_end(t, end - 1u);
        }
    }
    // A tile that stopped early counts every round done: its neighbours
    // must not wait on it.
    if t == 0u {
        atomicStore(&tile_progress[tile_index()], chain.y + chain.x);
    }
    phase_mark(t, PHASE_LEAVE);
    phase_flush(t, TILE_THREADS, tile_index());
}

// Thread t's first lane run item of a step whose force phase has `bulk`
// items (blocks, or patches), which threads 0, 1, … take first. The runs
// start at the first thread after them and wrap past the last, so that
// where the threads are enough for both no thread steps a bulk item and a
// run: the phase lasts the longer of the two chains, not their sum. The
// start is a multiple of 64 (where the threads are), so that item k keeps
// its place k mod 64 in its subgroup and a block's runs their butterfly
// (lane_shuffle.wgsl); an item's pass, and so its partners', is still
// k / TILE_THREADS. The same items and sums, on other threads.
fn first_run_item(t: u32, bulk: u32) -> u32 {
    var start = 0u;
    if TILE_THREADS % 64u == 0u {
        start = ((bulk + 63u) / 64u * 64u) % TILE_THREADS;
    }
    return (t + TILE_THREADS - start) % TILE_THREADS;
}

// This tile's own columns' state at step `end` into that step's copy.
fn store_tile_end(t: u32, end: u32) {
    let copy = copy_of(end);
    for (var b = grid_walk(t, TILE_THREADS, tile_x1 - tile_x0); b.row < c.nz; grid_walk_next(&b)) {
        let ix = tile_x0 + b.column;
        let i = b.row * c.nx + ix;
        store_copy(i, copy, load_disp_at(i, ix, b.row), load_vel_at(i, ix, b.row));
    }
}

// Round d of the batch: steps tile_ends[d − 1] .. tile_ends[d] (0 for the
// first), reading published copy d mod 2 and publishing in the other.
// `first`: its own columns come from storage; `last`: its end state goes
// to storage after it (`store_tile_end`). Returns its end step plus one,
// or 0 where the scene has stopped (a blow-up, a stalled tile): no step.
fn tile_round(t: u32, d: u32, lanes: u32, stride: u32, first: bool, last: bool) -> u32 {
    if t == 0u {
        let start = select(tile_ends[max(d, 1u) - 1u] & ~ROUND_ENDS_DISPATCH, 0u, d == 0u);
        let stalled = atomicLoad(&status[status_base() + STATUS_STALLED_TILE]) != 0u;
        tile_plan = vec4<u32>(start, tile_ends[d] & ~ROUND_ENDS_DISPATCH, u32(scene_stopped() || stalled), 0u);
    }
    let plan = workgroupUniformLoad(&tile_plan);
    if plan.z != 0u {
        return 0u;
    }
    let update = batch.forces_only == 0u;
    var next = vec2<u32>(0u, NO_SAMPLE);
    if TILE_RECORDS {
        if t == 0u {
            tile_next_sample = sample_at_or_after(0u, plan.x);
        }
        next = workgroupUniformLoad(&tile_next_sample);
    }
    phase_mark(t, PHASE_CHECKS);
    load_tile(t, plan.x, d & 1u, first);
    phase_arrive(t, PHASE_LOAD);
    workgroup_storage_barrier();
    workgroupBarrier();
    // The first step's junction blocks, for every column the round steps
    // (noted_blocks.wgsl; a note a column from tile_lo).
    if NOTED_JUNCTION_BLOCKS && FRICTION_LAW == LAW_JUNCTIONS {
        let first = loads_at(plan.x);
        for (var ix = tile_lo + t; ix < tile_hi; ix += TILE_THREADS) {
            if tile_steps(ix) {
                note_junction_block(ix - tile_lo, ix, first);
            }
        }
        // Arrived again, at the phase's last barrier: the notes are the
        // slowest warp's work, and the barrier before them too (the
        // latest arrival is a maximum, so this one stands).
        phase_arrive(t, PHASE_LOAD);
        workgroupBarrier();
    }
    phase_mark(t, PHASE_LOAD);
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
        // Step s is a sample: its own columns' part of it, from the state
        // before their update.
        let sampling = TILE_RECORDS && next.y == s;
        if !ready {
            if BOND_PATCHES {
                // Patches from column a; the last is half one where cols
                // is odd (bulk_force_patch stops at column b).
                for (var p = grid_walk(t, TILE_THREADS, (cols + 1u) / 2u); 2u * p.row < c.nz; grid_walk_next(&p)) {
                    let x0 = a + 2u * p.column;
                    let z0 = 2u * p.row;
                    let f = bulk_force_patch(x0, z0, b, ld);
                    store_tile_force(x0, z0, f.a);
                    if x0 + 1u < b {
                        store_tile_force(x0 + 1u, z0, f.b);
                    }
                    if z0 + 1u < c.nz {
                        store_tile_force(x0, z0 + 1u, f.c);
                        if x0 + 1u < b {
                            store_tile_force(x0 + 1u, z0 + 1u, f.d);
                        }
                    }
                }
            } else {
                // Inner blocks first, without bounds, then the rim: item
                // k = t, t + threads, … of inner then rim blocks.
                let span = block_span(a, b);
                var k = t;
                for (var w = grid_walk(t, TILE_THREADS, max(span.inner_columns, 1u)); k < span.inner_count; grid_walk_next(&w)) {
                    let ix = span.inner_first + w.column;
                    let iz = w.row + 1u;
                    store_tile_force(ix, iz, inner_bulk_force(iz * c.nx + ix, ix, iz, ld));
                    k += TILE_THREADS;
                }
                for (; k < cols * c.nz; k += TILE_THREADS) {
                    let r = span_rim_block(span, k - span.inner_count);
                    store_tile_force(r.x, r.y, bulk_force(r.y * c.nx + r.x, r.x, r.y, ld));
                }
            }
            if FRICTION_LAW == LAW_JUNCTIONS {
                // Item (column, run): a block's lane run (LANE_RUN lanes),
                // on the threads after the bulk items' (first_run_item).
                let bulk = select(cols * c.nz, ((cols + 1u) / 2u) * ((c.nz + 1u) / 2u), BOND_PATCHES);
                for (var w = grid_walk(first_run_item(t, bulk), TILE_THREADS, lane_runs(lanes)); w.row < cols; grid_walk_next(&w)) {
                    let ix = a + w.row;
                    let l = w.column * LANE_RUN;
                    let jb = lanes_junction_block(ix - tile_lo, ix, ld);
                    // A kept block's partials are not merged: not written.
                    // Where lanes merge in subgroups, a run's first lane
                    // writes its subtree.
                    if !jb.kept {
                        let sum = lane_subtree(lane_run(ix, l, jb, ld), l);
                        if (l & (stride - 1u)) == 0u {
                            lane_partial[lane_first + (ix - tile_lo) * lanes + l] = sum;
                        }
                    }
                }
            }
        }
        phase_arrive(t, PHASE_FORCES);
        workgroup_storage_barrier();
        workgroupBarrier();
        phase_mark(t, PHASE_FORCES);
        if sampling {
            sample_rows_above(t, record_entries[next.x], ready);
        }
        for (var b = grid_walk(t, TILE_THREADS, cols); b.row < c.nz; grid_walk_next(&b)) {
            let ix = a + b.column;
            let iz = b.row;
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
                    let jb = update_junction_block(ix - tile_lo, ix, ld);
                    var sums: LaneSum;
                    if jb.kept {
                        sums = kept_lane_sum(jb);
                    } else {
                        sums = merged_lane_partials(lane_first + (ix - tile_lo) * lanes, lanes);
                    }
                    friction = junction_friction(ix, jb, sums, f.x);
                    if tile_owns(ix) {
                        contact[interface_base() + ix] = vec2<real>(friction, foundation_normal(coord_value(load_disp_at(ix, ix, 0u).z)));
                    }
                }
            }
            // What the sample reads of an own interface block, before its
            // update: the update computes its friction.
            if sampling && iz == 0u && tile_owns(ix) {
                let normal = contact[interface_base() + ix].y;
                tile_interface_inputs[ix - tile_x0] = InterfaceInputs(load_disp_at(i, ix, 0u), load_vel_at(i, ix, 0u), f, friction, normal);
            }
            if update {
                verlet(i, ix, iz, f, friction, ld, s);
            }
            // Its junction block for step s + 1 (whose columns this
            // step's contain).
            if NOTED_JUNCTION_BLOCKS && FRICTION_LAW == LAW_JUNCTIONS && iz == 0u {
                note_junction_block(ix - tile_lo, ix, ld);
            }
        }
        if sampling {
            sample_interface(t, next, s);
            next = workgroupUniformLoad(&tile_next_sample);
        }
        phase_arrive(t, PHASE_UPDATES);
        workgroup_storage_barrier();
        workgroupBarrier();
        phase_mark(t, PHASE_UPDATES);
    }
    publish_edges(t, (d + 1u) & 1u);
    return plan.y + 1u;
}

// The part of sample e of this tile's own blocks above the interface row,
// from the state before their update (no friction acts there), reduced
// across the tile into wg_sums[0]. A pass of its own, so that no sample's
// sums are held through the update (the interface row's part needs the
// friction the update computes: sample_interface).
fn sample_rows_above(t: u32, e: RecordEntry, ready: bool) {
    var acc = no_sums();
    for (var b = grid_walk(t, TILE_THREADS, tile_x1 - tile_x0); b.row + 1u < c.nz; grid_walk_next(&b)) {
        let ix = tile_x0 + b.column;
        let iz = b.row + 1u;
        let i = iz * c.nx + ix;
        var f: vec2<real>;
        if ready {
            f = force[block_base() + i];
        } else {
            f = tile_force[tile_slot_at(ix, iz)];
        }
        let v_half = load_vel_at(i, ix, iz);
        let v = sampled_velocity(flags[i], v_half, f, 0.0);
        acc = combine(acc, block_sample_besides_interface(i, e, load_disp_at(i, ix, iz), v_half, v, f, 0.0));
    }
    // Only the tile that holds the driven block's column, or with a top
    // drive every tile (the top row's reaction), adds more above the
    // interface than its kinetic energy.
    let driven = plans[scene].driven_block;
    let holds_driven = driven < c.n_blocks && tile_owns(driven % c.nx);
    reduce_threads(t, TILE_THREADS, acc, holds_driven || plans[scene].top_reaction != 0u);
}

// The part of sample `next` (index, step s) of this tile's own interface
// blocks, from what the update phase kept of them, added to the rows
// above (wg_sums[0]) in column order: the tile's partial. Thread 0 then
// finds the next sample.
fn sample_interface(t: u32, next: vec2<u32>, s: u32) {
    workgroupBarrier();
    let e = record_entries[next.x];
    let own = tile_x1 - tile_x0;
    for (var k = t; k < own; k += TILE_THREADS) {
        let x = tile_interface_inputs[k];
        let ix = tile_x0 + k;
        tile_interface_sums[k] = block_sample(ix, e, flags[ix], x.u, x.v_half, x.f, x.friction, x.normal, interface_planned(e));
    }
    workgroupBarrier();
    if t == 0u {
        var total = wg_sums[0];
        for (var k = 0u; k < own; k++) {
            total = combine(total, tile_interface_sums[k]);
        }
        sums[batch_partial_slot(e, tile)] = total;
        tile_next_sample = sample_at_or_after(next.x + 1u, s + 1u);
    }
}

// The first of the batch's samples from index `first` on whose step is
// `step` or later: (its index, its step), or (batch.records, NO_SAMPLE).
// The entries are in step order: a binary search (no loop of a sample a
// round: llvmpipe counts every iteration against its limit).
fn sample_at_or_after(first: u32, step: u32) -> vec2<u32> {
    var lo = first;
    var hi = batch.records;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if record_entries[mid].offset < step {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    if lo < batch.records {
        return vec2<u32>(lo, record_entries[lo].offset);
    }
    return vec2<u32>(lo, NO_SAMPLE);
}
