//! The device time of each batch: timestamps at the start and end of its
//! compute pass (where the adapter has timestamp queries), read back with
//! the batch's status. Summed, they say how long the device was busy
//! stepping and recording, against the wall time a run took: what output
//! costs on the device, apart from what it costs the host.

use super::context::GpuContext;

/// Query slots (two timestamps each), used in turn: more than the batches
/// that can be in flight at once (`MAX_RUN_AHEAD_BATCHES` + 1), so a slot
/// is read back before it is written again.
const SLOTS: u32 = 80;

/// Bytes a batch's timestamps take in its status staging buffer.
pub const TIMESTAMP_BYTES: u64 = 16;

pub struct DeviceTimer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    next: u32,
    period_ns: f64,
    busy_ns: f64,
}

impl DeviceTimer {
    /// A timer, where the context's adapter has timestamp queries.
    pub fn new(ctx: &GpuContext) -> Option<DeviceTimer> {
        let period_ns = ctx.timestamp_period_ns?;
        let queries = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("batch timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * SLOTS,
        });
        let resolved = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("batch timestamps"),
            size: SLOTS as u64 * wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Some(DeviceTimer {
            queries,
            resolved,
            next: 0,
            period_ns,
            busy_ns: 0.0,
        })
    }

    /// The next slot, for one batch's pass.
    pub fn take_slot(&mut self) -> u32 {
        let slot = self.next;
        self.next = (self.next + 1) % SLOTS;
        slot
    }

    /// The pass's timestamp writes into `slot`.
    pub fn pass_writes(&self, slot: u32) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(2 * slot),
            end_of_pass_write_index: Some(2 * slot + 1),
        }
    }

    /// After the pass: its two timestamps into `staging` at `at`.
    pub fn copy_out(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: u32,
        staging: &wgpu::Buffer,
        at: u64,
    ) {
        let from = slot as u64 * wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT;
        encoder.resolve_query_set(&self.queries, 2 * slot..2 * slot + 2, &self.resolved, from);
        encoder.copy_buffer_to_buffer(&self.resolved, from, staging, at, TIMESTAMP_BYTES);
    }

    /// Adds a retired batch's pass time, from its two timestamps as read
    /// back (a pair out of order, as a driver may give across a clock
    /// change, counts nothing).
    pub fn add(&mut self, bytes: &[u8]) {
        let stamps: [u64; 2] = bytemuck::pod_read_unaligned(&bytes[..TIMESTAMP_BYTES as usize]);
        if stamps[1] > stamps[0] {
            self.busy_ns += (stamps[1] - stamps[0]) as f64 * self.period_ns;
        }
    }

    /// Seconds the device spent in the retired batches' passes.
    pub fn busy_seconds(&self) -> f64 {
        self.busy_ns * 1e-9
    }
}
