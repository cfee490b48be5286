//! How often an interface block's junction sums are kept (no junction can
//! change this step, so none is loaded), and how often every block's are,
//! through the driving of the built-in Table S1 stick-slip scene on the CPU
//! sweep engine (mixed f32, which keeps them as the GPU kernels do).
//!
//! A GPU step waits for its slowest interface block, so the second figure
//! is the share of steps that skip the junction work on the critical path.
//!
//!     cargo run --release --example kept_fraction -- [DRIVING_SECONDS]
//!
//! Prints, every 20,000 samples (one sample every 7 steps), the window's
//! fraction of blocks kept and of samples with every block kept.
use slipfront::engines::cpu::SweepEngine;
use slipfront::model::real::DoubleSingle;
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Model};

fn main() -> anyhow::Result<()> {
    let driving_seconds: f64 = match std::env::args().nth(1) {
        Some(text) => text
            .parse()
            .map_err(|_| anyhow::anyhow!("DRIVING_SECONDS: {text:?} is not a number"))?,
        None => 0.2,
    };
    let s = Scenario::parse(DEFAULT_SCENARIO, "built-in scene", &[])?;
    let m = Model::from_scenario(&s, false)?;
    let mut e = SweepEngine::<f32, DoubleSingle>::new(&m, 1)?;
    advance_to(&mut e, m.prep_steps)?;
    let steps = (driving_seconds / m.dt) as u64;
    let every = 7u64;
    let (mut kept, mut samples) = (0usize, 0usize);
    let mut all_kept_samples = 0usize;
    let mut at = m.prep_steps;
    let mut window = (0usize, 0usize, 0usize);
    while at < m.prep_steps + steps {
        at += every;
        advance_to(&mut e, at)?;
        let k = e.kept_junction_blocks();
        kept += k;
        samples += 1;
        window.0 += k;
        window.1 += 1;
        if k == m.nx {
            all_kept_samples += 1;
            window.2 += 1;
        }
        if window.1 == 20000 {
            println!(
                "t={:.4} s kept {:.4} every block kept {:.4}",
                (at - m.prep_steps) as f64 * m.dt,
                window.0 as f64 / (window.1 * m.nx) as f64,
                window.2 as f64 / window.1 as f64
            );
            window = (0, 0, 0);
        }
    }
    println!(
        "nx {} steps {} kept fraction {:.5} samples with every block kept {:.5}",
        m.nx,
        steps,
        kept as f64 / (samples * m.nx) as f64,
        all_kept_samples as f64 / samples as f64
    );
    Ok(())
}
