//! Parameter sweeps: many runs from one sweep file, one CPU scene per
//! thread or many GPU scenes per dispatch (`ensembles`), each run's
//! outcomes a row of `summary.csv`; crash-safe and
//! resumable (finished rows are synced as they come and skipped on a
//! rerun), and split into shards for Slurm job arrays (`slurm`), whose
//! tables `collect` merges.

pub mod compare;
mod ensembles;
mod kernels;
pub mod modes;
pub mod outcome_rows;
pub mod outcomes;
pub mod plan;
pub mod slurm;
pub mod table;
pub mod verdict;

pub use plan::{Point, Sweep, SweepFile};

use crate::app::runner::{run_scene, RunError, RunOptions, StartFrom};
use crate::engines::backend::{make_engine_with, Backend, Precision};
use crate::engines::{Engine, EngineError, EngineState};
use crate::io::checkpoint::RunnerState;
use crate::io::output::reader::RunFile;
use crate::io::output::ChunkCompression;
use crate::model::Model;
use kernels::SweepKernels;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// Which runs keep their MCAP file (`DIR/runs/point-NNNNN.mcap`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeepMcap {
    All,
    None,
    /// The first n points.
    First(usize),
}

impl std::str::FromStr for KeepMcap {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "all" => Ok(KeepMcap::All),
            "none" => Ok(KeepMcap::None),
            _ => s
                .strip_prefix("first:")
                .and_then(|n| n.parse().ok())
                .map(KeepMcap::First)
                .ok_or_else(|| format!("--mcap {s}: expected all, none or first:N")),
        }
    }
}

/// `I/N`: this process runs the points whose index is I modulo N.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("--shard {s}: expected I/N with 0 ≤ I < N");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

pub struct SweepOptions {
    pub out_dir: PathBuf,
    pub backend: Backend,
    pub precision: Precision,
    /// Scenes run at once (0: one per core); each scene runs on one thread.
    pub threads: usize,
    pub shard: Option<Shard>,
    pub keep_mcap: KeepMcap,
    /// A line per finished point on stderr.
    pub progress: bool,
    /// Run the normal-load phase once for the points that share it
    /// (`checkpoint::branch::same_loading`) and start each from that state.
    pub share_loading: bool,
    /// GPU backend: scenes stepped together in one dispatch at most (1: one
    /// point at a time).
    pub ensemble: usize,
    /// GPU backend: how points are stepped, alone or as ensembles (the
    /// kernel, and whether samples are made on the device or as host
    /// snapshots).
    pub gpu: crate::engines::gpu::GpuOptions,
    /// Called as each point finishes, with the points finished and the
    /// points this invocation runs (a host's progress bar).
    pub on_point: Option<PointHook>,
}

/// See [`SweepOptions::on_point`].
pub type PointHook = std::sync::Arc<dyn Fn(usize, usize) + Send + Sync>;

/// Scenes per GPU ensemble by default (fewer where one storage binding
/// holds fewer, `kernels::ensemble_limit`). On an H200 (132 SMs) 64
/// Table S1 scenes were one wave of workgroups on half its SMs: 256 in one
/// dispatch ran at twice their aggregate rate, 9.0e9 against 4.5e9
/// block-steps/s (BENCHMARKS.md, 2026-11-27).
pub const DEFAULT_ENSEMBLE: usize = 256;

/// How GPU points are stepped unless asked otherwise: the kernel `auto`
/// picks, samples recorded on the device. Ensembles and points alone make
/// their samples the same way, so a table does not depend on --ensemble.
pub fn default_gpu() -> crate::engines::gpu::GpuOptions {
    crate::engines::gpu::GpuOptions::default()
}

/// What a sweep invocation did.
#[derive(Debug)]
pub struct SweepReport {
    pub points: usize,
    /// Points of this shard already in the table (skipped).
    pub skipped: usize,
    pub ran: usize,
    /// Runs that did not end with status ok (blew up, failed).
    pub not_ok: usize,
    pub interrupted: bool,
    pub table: PathBuf,
    pub wall_seconds: f64,
    /// Normal-load phases this invocation's points share (0: none shared).
    pub shared_loadings: usize,
    /// Points per GPU ensemble run (empty: none).
    pub ensembles: Vec<usize>,
}

/// Points with one normal-load phase, and their loaded state (one step
/// before driving starts), made once by whichever point needs it first.
struct Loading<'a> {
    leader: &'a Point,
    state: std::sync::OnceLock<Result<EngineState, String>>,
}

impl Loading<'_> {
    fn state(&self, opts: &SweepOptions, kernels: &SweepKernels) -> Result<&EngineState, String> {
        self.state
            .get_or_init(|| {
                let model = Model::from_scenario(&self.leader.scenario, false)
                    .map_err(|e| e.to_string())?;
                let gpu = kernels.options(&model, opts.gpu);
                let mut e = make_engine_with(&model, opts.backend, opts.precision, 1, gpu)
                    .map_err(|e| e.to_string())?;
                e.advance(model.prep_steps - 1).map_err(|e| e.to_string())?;
                e.save_state().map_err(|e| e.to_string())
            })
            .as_ref()
            .map_err(Clone::clone)
    }
}

/// Groups `todo` by normal-load phase; only groups of two or more and
/// scenes with a normal-load phase gain anything.
fn loading_groups<'a>(todo: &[&'a Point]) -> (Vec<Loading<'a>>, Vec<Option<usize>>) {
    let mut groups: Vec<Loading> = Vec::new();
    let mut members: Vec<Vec<usize>> = Vec::new();
    let mut of = vec![None; todo.len()];
    for (k, p) in todo.iter().enumerate() {
        let prep = Model::from_scenario(&p.scenario, false).map_or(0, |m| m.prep_steps);
        if prep < 2 {
            continue;
        }
        let g = groups
            .iter()
            .position(|g| {
                crate::io::checkpoint::branch::same_loading(&g.leader.scenario, &p.scenario)
            })
            .unwrap_or_else(|| {
                groups.push(Loading {
                    leader: p,
                    state: std::sync::OnceLock::new(),
                });
                members.push(Vec::new());
                groups.len() - 1
            });
        members[g].push(k);
        of[k] = Some(g);
    }
    // Only phases two or more points share are kept: a point alone makes
    // its own loading as part of its run (making it here as well, as the
    // GPU sweep did for every group, doubled that work).
    let mut shared = Vec::new();
    for (group, m) in groups.into_iter().zip(&members) {
        let kept = (m.len() >= 2).then_some(shared.len());
        for &k in m {
            of[k] = kept;
        }
        if kept.is_some() {
            shared.push(group);
        }
    }
    (shared, of)
}

/// The table this invocation writes.
pub fn table_path(dir: &Path, shard: Option<Shard>) -> PathBuf {
    match shard {
        Some(s) => dir.join(format!("summary.shard-{}-of-{}.csv", s.index, s.count)),
        None => dir.join("summary.csv"),
    }
}

/// Where a point's engine comes from.
enum EngineSource<'a> {
    /// Its own, built for it (from the shared loaded slider when given).
    Own(Option<&'a Loading<'a>>),
    /// A scene of a GPU ensemble, standing at the point's start (the end of
    /// its normal-load phase when `loaded`).
    Ensemble {
        engine: Box<dyn Engine + Send>,
        loaded: bool,
    },
}

/// Runs one point: its row (status ok, blew_up or failed with the
/// message), or None if the run was interrupted.
fn run_point(
    p: &Point,
    opts: &SweepOptions,
    kernels: &SweepKernels,
    header_len: usize,
    source: EngineSource,
) -> Option<Vec<String>> {
    let runs = opts.out_dir.join("runs");
    let keep = match opts.keep_mcap {
        KeepMcap::All => true,
        KeepMcap::None => false,
        KeepMcap::First(n) => p.index < n,
    };
    let name = format!("{}point-{:05}.mcap", if keep { "" } else { "." }, p.index);
    let mcap = runs.join(name);
    let started = Instant::now();
    let mut row = vec![p.index.to_string(), p.id(), p.seed.to_string()];
    row.extend(p.values.iter().map(|(_, v)| match v {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }));
    let result = (|| -> Result<_, RunError> {
        let model = Model::from_scenario(&p.scenario, false)
            .map_err(|e| RunError::Engine(EngineError::State(e.to_string())))?;
        let (mut engine, loaded): (Box<dyn Engine>, bool) = match source {
            EngineSource::Own(loaded) => {
                // The kernel an ensemble of this point would run.
                let gpu = kernels.options(&model, opts.gpu);
                let mut engine = make_engine_with(&model, opts.backend, opts.precision, 1, gpu)?;
                if let Some(l) = loaded {
                    let state = l
                        .state(opts, kernels)
                        .map_err(|e| RunError::Engine(EngineError::State(e)))?;
                    engine.load_state(state)?;
                }
                (engine, loaded.is_some())
            }
            EngineSource::Ensemble { engine, loaded } => (engine, loaded),
        };
        let start = loaded.then(|| StartFrom {
            runner: RunnerState::default(),
            parent_output: None,
        });
        let summary = run_scene(
            engine.as_mut(),
            &p.scenario,
            &RunOptions {
                output: Some(mcap.clone()),
                // A file read back once below and deleted needs no compression.
                output_compression: if keep {
                    ChunkCompression::Zstd
                } else {
                    ChunkCompression::None
                },
                start,
                ..RunOptions::default()
            },
        )?;
        // The scene's steps (a shared normal-load phase counts).
        Ok((summary, model.total_steps()))
    })();
    let wall = format!("{:.3}", started.elapsed().as_secs_f64());
    // A run without outcomes: its status and message, blank outcomes, and
    // the wall time in the last column.
    let without_outcomes = |row: &mut Vec<String>, status: &str, message: String| {
        row.extend([status.to_string(), message]);
        row.resize(header_len - 1, String::new());
        row.push(wall.clone());
    };
    match result {
        Ok((s, _)) if s.interrupted => return None,
        Ok((s, steps)) => match RunFile::read(&mcap) {
            Ok(run) => {
                row.extend(["ok".to_string(), String::new()]);
                row.extend(outcomes::analyse(&run));
                row.extend([
                    format!("{:e}", s.peak_drive_ratio),
                    steps.to_string(),
                    wall.clone(),
                ]);
            }
            Err(e) => without_outcomes(&mut row, "failed", e.to_string()),
        },
        Err(e) => {
            let status = match e {
                RunError::Engine(EngineError::BlowUp { .. }) => "blew_up",
                _ => "failed",
            };
            without_outcomes(&mut row, status, e.to_string());
        }
    }
    if !keep {
        let mut files = crate::io::checkpoint::Checkpoint::candidates(&mcap);
        files.push(mcap.clone());
        for f in files {
            let _ = std::fs::remove_file(f);
        }
    }
    debug_assert_eq!(row.len(), header_len);
    Some(row)
}

/// h:mm:ss.
fn clock(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

/// Finished points so far, and whether the sweep must stop.
#[derive(Default)]
struct Tally {
    ran: usize,
    not_ok: usize,
    stopped: bool,
    error: Option<String>,
}

/// Appends each finished point's row to the table and reports progress;
/// shared by the threads that run points.
struct Recorder {
    appender: Mutex<table::Appender>,
    state: Mutex<Tally>,
    started: Instant,
    points: usize,
    /// Column of the status in a row.
    status_column: usize,
    progress: bool,
    on_point: Option<PointHook>,
}

impl Recorder {
    /// True once a point was interrupted, a row could not be written or
    /// the process was asked to stop.
    fn stopped(&self) -> bool {
        self.state.lock().expect("state").stopped || crate::app::runner::interrupted()
    }

    /// Records point `p`'s row (None: interrupted, the sweep stops).
    fn record(&self, p: &Point, row: Option<Vec<String>>, point_started: Instant) {
        let Some(row) = row else {
            self.state.lock().expect("state").stopped = true;
            return;
        };
        let ok = row[self.status_column] == "ok";
        let written = self.appender.lock().expect("table").append(&row);
        let mut s = self.state.lock().expect("state");
        if let Err(e) = written {
            s.error = Some(e);
            s.stopped = true;
            return;
        }
        s.ran += 1;
        s.not_ok += (!ok) as usize;
        if let Some(hook) = &self.on_point {
            hook(s.ran, self.points);
        }
        if self.progress {
            let elapsed = self.started.elapsed().as_secs_f64();
            let eta = elapsed / s.ran as f64 * (self.points - s.ran) as f64;
            eprintln!(
                "sweep: {}/{} run (point {}: {} in {:.1} s; {}) | ETA {}",
                s.ran,
                self.points,
                p.index,
                row[self.status_column],
                point_started.elapsed().as_secs_f64(),
                p.label(),
                clock(eta)
            );
        }
    }
}

/// Runs the sweep's points (this shard's), skipping those already in the
/// table.
pub fn run_sweep(sweep: &Sweep, opts: &SweepOptions) -> Result<SweepReport, String> {
    let started = Instant::now();
    crate::engines::backend::check_precision(opts.backend, opts.precision)?;
    let dir = &opts.out_dir;
    std::fs::create_dir_all(dir.join("runs"))
        .map_err(|e| format!("cannot create `{}`: {e}", dir.display()))?;
    write_manifest(dir, sweep)?;
    let header = table::header(&sweep.axis_keys);
    let path = table_path(dir, opts.shard);
    let done = table::read_rows(&path, &header)?.unwrap_or_default();
    for p in &sweep.points {
        if let Some(row) = done.get(&p.index).filter(|r| r[1] != p.id()) {
            return Err(format!(
                "`{}` holds a row for point {} of another sweep (id {}, this sweep's is {}); \
                 use another output folder",
                path.display(),
                p.index,
                row[1],
                p.id()
            ));
        }
    }
    let mine: Vec<&Point> = sweep
        .points
        .iter()
        .filter(|p| opts.shard.is_none_or(|s| p.index % s.count == s.index))
        .collect();
    let todo: Vec<&Point> = mine
        .iter()
        .copied()
        .filter(|p| !done.contains_key(&p.index))
        .collect();
    let skipped = mine.len() - todo.len();
    // The kernel of each lattice shape, from all the sweep's points (the
    // same on a rerun that skips the finished ones).
    let kernels = if todo.is_empty() {
        SweepKernels::default()
    } else {
        SweepKernels::choose(&sweep.points, opts)?
    };
    if opts.progress {
        for line in &kernels.report {
            eprintln!("sweep: {line}");
        }
    }
    let (groups, group_of) = if opts.share_loading {
        loading_groups(&todo)
    } else {
        (Vec::new(), vec![None; todo.len()])
    };
    let shared_loadings = group_of
        .iter()
        .flatten()
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    let recorder = Recorder {
        appender: Mutex::new(table::Appender::open(&path, &header)?),
        state: Mutex::new(Tally::default()),
        started,
        points: todo.len(),
        status_column: 3 + sweep.axis_keys.len(),
        progress: opts.progress,
        on_point: opts.on_point.clone(),
    };
    // GPU ensembles first (each its own dispatches), then the points left
    // to run alone.
    let mut alone: Vec<usize> = (0..todo.len()).collect();
    let mut ensemble_sizes = Vec::new();
    // (Another precision than the GPU's: each point fails alone, saying so.)
    let gpu_precision = matches!(opts.precision, Precision::F32 | Precision::F64);
    if opts.backend == Backend::Gpu && gpu_precision && opts.ensemble > 1 {
        let plan = ensembles::plan(&todo, &group_of, opts.ensemble, opts.precision);
        alone = plan.alone;
        let made = ensembles::prepare_loadings(&groups, opts, &kernels);
        if opts.progress && made > 0 {
            eprintln!("sweep: {made} shared normal-load phases run as GPU ensembles");
        }
        for members in &plan.ensembles {
            if recorder.stopped() {
                break;
            }
            let run = ensembles::Run {
                todo: &todo,
                loadings: &groups,
                group_of: &group_of,
                opts,
                kernels: &kernels,
                header_len: header.len(),
                recorder: &recorder,
            };
            match run.run(members) {
                Ok(()) => ensemble_sizes.push(members.len()),
                Err(why) => {
                    if opts.progress {
                        eprintln!("sweep: {why}; running those points one at a time");
                    }
                    alone.extend(members);
                }
            }
        }
    }
    let threads = match (opts.backend, opts.threads) {
        // GPU points alone: one at a time unless asked (they share the
        // device; with small scenes the host's encoding is the limit, so a
        // few at once can keep a hardware GPU busier).
        (Backend::Gpu, 0) => 1,
        (_, 0) => std::thread::available_parallelism().map_or(1, |n| n.get()),
        (_, t) => t,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| format!("thread pool: {e}"))?;
    pool.install(|| {
        use rayon::prelude::*;
        alone.par_iter().for_each(|&k| {
            if recorder.stopped() {
                return;
            }
            let p = todo[k];
            let point_started = Instant::now();
            let loaded = group_of[k].map(|g| &groups[g]);
            let row = run_point(p, opts, &kernels, header.len(), EngineSource::Own(loaded));
            recorder.record(p, row, point_started);
        })
    });
    let Tally {
        ran,
        not_ok,
        stopped,
        error,
    } = recorder.state.into_inner().expect("state");
    if let Some(e) = error {
        return Err(e);
    }
    let interrupted = stopped || crate::app::runner::interrupted();
    if opts.shard.is_none() && !interrupted {
        // The whole table in point order.
        let rows = table::read_rows(&path, &header)?.unwrap_or_default();
        table::write_sorted(&path, &header, &rows)?;
    }
    Ok(SweepReport {
        points: sweep.points.len(),
        skipped,
        ran,
        not_ok,
        interrupted,
        table: path,
        wall_seconds: started.elapsed().as_secs_f64(),
        shared_loadings,
        ensembles: ensemble_sizes,
    })
}

/// `DIR/sweep.json`: the points and axes, for `collect`.
fn write_manifest(dir: &Path, sweep: &Sweep) -> Result<(), String> {
    let manifest = serde_json::json!({
        "points": sweep.points.len(),
        "axes": sweep.axis_keys,
        "ids": sweep.points.iter().map(Point::id).collect::<Vec<_>>(),
    });
    let path = dir.join("sweep.json");
    std::fs::write(
        &path,
        serde_json::to_string_pretty(&manifest).expect("json"),
    )
    .map_err(|e| format!("`{}`: {e}", path.display()))
}

/// Merges the shard tables of `dir` into `dir/summary.csv` (point order);
/// returns its path, the rows, and the points no shard has finished.
pub fn collect(dir: &Path) -> Result<(PathBuf, usize, Vec<usize>), String> {
    let manifest_path = dir.join("sweep.json");
    let manifest: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(&manifest_path)
            .map_err(|e| format!("`{}`: {e} (not a sweep folder?)", manifest_path.display()))?,
    )
    .map_err(|e| format!("`{}`: {e}", manifest_path.display()))?;
    let axes: Vec<String> = manifest["axes"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|v| v.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    let points = manifest["points"].as_u64().unwrap_or(0) as usize;
    let header = table::header(&axes);
    let mut rows = BTreeMap::new();
    let mut shards: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("`{}`: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("summary.shard-") && n.ends_with(".csv"))
        })
        .collect();
    shards.sort();
    if shards.is_empty() {
        return Err(format!(
            "no shard tables (summary.shard-*.csv) in `{}`",
            dir.display()
        ));
    }
    for s in &shards {
        rows.extend(table::read_rows(s, &header)?.unwrap_or_default());
    }
    let path = dir.join("summary.csv");
    table::write_sorted(&path, &header, &rows)?;
    let missing = (0..points).filter(|p| !rows.contains_key(p)).collect();
    Ok((path, rows.len(), missing))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sweep(seeds: u32) -> Sweep {
        let text = format!(
            "base = \"scenarios/triggered_front.toml\"\nseeds = {seeds}\n\
             [axes]\n\"loading.trigger.shear_prestress\" = [0.2, 0.25, 0.3]\n"
        );
        let file: SweepFile = toml::from_str(&text).expect("sweep file");
        Sweep::build(file, Path::new(env!("CARGO_MANIFEST_DIR"))).expect("sweep")
    }

    #[test]
    fn only_phases_two_points_share_are_loading_groups() {
        // The prestress changes the normal-load phase, the seed does not.
        let shared = sweep(2);
        let todo: Vec<&Point> = shared.points.iter().collect();
        let (groups, of) = loading_groups(&todo);
        assert_eq!(groups.len(), 3);
        for (k, p) in todo.iter().enumerate() {
            let g = of[k].expect("every point shares its loading");
            assert!(crate::io::checkpoint::branch::same_loading(
                &groups[g].leader.scenario,
                &p.scenario
            ));
        }
        // One seed per prestress: nothing is shared, so no phase is made
        // apart from the points' own runs.
        let alone = sweep(1);
        let todo: Vec<&Point> = alone.points.iter().collect();
        let (groups, of) = loading_groups(&todo);
        assert!(groups.is_empty(), "{} groups", groups.len());
        assert!(of.iter().all(Option::is_none));
    }
}
