use slipfront::engines::backend::{make_engine, measure_steps_per_second, Backend, Precision};
use slipfront::model::Model;
use std::path::PathBuf;
use std::process::ExitCode;

/// Wall time spent measuring each engine.
const MEASURE_SECONDS: f64 = 0.4;

/// One engine's measured speed on the scene and the run's wall time at it.
struct Estimate {
    engine: String,
    steps_per_second: f64,
    wall_seconds: f64,
}

/// Measures every engine this machine can run the scene on (the CPU in f64
/// and mixed f32, with the threads `run` would use; the GPU, when an
/// adapter is found, in f64 where it has f64 shaders, the precision
/// `run --backend gpu` then takes, and in mixed f32), at the start of the
/// scene: the speed of quiet loading (events cost more, fast-forward skips
/// some). An engine that
/// cannot run the scene here (more memory than the machine has, beyond the
/// adapter's limits) is not measured, and the second list says why, as
/// `run` would refuse it.
fn estimates(m: &Model) -> (Vec<Estimate>, Vec<String>) {
    let mut engines: Vec<(Backend, Precision)> = vec![
        (Backend::Cpu, Precision::F64),
        (Backend::Cpu, Precision::F32),
    ];
    if let Ok(ctx) = slipfront::engines::gpu::context::shared() {
        if ctx.check_precision::<f64>().is_ok() {
            engines.push((Backend::Gpu, Precision::F64));
        }
        engines.push((Backend::Gpu, Precision::F32));
    }
    let mut measured = Vec::new();
    let mut not_measured = Vec::new();
    for (backend, precision) in engines {
        let label = format!("{backend:?} {precision:?}");
        let fits = slipfront::engines::memory::check(
            precision.memory_bytes(m),
            slipfront::engines::memory::available_bytes(),
            &format!("{label}: a {} × {} lattice", m.nx, m.nz),
            "run it elsewhere",
        );
        let measure = fits.and_then(|()| {
            let mut e =
                make_engine(m, backend, precision, 0).map_err(|e| format!("{label}: {e}"))?;
            let rate = measure_steps_per_second(e.as_mut(), MEASURE_SECONDS)
                .map_err(|e| format!("{label}: {e}"))?;
            Ok(Estimate {
                engine: e.describe(),
                steps_per_second: rate,
                wall_seconds: m.total_steps() as f64 / rate,
            })
        });
        match measure {
            Ok(e) => measured.push(e),
            Err(why) => not_measured.push(why),
        }
    }
    (measured, not_measured)
}

/// 95 s, 3.2 min, 1.5 h.
fn duration(seconds: f64) -> String {
    match seconds {
        s if s < 120.0 => format!("{s:.0} s"),
        s if s < 7200.0 => format!("{:.1} min", s / 60.0),
        s => format!("{:.1} h", s / 3600.0),
    }
}

/// Prints the scene's derived quantities; exits 1 when dt is above the
/// stability limit.
pub fn check(scenario: Option<PathBuf>, set: &[String], json: bool) -> anyhow::Result<ExitCode> {
    let (s, name) = super::load_scenario(scenario.as_deref(), set)?;
    let m = Model::from_scenario(&s, true)?;
    let lim = m.stability_limit();
    let stable = m.dt <= lim.min();
    let (estimates, not_measured) = if stable {
        estimates(&m)
    } else {
        (Vec::new(), Vec::new())
    };
    let report = serde_json::json!({
        "scenario": name,
        "blocks": [m.nx, m.nz],
        "junctions_per_block": m.junctions.map_or(0, |j| j.count),
        "spacing_m": m.spacing,
        "block_mass_kg": m.mass,
        "spring_stiffness_N_per_m": m.k,
        "diagonal_stiffness_N_per_m": m.k_diag,
        "damping_kg_per_s": m.eta,
        "foundation_stiffness_N_per_m": m.k_foundation,
        "junction_stiffness_bound_N_per_m": m.junction_stiffness_bound(),
        "period_s": m.period,
        "dt_s": m.dt,
        "dt_over_period": m.dt / m.period,
        "stability_limit_s": {
            "bulk_undamped": lim.bulk_undamped,
            "bulk": lim.bulk,
            "interface": lim.interface,
            "relaxation": lim.relaxation,
            "driven_block": if lim.driven.is_finite() { serde_json::json!(lim.driven) } else { serde_json::Value::Null },
            "binding": lim.min(),
        },
        "stable": stable,
        "wave_speed_m_per_s": {
            "p": m.pressure_wave_speed(),
            "s": m.shear_wave_speed(),
            "rayleigh": m.rayleigh_wave_speed(),
        },
        "steps": {
            "normal_load_phase": m.prep_steps,
            "driving": m.drive_steps,
            "total": m.total_steps(),
        },
        "memory_bytes": { "f32": m.memory_bytes(4, 8), "f64": m.memory_bytes(8, 8) },
        "terms": m.terms(),
        "estimates": estimates.iter().map(|e| serde_json::json!({
            "engine": e.engine,
            "steps_per_second": e.steps_per_second,
            "block_steps_per_second": e.steps_per_second * m.n_blocks() as f64,
            "wall_seconds": e.wall_seconds,
        })).collect::<Vec<_>>(),
        "not_measured": not_measured,
    });
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!("scenario        {name}");
        println!(
            "lattice         {} x {} blocks, l = {:.4e} m",
            m.nx, m.nz, m.spacing
        );
        println!("block mass      m   = {:.5e} kg", m.mass);
        println!(
            "springs         k   = {:.5e} N/m (diagonal {:.5e})",
            m.k, m.k_diag
        );
        println!("damping         eta = {:.4} kg/s", m.eta);
        println!("foundation      k_f = {:.5e} N/m", m.k_foundation);
        if let Some(j) = m.junctions {
            println!(
                "junctions       Ns = {}, k_j up to {:.4e} N/m",
                j.count,
                m.junction_stiffness_bound()
            );
        }
        println!("period          T   = {:.5e} s", m.period);
        println!(
            "time step       dt  = {:.5e} s = T/{:.1}",
            m.dt,
            m.period / m.dt
        );
        println!(
            "stability       dt <= {:.4e} s (bulk undamped {:.4e}, bulk {:.4e}, interface {:.4e}, relaxation {:.4e}{}): {}",
            lim.min(),
            lim.bulk_undamped,
            lim.bulk,
            lim.interface,
            lim.relaxation,
            if lim.driven.is_finite() {
                format!(", side-spring block {:.4e}", lim.driven)
            } else {
                String::new()
            },
            if stable { "stable" } else { "UNSTABLE" }
        );
        println!(
            "wave speeds     c_p = {:.1} m/s, c_s = {:.1} m/s, c_R = {:.1} m/s",
            m.pressure_wave_speed(),
            m.shear_wave_speed(),
            m.rayleigh_wave_speed()
        );
        println!(
            "steps           {} normal-load + {} driving = {}",
            m.prep_steps,
            m.drive_steps,
            m.total_steps()
        );
        println!(
            "memory          {:.2} MiB (f32), {:.2} MiB (f64)",
            m.memory_bytes(4, 8) as f64 / 1048576.0,
            m.memory_bytes(8, 8) as f64 / 1048576.0
        );
        println!("terms           {}", m.terms().join(", "));
        for (k, e) in estimates.iter().enumerate() {
            println!(
                "{:<16}{} for the {} steps at {:.2e} steps/s ({:.2e} block-steps/s) on {}",
                if k == 0 { "wall time" } else { "" },
                duration(e.wall_seconds),
                m.total_steps(),
                e.steps_per_second,
                e.steps_per_second * m.n_blocks() as f64,
                e.engine
            );
        }
        if !estimates.is_empty() {
            println!(
                "                (measured here over {MEASURE_SECONDS} s of quiet loading: events \
                 run slower, --fast-forward skips quiet stretches)"
            );
        }
        for why in &not_measured {
            println!("not measured    {why}");
        }
    }
    Ok(if stable {
        ExitCode::SUCCESS
    } else {
        eprintln!(
            "error: time.dt = {:.4e} s is above the stability limit {:.4e} s",
            m.dt,
            lim.min()
        );
        ExitCode::from(1)
    })
}
