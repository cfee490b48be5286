// Where the tiled kernel keeps the junctions it steps (the
// `junction_store` slot): its own columns' in the storage buffers, as
// every kernel; its halo's interface blocks' in a private copy per tile
// (halo_junction_state/spring, filled by tile_gather), stepped exactly as
// their owner steps the originals, and dropped at the dispatch's end. A
// halo junction's index carries HALO_JUNCTION.
// CPU twin: src/engines/gpu/tiles.rs TileGeometry (the host side of this layout).
// import: common, scene, state

@group(0) @binding(21) var<storage, read_write> halo_junction_state: array<vec2<u32>>;
@group(0) @binding(22) var<storage, read_write> halo_junction_spring: array<JunctionSpring>;

const HALO_JUNCTION: u32 = 0x80000000u;

// Block ix's first junction in this tile's private copy (any held column).
fn halo_junction_first(ix: u32) -> u32 {
    return (tile_index() * tile_span() + (ix - tile_lo)) * c.junction_count;
}

fn junction_first(ix: u32) -> u32 {
    if tile_owns(ix) {
        return junction_base() + ix * c.junction_count;
    }
    return HALO_JUNCTION | halo_junction_first(ix);
}

fn junction_state_at(k: u32) -> vec2<u32> {
    if (k & HALO_JUNCTION) != 0u {
        return halo_junction_state[k & ~HALO_JUNCTION];
    }
    return junction_state[k];
}

fn junction_spring_at(k: u32) -> JunctionSpring {
    if (k & HALO_JUNCTION) != 0u {
        return halo_junction_spring[k & ~HALO_JUNCTION];
    }
    return junction_spring[k];
}

fn set_junction_state(k: u32, state: vec2<u32>) {
    if (k & HALO_JUNCTION) != 0u {
        halo_junction_state[k & ~HALO_JUNCTION] = state;
    } else {
        junction_state[k] = state;
    }
}

fn set_junction_spring(k: u32, spring: JunctionSpring) {
    if (k & HALO_JUNCTION) != 0u {
        halo_junction_spring[k & ~HALO_JUNCTION] = spring;
    } else {
        junction_spring[k] = spring;
    }
}
