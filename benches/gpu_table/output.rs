//! Section 4: what an output file at the default cadences costs (device
//! records), against the same steps without one.

use crate::bench_scene;
use crate::gpu_timing::{output_run, Timed};
use slipfront::engines::gpu::GpuOptions;
use std::path::Path;

/// The lines printed after section 4's table, gathered over its lattices.
#[derive(Default)]
struct Notes {
    /// What the longer run adds per step, in mixed f32 and in f64.
    marginal: Vec<String>,
    marginal_f64: Vec<String>,
    /// The device time of a run with -o by dispatch, in mixed f32 and in
    /// f64.
    split: Vec<String>,
    split_f64: Vec<String>,
    /// The CPU each host thread used per wall second, by run.
    threads_seen: Vec<String>,
}

/// One length of run in mixed f32: wall seconds without output, with -o,
/// and with -o not running ahead; the device's busy seconds without output
/// and with -o, where the adapter times them.
#[derive(Clone, Copy)]
struct Walls {
    without: f64,
    with: f64,
    waiting: f64,
    device_without: Option<f64>,
    device_with: Option<f64>,
}

/// Section 4: a row for each lattice and length of run in mixed f32, then
/// the cost per step, the device's time by dispatch and the host threads'
/// CPU, in mixed f32 and f64. The runs' files go in `dir`.
pub fn cost(dir: &Path, quick: bool) {
    // 4. Output cost at the default cadences.
    print_header();
    let output_sizes: &[(u32, u32, u64)] = if quick {
        &[(57, 31, 2000)]
    } else {
        &[(57, 31, 40_000), (1024, 512, 20_000)]
    };
    let mut notes = Notes::default();
    // Each lattice at `steps` and twice as many: what the longer run
    // adds is the output's cost per step, without what a run pays once
    // (the file's creation, the checkpoint at the end: 37 MB at
    // 1024×512), which a run of a second or less weighs heavily.
    for &(nx, nz, first) in output_sizes {
        let mut walls = Vec::new();
        for steps in [first, 2 * first] {
            walls.extend(f32_run(dir, (nx, nz), first, steps, &mut notes));
        }
        f64_runs(dir, (nx, nz), first, &mut notes);
        if let [short, long] = walls[..] {
            notes
                .marginal
                .push(f32_marginal((nx, nz), first, short, long));
        }
    }
    notes.print();
}

fn print_header() {
    println!("\n## 4. An output file at the default cadences (device records) against none\n");
    println!(
        "| lattice | kernel | steps | wall without | wall with -o | ratio | \
         host CPU / wall with -o | with -o, not running ahead | ratio | \
         device busy without | device busy with -o |"
    );
    println!("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
}

/// `steps` steps of lattice `nx`×`nz` in mixed f32 without output, with -o
/// and with -o not running ahead: prints its row, and returns its times
/// where all three ran. The shorter run (`steps == first`) is also timed
/// by dispatch.
fn f32_run(
    dir: &Path,
    (nx, nz): (u32, u32),
    first: u64,
    steps: u64,
    notes: &mut Notes,
) -> Option<Walls> {
    let model = bench_scene::scene(nx, nz);
    let t_end = steps as f64 * model.dt;
    let scenario = bench_scene::scenario(nx, nz, &[&format!("time.end={t_end:e}")]);
    let file = dir.join("run.mcap");
    let ahead = GpuOptions::default().run_ahead;
    let wall = |output: Option<&Path>, run_ahead: usize, time: bool| {
        output_run::<f32>(&scenario, output, run_ahead, time)
    };
    // An untimed run with output first: the first one in a process
    // builds the record pipelines, which cost the first timed
    // column 0.22–0.28 s at 57×31 on an H200 (session 15).
    if steps == first {
        let _ = wall(Some(&file), ahead, false);
    }
    let walls = match (
        wall(None, ahead, false),
        wall(Some(&file), ahead, false),
        wall(Some(&file), 0, false),
    ) {
        (Ok(quiet_run), Ok(output_run), Ok(waiting_run)) => {
            let runs = [quiet_run, output_run, waiting_run];
            Some(f32_row((nx, nz), steps, runs, &mut notes.threads_seen))
        }
        (a, b, c) => {
            println!("| {nx}×{nz} | not run: {a:?} {b:?} {c:?} | | | | | | | | | |");
            None
        }
    };
    // Where the output's device time goes: the shorter run again,
    // its dispatches timed.
    if steps == first {
        notes.split.push(match wall(Some(&file), ahead, true) {
            Ok(Timed {
                dispatches: Some(t),
                wall,
                ..
            }) => format!("- {nx}×{nz}, {steps} steps with -o ({wall:.3} s): {t}"),
            Ok(_) => format!("- {nx}×{nz}: the dispatches were not timed"),
            Err(e) => format!("- {nx}×{nz}: not run: {e}"),
        });
    }
    walls
}

/// Prints the row of `steps` steps at `nx`×`nz` from its runs without
/// output, with -o and with -o not running ahead; notes the CPU their
/// threads used in `threads_seen`.
fn f32_row(
    (nx, nz): (u32, u32),
    steps: u64,
    [quiet_run, output_run, waiting_run]: [Timed; 3],
    threads_seen: &mut Vec<String>,
) -> Walls {
    let (without, device_without) = (quiet_run.wall, quiet_run.device);
    let (with, host, device_with) = (output_run.wall, output_run.cpu, output_run.device);
    let samples = output_run.samples_text();
    let (how, quiet, busy) = (quiet_run.how, quiet_run.threads, output_run.threads);
    let waiting = waiting_run.wall;
    let kernel = how.split(", ").nth(1).unwrap_or(&how).to_string();
    let device = |d: Option<f64>| d.map_or("–".to_string(), |d| format!("{d:.3} s"));
    println!(
        "| {nx}×{nz} | {kernel} | {steps} | {without:.3} s | {with:.3} s | {:.2} | \
         {host:.2} | {waiting:.3} s | {:.2} | {} | {} |",
        with / without,
        waiting / without,
        device(device_without),
        device(device_with),
    );
    threads_seen.push(format!(
        "- {nx}×{nz}, {steps} steps, CPU seconds per wall second by thread: \
         without output {quiet}; with -o {busy}; device samples {samples}"
    ));
    Walls {
        without,
        with,
        waiting,
        device_without,
        device_with,
    }
}

/// What the second `first` steps at `nx`×`nz` cost in mixed f32: the
/// `long` run less the `short` one.
fn f32_marginal((nx, nz): (u32, u32), first: u64, short: Walls, long: Walls) -> String {
    let device = busy_note(
        (short.device_without, long.device_without),
        (short.device_with, long.device_with),
    );
    format!(
        "- {nx}×{nz}: the second {first} steps cost {:.3} s without output, {:.3} s with \
         -o ({:.2}×), {:.3} s with -o not running ahead ({:.2}×){device}",
        long.without - short.without,
        long.with - short.with,
        (long.with - short.with) / (long.without - short.without),
        long.waiting - short.waiting,
        (long.waiting - short.waiting) / (long.without - short.without),
    )
}

/// f64, the default precision where the adapter has it (its
/// samples recorded on the device since session 17): the same
/// two lengths, without and with -o, and the split.
fn f64_runs(dir: &Path, (nx, nz): (u32, u32), first: u64, notes: &mut Notes) {
    let file = dir.join("run.mcap");
    let ahead = GpuOptions::default().run_ahead;
    let scenario_of = |steps: u64| {
        let t_end = steps as f64 * bench_scene::scene(nx, nz).dt;
        bench_scene::scenario(nx, nz, &[&format!("time.end={t_end:e}")])
    };
    let _ = output_run::<f64>(&scenario_of(first), Some(&file), ahead, false);
    let mut f64_walls = Vec::new();
    for steps in [first, 2 * first] {
        let scenario = scenario_of(steps);
        match (
            output_run::<f64>(&scenario, None, ahead, false),
            output_run::<f64>(&scenario, Some(&file), ahead, false),
        ) {
            (Ok(a), Ok(b)) => f64_walls.push((a.wall, b.wall, a.device, b.device)),
            (a, b) => notes.marginal_f64.push(format!(
                "- {nx}×{nz} in f64, {steps} steps: not run: {:?} {:?}",
                a.err(),
                b.err()
            )),
        }
    }
    if let [short, long] = f64_walls[..] {
        let device = busy_note((short.2, long.2), (short.3, long.3));
        notes.marginal_f64.push(format!(
            "- {nx}×{nz} in f64: the second {first} steps cost {:.3} s without output, \
             {:.3} s with -o ({:.2}×){device}",
            long.0 - short.0,
            long.1 - short.1,
            (long.1 - short.1) / (long.0 - short.0),
        ));
    }
    notes.split_f64.push(
        match output_run::<f64>(&scenario_of(first), Some(&file), ahead, true) {
            Ok(Timed {
                dispatches: Some(t),
                wall,
                ..
            }) => format!("- {nx}×{nz} in f64, {first} steps with -o ({wall:.3} s): {t}"),
            Ok(_) => format!("- {nx}×{nz} in f64: the dispatches were not timed"),
            Err(e) => format!("- {nx}×{nz} in f64: not run: {e}"),
        },
    );
}

/// How long the device was busy in the longer run less the shorter,
/// without output and with -o: each a pair (shorter, longer), where the
/// adapter timed both.
fn busy_note(without: (Option<f64>, Option<f64>), with: (Option<f64>, Option<f64>)) -> String {
    match (without.0.zip(without.1), with.0.zip(with.1)) {
        (Some((a, b)), Some((c, d))) => format!(
            "; the device was busy {:.3} s of them without output, {:.3} s with -o",
            b - a,
            d - c
        ),
        _ => String::new(),
    }
}

impl Notes {
    fn print(&self) {
        println!("\nPer step, without what a run pays once (the longer run less the shorter):\n");
        for line in self.marginal.iter().chain(&self.marginal_f64) {
            println!("{line}");
        }
        println!("\nThe device time of a run with -o by dispatch (timestamps inside the pass):\n");
        for line in self.split.iter().chain(&self.split_f64) {
            println!("{line}");
        }
        // Which host thread the output keeps busy: the runner ("main"),
        // the file's writing thread (slipfront-mcap) or the driver's.
        println!();
        for line in &self.threads_seen {
            println!("{line}");
        }
    }
}
