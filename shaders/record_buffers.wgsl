// The record buffers (src/engines/gpu/recorder.rs): one plan per scene,
// whose fast flag the device updates; each scene's region of the others,
// from the offsets of its plan: its samples' sums from plan.sums_offset,
// then from plan.partials_offset one partial per workgroup of
// record_sample; its interface rows (RECORD_INTERFACE_WORDS per block)
// from plan.interface_offset and its bulk fields (RECORD_BULK_WORDS per
// block) from plan.bulk_offset, in the slots an entry names. The entries
// (the steps sampled) are the same for every scene.
// CPU twin: src/engines/gpu/layout.rs GpuRecordPlan, GpuSampleSums (the host's layout).
// import: (none)

@group(0) @binding(13) var<storage, read_write> plans: array<RecordPlan>;
@group(0) @binding(14) var<storage, read_write> sums: array<SampleSums>;
@group(0) @binding(15) var<storage, read_write> rows: array<real>;
