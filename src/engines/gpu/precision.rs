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
    /// How a shared struct's field of this type is spelled: the type
    /// itself, or the prelude's alias where the type is an array. naga
    /// gives an aliased array a type of its own, so a struct field
    /// spelled `array<f32, 2>` and a function parameter spelled
    /// `packed_coord` would be two SPIR-V types, and passing the one where
    /// the other is declared is invalid SPIR-V (`spirv-val`: "OpFunctionCall
    /// Argument's type does not match").
    const FIELD: &'static str = Self::WGSL;
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
    const FIELD: &'static str = "packed_coord";
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
    /// Whether wgpu's modules guard compensated arithmetic against a
    /// driver's fusing (`FUSION_GUARDS` in `shaders/double_single.wgsl`):
    /// then strict arithmetic, which compiles the guards out, is the
    /// leaner build (`Arithmetic::Leaner`).
    const FUSION_GUARDS: bool;
    /// The fast cadence's threshold (≥ 0) in `T`, rounded down where it is
    /// not a value of `T`: for every `x` of `T`, `x > fast_threshold(v)`
    /// exactly when `x as f64 > v` (the host's rule), where rounding to the
    /// nearest would part from it for the `x` between the two.
    fn fast_threshold(v: f64) -> Self;
    /// The order bits (of the f32 rounding of `|x|`) at and above which a
    /// speed `x` of `T` may be over the threshold `v` (≥ 0):
    /// `x as f64 > v` implies `(x as f32).to_bits() >= fast_order_bits(v)`.
    /// Exact in mixed precision (the converse holds too); in f64 the f32
    /// rounding may let a speed at the threshold through.
    fn fast_order_bits(v: f64) -> u32;
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
    const FUSION_GUARDS: bool = true;
    fn fast_threshold(v: f64) -> f32 {
        let nearest = v as f32;
        match nearest as f64 > v {
            true => nearest.next_down(),
            false => nearest,
        }
    }
    fn fast_order_bits(v: f64) -> u32 {
        // The least f32 over v.
        let nearest = v as f32;
        match nearest as f64 > v {
            true => nearest.to_bits(),
            false => nearest.next_up().to_bits(),
        }
    }
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
    const FUSION_GUARDS: bool = false;
    fn fast_threshold(v: f64) -> f64 {
        v
    }
    fn fast_order_bits(v: f64) -> u32 {
        // Rounding to f32 keeps order (x > v gives f32(x) ≥ f32(v)).
        (v as f32).to_bits()
    }
}

/// The coordinate type of `T`'s kernels.
pub type Coord<T> = <T as Real>::Coord;
/// Its packed form.
pub type Packed<T> = <T as GpuReal>::Packed;

#[cfg(test)]
mod tests {
    use super::GpuReal;

    /// Thresholds of f32 values and between them, at zero, tiny and huge.
    const THRESHOLDS: [f64; 8] = [0.0, 0.1, 0.5, 1e-3, 3.3e-4, 1e-40, 2.5, 1e39];

    /// The f32 values near `v`: its rounding and eight ulps each side.
    fn f32_near(v: f64) -> Vec<f32> {
        let mut x = (v as f32).max(0.0);
        for _ in 0..8 {
            x = x.next_down().max(0.0);
        }
        (0..17)
            .scan(x, |x, _| {
                let now = *x;
                *x = x.next_up();
                Some(now)
            })
            .collect()
    }

    #[test]
    fn the_mixed_threshold_is_the_host_rule_exactly() {
        for v in THRESHOLDS {
            let down = f32::fast_threshold(v);
            let bits = f32::fast_order_bits(v);
            for x in f32_near(v) {
                let host = x as f64 > v;
                assert_eq!(x > down, host, "threshold {v}, speed {x:e}");
                assert_eq!(x.to_bits() >= bits, host, "order bits at {v}, speed {x:e}");
            }
        }
    }

    /// The negative control: the threshold rounded to the nearest f32 parts
    /// from the host's rule at the f32 just above 0.1 (0.1f32 itself).
    #[test]
    fn the_nearest_f32_threshold_would_part_from_the_host_rule() {
        let v = 0.1;
        let parts = f32_near(v)
            .into_iter()
            .any(|x| (x > v as f32) != (x as f64 > v));
        assert!(parts);
    }

    #[test]
    fn the_f64_order_bits_let_every_fast_speed_through() {
        for v in THRESHOLDS {
            let bits = f64::fast_order_bits(v);
            assert_eq!(f64::fast_threshold(v), v);
            let mut near: Vec<f64> = f32_near(v).into_iter().map(f64::from).collect();
            let mut x = v;
            for _ in 0..8 {
                x = x.next_up();
                near.push(x);
            }
            for x in near {
                if x > v {
                    assert!(((x as f32).to_bits()) >= bits, "threshold {v}, speed {x:e}");
                }
            }
        }
    }
}
