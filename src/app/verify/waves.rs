//! Wave speeds by the thesis Appendix B protocol: a Gaussian displacement
//! pulse along x, uniform in z; u_z = 0 on top and bottom for P waves,
//! u_x = 0 there for S waves; no friction. The right-going peak is tracked
//! on the middle row and its speed fitted by least squares.

use super::{bare_scene, scene_model, CaseResult, EngineFactory, VerifyError};
use crate::engines::advance_to;
use crate::model::scenario::{Component, EdgeConstraint, Pulse};

/// Measured and lattice long-wave speed (m/s) of a pulse of `component` on
/// an `nx`-wide lattice, at time step `dt_fraction`·T.
pub fn measure_wave_speed(
    factory: EngineFactory<'_>,
    component: Component,
    nx: u32,
    dt_fraction: f64,
) -> Result<(f64, f64), VerifyError> {
    let mut s = bare_scene("wave_speed");
    s.time.dt_fraction = Some(dt_fraction);
    let length = s.geometry.length;
    s.geometry.nx = nx;
    s.geometry.nz = (nx - 1) * 30 / 56 + 1;
    s.geometry.height = length * (s.geometry.nz - 1) as f64 / (nx - 1) as f64;
    let fix = match component {
        Component::X => EdgeConstraint::FixZ,
        Component::Z => EdgeConstraint::FixX,
    };
    s.boundary.top = fix;
    s.boundary.bottom = fix;
    s.pulse = Some(Pulse {
        component,
        center: 0.25 * length,
        width: 0.05 * length,
        amplitude: 1e-6,
    });
    let model = scene_model(&s)?;
    let expected = match component {
        Component::X => model.pressure_wave_speed(),
        Component::Z => model.shear_wave_speed(),
    };
    // Follow the peak from 0.4 L to 0.7 L.
    let t_end = 0.5 * length / expected;
    s.time.end = t_end;
    let model = scene_model(&s)?;
    let mut engine = factory(&model)?;
    let samples = 60u64;
    let stride = (model.drive_steps / samples).max(1);
    let c = match component {
        Component::X => 0,
        Component::Z => 1,
    };
    let row = model.nz / 2;
    let (mut ts, mut xs) = (Vec::new(), Vec::new());
    let mut step = 0;
    while step + stride <= model.total_steps() {
        step += stride;
        advance_to(engine.as_mut(), step)?;
        let snap = engine.snapshot()?;
        let line: Vec<f64> = (0..model.nx)
            .map(|ix| snap.disp[row * model.nx + ix][c])
            .collect();
        let start = (0.3 * (model.nx - 1) as f64) as usize;
        let (imax, _) =
            line.iter()
                .enumerate()
                .skip(start)
                .fold(
                    (start, f64::MIN),
                    |a, (i, &v)| if v > a.1 { (i, v) } else { a },
                );
        if imax == 0 || imax + 1 >= model.nx {
            continue;
        }
        // Parabolic refinement of the peak between lattice sites.
        let (a, b, cc) = (line[imax - 1], line[imax], line[imax + 1]);
        let denom = a - 2.0 * b + cc;
        let shift = if denom != 0.0 {
            0.5 * (a - cc) / denom
        } else {
            0.0
        };
        let x = (imax as f64 + shift) * model.spacing;
        if x > 0.4 * length && x < 0.7 * length {
            ts.push(snap.time);
            xs.push(x);
        }
    }
    Ok((least_squares_slope(&ts, &xs), expected))
}

pub fn least_squares_slope(t: &[f64], x: &[f64]) -> f64 {
    let n = t.len() as f64;
    if t.len() < 2 {
        return f64::NAN;
    }
    let mt = t.iter().sum::<f64>() / n;
    let mx = x.iter().sum::<f64>() / n;
    let sxy: f64 = t.iter().zip(x).map(|(a, b)| (a - mt) * (b - mx)).sum();
    let sxx: f64 = t.iter().map(|a| (a - mt) * (a - mt)).sum();
    sxy / sxx
}

pub fn wave_speed_cases(factory: EngineFactory<'_>) -> Result<Vec<CaseResult>, VerifyError> {
    let mut out = Vec::new();
    for (component, label) in [(Component::X, "p"), (Component::Z, "s")] {
        let mut errors = Vec::new();
        for nx in [57u32, 113] {
            let (measured, expected) = measure_wave_speed(factory, component, nx, 0.02)?;
            errors.push(((measured - expected) / expected).abs());
            out.push(CaseResult::new(
                &format!("{label}_wave_speed_{nx}x{}", (nx - 1) * 30 / 56 + 1),
                measured,
                expected,
                0.02 * expected,
                "m/s",
            ));
        }
        out.push(CaseResult::at_most(
            &format!("{label}_wave_error_ratio_fine_over_coarse"),
            errors[1] / errors[0],
            1.0,
            "1",
        ));
    }
    Ok(out)
}
