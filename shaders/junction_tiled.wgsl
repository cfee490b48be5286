// Where the tiled kernel keeps the junctions it steps (the
// `junction_store` slot): its own columns' in the storage buffers, as
// every kernel; its halo's interface blocks' in a private copy per tile,
// stepped exactly as their owner steps the originals, and dropped at the
// dispatch's end. A halo junction's index carries HALO_JUNCTION.
// tile_junction_state/spring hold two published copies of every scene's
// junctions (as pub_disp: only the edge columns' are used), then the
// tiles' private copies; a dispatch fills its private copy from the
// published one it reads.
// CPU twin: src/engines/gpu/tiles.rs TileGeometry (the host side of this layout).
// import: common, scene, state

@group(0) @binding(21) var<storage, read_write> tile_junction_state: array<vec2<u32>>;
@group(0) @binding(22) var<storage, read_write> tile_junction_spring: array<JunctionSpring>;

const HALO_JUNCTION: u32 = 0x80000000u;

// Junctions of all scenes in one published copy.
fn junctions_per_copy() -> u32 {
    return scene_count() * c.nx * c.junction_count;
}

// Block ix's first junction in published copy `copy`.
fn pub_junction_first(copy: u32, ix: u32) -> u32 {
    return copy * junctions_per_copy() + junction_base() + ix * c.junction_count;
}

// Block ix's first junction in this tile's private copy (any held column).
fn halo_junction_first(ix: u32) -> u32 {
    return 2u * junctions_per_copy() + (tile_index() * tile_span() + (ix - tile_lo)) * c.junction_count;
}

fn junction_first(ix: u32) -> u32 {
    if tile_owns(ix) {
        return junction_base() + ix * c.junction_count;
    }
    return HALO_JUNCTION | halo_junction_first(ix);
}

fn junction_state_at(k: u32) -> vec2<u32> {
    if (k & HALO_JUNCTION) != 0u {
        return tile_junction_state[k & ~HALO_JUNCTION];
    }
    return junction_state[k];
}

fn junction_spring_at(k: u32) -> JunctionSpring {
    if (k & HALO_JUNCTION) != 0u {
        return tile_junction_spring[k & ~HALO_JUNCTION];
    }
    return junction_spring[k];
}

fn set_junction_state(k: u32, state: vec2<u32>) {
    if (k & HALO_JUNCTION) != 0u {
        tile_junction_state[k & ~HALO_JUNCTION] = state;
    } else {
        junction_state[k] = state;
    }
}

fn set_junction_spring(k: u32, spring: JunctionSpring) {
    if (k & HALO_JUNCTION) != 0u {
        tile_junction_spring[k & ~HALO_JUNCTION] = spring;
    } else {
        junction_spring[k] = spring;
    }
}

// Where block ix's kept junction sums are: its own columns' in the
// scenes' records, as every kernel; a halo block's in this tile's private
// records after every scene's (its owner rewrites the scene's record in
// the same dispatch). load_tile empties the private ones, so a halo block
// sums its junctions at a dispatch's first step and keeps them from then.
fn junction_sums_slot(ix: u32) -> u32 {
    if tile_owns(ix) {
        return interface_base() + ix;
    }
    return scene_count() * c.nx + tile_index() * tile_span() + (ix - tile_lo);
}
