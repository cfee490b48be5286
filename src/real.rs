//! The floating-point type an engine computes in (f64, or f32 as on the GPU).

use num_traits::Float;

pub trait Real:
    Float + Send + Sync + Default + std::fmt::Debug + std::fmt::Display + bytemuck::Pod + 'static
{
    const NAME: &'static str;
    fn from_f64(v: f64) -> Self;
    fn as_f64(self) -> f64;
}

impl Real for f64 {
    const NAME: &'static str = "f64";
    #[inline]
    fn from_f64(v: f64) -> Self {
        v
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self
    }
}

impl Real for f32 {
    const NAME: &'static str = "f32";
    #[inline]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[inline]
    fn as_f64(self) -> f64 {
        self as f64
    }
}
