use slipfront::app::sweeps::slurm::{script, SlurmOptions};
use slipfront::app::sweeps::{collect, run_sweep, KeepMcap, Shard, Sweep, SweepOptions};
use slipfront::engines::backend::{Backend, Precision};
use slipfront::model::Model;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

pub struct SweepArgs {
    pub file: PathBuf,
    pub out_dir: Option<PathBuf>,
    pub dry_run: bool,
    pub backend: Backend,
    pub precision: Option<Precision>,
    pub threads: usize,
    pub shard: Option<Shard>,
    pub mcap: KeepMcap,
    pub slurm: bool,
    pub partition: Option<String>,
    pub time: Option<String>,
    pub array_size: Option<usize>,
    pub cpus_per_task: usize,
    pub quiet: bool,
    pub no_shared_loading: bool,
    pub ensemble: usize,
    pub gpu: slipfront::engines::gpu::GpuOptions,
}

/// `NAME.toml` → `NAME_sweep` beside it.
fn default_dir(file: &Path) -> PathBuf {
    let stem = file
        .file_stem()
        .map_or("sweep".into(), |s| s.to_string_lossy().into_owned());
    file.with_file_name(format!("{stem}_sweep"))
}

fn load(file: &Path) -> anyhow::Result<Sweep> {
    Sweep::load(file).map_err(|problems| {
        anyhow::anyhow!(
            "invalid sweep `{}`:\n  - {}",
            file.display(),
            problems.join("\n  - ")
        )
    })
}

/// `--backend B [--precision P]` as the command line gave them.
fn engine_args(backend: Backend, precision: Option<Precision>) -> String {
    let name = |v: Option<clap::builder::PossibleValue>| {
        v.map_or(String::new(), |v| v.get_name().to_string())
    };
    let mut args = format!(
        "--backend {}",
        name(clap::ValueEnum::to_possible_value(&backend))
    );
    if let Some(p) = precision {
        args.push_str(&format!(
            " --precision {}",
            name(clap::ValueEnum::to_possible_value(&p))
        ));
    }
    args
}

pub fn sweep(a: SweepArgs) -> anyhow::Result<ExitCode> {
    let sweep = load(&a.file)?;
    let dir = a.out_dir.clone().unwrap_or_else(|| default_dir(&a.file));
    if a.dry_run {
        return dry_run(&sweep, a.shard);
    }
    if a.slurm {
        let tasks = a
            .array_size
            .unwrap_or(sweep.points.len())
            .clamp(1, sweep.points.len().max(1));
        let absolute = |p: &Path| std::path::absolute(p).unwrap_or(p.to_path_buf());
        std::fs::create_dir_all(&dir)?;
        let text = script(
            &absolute(&std::env::current_exe()?),
            &absolute(&a.file),
            &absolute(&dir),
            &SlurmOptions {
                tasks,
                partition: a.partition.as_deref(),
                time: a.time.as_deref(),
                cpus_per_task: a.cpus_per_task,
                engine_args: &engine_args(a.backend, a.precision),
            },
        );
        let path = dir.join("sweep.sbatch");
        std::fs::write(&path, text)?;
        println!("{}", path.display());
        eprintln!(
            "slipfront: {} points in {tasks} array tasks; submit with `sbatch {}`, then \
             `slipfront sweep collect {}`",
            sweep.points.len(),
            path.display(),
            dir.display()
        );
        return Ok(ExitCode::SUCCESS);
    }
    let precision = a.precision.unwrap_or(a.backend.default_precision());
    let backend = match a.backend {
        Backend::Auto => {
            let (backend, why) = slipfront::engines::backend::resolve_auto(precision);
            if !a.quiet {
                eprintln!("sweep: --backend auto: {why}");
            }
            backend
        }
        b => b,
    };
    let report = run_sweep(
        &sweep,
        &SweepOptions {
            out_dir: dir,
            backend,
            precision,
            threads: a.threads,
            shard: a.shard,
            keep_mcap: a.mcap,
            progress: !a.quiet,
            share_loading: !a.no_shared_loading,
            ensemble: a.ensemble,
            gpu: a.gpu,
            on_point: None,
        },
    )
    .map_err(|e| anyhow::anyhow!(e))?;
    println!(
        "sweep {}: {} points{}, {} run now ({} not ok), {} already done, {:.1} s, \
         {} shared normal-load phases{}\n  table {}",
        if report.interrupted {
            "INTERRUPTED"
        } else {
            "complete"
        },
        report.points,
        a.shard.map_or(String::new(), |s| format!(
            " (shard {}/{})",
            s.index, s.count
        )),
        report.ran,
        report.not_ok,
        report.skipped,
        report.wall_seconds,
        report.shared_loadings,
        if report.ensembles.is_empty() {
            String::new()
        } else {
            let sizes: Vec<String> = report.ensembles.iter().map(|n| n.to_string()).collect();
            format!(", GPU ensembles of {}", sizes.join(", "))
        },
        report.table.display()
    );
    Ok(if report.interrupted {
        ExitCode::from(130)
    } else {
        ExitCode::SUCCESS
    })
}

fn dry_run(sweep: &Sweep, shard: Option<Shard>) -> anyhow::Result<ExitCode> {
    let mut steps = 0u64;
    let mut memory = 0usize;
    let mine: Vec<_> = sweep
        .points
        .iter()
        .filter(|p| shard.is_none_or(|s| p.index % s.count == s.index))
        .collect();
    for p in &mine {
        let m = Model::from_scenario(&p.scenario, false)?;
        steps += m.total_steps();
        memory = memory.max(m.memory_bytes(8, 8));
        println!(
            "point {:<5} {} ({} × {} blocks, {} steps)",
            p.index,
            p.label(),
            m.nx,
            m.nz,
            m.total_steps()
        );
    }
    println!(
        "{} points{}, {steps} steps in all, at most {:.2} MiB per scene (f64)",
        mine.len(),
        shard.map_or(String::new(), |s| format!(
            " of {} (shard {}/{})",
            sweep.points.len(),
            s.index,
            s.count
        )),
        memory as f64 / 1048576.0
    );
    Ok(ExitCode::SUCCESS)
}

pub fn collect_tables(dir: &Path) -> anyhow::Result<ExitCode> {
    let (path, rows, missing) = collect(dir).map_err(|e| anyhow::anyhow!(e))?;
    println!("{}: {rows} rows", path.display());
    if missing.is_empty() {
        Ok(ExitCode::SUCCESS)
    } else {
        eprintln!(
            "slipfront: {} points have no row yet: {:?}",
            missing.len(),
            missing
        );
        Ok(ExitCode::from(1))
    }
}

/// `sweep plot DIR --x KEY --y OUTCOME [--color KEY]`: the outcome against
/// a swept key, one colour per value of another, as a PNG beside the
/// table, with the legend and the per-(x, colour) medians printed.
pub fn plot(
    dir: &Path,
    x: &str,
    y: &str,
    color: Option<&str>,
    log_y: bool,
) -> anyhow::Result<ExitCode> {
    use slipfront::app::sweeps::table::split;
    let path = dir.join("summary.csv");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        anyhow::anyhow!("`{}`: {e} (run or collect the sweep first)", path.display())
    })?;
    let mut lines = text.lines();
    let header = split(lines.next().unwrap_or_default());
    let col = |name: &str| {
        header.iter().position(|h| h == name).ok_or_else(|| {
            anyhow::anyhow!(
                "`{name}` is not a column of {}: {}",
                path.display(),
                header.join(", ")
            )
        })
    };
    let (cx, cy, status) = (col(x)?, col(y)?, col("status")?);
    let cc = color.map(col).transpose()?;
    let mut groups: Vec<String> = Vec::new();
    let mut points = Vec::new();
    for row in lines
        .map(split)
        .filter(|r| r.len() == header.len() && r[status] == "ok")
    {
        let (Ok(a), Ok(b)) = (row[cx].parse::<f64>(), row[cy].parse::<f64>()) else {
            continue;
        };
        let g = cc.map_or(String::new(), |c| row[c].clone());
        let k = groups.iter().position(|x| *x == g).unwrap_or_else(|| {
            groups.push(g);
            groups.len() - 1
        });
        points.push((a, b, k));
    }
    if points.is_empty() {
        anyhow::bail!("no ok rows with numbers in `{x}` and `{y}`");
    }
    let file = dir.join(format!("plot_{}_vs_{}.png", y, x).replace(['/', ' '], "_"));
    let title = format!("{y} against {x}");
    slipfront::analysis::plot::write(
        &slipfront::analysis::plot::scatter::Scatter {
            points: &points,
            groups: &groups,
            group_label: color.unwrap_or(""),
            x_label: x,
            y_label: y,
            log_y,
            title: &title,
            connect: false,
        },
        &file,
        &slipfront::analysis::plot::FigureOptions::default(),
        &dir.display().to_string(),
    )?;
    println!("{}", file.display());
    const COLOURS: [&str; 6] = ["black", "red", "blue", "green", "orange", "purple"];
    println!(
        "{x:<24} {:<16} {y} (median of {} rows)",
        color.unwrap_or(""),
        points.len()
    );
    let mut xs: Vec<f64> = points.iter().map(|p| p.0).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    for xv in xs {
        for (k, g) in groups.iter().enumerate() {
            let mut v: Vec<f64> = points
                .iter()
                .filter(|p| p.0 == xv && p.2 == k)
                .map(|p| p.1)
                .collect();
            if v.is_empty() {
                continue;
            }
            v.sort_by(f64::total_cmp);
            let median = if v.len() % 2 == 1 {
                v[v.len() / 2]
            } else {
                0.5 * (v[v.len() / 2 - 1] + v[v.len() / 2])
            };
            println!(
                "{xv:<24} {:<16} {median:.4e} (n = {}, {} .. {})",
                format!("{g} ({})", COLOURS[k % COLOURS.len()]),
                v.len(),
                format_args!("{:.3e}", v[0]),
                format_args!("{:.3e}", v[v.len() - 1])
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
