// Whether each interface block of a workgroup keeps its junction sums this
// step (junction_block's `kept`), a bit a block, so that a block's junction
// lanes learn it from one load, where each lane would call junction_block
// (four loads, a division) to learn it. The thread that updates a block
// notes the bit for the next step after the update; at a dispatch's start
// every thread notes its blocks' bits for the first step. A bit is read
// after the barrier that ends a step, so only kernels whose step ends at a
// workgroup barrier set LANES_READ_KEPT: resident and tiled (the
// persistent kernel's ends at a storage barrier, which does not order
// workgroup memory). The same sums either way: a kept block's lanes make
// none (GpuOptions::lanes_read_kept).
// CPU twin: src/engines/kernels/junctions.rs junction_block (the flag it caches).
// import: junctions

override LANES_READ_KEPT: bool = false;
// Words of the bits: the workgroup's interface blocks / 32, rounded up.
override KEPT_WORDS: u32 = 1u;
var<workgroup> kept_bits: array<atomic<u32>, KEPT_WORDS>;

// Notes bit `slot` (the block's place in the workgroup) for block ix:
// junction_block(ix, ld).kept, which depends on ld only through
// ld.preparing, the same for every step of a batch.
fn note_kept(slot: u32, ix: u32, ld: Loads) {
    let bit = 1u << (slot & 31u);
    if junction_block(ix, ld).kept {
        atomicOr(&kept_bits[slot >> 5u], bit);
    } else {
        atomicAnd(&kept_bits[slot >> 5u], ~bit);
    }
}

// Block ix's junction block for its lanes: where its bit says it keeps its
// sums, only that (its lanes load nothing and make no sums).
fn lanes_junction_block(slot: u32, ix: u32, ld: Loads) -> JunctionBlock {
    if LANES_READ_KEPT && (atomicLoad(&kept_bits[slot >> 5u]) & (1u << (slot & 31u))) != 0u {
        var kept: JunctionBlock;
        kept.kept = true;
        return kept;
    }
    return junction_block(ix, ld);
}
