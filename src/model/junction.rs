//! The state of one micro-junction, shared by every engine and by the
//! snapshot: its spring and the value of a pinned junction's countdown.

/// `slip_steps_left` value of a pinned junction.
pub const PINNED: u32 = u32::MAX;

/// A junction's spring: the anchor a_ij (a coordinate, like u) and the
/// stiffness k_j taken when it pinned. Laid out as the WGSL `JunctionSpring`
/// (anchor hi, anchor lo, stiffness) in mixed precision.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct JunctionSpring<C, T> {
    pub anchor: C,
    pub stiffness: T,
}

/// Junctions of one block are summed in this many interleaved lanes (lane
/// l holds junctions l, l + LANES, ...), then the lanes in order: the GPU
/// gives each lane a thread and adds the lane sums in the same order, so
/// CPU and GPU round the friction alike.
pub const JUNCTION_LANES: usize = 64;
