use slipfront::app::runner::{run_scene, sample_plan, ProgressMode, RunOptions, StartFrom};
use slipfront::engines::backend::{make_engine_with, Backend, Precision};
use slipfront::engines::gpu::{GpuOutput, GpuPath};
use slipfront::engines::{Engine, SamplePlan};
use slipfront::io::checkpoint::{branch, path_for, Checkpoint};
use slipfront::io::live::{largest_record, LiveAddress, DEFAULT_LIVE_ADDRESS};
use slipfront::io::output::fnv1a;
use slipfront::io::output::lock::RunLock;
use slipfront::model::scenario::Scenario;
use slipfront::model::Model;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `slipfront run`: its options, parsed by clap straight into this.
#[derive(clap::Args)]
pub struct RunArgs {
    pub scenario: Option<PathBuf>,
    #[arg(long, value_enum, default_value = "auto")]
    pub backend: Backend,
    /// GPU kernel: one-step (1 dispatch per step), one-step-lanes
    /// (junction lanes in parallel), persistent (many steps per
    /// dispatch, small lattices), resident (persistent with the lattice
    /// in workgroup memory, where it fits), tiled (a workgroup per column
    /// tile, up to 4 steps per dispatch; junction friction), auto (on a hardware GPU the fastest,
    /// timed on this scene at start-up and cached per adapter and
    /// lattice) or measure (time them now, on any adapter).
    #[arg(long, value_enum, default_value = "auto")]
    pub gpu_path: GpuPath,
    /// Where a GPU run's output samples are made: device (only the
    /// channels due are read back) or host (a snapshot per sample).
    #[arg(long, value_enum, default_value = "device")]
    pub gpu_output: GpuOutput,
    #[command(flatten)]
    pub gpu: crate::commands::gpu_launch::GpuLaunchArgs,
    #[arg(long, value_enum)]
    pub precision: Option<Precision>,
    /// Override a scenario key: --set loading.drive.velocity=1e-3
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Simulated time after the normal-load phase (s); overrides time.end.
    #[arg(long, value_parser = parse_t_end)]
    pub t_end: Option<f64>,
    /// Quasi-static fast-forward through the stick phases: on or off
    /// (overrides time.fast_forward).
    #[arg(long, value_name = "on|off", value_parser = parse_on_off)]
    pub fast_forward: Option<bool>,
    /// MCAP output file.
    #[arg(short = 'o', long)]
    pub output: Option<PathBuf>,
    /// CPU threads (0: every core on a lattice of 4096 blocks or more, the
    /// count timed fastest on a smaller one; 1: deterministic single thread).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Run even if dt is above the computed stability limit.
    #[arg(long)]
    pub allow_unstable: bool,
    /// Progress: a bar on a terminal, else a log line every 10 s (auto),
    /// or bar, plain or none.
    #[arg(long, value_enum, default_value = "auto")]
    pub progress: ProgressMode,
    /// No progress report (--progress none).
    #[arg(long)]
    pub quiet: bool,
    /// Continue RUN.mcap from its checkpoint (RUN.mcap.ckpt), in the
    /// same file unless -o names another; --t-end extends a finished run.
    #[arg(long, value_name = "RUN.mcap", conflicts_with = "from")]
    pub resume: Option<PathBuf>,
    /// Start from a saved state (a checkpoint, or a run file with one
    /// beside it): the scenario given (or the checkpoint's) with --set
    /// changes the saved state allows.
    #[arg(long, value_name = "CHECKPOINT")]
    pub from: Option<PathBuf>,
    /// Replace the output file if it exists.
    #[arg(long)]
    pub force: bool,
    /// Start even if the engine needs more memory than the machine has
    /// available now.
    #[arg(long)]
    pub no_memory_check: bool,
    /// Stream the run to Foxglove viewers over WebSocket, with or without
    /// -o: ADDR is HOST:PORT (default 127.0.0.1:8765; 0.0.0.0:PORT to
    /// serve other machines; port 0 takes a free one).
    #[arg(long, value_name = "ADDR", num_args = 0..=1,
          default_missing_value = DEFAULT_LIVE_ADDRESS)]
    pub live: Option<LiveAddress>,
    /// With --live: start stepping once a viewer has subscribed, so that
    /// it sees the run from its first record.
    #[arg(long, requires = "live")]
    pub live_wait: bool,
}

/// The same file (both exist and resolve to one path).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

impl RunArgs {
    /// A new run's output: never one of its inputs; an existing file only
    /// with --force; a previous run's checkpoints beside it removed, so a
    /// later --resume cannot take one of them for this run's.
    fn claim_output(&self, inputs: &[&Path]) -> anyhow::Result<()> {
        let Some(out) = &self.output else {
            return Ok(());
        };
        if let Some(input) = inputs.iter().find(|i| same_file(out, i)) {
            anyhow::bail!(
                "-o {}: that is an input of this run ({}); choose another output file",
                out.display(),
                input.display()
            );
        }
        if out.exists() && !self.force {
            anyhow::bail!(
                "`{}` exists: continue it with `slipfront run --resume {}`, or replace it \
                 with --force",
                out.display(),
                out.display()
            );
        }
        // The run's checkpoint, the one before it, the loaded slider's.
        for stale in Checkpoint::candidates(out) {
            let _ = std::fs::remove_file(&stale);
        }
        Ok(())
    }

    /// `--set` items with `--t-end` and `--fast-forward` folded in.
    fn overrides(&self) -> Vec<String> {
        let mut set = self.set.clone();
        if let Some(t) = self.t_end {
            set.push(format!("time.end={t:e}"));
        }
        if let Some(on) = self.fast_forward {
            set.push(format!("time.fast_forward={on}"));
        }
        set
    }

    /// The run's engine. `samples`: the cadences of the output file it
    /// writes, if any, which `auto` times the GPU's launches recording at
    /// (output weighs on them unequally).
    fn engine(
        &self,
        model: &Model,
        precision: Precision,
        samples: Option<SamplePlan>,
    ) -> anyhow::Result<Box<dyn Engine>> {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        if self.threads > 4 * cores {
            anyhow::bail!(
                "--threads {}: at most {} on this machine (4 × its {cores} cores; 0 takes \
                 them all)",
                self.threads,
                4 * cores
            );
        }
        if matches!(self.backend, Backend::Cpu) && self.threads > model.nz {
            // The CPU engine shares the rows out: one band of rows a thread.
            eprintln!(
                "slipfront: --threads {}: the CPU engine gives each thread whole rows of \
                 blocks, and this lattice has {} rows, so {} threads work on it",
                self.threads, model.nz, model.nz
            );
        }
        if !self.no_memory_check {
            precision
                .check_memory(model, "pass --no-memory-check to try anyway")
                .map_err(anyhow::Error::msg)?;
        }
        let mut gpu = self.gpu.options(self.gpu_path, self.gpu_output);
        gpu.samples = samples.filter(|_| gpu.output == GpuOutput::Device);
        Ok(make_engine_with(
            model,
            self.backend,
            precision,
            self.threads,
            gpu,
        )?)
    }
}

pub fn run(a: RunArgs) -> anyhow::Result<ExitCode> {
    if a.resume.is_some() {
        return resume(a);
    }
    if a.from.is_some() {
        return branch_run(a);
    }
    let (scenario, name) = super::load_scenario(a.scenario.as_deref(), &a.overrides())?;
    let model = Model::from_scenario(&scenario, a.allow_unstable)?;
    a.claim_output(&a.scenario.iter().map(PathBuf::as_path).collect::<Vec<_>>())?;
    let _lock = lock_output(&a, "run")?;
    let precision = a.precision.unwrap_or(a.backend.default_precision());
    let samples = a.output.is_some().then(|| sample_plan(&model, &scenario));
    let mut engine = a.engine(&model, precision, samples)?;
    eprintln!("slipfront: {name} on {}", engine.describe());
    let history = vec![format!(
        "started: scenario `{}` ({name}, hash {:016x}) on {}",
        scenario.name,
        fnv1a(scenario.to_toml().as_bytes()),
        engine.describe()
    )];
    finish(&a, engine.as_mut(), &scenario, history, None)
}

/// Runs to the end and prints the summary.
fn finish(
    a: &RunArgs,
    engine: &mut dyn Engine,
    scenario: &Scenario,
    history: Vec<String>,
    start: Option<StartFrom>,
) -> anyhow::Result<ExitCode> {
    if a.output.is_none() {
        eprintln!("slipfront: no output file: nothing of this run is kept (-o run.mcap keeps it)");
    }
    let live = match &a.live {
        Some(address) => Some(super::replay::start_live(
            address,
            largest_record(
                engine.model().nx,
                engine.model().nz,
                scenario.output.bulk_interval > 0.0,
            ),
            a.live_wait,
        )?),
        None => None,
    };
    let summary = run_scene(
        engine,
        scenario,
        &RunOptions {
            live: live.clone(),
            output: a.output.clone(),
            progress: if a.quiet {
                ProgressMode::None
            } else {
                a.progress
            },
            history,
            start,
            ..RunOptions::default()
        },
    );
    if let Some(live) = &live {
        live.close();
    }
    let summary = summary?;
    println!("{summary}");
    // 128 + the signal (130 for Ctrl-C, 143 for SIGTERM), as shells report
    // it; the file is closed and a checkpoint written by now.
    Ok(if summary.interrupted {
        ExitCode::from(128 + slipfront::app::runner::stopping_signal().unwrap_or(2) as u8)
    } else {
        ExitCode::SUCCESS
    })
}

/// The file starts as a checkpoint does.
fn is_checkpoint(path: &Path) -> bool {
    use std::io::Read;
    let mut magic = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut magic))
        .is_ok_and(|_| &magic == slipfront::io::checkpoint::format::MAGIC)
}

/// The checkpoint named by `path`: a checkpoint file, or a run file with
/// one beside it.
fn checkpoint_of(path: &Path) -> PathBuf {
    let beside = path_for(path);
    if beside.exists() || !path.exists() {
        beside
    } else {
        path.to_path_buf()
    }
}

fn precision_of(ckpt: &Checkpoint, asked: Option<Precision>) -> anyhow::Result<Precision> {
    match asked {
        Some(p) => Ok(p),
        None => Precision::of_state(&ckpt.header.precision).ok_or_else(|| {
            anyhow::anyhow!(
                "the checkpoint's precision `{}` is unknown; choose one with --precision",
                ckpt.header.precision
            )
        }),
    }
}

/// "…; precision changed A → B" when the engine computes in another
/// precision than the one that saved the state.
fn precision_note(ckpt: &Checkpoint, engine: &mut dyn Engine) -> anyhow::Result<String> {
    let now = engine.save_state()?.precision;
    Ok(if now == ckpt.header.precision {
        String::new()
    } else {
        format!(
            "; precision changed {} → {now} (the state was rounded once)",
            ckpt.header.precision
        )
    })
}

/// Refuses, before anything is written, a checkpoint `used` of another
/// scene than the run file `file` it would continue (a checkpoint copied
/// over, or a file replaced): the two scenarios must be the same but for
/// their end time (which --t-end moves).
fn check_checkpoint_belongs(file: &Path, used: &Path, ckpt: &Checkpoint) -> anyhow::Result<()> {
    if !file.is_file() {
        return Ok(());
    }
    let (meta, text) = slipfront::io::output::reader::RunFile::read_head(file)
        .map_err(|e| anyhow::anyhow!("cannot resume `{}`: {e}", file.display()))?;
    let Some(text) = text else {
        anyhow::bail!(
            "cannot resume `{}`: it holds no scenario (not a slipfront run file); nothing was \
             changed",
            file.display()
        );
    };
    let parse = |text: &str, what: &str| {
        Scenario::parse(text, what, &[]).map(|mut s| {
            s.time.end = 0.0;
            s
        })
    };
    let (ours, theirs) = (
        parse(&text, "the run file's scenario")?,
        parse(&ckpt.header.scenario, "the checkpoint's scenario")?,
    );
    if ours != theirs {
        let shape =
            |s: &Scenario| format!("`{}`, {} × {} blocks", s.name, s.geometry.nx, s.geometry.nz);
        anyhow::bail!(
            "cannot resume `{}`: its checkpoint `{}` is of another scene (the file: {}{}; the \
             checkpoint: {}); nothing was changed. Resume from the run's own checkpoint, or \
             start a new run from this one with --from {} -o NEW.mcap",
            file.display(),
            used.display(),
            shape(&ours),
            meta.get("scenario_hash")
                .map_or(String::new(), |h| format!(", scenario hash {h}")),
            shape(&theirs),
            used.display()
        );
    }
    Ok(())
}

/// `--resume RUN.mcap`: the same run, continued from its newest good
/// checkpoint into the same file (or `-o`), to its end or a new `--t-end`.
fn resume(mut a: RunArgs) -> anyhow::Result<ExitCode> {
    let file = a.resume.clone().expect("resume");
    if a.scenario.is_some() || !a.set.is_empty() || a.fast_forward.is_some() {
        anyhow::bail!(
            "--resume continues a run as it was (only --t-end may move its end); to change \
             the scenario, branch: slipfront run [SCENARIO] --from {} --set KEY=VALUE -o NEW.mcap",
            path_for(&file).display()
        );
    }
    // The run file is locked before anything of it is read: a run still
    // writing it, or another resume, is refused here.
    let mut locks = Vec::new();
    if !is_checkpoint(&file) {
        locks.push(RunLock::acquire(&file, "resume").map_err(anyhow::Error::msg)?);
    }
    // The run file's checkpoints, newest first (or the one named).
    let candidates = if path_for(&file).exists() || !is_checkpoint(&file) {
        Checkpoint::candidates(&file)
    } else {
        vec![file.clone()]
    };
    let (ckpt, used, passed_over) = Checkpoint::first_good(&candidates).map_err(|why| {
        anyhow::anyhow!(
            "cannot resume `{}`: {}\n  (a run saves the loaded slider before driving starts, \
             then a checkpoint every output.checkpoint_interval seconds of wall time)",
            file.display(),
            why.join("; ")
        )
    })?;
    for why in passed_over {
        eprintln!("slipfront: passing over {why}");
    }
    if used != candidates[0] {
        eprintln!("slipfront: resuming from `{}`", used.display());
    }
    // Named by its checkpoint: the run file is the one it names.
    let file = match (is_checkpoint(&file), &ckpt.header.output) {
        (false, _) => file,
        (true, Some(out)) => out.clone(),
        (true, None) => anyhow::bail!(
            "`{}` names no run file to continue; branch from it with --from",
            file.display()
        ),
    };
    if locks.is_empty() {
        locks.push(RunLock::acquire(&file, "resume").map_err(anyhow::Error::msg)?);
    }
    check_checkpoint_belongs(&file, &used, &ckpt)?;
    let scenario = Scenario::parse(
        &ckpt.header.scenario,
        "the checkpoint's scenario",
        &a.overrides(),
    )?;
    // The run passed the stability check when it started (or was let
    // through it on purpose).
    let model = Model::from_scenario(&scenario, true)?;
    let step = ckpt.header.step;
    if model.total_steps() < step {
        anyhow::bail!(
            "--t-end {:e} s is before the checkpoint (t = {:.6e} s)",
            scenario.time.end,
            ckpt.header.time
        );
    }
    if model.total_steps() == step && a.t_end.is_none() {
        anyhow::bail!(
            "`{}` already reached its end (t = {:.6e} s); extend it with --t-end SECONDS",
            file.display(),
            ckpt.header.time
        );
    }
    let precision = precision_of(&ckpt, a.precision)?;
    // A resumed run always writes its file.
    let mut engine = a.engine(&model, precision, Some(sample_plan(&model, &scenario)))?;
    engine.load_state(&ckpt.engine)?;
    let note = precision_note(&ckpt, engine.as_mut())?;
    let mut history = ckpt.header.history.clone();
    history.push(format!(
        "resumed at step {step} (t = {:.6e} s) from `{}`, saved by {}; continued on {}{note}",
        ckpt.header.time,
        used.display(),
        ckpt.header.backend,
        engine.describe()
    ));
    eprintln!(
        "slipfront: resuming `{}` at t = {:.6e} s on {}{note}",
        file.display(),
        ckpt.header.time,
        engine.describe()
    );
    match &a.output {
        None => a.output = Some(file.clone()),
        Some(out) if !same_file(out, &file) => {
            a.claim_output(&[&file, &used])?;
            locks.push(lock_output(&a, "resume")?.expect("an output"));
        }
        Some(_) => {}
    }
    let start = StartFrom {
        runner: ckpt.header.runner.clone(),
        parent_output: Some(file),
    };
    finish(&a, engine.as_mut(), &scenario, history, Some(start))
}

/// `--from CHECKPOINT`: a new run from a saved state, with the scenario's
/// changes where the saved state allows them.
fn branch_run(a: RunArgs) -> anyhow::Result<ExitCode> {
    let from = a.from.clone().expect("from");
    if !from.exists() && !path_for(&from).exists() {
        anyhow::bail!(
            "--from `{}`: no such file (a checkpoint, or a run file with its checkpoint \
             `{}` beside it)",
            from.display(),
            path_for(&from).display()
        );
    }
    let ckpt_path = checkpoint_of(&from);
    let ckpt = Checkpoint::read(&ckpt_path)
        .map_err(|e| anyhow::anyhow!("cannot branch from `{}`: {e}", ckpt_path.display()))?;
    let parent = Scenario::parse(&ckpt.header.scenario, "the checkpoint's scenario", &[])?;
    let parent_model = Model::from_scenario(&parent, true)?;
    let (child, name) = match &a.scenario {
        Some(p) => super::load_scenario(Some(p), &a.overrides())?,
        None => (
            Scenario::parse(
                &ckpt.header.scenario,
                "the checkpoint's scenario",
                &a.overrides(),
            )?,
            format!("the scenario of {}", ckpt_path.display()),
        ),
    };
    let child_model = Model::from_scenario(&child, a.allow_unstable)?;
    let mut inputs = vec![ckpt_path.as_path()];
    inputs.extend(a.scenario.as_deref());
    inputs.extend(ckpt.header.output.as_deref());
    a.claim_output(&inputs)?;
    let _lock = lock_output(&a, "branch")?;
    let step = ckpt.header.step;
    let changes =
        branch::check(&parent, &parent_model, &child, &child_model, step).map_err(|refusals| {
            anyhow::anyhow!(
                "cannot branch {name} from `{}` (step {step}):\n  - {}",
                ckpt_path.display(),
                refusals.join("\n  - ")
            )
        })?;
    let mut state = ckpt.engine.clone();
    let mut runner = ckpt.header.runner.clone();
    branch::rebase_drive(&parent_model, &child_model, &mut state, &mut runner);
    let precision = precision_of(&ckpt, a.precision)?;
    let samples = a
        .output
        .is_some()
        .then(|| sample_plan(&child_model, &child));
    let mut engine = a.engine(&child_model, precision, samples)?;
    engine.load_state(&state)?;
    let note = precision_note(&ckpt, engine.as_mut())?;
    let mut history = ckpt.header.history.clone();
    history.push(format!(
        "branched at step {step} (t = {:.6e} s) from `{}` with {}; on {}{note}",
        ckpt.header.time,
        ckpt_path.display(),
        if changes.is_empty() {
            "no changes".to_string()
        } else {
            changes.join(", ")
        },
        engine.describe()
    ));
    eprintln!("slipfront: {}", history.last().expect("a line"));
    // The branch's file starts with the parent's records up to the branch
    // point, when the parent's file is still there.
    let parent_output = ckpt.header.output.clone().filter(|p| {
        let there = p.exists();
        if !there && a.output.is_some() {
            eprintln!(
                "slipfront: the parent run file `{}` is gone; the branch's file starts at the \
                 branch point",
                p.display()
            );
        }
        there
    });
    if parent_output.is_none() {
        // Its numbering starts afresh with the file.
        runner.sequence = 0;
    }
    let start = StartFrom {
        runner,
        parent_output,
    };
    finish(&a, engine.as_mut(), &child, history, Some(start))
}

/// The lock of the run's output file, if it has one
/// (`slipfront::io::output::lock`): held until the command returns.
fn lock_output(a: &RunArgs, what: &str) -> anyhow::Result<Option<RunLock>> {
    a.output
        .as_deref()
        .map(|out| RunLock::acquire(out, what).map_err(anyhow::Error::msg))
        .transpose()
}

fn parse_t_end(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        // 0: the normal-load phase only (a loaded slider to branch from).
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!(
            "--t-end = {}: expected a time in seconds, finite, 0 or more",
            text.chars().take(40).collect::<String>()
        )),
    }
}

fn parse_on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" | "true" => Ok(true),
        "off" | "false" => Ok(false),
        _ => Err(format!("`{s}`: expected on or off")),
    }
}
