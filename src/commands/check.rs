use slipfront::model::Model;
use std::path::PathBuf;
use std::process::ExitCode;

pub fn check(scenario: Option<PathBuf>, set: &[String], json: bool) -> anyhow::Result<ExitCode> {
    let (s, name) = super::load_scenario(scenario.as_deref(), set)?;
    let m = Model::from_scenario(&s, true)?;
    let lim = m.stability_limit();
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
            "binding": lim.min(),
        },
        "stable": m.dt <= lim.min(),
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
            "stability       dt <= {:.4e} s (bulk undamped {:.4e}, bulk {:.4e}, interface {:.4e}, relaxation {:.4e}): {}",
            lim.min(),
            lim.bulk_undamped,
            lim.bulk,
            lim.interface,
            lim.relaxation,
            if m.dt <= lim.min() { "stable" } else { "UNSTABLE" }
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
    }
    Ok(ExitCode::SUCCESS)
}
