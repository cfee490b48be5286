//! Checkpoints: everything a run needs to continue exactly — the engine's
//! state, the runner's output and fast-forward bookkeeping, the scenario —
//! in one versioned, checksummed file beside the run's output
//! (`RUN.mcap.ckpt`), written atomically (write, sync, rename) with the
//! previous one kept as `RUN.mcap.ckpt.prev`.

pub mod branch;
pub mod format;

use crate::engines::quasistatic::FastForwardState;
use crate::engines::EngineState;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// What the runner keeps between steps besides the engine: output
/// bookkeeping (so the records after a resume are those of an uninterrupted
/// run) and the fast-forward's detector and solver.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct RunnerState {
    /// The side spring's far-end origin (m), for the reported drive force.
    pub origin: f64,
    /// The interface cadence is the fast one.
    pub fast: bool,
    /// Peak and last F/F_N and the rupture count reported so far.
    pub peak: f64,
    pub last: f64,
    pub ruptures: u64,
    /// MCAP messages written so far (their sequence numbers are 1..=this).
    pub sequence: u32,
    /// u_x of the interface at its first output record (slip is measured
    /// from it).
    pub slip_origin: Option<Vec<f64>>,
    pub fast_forward: Option<FastForwardState>,
    /// Slip events seen so far and the last sample with a ruptured block
    /// (progress report only).
    #[serde(default)]
    pub events: u64,
    #[serde(default)]
    pub last_slip: Option<f64>,
}

/// The checkpoint's JSON header.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Header {
    pub slipfront_version: String,
    /// Seconds since the Unix epoch when it was written.
    pub created_unix: u64,
    /// The scenario of the run, canonical TOML.
    pub scenario: String,
    pub scenario_hash: String,
    /// The engine that wrote it (`Engine::describe`).
    pub backend: String,
    /// Its precision (`real::precision_name`).
    pub precision: String,
    pub step: u64,
    /// Time since driving started (s).
    pub time: f64,
    /// Steps the run was to reach.
    pub total_steps: u64,
    pub blocks: usize,
    pub nx: usize,
    pub junctions: usize,
    /// The run's output file (absolute), whose first `runner.sequence`
    /// messages belong to this state.
    pub output: Option<PathBuf>,
    pub runner: RunnerState,
    /// (size, half bandwidth) of the fast-forward solver's factor.
    pub solver_factor_shape: Option<(usize, usize)>,
    /// One line per start, resume and branch of the run, oldest first.
    pub history: Vec<String>,
}

#[derive(Debug, Clone)]
pub struct Checkpoint {
    /// Holds the runner's state, the fast-forward solver's factor with it.
    pub header: Header,
    pub engine: EngineState,
}

#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("not a slipfront checkpoint (no SLIPCKPT magic at its start)")]
    NotACheckpoint,
    #[error(
        "written in checkpoint format version {0}; this slipfront ({ours}) reads versions \
         1 to {reads}: continue it with the slipfront version that wrote it",
        ours = env!("CARGO_PKG_VERSION"),
        reads = format::FORMAT_VERSION
    )]
    Version(u32),
    #[error("damaged: {0}")]
    Damaged(String),
    #[error("{0}")]
    Io(String),
}

/// The checkpoint beside a run file: `RUN.mcap` → `RUN.mcap.ckpt`.
pub fn path_for(output: &Path) -> PathBuf {
    with_suffix(output, ".ckpt")
}

/// The loaded slider's checkpoint, one step before driving starts:
/// `RUN.mcap` → `RUN.mcap.loaded.ckpt`.
pub fn loaded_path_for(output: &Path) -> PathBuf {
    with_suffix(output, ".loaded.ckpt")
}

fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(suffix);
    PathBuf::from(s)
}

impl Checkpoint {
    /// The checkpoint of `engine` at the step it stands at: its state, the
    /// runner's `runner` state, the run's scenario (canonical TOML), its
    /// output file and history.
    pub fn of_engine(
        engine: &mut dyn crate::engines::Engine,
        scenario: String,
        runner: RunnerState,
        output: Option<PathBuf>,
        history: Vec<String>,
    ) -> Result<Checkpoint, crate::engines::EngineError> {
        let model = engine.model().clone();
        let state = engine.save_state()?;
        let solver_factor_shape = runner
            .fast_forward
            .as_ref()
            .and_then(|f| f.factor.as_ref())
            .map(|f| {
                let (n, band, _) = f.parts();
                (n, band)
            });
        let header = Header {
            slipfront_version: env!("CARGO_PKG_VERSION").into(),
            created_unix: unix_now(),
            scenario_hash: format!("{:016x}", crate::io::output::fnv1a(scenario.as_bytes())),
            scenario,
            backend: engine.describe(),
            precision: state.precision.clone(),
            step: state.step,
            time: model.time_of_step(state.step),
            total_steps: model.total_steps(),
            blocks: model.n_blocks(),
            nx: model.nx,
            junctions: model.n_junctions(),
            output,
            runner,
            solver_factor_shape,
            history,
        };
        Ok(Checkpoint {
            header,
            engine: state,
        })
    }

    /// Writes `path` atomically: the bytes go to `path.tmp`, are synced,
    /// the current checkpoint (if any) becomes `path.prev`, and the new one
    /// takes its name. A crash at any point leaves a complete checkpoint
    /// under `path` or `path.prev`.
    pub fn write(&self, path: &Path) -> Result<(), CheckpointError> {
        let io = |what: &str, p: &Path, e: std::io::Error| {
            CheckpointError::Io(format!("cannot {what} `{}`: {e}", p.display()))
        };
        let tmp = with_suffix(path, ".tmp");
        let bytes = format::encode(self);
        let written = (|| {
            let mut f = std::fs::File::create(&tmp).map_err(|e| io("create", &tmp, e))?;
            f.write_all(&bytes).map_err(|e| io("write", &tmp, e))?;
            f.sync_all().map_err(|e| io("sync", &tmp, e))
        })();
        if let Err(e) = written {
            // No stray temporary (a full disk): the last good checkpoint
            // stays as it was.
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
        if path.exists() {
            let prev = with_suffix(path, ".prev");
            std::fs::rename(path, &prev).map_err(|e| io("rename", path, e))?;
        }
        std::fs::rename(&tmp, path).map_err(|e| io("rename", &tmp, e))?;
        sync_parent(path);
        Ok(())
    }

    /// Reads and checks one checkpoint file.
    pub fn read(path: &Path) -> Result<Checkpoint, CheckpointError> {
        let bytes = std::fs::read(path)
            .map_err(|e| CheckpointError::Io(format!("cannot read `{}`: {e}", path.display())))?;
        format::decode(&bytes)
    }

    /// The first good checkpoint of `candidates` (newest first): the
    /// checkpoint, its file, and why each candidate before it was passed
    /// over. Missing files are passed over silently; when none is good,
    /// every reason.
    pub fn first_good(
        candidates: &[PathBuf],
    ) -> Result<(Checkpoint, PathBuf, Vec<String>), Vec<String>> {
        let mut passed = Vec::new();
        for path in candidates {
            match Checkpoint::read(path) {
                Ok(c) => return Ok((c, path.clone(), passed)),
                Err(_) if !path.exists() => {}
                Err(e) => passed.push(format!("`{}`: {e}", path.display())),
            }
        }
        if passed.is_empty() {
            let names: Vec<String> = candidates
                .iter()
                .map(|p| format!("`{}`", p.display()))
                .collect();
            passed.push(format!("no checkpoint ({} do not exist)", names.join(", ")));
        }
        Err(passed)
    }

    /// Where a run's checkpoints are, newest first: `RUN.mcap.ckpt`, the
    /// one before it, and the loaded slider's.
    pub fn candidates(output: &Path) -> Vec<PathBuf> {
        let ckpt = path_for(output);
        let prev = with_suffix(&ckpt, ".prev");
        vec![ckpt, prev, loaded_path_for(output)]
    }
}

#[cfg(unix)]
fn sync_parent(path: &Path) {
    // The renames are durable once the folder is synced.
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
}

#[cfg(not(unix))]
fn sync_parent(_: &Path) {}

/// Seconds since the Unix epoch.
pub fn unix_now() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}
