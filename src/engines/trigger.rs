//! Set-up done once when driving starts: the side spring's origin and the
//! trigger's initial junction forces. Host code shared by both engines.

use crate::engines::Snapshot;
use crate::model::rng::{draw_key, pcg_hash, unit_from_bits, TRIGGER_STREAM};
use crate::model::Model;

/// New anchors (index ix·Ns + j) so that junction j of interface block ix
/// carries force −r·f_N, with r uniform in prestress ± width/2, or the strip
/// prestress inside the trigger strip. Computed from the state when driving
/// starts; both engines upload the result.
pub fn trigger_anchors(model: &Model, snap: &Snapshot) -> Vec<f64> {
    let ns = model.junctions.map_or(0, |j| j.count);
    if model.prestress.is_some() {
        return prestress_anchors(model, snap, ns);
    }
    let Some(t) = model.trigger else {
        return snap.anchor.clone();
    };
    let mut anchors = Vec::with_capacity(snap.anchor.len());
    for ix in 0..model.nx {
        let ux = snap.disp[ix][0];
        let f_n =
            crate::model::laws::foundation_normal(model.k_foundation, snap.disp[ix][1]) / ns as f64;
        for j in 0..ns {
            let ratio = if ix < t.strip_blocks {
                t.strip_prestress
            } else {
                let key = draw_key(model.seed ^ TRIGGER_STREAM, ix as u32, j as u32, 0);
                t.shear_prestress + t.force_width * (unit_from_bits::<f64>(pcg_hash(key)) - 0.5)
            };
            let k = snap.junction_stiffness[ix * ns + j];
            anchors.push(if k > 0.0 { ux - ratio * f_n / k } else { ux });
        }
    }
    anchors
}

/// Anchors that make the junctions of each interface block balance the
/// prestress the block is loaded with (`Model::interface_shear`), shared
/// equally: the block starts in equilibrium (up to its bulk springs), each
/// junction at the block's τ/p of its threshold.
fn prestress_anchors(model: &Model, snap: &Snapshot, ns: usize) -> Vec<f64> {
    let mut anchors = Vec::with_capacity(snap.anchor.len());
    for ix in 0..model.nx {
        let ux = snap.disp[ix][0];
        let per_junction = model.interface_shear(ix) / ns as f64;
        for j in 0..ns {
            let k = snap.junction_stiffness[ix * ns + j];
            anchors.push(if k > 0.0 { ux - per_junction / k } else { ux });
        }
    }
    anchors
}
