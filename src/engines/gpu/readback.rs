//! Reading device buffers back to the host.

use super::context::GpuContext;
use crate::engines::EngineError;
use std::sync::mpsc;

/// A byte range of a device buffer.
pub struct Range<'a> {
    pub buffer: &'a wgpu::Buffer,
    pub offset: u64,
    pub size: u64,
}

/// Copies `ranges` into one staging buffer with one submit and one wait,
/// and returns each range's bytes.
pub fn read_ranges(ctx: &GpuContext, ranges: &[Range]) -> Result<Vec<Vec<u8>>, EngineError> {
    let total: u64 = ranges.iter().map(|r| r.size).sum();
    if total == 0 {
        return Ok(vec![Vec::new(); ranges.len()]);
    }
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: total,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    let mut at = 0;
    for r in ranges {
        if r.size > 0 {
            encoder.copy_buffer_to_buffer(r.buffer, r.offset, &staging, at, r.size);
        }
        at += r.size;
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
    let mut out = Vec::with_capacity(ranges.len());
    let mut at = 0usize;
    for r in ranges {
        let size = r.size as usize;
        out.push(data[at..at + size].to_vec());
        at += size;
    }
    Ok(out)
}

/// The first `len` elements of type `T` in `bytes`, whatever the bytes'
/// alignment (an empty read-back is not aligned at all).
pub fn cast_prefix<T: bytemuck::Pod>(bytes: &[u8], len: usize) -> Vec<T> {
    bytemuck::pod_collect_to_vec(&bytes[..len * std::mem::size_of::<T>()])
}
