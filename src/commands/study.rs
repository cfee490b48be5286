//! `slipfront study NAME`: regenerates one thesis study into a folder.

use anyhow::Context;
use rayon::prelude::*;
use slipfront::app::studies::{coulomb_precursors, front_1d, junction_laws, slow_slip};
use slipfront::engines::backend::{Backend, Precision};
use slipfront::model::friction::junctions::SlipAtRest;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum StudyName {
    /// Steady-state front speed along 1D chains (Amundsen et al. 2015).
    #[value(name = "front-1d")]
    Front1d,
    /// Precursors with Coulomb friction under Maegawa's normal loadings
    /// (Trømborg et al. 2011).
    CoulombPrecursors,
    /// One block under prescribed motion: μ(v) of three junction laws and
    /// the next static threshold against the stop (Thøgersen et al. 2014).
    SingleBlock,
}

pub struct StudyArgs {
    pub study: StudyName,
    pub out_dir: PathBuf,
    pub quick: bool,
    pub backend: Backend,
    pub precision: Precision,
    pub threads: usize,
}

pub fn study(a: StudyArgs) -> anyhow::Result<ExitCode> {
    std::fs::create_dir_all(&a.out_dir)
        .with_context(|| format!("creating {}", a.out_dir.display()))?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads)
        .build()
        .context("thread pool")?;
    match a.study {
        StudyName::Front1d => pool.install(|| front_1d_study(&a))?,
        StudyName::CoulombPrecursors => pool.install(|| coulomb_precursors_study(&a))?,
        StudyName::SingleBlock => pool.install(|| single_block_study(&a))?,
    }
    Ok(ExitCode::SUCCESS)
}

fn front_1d_study(a: &StudyArgs) -> anyhow::Result<()> {
    let grid = if a.quick {
        front_1d::Grid::quick()
    } else {
        front_1d::Grid::full()
    };
    let points = grid.points();
    eprintln!(
        "front-1d: {} points × lengths {:?} (+ dt/2 at {}) on {:?} {:?}",
        points.len(),
        grid.lengths,
        grid.dt_check_length,
        a.backend,
        a.precision
    );
    let started = Instant::now();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let results = points
        .par_iter()
        .map(|&case| {
            let r = front_1d::run_point(case, &grid, a.backend, a.precision);
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if n.is_multiple_of((points.len() / 10).max(1)) {
                eprintln!(
                    "front-1d: {n} of {} points, {:.0} s",
                    points.len(),
                    started.elapsed().as_secs_f64()
                );
            }
            r
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let wall = started.elapsed().as_secs_f64();
    let csv_path = a.out_dir.join("front_speed_1d.csv");
    std::fs::write(&csv_path, front_1d::csv(&results))
        .with_context(|| format!("writing {}", csv_path.display()))?;
    let how = format!(
        "slipfront study front-1d{} --backend {:?} --precision {:?}",
        if a.quick { " --quick" } else { "" },
        a.backend,
        a.precision
    )
    .to_lowercase();
    let mut notes = front_1d::report(&results, &grid, &how);
    notes.push_str(&format!(
        "Wall time {wall:.0} s on {} threads ({}).\n",
        rayon::current_num_threads(),
        machine()
    ));
    let md_path = a.out_dir.join("front_speed_1d.md");
    std::fs::write(&md_path, notes).with_context(|| format!("writing {}", md_path.display()))?;
    let figures = front_1d::write_figures(&results, &a.out_dir)?;
    eprintln!(
        "front-1d: {}, {} and {} figure(s) in {wall:.0} s",
        csv_path.display(),
        md_path.display(),
        figures.len()
    );
    Ok(())
}

/// The CPU model and core count, for the notes.
fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{cpu}, {cores} cores")
}

fn coulomb_precursors_study(a: &StudyArgs) -> anyhow::Result<()> {
    use coulomb_precursors::{Loading, SCENARIO_PATH};
    let scenario = std::path::Path::new(SCENARIO_PATH);
    let base = slipfront::Scenario::load(scenario, &[])?;
    let area = base.geometry.length * base.geometry.width;
    let runs = a.out_dir.join("tromborg2011_runs");
    std::fs::create_dir_all(&runs).with_context(|| format!("creating {}", runs.display()))?;
    // The quick version stops after the first precursors.
    let t_end = if a.quick { Some(0.06) } else { None };
    let started = Instant::now();
    let results = Loading::MAEGAWA
        .par_iter()
        .map(|&loading| {
            let output = runs.join(format!("{}.mcap", loading.file_stem()));
            crate::commands::run::run(crate::commands::run::RunArgs {
                scenario: Some(scenario.to_path_buf()),
                backend: a.backend,
                gpu_path: slipfront::engines::gpu::GpuPath::Auto,
                gpu_output: slipfront::engines::gpu::GpuOutput::Device,
                gpu: Default::default(),
                precision: Some(a.precision),
                set: loading.overrides(),
                t_end,
                fast_forward: None,
                output: Some(output.clone()),
                threads: 1,
                allow_unstable: false,
                progress: slipfront::app::runner::ProgressMode::None,
                quiet: true,
                resume: None,
                from: None,
                force: true,
                no_memory_check: false,
                live: None,
                live_wait: false,
            })?;
            coulomb_precursors::analyse(loading, &output)
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let wall = started.elapsed().as_secs_f64();
    let mean = |l: &Loading| (l.trailing + l.leading) / area;
    let how = format!(
        "slipfront study coulomb-precursors{} --backend {:?} --precision {:?}",
        if a.quick { " --quick" } else { "" },
        a.backend,
        a.precision
    )
    .to_lowercase();
    let mut notes = coulomb_precursors::report(&results, &how, mean);
    notes.push_str(&format!(
        "\nThe study writes the three runs (MCAP, readable with `slipfront info` and \
         `slipfront plot`) to `{}`; run files are not kept in the repository. Wall time {wall:.0} s for the three on {} threads ({}).\n",
        runs.display(),
        rayon::current_num_threads(),
        machine()
    ));
    let csv_path = a.out_dir.join("tromborg2011_coulomb_precursors.csv");
    std::fs::write(&csv_path, coulomb_precursors::csv(&results))
        .with_context(|| format!("writing {}", csv_path.display()))?;
    let md_path = a.out_dir.join("tromborg2011_coulomb_precursors.md");
    std::fs::write(&md_path, notes).with_context(|| format!("writing {}", md_path.display()))?;
    let figures = coulomb_precursors::write_figures(&results, &a.out_dir, mean)?;
    eprintln!(
        "coulomb-precursors: {}, {} and {} figure(s) in {wall:.0} s",
        csv_path.display(),
        md_path.display(),
        figures.len()
    );
    Ok(())
}

fn single_block_study(a: &StudyArgs) -> anyhow::Result<()> {
    let scene = slipfront::engines::single_block::SingleBlockScene::parse(
        slipfront::engines::single_block::SCENARIO,
        "scenarios/thogersen2014_single_block.toml",
    )?;
    let started = Instant::now();
    let laws = junction_laws::laws(&scene.law);
    let (per_decade, cycles) = if a.quick { (1, 10.0) } else { (4, 40.0) };
    let points = junction_laws::friction_curves(
        &laws,
        &junction_laws::speeds(per_decade),
        scene.junctions as usize,
        cycles,
    );
    let decelerations: Vec<f64> = if a.quick {
        vec![1e-2, 1.0, 1e2]
    } else {
        (0..=12)
            .map(|i| 10f64.powf(-3.0 + 0.5 * i as f64))
            .collect()
    };
    let thresholds = junction_laws::threshold_vs_deceleration(&scene, &decelerations);
    let count = if a.quick { 100 } else { 1000 };
    let mut slow = Vec::new();
    for rule in [SlipAtRest::Hold, SlipAtRest::Sign] {
        slow.extend(slow_slip::cases(
            "constant μd",
            &scene.law,
            rule,
            count,
            scene.seed,
        ));
    }
    let wall = started.elapsed().as_secs_f64();
    let how = format!(
        "slipfront study single-block{}",
        if a.quick { " --quick" } else { "" }
    );
    let mut notes = junction_laws::report(&laws, &points, &thresholds, &scene, &how);
    notes.push_str(&slow_slip::report(&slow, count));
    notes.push_str(&format!(
        "\nWall time {wall:.0} s on {} threads ({}); the single-block model runs on the CPU only (one \
         block has no parallel work for a GPU).\n",
        rayon::current_num_threads(),
        machine()
    ));
    let write = |name: &str, text: String| -> anyhow::Result<()> {
        let path = a.out_dir.join(name);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))
    };
    write(
        "thogersen2014_friction_vs_speed.csv",
        junction_laws::friction_csv(&laws, &points),
    )?;
    let mut t = String::from("deceleration_m_per_s2,static_threshold\n");
    for (d, m) in &thresholds {
        t.push_str(&format!("{d:.4e},{m:.6}\n"));
    }
    write("thogersen2014_threshold_vs_deceleration.csv", t)?;
    write("thogersen2014_single_block.md", notes)?;
    let mut figures = junction_laws::write_figures(&laws, &points, &thresholds, &a.out_dir)?;
    figures.extend(slow_slip::write_figures(&slow, &a.out_dir)?);
    eprintln!(
        "single-block: notes, 2 tables and {} figure(s) in {} in {wall:.0} s",
        figures.len(),
        a.out_dir.display()
    );
    Ok(())
}

/// `slipfront single-block [SCENARIO] -o OUT.csv`.
pub fn single_block_run(
    scenario: Option<&std::path::Path>,
    output: &std::path::Path,
) -> anyhow::Result<ExitCode> {
    use slipfront::engines::single_block::SingleBlockScene;
    let scene = match scenario {
        Some(p) => SingleBlockScene::load(p)?,
        None => SingleBlockScene::parse(
            slipfront::engines::single_block::SCENARIO,
            "scenarios/thogersen2014_single_block.toml (built in)",
        )?,
    };
    let mut csv =
        String::from("time_s,position_m,velocity_m_per_s,friction_coefficient,pinned_fraction\n");
    let mut peak: f64 = 0.0;
    scene.run(|s| {
        peak = peak.max(s.friction);
        csv.push_str(&format!(
            "{:.9e},{:.9e},{:.6e},{:.6},{:.5}\n",
            s.time, s.position, s.velocity, s.friction, s.pinned
        ));
    });
    let tmp = output.with_extension("csv.partial");
    std::fs::write(&tmp, csv).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, output).with_context(|| format!("writing {}", output.display()))?;
    eprintln!(
        "single-block `{}`: {} junctions, peak friction coefficient {peak:.4}; {}",
        scene.name,
        scene.junctions,
        output.display()
    );
    Ok(ExitCode::SUCCESS)
}
