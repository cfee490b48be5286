//! Comparing two engine states field by field (the GPU against the CPU
//! reference): the maximum error of each field relative to its scale.

use crate::engine::Snapshot;

/// Maximum |a − b| of one field, and the field's scale (max |a|).
#[derive(Debug, Clone, PartialEq)]
pub struct FieldError {
    pub field: &'static str,
    pub max_error: f64,
    pub scale: f64,
}

impl FieldError {
    /// Error relative to the field's scale (0 when both are zero).
    pub fn relative(&self) -> f64 {
        if self.scale > 0.0 {
            self.max_error / self.scale
        } else {
            self.max_error
        }
    }
}

fn field(name: &'static str, a: &[f64], b: &[f64]) -> FieldError {
    let max_error = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let scale = a.iter().map(|x| x.abs()).fold(0.0, f64::max);
    FieldError {
        field: name,
        max_error: if a.len() == b.len() {
            max_error
        } else {
            f64::INFINITY
        },
        scale,
    }
}

/// Per-field errors of `b` against the reference `a`.
pub fn compare_snapshots(a: &Snapshot, b: &Snapshot) -> Vec<FieldError> {
    let comp = |s: &Snapshot, k: usize, v: bool| -> Vec<f64> {
        let src = if v { &s.vel } else { &s.disp };
        src.iter().map(|x| x[k]).collect()
    };
    let as_f64 = |v: &[u32]| v.iter().map(|&x| x as f64).collect::<Vec<_>>();
    vec![
        field("ux", &comp(a, 0, false), &comp(b, 0, false)),
        field("uz", &comp(a, 1, false), &comp(b, 1, false)),
        field("vx", &comp(a, 0, true), &comp(b, 0, true)),
        field("vz", &comp(a, 1, true), &comp(b, 1, true)),
        field("friction", &a.friction, &b.friction),
        field("normal", &a.normal, &b.normal),
        field("anchor", &a.anchor, &b.anchor),
        field(
            "junction_stiffness",
            &a.junction_stiffness,
            &b.junction_stiffness,
        ),
        field("ruptures", &as_f64(&a.ruptures), &as_f64(&b.ruptures)),
    ]
}

/// Fields whose relative error exceeds `tolerance`; velocity errors under
/// `velocity_floor` (m/s) pass whatever their scale.
pub fn fields_over(errors: &[FieldError], tolerance: f64, velocity_floor: f64) -> Vec<String> {
    errors
        .iter()
        .filter(|e| {
            let floor = e.field.starts_with('v') && e.max_error <= velocity_floor;
            !(e.relative() <= tolerance || floor)
        })
        .map(|e| format!("{}: {:.3e} of {:.3e}", e.field, e.max_error, e.scale))
        .collect()
}
