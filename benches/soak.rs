//! Soak: 1e7 steps of the Table S1 scene (2.2 s of driving) with checks every
//! 1e5 steps: everything finite, the foundation carrying F_N, the slider's
//! mean height bounded. `cargo bench --bench soak [-- f64|f32|gpu]`.

use slipfront::app::runner::global_sample;
use slipfront::engines::backend::{make_engine, Backend, Precision};
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Model};
use std::time::Instant;

fn main() {
    let mode = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .unwrap_or("f32".into());
    let (backend, precision) = match mode.as_str() {
        "f64" => (Backend::Cpu, Precision::F64),
        "gpu" => (Backend::Gpu, Precision::F32),
        _ => (Backend::Cpu, Precision::F32),
    };
    let steps: u64 = std::env::var("SLIPFRONT_SOAK_STEPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000_000);
    let s = Scenario::parse(DEFAULT_SCENARIO, "soak", &["time.end=3.0".into()]).unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    let mut e = make_engine(&m, backend, precision, 0).unwrap();
    println!("soak: {} steps of {} on {}", steps, m.name, e.describe());
    println!("| step | t (s) | F/F_N | pinned | normal sum / F_N | mean u_z (m) | kinetic (J) | ruptures |");
    println!("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    let t0 = Instant::now();
    advance_to(e.as_mut(), m.prep_steps).unwrap();
    let origin = e.snapshot().unwrap().disp[2 * m.nx][0];
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    let mut max_ratio: f64 = 0.0;
    let every = 100_000;
    let mut step = m.prep_steps;
    while step < m.prep_steps + steps {
        step += every;
        if let Err(err) = advance_to(e.as_mut(), step) {
            println!("STOPPED: {err}");
            std::process::exit(1);
        }
        let snap = e.snapshot().unwrap();
        assert!(
            snap.disp
                .iter()
                .chain(&snap.vel)
                .flatten()
                .all(|x| x.is_finite()),
            "non-finite at {step}"
        );
        let g = global_sample(&m, &snap, origin);
        let normal = snap.normal.iter().sum::<f64>() / m.normal_force;
        let mean_uz = snap.disp.iter().map(|u| u[1]).sum::<f64>() / m.n_blocks() as f64;
        lo = lo.min(normal);
        hi = hi.max(normal);
        max_ratio = max_ratio.max(g.drive_ratio);
        if (step - m.prep_steps).is_multiple_of(1_000_000) {
            println!(
                "| {} | {:.4} | {:.4} | {:.3} | {:.5} | {:.4e} | {:.3e} | {} |",
                step - m.prep_steps,
                g.time,
                g.drive_ratio,
                g.pinned_fraction,
                normal,
                mean_uz,
                g.kinetic_energy,
                g.ruptures
            );
        }
    }
    println!(
        "soak done: {steps} steps in {:.0} s, no NaN; foundation carried {lo:.5}..{hi:.5} of F_N; peak F/F_N {max_ratio:.4}",
        t0.elapsed().as_secs_f64()
    );
}
