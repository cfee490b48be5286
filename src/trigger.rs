//! Set-up done once when driving starts: the side spring's origin and the
//! trigger's initial junction forces. Host code shared by both engines.

use crate::model::Model;
use crate::rng::{draw_key, pcg_hash, unit_from_bits, TRIGGER_STREAM};

/// New anchors for the junctions of interface block `ix` so that junction
/// `j` carries force −r·f_N, with r uniform in prestress ± width/2 (or the
/// strip prestress inside the trigger strip).
pub fn trigger_anchors(
    model: &Model,
    ix: usize,
    ux: f64,
    normal: f64,
    stiffness: &[f64],
    anchor: &mut [f64],
) {
    let Some(t) = model.trigger else { return };
    let ns = stiffness.len();
    let f_n = normal / ns as f64;
    for j in 0..ns {
        let ratio = if ix < t.strip_blocks {
            t.strip_prestress
        } else {
            let bits = pcg_hash(draw_key(
                model.seed ^ TRIGGER_STREAM,
                ix as u32,
                j as u32,
                0,
            ));
            t.shear_prestress + t.force_width * (unit_from_bits::<f64>(bits) - 0.5)
        };
        anchor[j] = if stiffness[j] > 0.0 {
            ux - ratio * f_n / stiffness[j]
        } else {
            ux
        };
    }
}
