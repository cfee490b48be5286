//! The output kernels' pipelines (`shaders/record.wgsl`) and their bind
//! group layouts, built once per device (`GpuContext::record_pipelines`).

use super::bindings::entry;

/// Lattices up to this many blocks record a sample in one dispatch of one
/// workgroup (`record_small`): a dispatch costs more than the work there.
pub const RECORD_SMALL_BLOCKS: usize = 16_384;

/// The layouts and pipelines of the output kernels, built once per context.
pub struct RecordPipelines {
    pub group: wgpu::BindGroupLayout,
    pub entry: wgpu::BindGroupLayout,
    pub small: wgpu::ComputePipeline,
    pub sample: wgpu::ComputePipeline,
    pub finish: wgpu::ComputePipeline,
}

impl RecordPipelines {
    /// `threads`: the workgroup of the one-workgroup kernels (a power of
    /// two up to 256).
    pub fn new(device: &wgpu::Device, threads: u32) -> RecordPipelines {
        let read = wgpu::BufferBindingType::Storage { read_only: true };
        let write = wgpu::BufferBindingType::Storage { read_only: false };
        // 0: constants; 1–7, 9, 10: the state (read only); 13: the plan;
        // 14: sums and partials; 15: rows.
        let mut entries = vec![entry(0, wgpu::BufferBindingType::Uniform, false)];
        entries.extend([1, 2, 3, 4, 5, 6, 7, 9, 10].map(|b| entry(b, read, false)));
        entries.extend([13, 14, 15].map(|b| entry(b, write, false)));
        let group = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("record"),
            entries: &entries,
        });
        let entry_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("record entry"),
            entries: &[entry(0, read, true)],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("record"),
            bind_group_layouts: &[Some(&group), Some(&entry_layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("record"),
            source: wgpu::ShaderSource::Wgsl(super::shaders::record_source::<f32>().into()),
        });
        let pipeline = |name: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(name),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(name),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &[("RECORD_THREADS", threads as f64)],
                    ..Default::default()
                },
                cache: None,
            })
        };
        RecordPipelines {
            small: pipeline("record_small"),
            sample: pipeline("record_sample"),
            finish: pipeline("record_finish"),
            group,
            entry: entry_layout,
        }
    }
}
