//! When a run writes its checkpoint, and what goes into it.

use super::outputs::Outputs;
use super::RunError;
use crate::engines::quasistatic::FastForward;
use crate::engines::Engine;
use crate::io::checkpoint::Checkpoint;
use crate::model::scenario::Scenario;
use std::path::PathBuf;
use std::time::{Duration, Instant};

pub(super) struct Checkpointer {
    pub path: PathBuf,
    /// The run file the checkpoints go beside.
    pub output_path: PathBuf,
    /// Wall time between periodic checkpoints (None: only at the start of
    /// driving, at the end, and on a signal).
    interval: Option<Duration>,
    last: Instant,
    scenario: String,
    /// The run file (absolute), named in the checkpoint.
    output: PathBuf,
    history: Vec<String>,
    pub written: u64,
}

impl Checkpointer {
    pub fn new(output: PathBuf, scenario: &Scenario, history: Vec<String>) -> Self {
        let every = scenario.output.checkpoint_interval;
        Checkpointer {
            path: crate::io::checkpoint::path_for(&output),
            interval: (every > 0.0).then(|| Duration::from_secs_f64(every)),
            last: Instant::now(),
            scenario: scenario.to_toml(),
            output: std::path::absolute(&output).unwrap_or(output.clone()),
            output_path: output,
            history,
            written: 0,
        }
    }

    /// A periodic checkpoint is due.
    pub fn due(&self) -> bool {
        self.interval.is_some_and(|i| self.last.elapsed() >= i)
    }

    /// Writes the run's checkpoint.
    pub fn write(
        &mut self,
        engine: &mut dyn Engine,
        outputs: &mut Outputs,
        ff: Option<&FastForward>,
    ) -> Result<(), RunError> {
        let path = self.path.clone();
        self.write_to(&path, engine, outputs, ff)?;
        self.last = Instant::now();
        self.written += 1;
        Ok(())
    }

    /// Syncs the run file (the checkpoint counts on its messages), then
    /// writes the engine's and the runner's state to `path`.
    pub fn write_to(
        &mut self,
        path: &std::path::Path,
        engine: &mut dyn Engine,
        outputs: &mut Outputs,
        ff: Option<&FastForward>,
    ) -> Result<(), RunError> {
        // The saved runner state must hold every sample up to the engine's step.
        super::settle(engine, outputs)?;
        if let Some(sink) = outputs.sink.as_mut() {
            sink.sync()?;
        }
        let mut runner = outputs.save();
        runner.fast_forward = ff.map(FastForward::state);
        Checkpoint::of_engine(
            engine,
            self.scenario.clone(),
            runner,
            Some(self.output.clone()),
            self.history.clone(),
        )?
        .write(path)
        .map_err(|e| RunError::Checkpoint(e.to_string()))
    }
}
