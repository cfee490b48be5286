//! Long-run accuracy of the precisions: the same side-driven scene in CPU
//! f64, f64 with the drive speed perturbed by 1e-6 (the chaos yardstick),
//! CPU f32 mixed, CPU f32 plain (the negative control) and, with `--gpu`,
//! the GPU engine; each run's precursors and first full event compared with
//! f64's (`compare::outcome_mismatch`, 0.1%). `--seeds N` instead runs f64
//! and f32 mixed over seeds 1..=N and prints their event statistics side by
//! side. Runs go in parallel, one engine thread each.
//!
//! cargo bench --bench long_run_precision -- [--t-end 0.4] [--gpu]
//!     [--seeds 8] [--scenario scenarios/tromborg2014_precursors.toml]
//!     [--set key=value ...]
//!
//! `--seeds N --reanalyse PREFIX [--t-max T]` reads the run files of an
//! earlier (possibly interrupted) seed run, PREFIX_f64_seed_K.mcap and
//! PREFIX_f32_seed_K.mcap, and tabulates them up to the time every file
//! reached (or T).

use slipfront::app::runner::{run_scene, RunOptions};
use slipfront::engines::backend::{make_engine, Backend, Precision};
use slipfront::io::compare::{outcome_mismatch, RunOutcome};
use slipfront::io::output::reader::RunFile;
use slipfront::model::scenario::Scenario;
use slipfront::Model;
use std::path::PathBuf;

struct Case {
    label: String,
    backend: Backend,
    precision: Precision,
    set: Vec<String>,
}

struct Done {
    label: String,
    run: RunFile,
    wall: f64,
    describe: String,
}

fn arg<T: std::str::FromStr>(args: &[String], name: &str) -> Option<T> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
}

fn run_case(scenario: &std::path::Path, t_end: f64, base: &[String], case: &Case) -> Done {
    let mut set = base.to_vec();
    set.extend(case.set.iter().cloned());
    set.push(format!("time.end={t_end}"));
    let s = Scenario::load(scenario, &set).expect("scenario");
    let m = Model::from_scenario(&s, false).expect("model");
    let mut e = make_engine(&m, case.backend, case.precision, 1).expect("engine");
    let out: PathBuf = std::env::temp_dir().join(format!(
        "slipfront_lrp_{}_{}.mcap",
        std::process::id(),
        case.label.replace([' ', '/', '='], "_")
    ));
    let summary = run_scene(
        e.as_mut(),
        &s,
        &RunOptions {
            fast_forward: None,
            output: Some(out.clone()),
            ..RunOptions::default()
        },
    )
    .expect("run");
    let run = RunFile::read(&out).expect("read run");
    let _ = std::fs::remove_file(&out);
    Done {
        label: case.label.clone(),
        run,
        wall: summary.wall_seconds,
        describe: summary.backend,
    }
}

fn run_all(scenario: &std::path::Path, t_end: f64, base: &[String], cases: &[Case]) -> Vec<Done> {
    std::thread::scope(|sc| {
        let handles: Vec<_> = cases
            .iter()
            .map(|c| sc.spawn(move || run_case(scenario, t_end, base, c)))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    })
}

fn case(label: &str, backend: Backend, precision: Precision, set: &[String]) -> Case {
    Case {
        label: label.into(),
        backend,
        precision,
        set: set.to_vec(),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scenario: PathBuf =
        arg(&args, "--scenario").unwrap_or_else(|| "scenarios/tromborg2014_precursors.toml".into());
    let t_end: f64 = arg(&args, "--t-end").unwrap_or(0.4);
    let quiet_gap = 1e-3;
    let base: Vec<String> = args
        .windows(2)
        .filter(|w| w[0] == "--set")
        .map(|w| w[1].clone())
        .collect();
    let s = Scenario::load(&scenario, &base).expect("scenario");
    println!(
        "long-run precision: {} ({}), {t_end} s of driving, extra settings {base:?}",
        s.name,
        scenario.display()
    );
    if let Some(seeds) = arg::<u32>(&args, "--seeds") {
        let done: Vec<Done> = match arg::<String>(&args, "--reanalyse") {
            Some(prefix) => (1..=seeds)
                .flat_map(|seed| ["f64", "f32"].map(|p| format!("{p}_seed_{seed}")))
                .map(|label| {
                    let path = format!("{prefix}_{label}.mcap");
                    let run = RunFile::read(std::path::Path::new(&path)).expect("run file");
                    Done {
                        label: label.replace('_', " "),
                        run,
                        wall: f64::NAN,
                        describe: String::new(),
                    }
                })
                .collect(),
            None => {
                let mut cases = Vec::new();
                for seed in 1..=seeds {
                    let set = vec![format!("time.seed={seed}")];
                    cases.push(case(
                        &format!("f64 seed {seed}"),
                        Backend::Cpu,
                        Precision::F64,
                        &set,
                    ));
                    cases.push(case(
                        &format!("f32 seed {seed}"),
                        Backend::Cpu,
                        Precision::F32,
                        &set,
                    ));
                }
                run_all(&scenario, t_end, &base, &cases)
            }
        };
        seed_table(done, seeds, arg(&args, "--t-max"), quiet_gap);
        return;
    }
    let v: f64 = s.loading.drive.velocity.unwrap_or(0.0);
    let perturbed = vec![format!("loading.drive.velocity={}", v * (1.0 + 1e-6))];
    let mut cases = vec![
        case("cpu f64", Backend::Cpu, Precision::F64, &[]),
        case(
            "cpu f64, V x (1 + 1e-6)",
            Backend::Cpu,
            Precision::F64,
            &perturbed,
        ),
        case("cpu f32 mixed", Backend::Cpu, Precision::F32, &[]),
        case("cpu f32 plain", Backend::Cpu, Precision::F32Plain, &[]),
    ];
    if args.iter().any(|a| a == "--gpu") {
        cases.push(case("gpu f32 mixed", Backend::Gpu, Precision::F32, &[]));
    }
    let done = run_all(&scenario, t_end, &base, &cases);
    let reference = RunOutcome::from_run(&done[0].run, quiet_gap);
    println!("| run | engine | precursors (mm) | first full event t (s) | F/F_N | against f64 (0.1%) | wall (s) |");
    println!("| --- | --- | --- | ---: | ---: | --- | ---: |");
    for d in &done {
        let o = RunOutcome::from_run(&d.run, quiet_gap);
        let lengths: Vec<String> = o
            .precursors
            .iter()
            .map(|p| format!("{:.1}", p.0 * 1e3))
            .collect();
        let (t, r) = o.first_full.unwrap_or((f64::NAN, f64::NAN));
        let verdict = outcome_mismatch(&reference, &o, 1e-3);
        println!(
            "| {} | {} | {} | {t:.6} | {r:.5} | {} | {:.0} |",
            d.label,
            d.describe,
            lengths.join(", "),
            if verdict.is_empty() {
                "agrees".to_string()
            } else {
                format!("DEPARTS: {}", verdict.join("; "))
            },
            d.wall
        );
    }
}

/// Event statistics of f64 and f32 runs (alternating in `done`) up to the
/// time every run reached, or `t_max`.
fn seed_table(mut done: Vec<Done>, seeds: u32, t_max: Option<f64>, quiet_gap: f64) {
    let reached = done
        .iter()
        .map(|d| d.run.interface.last().map_or(0.0, |m| m.time))
        .fold(f64::INFINITY, f64::min);
    let t_max = t_max.unwrap_or(reached).min(reached);
    for d in &mut done {
        d.run.interface.retain(|m| m.time <= t_max);
        d.run.global.retain(|m| m.time <= t_max);
    }
    println!("events up to t = {t_max:.4} s of driving");
    println!("| run | events | full events | mean F/F_N of full events | mean slip per event (m) | precursors | wall (s) |");
    println!("| --- | ---: | ---: | ---: | ---: | ---: | ---: |");
    let mut totals = [[0.0f64; 5]; 2];
    for (k, d) in done.iter().enumerate() {
        let events = d.run.interface_series().events_separated_by(quiet_gap);
        let full: Vec<_> = events.iter().filter(|e| e.full).collect();
        let mean_ratio = full
            .iter()
            .map(|e| d.run.drive_ratio_at(e.start))
            .sum::<f64>()
            / full.len().max(1) as f64;
        let mean_slip = events.iter().map(|e| e.slip).sum::<f64>() / events.len().max(1) as f64;
        let precursors = RunOutcome::from_run(&d.run, quiet_gap).precursors.len();
        let row = [
            events.len() as f64,
            full.len() as f64,
            mean_ratio,
            mean_slip,
            precursors as f64,
        ];
        for (t, v) in totals[k % 2].iter_mut().zip(row) {
            *t += v / seeds as f64;
        }
        let or_dash = |ok: bool, v: String| if ok { v } else { "-".into() };
        println!(
            "| {} | {} | {} | {} | {} | {} | {:.0} |",
            d.label,
            events.len(),
            full.len(),
            or_dash(!full.is_empty(), format!("{mean_ratio:.4}")),
            or_dash(!events.is_empty(), format!("{mean_slip:.4e}")),
            precursors,
            d.wall
        );
    }
    for (name, t) in ["f64 mean", "f32 mean"].iter().zip(totals) {
        println!(
            "| **{name}** | {:.2} | {:.2} | {:.4} | {:.4e} | {:.2} | |",
            t[0], t[1], t[2], t[3], t[4]
        );
    }
}
