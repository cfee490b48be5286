//! The fixed sizes the GPU engine's batches, buffers and workgroup
//! reductions are built around. They sit below `options` (the choices a
//! run makes), `tiles` (the tiled kernel's geometry) and `batches`, which
//! all read them.

use super::layout;
use super::precision::GpuReal;

/// Steps of one batch of the persistent kernel (one dispatch). The drive
/// target arithmetic in the kernels needs it ≤ 4096.
pub const PERSISTENT_BATCH: u64 = 4096;
/// Dispatches of the one-step kernel per batch (one submit).
pub const ONE_STEP_BATCH: u64 = 1024;
/// Batches queued on the device at most.
pub const IN_FLIGHT: usize = 2;
/// Reduction slots of the resident and tiled kernels' output samples
/// (their threads fold into them first): their workgroup memory holds the
/// lattice, or a tile of it.
pub const WORKGROUP_STATE_REDUCTION_WIDTH: u32 = 64;

/// The resident and tiled kernels' reduction slots in precision `T`.
pub fn workgroup_state_reduction_width<T: GpuReal>() -> u32 {
    WORKGROUP_STATE_REDUCTION_WIDTH.min(layout::reduction_slots::<T>())
}
