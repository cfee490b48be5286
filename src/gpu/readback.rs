//! Reading device buffers back to the host.

use super::context::GpuContext;
use crate::engine::EngineError;
use std::sync::mpsc;

/// Copies `buffers` into one staging buffer with one submit and one wait,
/// and returns each buffer's bytes.
pub fn read_buffers(
    ctx: &GpuContext,
    buffers: &[&wgpu::Buffer],
) -> Result<Vec<Vec<u8>>, EngineError> {
    let total: u64 = buffers.iter().map(|b| b.size()).sum();
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: total,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    let mut offset = 0;
    for b in buffers {
        encoder.copy_buffer_to_buffer(b, 0, &staging, offset, b.size());
        offset += b.size();
    }
    ctx.queue.submit([encoder.finish()]);
    let slice = staging.slice(..);
    let (tx, rx) = mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| EngineError::Gpu(format!("device lost while reading back: {e}")))?;
    rx.recv()
        .map_err(|e| EngineError::Gpu(format!("readback: {e}")))?
        .map_err(|e| EngineError::Gpu(format!("readback: {e}")))?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| EngineError::Gpu(format!("readback: {e}")))?
        .to_vec();
    staging.unmap();
    ctx.check()?;
    let mut out = Vec::with_capacity(buffers.len());
    let mut at = 0usize;
    for b in buffers {
        let size = b.size() as usize;
        out.push(data[at..at + size].to_vec());
        at += size;
    }
    Ok(out)
}

pub fn cast_prefix<T: bytemuck::Pod>(bytes: &[u8], len: usize) -> Vec<T> {
    bytemuck::cast_slice::<u8, T>(bytes)[..len].to_vec()
}
