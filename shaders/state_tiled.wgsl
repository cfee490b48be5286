// Block state of the tiled kernel (temporal blocking, tiled.wgsl): a
// workgroup owns the columns [tile_x0, tile_x1) of one scene, all rows, and
// holds them with a halo of up to TILE_HALO columns on each side in
// workgroup memory, at local slot row · TILE_SPAN + (column − tile_lo).
// In storage the state is the one-step kernels' pair of copies: a
// dispatch reads copy (parity + first step) and leaves step end in its
// copy, as a run of one-step dispatches would (the other copy, which
// only the output kernels after a one-step dispatch read, is left as it
// was: the tiled kernel records its samples itself). A neighbour
// overwrites its columns meanwhile, so the halo comes from a published
// copy instead (pub_disp, pub_vel: two copies of the lattice, of which
// only the columns near a tile's edges are used): dispatch d of a batch
// reads copy d mod 2 and publishes its own edge columns' end state in the
// other; tile_gather publishes them before the batch's first.
// CPU twin: src/engines/gpu/tiles.rs TileGeometry (the host side of this layout).
// import: scene

@group(0) @binding(1) var<storage, read_write> disp_a: array<Disp>;
@group(0) @binding(2) var<storage, read_write> vel_a: array<vec2<real>>;
@group(0) @binding(3) var<storage, read_write> disp_b: array<Disp>;
@group(0) @binding(4) var<storage, read_write> vel_b: array<vec2<real>>;
// Two published copies of every scene's blocks (scene-major in each).
@group(0) @binding(19) var<storage, read_write> pub_disp: array<Disp>;
@group(0) @binding(20) var<storage, read_write> pub_vel: array<vec2<real>>;
// The step after each dispatch of the batch (`tiles::dispatch_ends`).
@group(0) @binding(16) var<storage, read> tile_ends: array<u32>;
// Lane sums of each tile's interface blocks: TILE_SPAN · lanes per tile.
@group(0) @binding(12) var<storage, read_write> lane_partial: array<LaneSum>;

// Columns a tile owns, and steps (≤ halo columns) a dispatch may run.
override TILE_WIDTH: u32 = 8u;
override TILE_HALO: u32 = 4u;
// (TILE_WIDTH + 2 TILE_HALO) · nz: the host compiles it to the lattice.
override TILE_BLOCKS: u32 = 1u;

var<workgroup> tile_disp: array<Disp, TILE_BLOCKS>;
var<workgroup> tile_vel: array<vec2<real>, TILE_BLOCKS>;

// This workgroup's tile, its owned columns and the columns it holds.
var<private> tile: u32;
var<private> tile_x0: u32;
var<private> tile_x1: u32;
var<private> tile_lo: u32;
var<private> tile_hi: u32;

fn tile_span() -> u32 {
    return TILE_WIDTH + 2u * TILE_HALO;
}

fn tile_count() -> u32 {
    return (c.nx + TILE_WIDTH - 1u) / TILE_WIDTH;
}

fn tile_enter(t: u32) {
    tile = t;
    tile_x0 = t * TILE_WIDTH;
    tile_x1 = min(c.nx, tile_x0 + TILE_WIDTH);
    tile_lo = tile_x0 - min(tile_x0, TILE_HALO);
    tile_hi = min(c.nx, tile_x1 + TILE_HALO);
}

// This tile's index among every scene's tiles (its scratch regions).
fn tile_index() -> u32 {
    return scene * tile_count() + tile;
}

fn tile_owns(ix: u32) -> bool {
    return ix >= tile_x0 && ix < tile_x1;
}

// Whether a round steps held column ix: every one but the outermost halo
// column each side, whose update would need a column the tile does not
// hold (a round's first step updates tile_lo + 1 .. tile_hi − 1, or from
// the lattice's edge, and each later step fewer).
fn tile_steps(ix: u32) -> bool {
    return (ix > tile_lo || tile_lo == 0u) && (ix + 1u < tile_hi || tile_hi == c.nx);
}

fn tile_slot_at(ix: u32, iz: u32) -> u32 {
    return iz * tile_span() + (ix - tile_lo);
}

fn tile_slot(i: u32) -> u32 {
    return tile_slot_at(i % c.nx, i / c.nx);
}

fn load_disp(i: u32) -> Disp {
    return tile_disp[tile_slot(i)];
}

fn load_vel(i: u32) -> vec2<real> {
    return tile_vel[tile_slot(i)];
}

// Block j at column jx and row jz: its slot without dividing j by nx
// (the bulk force's neighbours, whose column and row it has at hand).
fn load_disp_at(j: u32, jx: u32, jz: u32) -> Disp {
    return tile_disp[tile_slot_at(jx, jz)];
}

fn load_vel_at(j: u32, jx: u32, jz: u32) -> vec2<real> {
    return tile_vel[tile_slot_at(jx, jz)];
}

fn store_block(i: u32, u: Disp, v: vec2<real>) {
    store_block_at(i, i % c.nx, i / c.nx, u, v);
}

fn store_block_at(i: u32, ix: u32, iz: u32, u: Disp, v: vec2<real>) {
    let k = tile_slot_at(ix, iz);
    tile_disp[k] = u;
    tile_vel[k] = v;
}

// The storage copy that holds step `step` of the batch (the one-step
// kernels' convention, state_one_step.wgsl).
fn copy_of(step: u32) -> u32 {
    return (batch.parity + step) & 1u;
}

fn stored_disp(i: u32, copy: u32) -> Disp {
    if copy == 1u {
        return disp_b[block_base() + i];
    }
    return disp_a[block_base() + i];
}

fn stored_vel(i: u32, copy: u32) -> vec2<real> {
    if copy == 1u {
        return vel_b[block_base() + i];
    }
    return vel_a[block_base() + i];
}

fn store_copy(i: u32, copy: u32, u: Disp, v: vec2<real>) {
    if copy == 1u {
        disp_b[block_base() + i] = u;
        vel_b[block_base() + i] = v;
    } else {
        disp_a[block_base() + i] = u;
        vel_a[block_base() + i] = v;
    }
}

// Scenes in the buffers (pub_disp holds two copies of each).
fn scene_count() -> u32 {
    return arrayLength(&pub_disp) / (2u * c.n_blocks);
}

// Block i's slot in published copy `copy`.
fn pub_slot(copy: u32, i: u32) -> u32 {
    return (copy * scene_count() + scene) * c.n_blocks + i;
}

// The halos of this tile's nearest neighbours: the left one's holds
// columns ..< left_hi of this tile, the right one's right_lo.. (each as
// tile_enter bounds a neighbour's held columns). A farther neighbour, where
// the halo is wider than a tile, holds fewer of them, and steps a column
// only if the nearest one does.
fn neighbour_halos() -> vec2<u32> {
    return vec2<u32>(min(c.nx, tile_x0 + TILE_HALO), tile_x1 - min(tile_x1, TILE_HALO));
}

// Whether this tile's column ix is in a neighbour's halo: its u and v are
// published (the lattice's first and last tiles have a neighbour on one
// side only).
fn tile_edge(ix: u32) -> bool {
    let halos = neighbour_halos();
    return (tile_x0 > 0u && ix < halos.x) || (tile_x1 < c.nx && ix >= halos.y);
}

// Whether a neighbour steps this tile's column ix (tile_steps, there): its
// junctions and kept sums are published. A halo's outermost column is
// read by the stencil of the column inside it, so its u and v are
// published, but never stepped.
fn tile_edge_stepped(ix: u32) -> bool {
    let halos = neighbour_halos();
    let left = tile_x0 > 0u && (ix + 1u < halos.x || halos.x == c.nx);
    let right = tile_x1 < c.nx && (ix > halos.y || halos.y == 0u);
    return left || right;
}
