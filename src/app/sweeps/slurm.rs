//! The sbatch job-array script of a sweep: task I of N runs shard I/N into
//! the same folder; `slipfront sweep collect DIR` merges the tables.

use std::path::Path;

/// What the script asks of Slurm.
pub struct SlurmOptions<'a> {
    /// Array tasks (shards).
    pub tasks: usize,
    pub partition: Option<&'a str>,
    /// Time limit per task, as sbatch takes it (e.g. 2:00:00).
    pub time: Option<&'a str>,
    /// CPUs per task (scenes run at once in each task).
    pub cpus_per_task: usize,
    /// The engine flags every task passes on (`--backend … --precision …`),
    /// so that the shards compute as the command that wrote the script asked.
    pub engine_args: &'a str,
}

/// The script text. `exe`, `sweep_file` and `dir` should be absolute: the
/// tasks run wherever Slurm starts them.
pub fn script(exe: &Path, sweep_file: &Path, dir: &Path, o: &SlurmOptions) -> String {
    let mut s = String::from("#!/bin/bash\n");
    s.push_str("#SBATCH --job-name=slipfront-sweep\n");
    s.push_str(&format!("#SBATCH --array=0-{}\n", o.tasks.max(1) - 1));
    s.push_str(&format!(
        "#SBATCH --output={}/slurm-%A_%a.out\n",
        dir.display()
    ));
    s.push_str(&format!(
        "#SBATCH --cpus-per-task={}\n",
        o.cpus_per_task.max(1)
    ));
    if let Some(p) = o.partition {
        s.push_str(&format!("#SBATCH --partition={p}\n"));
    }
    if let Some(t) = o.time {
        s.push_str(&format!("#SBATCH --time={t}\n"));
    }
    s.push_str(&format!(
        "# Task I of N runs every N-th point from I; rerunning a task skips its finished points.\n\
         # When all tasks are done: {} sweep collect {}\n",
        exe.display(),
        dir.display()
    ));
    s.push_str(&format!(
        "exec {} sweep {} -o {} --shard \"${{SLURM_ARRAY_TASK_ID}}/{}\" --threads \"${{SLURM_CPUS_PER_TASK:-1}}\"{}{}\n",
        exe.display(),
        sweep_file.display(),
        dir.display(),
        o.tasks.max(1),
        if o.engine_args.is_empty() { "" } else { " " },
        o.engine_args
    ));
    s
}
