// Each interface block's JunctionBlock for the next step, worked out once
// by the thread that updates the block, right after the update, and kept
// in workgroup memory (NotedBlock: all of it but the kept sums). The
// block's junction lanes and its next update read it there, where each
// lane, and the update, would call junction_block (four loads, the
// reference's test) to work out the same values. At a dispatch's start
// every thread notes its blocks for the first step. A note is read after
// the barrier that ends a step, so only kernels whose step ends at a
// workgroup barrier set NOTED_JUNCTION_BLOCKS: resident and tiled (the
// persistent kernel's ends at a storage barrier, which does not order
// workgroup memory). The same values, so the same bits
// (GpuOptions::noted_junction_blocks).
// CPU twin: src/engines/kernels/junctions.rs junction_block.
// import: junctions

override NOTED_JUNCTION_BLOCKS: bool = false;
// The workgroup's interface blocks (the resident kernel's lattice, the
// tiled kernel's tile): a note each.
override NOTED_BLOCKS: u32 = 1u;
var<workgroup> noted_blocks: array<NotedBlock, NOTED_BLOCKS>;

// Notes block ix at `slot` (its place in the workgroup) for its next step:
// junction_block(ix, ld), which depends on ld only through ld.preparing,
// the same for every step of a batch. From the state that step starts
// from: the block's update, its sums stored, its junctions as the lanes
// left them.
fn note_junction_block(slot: u32, ix: u32, ld: Loads) {
    let jb = junction_block(ix, ld);
    noted_blocks[slot] = NotedBlock(jb.ux, jb.reference, jb.f_n, select(real(0.0), real(1.0), jb.kept));
}

// Block ix's junction block as noted at `slot`, without its kept sums: what
// its lanes read (a kept block's lanes load nothing and make no sums).
fn noted_junction_block(slot: u32, ld: Loads) -> JunctionBlock {
    let n = noted_blocks[slot];
    var jb = JunctionBlock();
    jb.ux = n.ux;
    jb.reference = n.reference;
    jb.f_n = n.f_n;
    // As junction_block works them out.
    jb.threshold = c.mu_s * n.f_n;
    jb.slipping_force = c.mu_d * n.f_n;
    jb.kept = n.kept != 0.0;
    jb.keeps = KEEP_JUNCTION_SUMS && !ld.preparing;
    return jb;
}

// Block ix's junction block for its lanes.
fn lanes_junction_block(slot: u32, ix: u32, ld: Loads) -> JunctionBlock {
    if NOTED_JUNCTION_BLOCKS {
        return noted_junction_block(slot, ld);
    }
    return junction_block(ix, ld);
}

// Block ix's junction block for its update, with the kept sums where it
// keeps them (kept_lane_sum and junction_friction read them).
fn update_junction_block(slot: u32, ix: u32, ld: Loads) -> JunctionBlock {
    if NOTED_JUNCTION_BLOCKS {
        var jb = noted_junction_block(slot, ld);
        if jb.kept {
            jb.sums = junction_cache[junction_sums_slot(ix)];
        }
        return jb;
    }
    return junction_block(ix, ld);
}
