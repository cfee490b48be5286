//! Static elastic constants: the slider, frictionless on its foundation, is
//! compressed by the normal load on its top row and relaxed to rest. The
//! strains in the central region give E = σ/ε_zz and ν = −ε_xx/ε_zz.

use super::{bare_scene, scene_model, CaseResult, EngineFactory, VerifyError};
use crate::engines::advance_to;

pub fn elastic_constant_cases(factory: EngineFactory<'_>) -> Result<Vec<CaseResult>, VerifyError> {
    let mut s = bare_scene("elastic_constants");
    s.foundation.stiffness_ratio = 0.5;
    s.loading.normal.force = 1920.0;
    s.loading.normal.ramp_time = 0.5e-3;
    s.loading.normal.relax_time = 4.0e-3;
    s.loading.normal.relax_damping_ratio = 0.05;
    s.time.end = 0.0;
    let model = scene_model(&s)?;
    let mut engine = factory(&model)?;
    advance_to(engine.as_mut(), model.total_steps())?;
    let snap = engine.snapshot()?;
    let (nx, nz) = (model.nx, model.nz);
    let at = |ix: usize, iz: usize| snap.disp[iz * nx + ix];
    // Central half of the slider, averaged over the central columns/rows.
    let (x0, x1) = (nx / 3, 2 * nx / 3);
    let (z0, z1) = (nz / 3, 2 * nz / 3);
    let mut ezz = 0.0;
    for ix in x0..=x1 {
        ezz += (at(ix, z1)[1] - at(ix, z0)[1]) / ((z1 - z0) as f64 * model.spacing);
    }
    ezz /= (x1 - x0 + 1) as f64;
    let mut exx = 0.0;
    for iz in z0..=z1 {
        exx += (at(x1, iz)[0] - at(x0, iz)[0]) / ((x1 - x0) as f64 * model.spacing);
    }
    exx /= (z1 - z0 + 1) as f64;
    let length = (nx - 1) as f64 * model.spacing;
    let stress = -model.normal_force / (length * model.width);
    let e = stress / ezz;
    let nu = -exx / ezz;
    let e_expected = model.lattice_youngs_modulus();
    Ok(vec![
        CaseResult::new(
            "static_youngs_modulus",
            e,
            e_expected,
            0.01 * e_expected,
            "Pa",
        ),
        CaseResult::new("static_poisson_ratio", nu, 1.0 / 3.0, 0.01 / 3.0, "1"),
    ])
}
