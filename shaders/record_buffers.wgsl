// The record buffers (src/engines/gpu/recorder.rs): the plan, whose fast flag the
// device updates; each sample's sums, then from plan.partials_offset one
// partial per workgroup of record_sample; the interface rows
// (RECORD_INTERFACE_WORDS per block) from plan.interface_offset and the
// bulk fields (RECORD_BULK_WORDS per block) from plan.bulk_offset, in the
// slots an entry names. One scene: block i is element i of every buffer.
// CPU twin: src/engines/gpu/layout.rs GpuRecordPlan, GpuSampleSums (the host's layout).
// import: (none)

@group(0) @binding(13) var<storage, read_write> plan: RecordPlan;
@group(0) @binding(14) var<storage, read_write> sums: array<SampleSums>;
@group(0) @binding(15) var<storage, read_write> rows: array<real>;
