//! The precisions the kernels compile in, from one WGSL source: mixed f32
//! (f32 forces and velocities, double-single coordinates) and f64. The
//! prelude (`layout::wgsl_prelude`) declares `real`, `coord` and
//! `packed_coord` as this precision's types, and the coordinate functions
//! (`coord_add`, `coord_diff`, ...) come from `COORDINATES`.

use crate::model::real::{DoubleSingle, Real};
use bytemuck::Pod;

/// The WGSL name of a field type.
pub trait WgslType {
    const WGSL: &'static str;
}
impl WgslType for u32 {
    const WGSL: &'static str = "u32";
}
impl WgslType for f32 {
    const WGSL: &'static str = "f32";
}
impl WgslType for f64 {
    const WGSL: &'static str = "f64";
}
/// A double-single coordinate, (hi, lo), as the kernels compute with it.
impl WgslType for DoubleSingle {
    const WGSL: &'static str = "vec2<f32>";
}
/// A packed double-single coordinate (4-byte aligned).
impl WgslType for [f32; 2] {
    const WGSL: &'static str = "array<f32, 2>";
}

/// A number type the kernels compute in: f32 (mixed) or f64.
pub trait GpuReal: Real<Coord: Pod + WgslType> + WgslType {
    /// A coordinate inside a struct that must stay 4-byte aligned (the
    /// junction springs: 12 bytes in mixed precision, not 16).
    type Packed: Pod + WgslType + std::fmt::Debug;
    fn pack(c: Self::Coord) -> Self::Packed;
    fn unpack(p: Self::Packed) -> Self::Coord;
    /// The shader file of the coordinate functions (the `coordinates`
    /// slot of `shaders::compose`).
    const COORDINATES: &'static str;
    /// What naga must allow, and the device must have, for these kernels.
    const CAPABILITIES: naga::valid::Capabilities;
    const FEATURES: wgpu::Features;
}

impl GpuReal for f32 {
    type Packed = [f32; 2];
    fn pack(c: DoubleSingle) -> [f32; 2] {
        [c.hi, c.lo]
    }
    fn unpack(p: [f32; 2]) -> DoubleSingle {
        DoubleSingle { hi: p[0], lo: p[1] }
    }
    const COORDINATES: &'static str = "double_single";
    const CAPABILITIES: naga::valid::Capabilities = naga::valid::Capabilities::empty();
    const FEATURES: wgpu::Features = wgpu::Features::empty();
}

impl GpuReal for f64 {
    type Packed = f64;
    fn pack(c: f64) -> f64 {
        c
    }
    fn unpack(p: f64) -> f64 {
        p
    }
    const COORDINATES: &'static str = "coord_f64";
    const CAPABILITIES: naga::valid::Capabilities = naga::valid::Capabilities::FLOAT64;
    const FEATURES: wgpu::Features = wgpu::Features::SHADER_F64;
}

/// The coordinate type of `T`'s kernels.
pub type Coord<T> = <T as Real>::Coord;
/// Its packed form.
pub type Packed<T> = <T as GpuReal>::Packed;
