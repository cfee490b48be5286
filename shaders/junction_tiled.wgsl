// Where the tiled kernel keeps the junctions it steps (the
// `junction_store` slot): its own columns' where every kernel keeps
// them; its halo's interface blocks' in a private copy per tile, stepped
// exactly as their owner steps the originals, and dropped at the
// dispatch's end. The private copies are the junction arrays' tail,
// after every scene's own junctions, so a junction is one index into one
// array whichever block it belongs to: the junction pass loads and stores
// it without a branch between buffers.
// tile_junction_state/spring hold the two published copies of every
// scene's junctions (as pub_disp: only the edge columns' are used); a
// dispatch fills its private copy from the published one it reads.
// CPU twin: src/engines/gpu/tiles.rs TileGeometry (the host side of this layout).
// import: common, scene, state

@group(0) @binding(21) var<storage, read_write> tile_junction_state: array<vec2<u32>>;
@group(0) @binding(22) var<storage, read_write> tile_junction_spring: array<JunctionSpring>;
// Two published copies of every scene's kept junction sums, beside the
// junctions (only the edge columns' are used).
@group(0) @binding(27) var<storage, read_write> tile_junction_cache: array<JunctionCache>;

// A halo block's kept sums come with its junctions: its owner's record, as
// the owner left it at the round's end, which describes exactly the
// junctions published with it (GpuOptions::published_halo_sums). So a
// quiet halo block keeps its sums from a round's first step, as its owner
// does. false: the private records are emptied at each round's start and
// a halo block sums its junctions at the round's first step (a full lane
// phase a round in every tile), as before session 60. Kept or made anew,
// sums of the same junctions have the same bits.
override PUBLISHED_HALO_SUMS: bool = true;

// Junctions of all scenes in one published copy, and in the junction
// arrays before the tiles' private copies.
fn junctions_per_copy() -> u32 {
    return scene_count() * c.nx * c.junction_count;
}

// Block ix's first junction in published copy `copy`.
fn pub_junction_first(copy: u32, ix: u32) -> u32 {
    return copy * junctions_per_copy() + junction_base() + ix * c.junction_count;
}

// Block ix's first junction in this tile's private copy (any held column),
// in the junction arrays.
fn halo_junction_first(ix: u32) -> u32 {
    return junctions_per_copy() + (tile_index() * tile_span() + (ix - tile_lo)) * c.junction_count;
}

fn junction_first(ix: u32) -> u32 {
    return select(halo_junction_first(ix), junction_base() + ix * c.junction_count, tile_owns(ix));
}

// Block ix's kept sums in published copy `copy`.
fn pub_sums_slot(copy: u32, ix: u32) -> u32 {
    return copy * scene_count() * c.nx + interface_base() + ix;
}

// Where block ix's kept junction sums are: its own columns' in the
// scenes' records, as every kernel; a halo block's in this tile's private
// records after every scene's (its owner rewrites the scene's record in
// the same dispatch). load_tile fills the private ones from the published
// copy it reads (PUBLISHED_HALO_SUMS), or empties them.
fn junction_sums_slot(ix: u32) -> u32 {
    if tile_owns(ix) {
        return interface_base() + ix;
    }
    return scene_count() * c.nx + tile_index() * tile_span() + (ix - tile_lo);
}
