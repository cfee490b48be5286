//! The `slipfront` command line.

mod commands;

use clap::{Parser, Subcommand};
use slipfront::engines::backend::{Backend, Precision};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "slipfront",
    version,
    about = "2D spring-block simulator of the onset of frictional sliding"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scenario (the built-in Table S1 stick-slip scene when none is given).
    Run(commands::run::RunArgs),
    /// Derived quantities, stability limit, memory and terms, without running.
    Check {
        scenario: Option<PathBuf>,
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        #[arg(long)]
        json: bool,
    },
    /// Channels, counts, time span and events of a run file.
    Info {
        file: PathBuf,
        /// Only the event table, as CSV.
        #[arg(long)]
        csv: bool,
        /// Ruptures less than this many seconds apart belong to one event.
        #[arg(long, default_value_t = DEFAULT_QUIET_GAP, value_parser = parse_quiet_gap)]
        quiet_gap: f64,
    },
    /// Figures of a run (PNG or SVG): space–time maps of the pinned
    /// fraction, τ/p and slip speed, the loading curve, front speed and
    /// tip, precursors, slip histories and profiles, slip against front
    /// speed.
    Plot {
        file: PathBuf,
        /// Folder for the figures (default: beside the run file).
        #[arg(short = 'o', long)]
        out_dir: Option<PathBuf>,
        /// Figures to draw, comma-separated (default: all).
        #[arg(long, value_enum, value_delimiter = ',')]
        kind: Vec<commands::plot::PlotKind>,
        /// Also draw event N alone (maps and front speed; numbers as in `info`).
        #[arg(long)]
        event: Option<usize>,
        /// Positions (mm) for the slip history, comma-separated (default:
        /// five spread from edge to edge).
        #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
        at: Vec<f64>,
        #[arg(long, value_enum, default_value = "png")]
        format: slipfront::analysis::plot::Format,
        /// Size in pixels at 100 dpi, WIDTHxHEIGHT.
        #[arg(long, default_value = "900x600", value_parser = slipfront::analysis::plot::FigureOptions::parse_size)]
        size: (u32, u32),
        /// Density: scales pixels, fonts and lines together (300 for print).
        #[arg(long, default_value_t = 100)]
        dpi: u32,
        /// Ruptures less than this many seconds apart belong to one event.
        #[arg(long, default_value_t = DEFAULT_QUIET_GAP, value_parser = parse_quiet_gap)]
        quiet_gap: f64,
    },
    /// Rewrite a run file cut short (a killed run) with its summary, so any
    /// MCAP reader opens it; in place (the cut file kept as RUN.mcap.cut)
    /// unless -o names another file.
    Recover {
        file: PathBuf,
        #[arg(short = 'o', long)]
        output: Option<PathBuf>,
        /// Replace an existing output (or .cut) file.
        #[arg(long)]
        force: bool,
    },
    /// Serve a run file to Foxglove viewers as `run --live` serves a
    /// running one, paced in simulated time (the whole run in a minute
    /// unless --speed says otherwise).
    Replay {
        file: PathBuf,
        /// Where to listen: HOST:PORT (default 127.0.0.1:8765; port 0
        /// takes a free one).
        #[arg(long, value_name = "ADDR", num_args = 0..=1,
              default_value = slipfront::io::live::DEFAULT_LIVE_ADDRESS,
              default_missing_value = slipfront::io::live::DEFAULT_LIVE_ADDRESS)]
        live: slipfront::io::live::LiveAddress,
        /// Simulated seconds per wall second (0: as fast as viewers take
        /// them).
        #[arg(long, value_parser = parse_speed)]
        speed: Option<f64>,
        /// Start once a viewer has subscribed.
        #[arg(long)]
        live_wait: bool,
    },
    /// Run a single-block scene (scenarios/thogersen2014_single_block.toml
    /// by default): one block and its junctions under a prescribed slip
    /// history or pulled through a spring; writes a CSV time series.
    SingleBlock {
        scenario: Option<PathBuf>,
        /// CSV output (time, position, velocity, friction coefficient,
        /// pinned fraction).
        #[arg(short = 'o', long, default_value = "single_block.csv")]
        output: PathBuf,
    },
    /// Regenerate one of the thesis studies into results/ (table, figure, notes).
    Study {
        #[arg(value_enum)]
        study: commands::study::StudyName,
        /// Folder for the table, figure and notes.
        #[arg(short = 'o', long, default_value = "results")]
        out_dir: PathBuf,
        /// A small grid (a few points, short chains): minutes, not hours.
        #[arg(long)]
        quick: bool,
        #[arg(long, value_enum, default_value = "cpu")]
        backend: Backend,
        /// Default: f64 (mixed f32 only on a GPU without SHADER_F64).
        #[arg(long, value_enum)]
        precision: Option<Precision>,
        /// Points run at once, one thread each (0: one per core).
        #[arg(long, default_value_t = 0)]
        threads: usize,
    },
    /// Run a parameter sweep (or `sweep collect DIR` to merge shard tables).
    #[command(args_conflicts_with_subcommands = true)]
    Sweep {
        #[command(subcommand)]
        action: Option<SweepAction>,
        #[command(flatten)]
        run: SweepRun,
    },
    /// Compare two sweep ensembles' outcome distributions (KS, Anderson–
    /// Darling, exact tests on counts and mode occupancy); exits 1 when an
    /// outcome differs at p < alpha (with --members: when the corrected
    /// verdict does).
    Compare {
        /// A sweep folder (its summary.csv) or a table (.csv).
        a: PathBuf,
        b: PathBuf,
        /// Significance level of each test.
        #[arg(long, default_value_t = slipfront::app::sweeps::compare::DEFAULT_ALPHA)]
        alpha: f64,
        /// Name of A in the report (default: its path).
        #[arg(long)]
        label_a: Option<String>,
        #[arg(long)]
        label_b: Option<String>,
        /// Print a JSON object instead of the tables.
        #[arg(long)]
        json: bool,
        /// Draw both ensembles' empirical CDFs, a panel per outcome (.png or .svg).
        #[arg(short = 'o', long, value_name = "FIGURE")]
        output: Option<PathBuf>,
        /// Judge by one Bonferroni-corrected verdict over the tests fair for
        /// these members; the closing line and exit status follow it.
        #[arg(long, value_enum)]
        members: Option<slipfront::app::sweeps::verdict::Members>,
    },
    /// Run the validation cases and compare measured against expected.
    Verify {
        #[arg(long, value_enum, default_value = "cpu")]
        backend: Backend,
        /// Default: f64 (mixed f32 only on a GPU without SHADER_F64).
        #[arg(long, value_enum)]
        precision: Option<Precision>,
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
enum SweepAction {
    /// Merge the shard tables of a sweep folder into its summary.csv.
    Collect { dir: PathBuf },
    /// An outcome against a swept key, coloured by another (PNG and medians).
    Plot {
        dir: PathBuf,
        /// Column for x (a swept key).
        #[arg(long)]
        x: String,
        /// Column for y (an outcome).
        #[arg(long)]
        y: String,
        /// Column whose values get one colour each.
        #[arg(long)]
        color: Option<String>,
        #[arg(long)]
        log_y: bool,
    },
}

#[derive(clap::Args)]
struct SweepRun {
    /// The sweep file (TOML: base, axes, combine, seeds, set).
    file: Option<PathBuf>,
    /// Folder for summary.csv and the runs (default: NAME_sweep beside the file).
    #[arg(short = 'o', long)]
    out_dir: Option<PathBuf>,
    /// List the points, the steps and the memory, and run nothing.
    #[arg(long)]
    dry_run: bool,
    /// `auto`: GPU ensembles on a hardware adapter that computes in the
    /// precision asked, else the CPU's threads.
    #[arg(long, value_enum, default_value = "auto")]
    backend: Backend,
    /// Default: f64 (mixed f32 only on a GPU without SHADER_F64).
    #[arg(long, value_enum)]
    precision: Option<Precision>,
    /// Scenes run at once, one thread each (0: one per core; on the GPU
    /// backend, 0 runs the points alone one at a time).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Run every N-th point from I (a job-array task's share): I/N.
    #[arg(long)]
    shard: Option<slipfront::app::sweeps::Shard>,
    /// Which runs keep their MCAP file: all, none or first:N.
    #[arg(long, default_value = "none")]
    mcap: slipfront::app::sweeps::KeepMcap,
    /// Write DIR/sweep.sbatch, a Slurm job array of shards, and run nothing.
    #[arg(long)]
    slurm: bool,
    #[arg(long, requires = "slurm")]
    partition: Option<String>,
    /// Time limit per array task (sbatch --time).
    #[arg(long, requires = "slurm")]
    time: Option<String>,
    /// Array tasks (default: one per point).
    #[arg(long, requires = "slurm")]
    array_size: Option<usize>,
    #[arg(long, requires = "slurm", default_value_t = 1)]
    cpus_per_task: usize,
    /// No line per finished point.
    #[arg(long)]
    quiet: bool,
    /// Run every point's normal-load phase itself, even where points share
    /// it (the results are the same bits either way).
    #[arg(long)]
    no_shared_loading: bool,
    /// GPU backend: scenes stepped together in one dispatch at most (points
    /// of one lattice shape and time schedule); 1 runs them one at a time.
    #[arg(long, default_value_t = slipfront::app::sweeps::DEFAULT_ENSEMBLE)]
    ensemble: usize,
    /// GPU backend: the kernel, as `run --gpu-path`. `auto` on a hardware
    /// GPU and `measure` time the kernels once per lattice shape on an
    /// ensemble of the sweep's own points (256, or as many as it has) and
    /// run every point of that shape on the fastest, alone or in ensembles.
    #[arg(long, value_enum, default_value = "auto")]
    gpu_path: slipfront::engines::gpu::GpuPath,
    /// GPU backend: where the points' samples are made, alone or as
    /// ensembles alike (so a table does not depend on --ensemble):
    /// `device` records every scene of an ensemble in one dispatch and
    /// reads back only what is due; `host` takes a snapshot per sample
    /// (the reference path).
    #[arg(long, value_enum, default_value = "device")]
    gpu_output: slipfront::engines::gpu::GpuOutput,
    #[command(flatten)]
    gpu: commands::gpu_launch::GpuLaunchArgs,
}

fn main() -> ExitCode {
    restore_default_sigpipe();
    private_runtime_dir();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => commands::run::run(args),
        Command::Check {
            scenario,
            set,
            json,
        } => commands::check::check(scenario, &set, json),
        Command::Info {
            file,
            csv: true,
            quiet_gap,
        } => commands::info::events_csv(&file, quiet_gap),
        Command::Info {
            file, quiet_gap, ..
        } => commands::info::info(&file, quiet_gap),
        Command::Plot {
            file,
            out_dir,
            kind,
            event,
            at,
            format,
            size,
            dpi,
            quiet_gap,
        } => commands::plot::plot(commands::plot::PlotArgs {
            file,
            out_dir,
            kinds: kind,
            event,
            at,
            options: slipfront::analysis::plot::FigureOptions {
                format,
                width: size.0,
                height: size.1,
                dpi,
            },
            quiet_gap,
        }),
        Command::Recover {
            file,
            output,
            force,
        } => commands::recover::recover(&file, output, force),
        Command::Verify {
            backend,
            precision,
            json,
        } => commands::verify::verify(backend, precision, json),
        Command::Compare {
            a,
            b,
            alpha,
            label_a,
            label_b,
            json,
            output,
            members,
        } => commands::compare::compare(commands::compare::CompareArgs {
            a,
            b,
            alpha,
            label_a,
            label_b,
            json,
            figure: output,
            members,
        }),
        Command::Replay {
            file,
            live,
            speed,
            live_wait,
        } => commands::replay::replay(commands::replay::ReplayArgs {
            file: &file,
            live: &live,
            speed,
            wait: live_wait,
        }),
        Command::SingleBlock { scenario, output } => {
            commands::study::single_block_run(scenario.as_deref(), &output)
        }
        Command::Study {
            study,
            out_dir,
            quick,
            backend,
            precision,
            threads,
        } => commands::study::study(commands::study::StudyArgs {
            study,
            out_dir,
            quick,
            backend,
            precision: precision.unwrap_or(backend.default_precision()),
            threads,
        }),
        Command::Sweep {
            action: Some(SweepAction::Collect { dir }),
            ..
        } => commands::sweep::collect_tables(&dir),
        Command::Sweep {
            action:
                Some(SweepAction::Plot {
                    dir,
                    x,
                    y,
                    color,
                    log_y,
                }),
            ..
        } => commands::sweep::plot(&dir, &x, &y, color.as_deref(), log_y),
        Command::Sweep { action: None, run } => match run.file {
            None => Err(anyhow::anyhow!(
                "sweep: give a sweep file (slipfront sweep SWEEP.toml) or `sweep collect DIR`"
            )),
            Some(file) => commands::sweep::sweep(commands::sweep::SweepArgs {
                file,
                out_dir: run.out_dir,
                dry_run: run.dry_run,
                backend: run.backend,
                precision: run.precision,
                threads: run.threads,
                shard: run.shard,
                mcap: run.mcap,
                slurm: run.slurm,
                partition: run.partition,
                time: run.time,
                array_size: run.array_size,
                cpus_per_task: run.cpus_per_task,
                quiet: run.quiet,
                no_shared_loading: run.no_shared_loading,
                ensemble: run.ensemble,
                gpu: run.gpu.options(run.gpu_path, run.gpu_output),
            }),
        },
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {}", error_text(&e));
            ExitCode::from(2)
        }
    }
}

use slipfront::analysis::events::DEFAULT_QUIET_GAP;

/// An error and its causes, each said once: most of our messages already
/// quote their cause, which the chain would repeat.
fn error_text(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text = format!("{text}: {cause}");
        }
    }
    text
}

fn parse_quiet_gap(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!(
            "--quiet-gap = {text}: expected a time in seconds, 0 or more"
        )),
    }
}

fn parse_speed(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!(
            "--speed = {text}: expected simulated seconds per wall second, 0 or more \
             (0: as fast as viewers take them)"
        )),
    }
}

/// Mesa's Vulkan drivers print "XDG_RUNTIME_DIR is invalid or not set" (twice)
/// whenever an adapter is probed without one, as on CI machines and under
/// Slurm; a private directory for this process keeps that noise out of
/// every run's output.
fn private_runtime_dir() {
    #[cfg(unix)]
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        use std::os::unix::fs::PermissionsExt;
        // SAFETY: libc::getuid has no preconditions.
        let uid = unsafe { libc::getuid() };
        let dir = std::env::temp_dir().join(format!("slipfront-runtime-{uid}"));
        let ok = std::fs::create_dir_all(&dir).is_ok()
            && std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700)).is_ok();
        if ok {
            // SAFETY: called first thing in main, before any thread exists.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}

/// Rust ignores SIGPIPE, so `slipfront info run.mcap | head` would panic
/// on the closed pipe; restore the default so the process just ends, as
/// other command-line tools do.
fn restore_default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any thread or I/O exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
