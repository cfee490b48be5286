//! A test kernel of its own (not one of the engine's), run once on the
//! shared context: its group 0 bound to the given buffers, one dispatch,
//! and one buffer read back. For tests that check a WGSL snippet's
//! arithmetic on the device against the host's.

use slipfront::engines::gpu::context::GpuContext;
use slipfront::engines::gpu::readback::{read_ranges, Range};

/// Runs `entry` of `source` (with its override `constants`) in
/// `workgroups` workgroups, group 0's `bindings` bound to their buffers,
/// and returns `read`'s bytes after.
pub fn run_once(
    ctx: &GpuContext,
    source: String,
    entry: &str,
    constants: &[(&str, f64)],
    bindings: &[(u32, &wgpu::Buffer)],
    workgroups: u32,
    read: &wgpu::Buffer,
) -> Vec<u8> {
    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(entry),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
    let pipeline = ctx
        .device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: None,
            module: &module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            cache: None,
        });
    let entries: Vec<wgpu::BindGroupEntry> = bindings
        .iter()
        .map(|&(binding, buffer)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(workgroups, 1, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    let range = Range {
        buffer: read,
        offset: 0,
        size: read.size(),
    };
    let bytes = read_ranges(ctx, &[range]).unwrap().remove(0);
    ctx.check().expect("the test kernel ran");
    bytes
}
