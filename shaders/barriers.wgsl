// The barrier between a step's phases, where what one thread of a
// workgroup wrote to storage is read by another thread of the same
// workgroup (lane sums, junctions, the persistent kernel's state).
// CPU twin: src/engines/gpu/spirv.rs scope_workgroup_barriers (its scope; the
// CPU engines step a block's phases in order, with nothing to order).
// import: (none)
//
// WGSL's storageBarrier orders storage within the workgroup, but naga
// writes it into SPIR-V with device memory scope, as if other workgroups
// read what it orders. A device-scope acquire and release can cost a
// multiprocessor its cached storage (an L1 invalidated, outstanding stores
// drained to L2) at every phase of every step. Where the engine writes a
// module's SPIR-V itself (`spirv::scope_workgroup_barriers`,
// `KernelBuild::workgroup_barriers`), the barrier in this function gets
// workgroup memory scope, as the WGSL spec defines storageBarrier and as
// Tint writes it. Barriers that order writes for other workgroups (the
// chained tiles' rounds, tiled.wgsl) call storageBarrier itself and keep
// device scope.
fn workgroup_storage_barrier() {
    storageBarrier();
}
