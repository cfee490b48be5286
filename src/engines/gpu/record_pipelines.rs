//! The output kernels' pipelines (`shaders/record.wgsl`) and their bind
//! group layouts, built once per device (`GpuContext::record_pipelines`).

use super::bindings::Bindings;
use super::compile::ShaderChecks;
use super::layout::WORKGROUP;
use super::precision::GpuReal;

/// The output module's binding that takes a dynamic offset per sample.
pub const RECORD_ENTRY: &str = "entry";

/// Lattices up to this many blocks record a sample in one dispatch of one
/// workgroup (`record_small`): a dispatch costs more than the work there.
pub const RECORD_SMALL_BLOCKS: usize = 16_384;

/// The layouts and pipelines of the output kernels, built once per context.
pub struct RecordPipelines {
    /// What the output module declares (`bindings::Bindings`).
    pub bindings: Bindings,
    pub group: wgpu::BindGroupLayout,
    pub entry: wgpu::BindGroupLayout,
    pub small: wgpu::ComputePipeline,
    pub sample: wgpu::ComputePipeline,
    pub special: wgpu::ComputePipeline,
    pub finish: wgpu::ComputePipeline,
}

impl RecordPipelines {
    /// The output kernels in precision `T`. `threads`: the workgroup of
    /// the one-workgroup kernels (a power of two up to 256), at most the
    /// slots of `T`'s sums in workgroup memory (`layout::reduction_slots`).
    pub fn new<T: GpuReal>(
        device: &wgpu::Device,
        threads: u32,
        checks: ShaderChecks,
    ) -> RecordPipelines {
        let all_slots = super::layout::reduction_slots::<T>();
        let threads = threads.min(all_slots);
        // The output module's own declarations (shaders/record.wgsl):
        // group 0 the constants, the state (read only) and the record
        // buffers; group 1 the sample's entry, at a dynamic offset.
        let source = super::shaders::record_source::<T>();
        let bindings = Bindings::reflect(&source).expect("record.wgsl parses (tested with naga)");
        let group = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("record"),
            entries: &bindings.layout(0, &[]),
        });
        let entry_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("record entry"),
            entries: &bindings.layout(1, &[RECORD_ENTRY]),
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("record"),
            bind_group_layouts: &[Some(&group), Some(&entry_layout)],
            immediate_size: 0,
        });
        let module = checks.module(device, "record", source);
        // `slots`: the reduction's slots in workgroup memory. The
        // one-workgroup kernels take the most that fit (their threads fold
        // into them); the kernels of a workgroup per 64 blocks use 64, so a
        // workgroup holds 4 KB (mixed f32) instead of 16 and more of them
        // share a multiprocessor when a sample reads the whole lattice.
        let pipeline = |name: &str, slots: u32| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(name),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(name),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &[
                        ("RECORD_THREADS", threads as f64),
                        ("REDUCTION_WIDTH", slots as f64),
                    ],
                    ..Default::default()
                },
                cache: None,
            })
        };
        let per_group = WORKGROUP.min(all_slots);
        RecordPipelines {
            bindings,
            small: pipeline("record_small", all_slots),
            sample: pipeline("record_sample", per_group),
            special: pipeline("record_special", per_group),
            finish: pipeline("record_finish", all_slots),
            group,
            entry: entry_layout,
        }
    }
}
