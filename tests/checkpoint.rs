//! Checkpoint, resume and branch: a run stopped (SIGKILL, SIGINT, its end)
//! and continued gives the records of the run that never stopped, bit for
//! bit on the CPU; damaged checkpoints are refused; branches differ from
//! their parent only after the branch point.

use slipfront::engines::backend::{cpu_engine, cpu_reference_engine, Precision};
use slipfront::io::checkpoint::{path_for, Checkpoint, CheckpointError};
use slipfront::io::output::reader::RunFile;
use slipfront::model::Model;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

/// The small side-driven scene (`verify::SMALL_SCENE`), driven fast
/// enough that junctions break from 0.6 ms on.
const DRIVE: &str = "loading.drive.velocity=0.2";

fn dir(name: &str) -> Scratch {
    Scratch::new("ckpt", name)
}

/// The engine most tests run on.
const CPU: &[&str] = &["--backend", "cpu", "--threads", "1"];
/// The GPU engine (lavapipe in CI), recording its samples on the device and
/// running ahead of the runner while it writes them.
const GPU: &[&str] = &["--backend", "gpu"];

fn command(args: &[&str], extra: &[String]) -> Command {
    command_on(CPU, args, extra)
}

fn command_on(backend: &[&str], args: &[&str], extra: &[String]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_slipfront"));
    c.args(["run", "--quiet"]).args(backend);
    c.args(args).args(extra);
    c
}

fn scene_args(more: &[&str]) -> Vec<String> {
    slipfront::app::verify::SMALL_SCENE
        .iter()
        .chain(&[DRIVE])
        .chain(more)
        .flat_map(|s| ["--set".to_string(), s.to_string()])
        .collect()
}

fn run_ok(args: &[&str], extra: &[String]) -> String {
    run_ok_on(CPU, args, extra)
}

fn run_ok_on(backend: &[&str], args: &[&str], extra: &[String]) -> String {
    let out = command_on(backend, args, extra).output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "slipfront run {args:?}: {text}");
    text
}

fn run_fails(args: &[&str], extra: &[String]) -> String {
    let out = command(args, extra).output().unwrap();
    assert!(!out.status.success(), "slipfront run {args:?} should fail");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every record of the series a user reads: /global, /interface, /bulk and
/// the fast-forward jumps, with their steps and values.
fn assert_same_records(a: &RunFile, b: &RunFile) {
    assert!(!a.global.is_empty() && !a.interface.is_empty());
    assert_eq!(a.global.len(), b.global.len(), "/global counts");
    assert!(a.global == b.global, "/global records differ");
    assert_eq!(a.interface.len(), b.interface.len(), "/interface counts");
    assert!(a.interface == b.interface, "/interface records differ");
    assert!(a.bulk == b.bulk, "/bulk records differ");
    assert!(
        a.fast_forward == b.fast_forward,
        "/fast_forward records differ"
    );
}

/// Waits until the run has written a second checkpoint in the driving
/// phase (`.prev` exists and the newest is past the normal-load phase: a
/// loaded machine may checkpoint during that phase too), then kills it
/// with `signal`.
fn stop_midway(mut child: Child, ckpt: &Path, signal: i32) -> std::process::Output {
    let prev = PathBuf::from(format!("{}.prev", ckpt.display()));
    let driving = |c: &Checkpoint| c.header.time > 0.0;
    let started = Instant::now();
    while !(prev.exists() && Checkpoint::read(ckpt).is_ok_and(|c| driving(&c))) {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before its second checkpoint: the test would be vacuous"
        );
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no checkpoint"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    unsafe {
        libc::kill(child.id() as i32, signal);
    }
    let out = child.wait_with_output().unwrap();
    assert!(!out.status.success() || signal == libc::SIGINT);
    out
}

fn uninterrupted(backend: &[&str], d: &Path, precision: &str, t_end: &str) -> RunFile {
    let whole = d.join("whole.mcap");
    run_ok_on(
        backend,
        &["--precision", precision, "--t-end", t_end, "-o", s(&whole)],
        &scene_args(&[]),
    );
    RunFile::read(&whole).unwrap()
}

fn killed_and_resumed(precision: &str, signal: i32) {
    killed_and_resumed_on(CPU, "0.006", precision, signal);
}

fn killed_and_resumed_on(backend: &[&str], t_end: &str, precision: &str, signal: i32) {
    let d = dir(&format!("{}-{precision}-{signal}", backend[1]));
    let whole = uninterrupted(backend, &d, precision, t_end);
    let cut = d.join("cut.mcap");
    let child = command_on(
        backend,
        &["--precision", precision, "--t-end", t_end, "-o", s(&cut)],
        &scene_args(&["output.checkpoint_interval=0.05"]),
    )
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()
    .unwrap();
    let out = stop_midway(child, &path_for(&cut), signal);
    let (ckpt, _, _) = Checkpoint::first_good(&Checkpoint::candidates(&cut)).unwrap();
    let model = Model::from_scenario(
        &slipfront::Scenario::parse(&ckpt.header.scenario, "ckpt", &[]).unwrap(),
        false,
    )
    .unwrap();
    assert!(
        ckpt.header.step > model.prep_steps && ckpt.header.step < model.total_steps(),
        "stopped at step {} of {}",
        ckpt.header.step,
        model.total_steps()
    );
    if signal == libc::SIGINT {
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains("INTERRUPTED") && text.contains("--resume"),
            "{text}"
        );
        // An interrupted run leaves a complete, readable file.
        assert!(!RunFile::read(&cut).unwrap().truncated);
    }
    let text = run_ok_on(backend, &["--resume", s(&cut)], &[]);
    assert!(text.contains("run complete"), "{text}");
    let resumed = RunFile::read(&cut).unwrap();
    assert!(!resumed.truncated);
    assert_same_records(&whole, &resumed);
    assert!(resumed
        .history
        .iter()
        .any(|l| l.starts_with("resumed at step")));
}

#[test]
fn sigkill_midway_then_resume_gives_the_uninterrupted_records_f64() {
    killed_and_resumed("f64", libc::SIGKILL);
}

#[test]
fn sigkill_midway_then_resume_gives_the_uninterrupted_records_f32() {
    killed_and_resumed("f32", libc::SIGKILL);
}

#[test]
fn sigint_checkpoints_and_the_resume_is_exact() {
    killed_and_resumed("f64", libc::SIGINT);
}

/// The GPU engine runs ahead of its runner while the runner writes the
/// samples recorded on the device; a checkpoint waits for those steps and
/// writes their samples first. Stopped at a checkpoint (SIGKILL) or by
/// SIGINT and resumed, the run file equals the uninterrupted one.
#[test]
fn a_gpu_run_killed_or_interrupted_midway_resumes_exactly() {
    for signal in [libc::SIGKILL, libc::SIGINT] {
        killed_and_resumed_on(GPU, "0.004", "f32", signal);
    }
}

#[test]
fn a_finished_run_extended_equals_the_longer_run() {
    let d = dir("extend");
    let whole = uninterrupted(CPU, &d, "f64", "0.004");
    let short = d.join("short.mcap");
    run_ok(&["--t-end", "0.002", "-o", s(&short)], &scene_args(&[]));
    // Resuming a finished run without a new end is refused, clearly.
    let err = run_fails(&["--resume", s(&short)], &[]);
    assert!(
        err.contains("already reached its end") && err.contains("--t-end"),
        "{err}"
    );
    run_ok(&["--resume", s(&short), "--t-end", "0.004"], &[]);
    assert_same_records(&whole, &RunFile::read(&short).unwrap());
    // The negative control: a run with V × (1 + 1e-6) is flagged.
    let other = d.join("other.mcap");
    run_ok(
        &["--t-end", "0.004", "-o", s(&other)],
        &scene_args(&["loading.drive.velocity=0.2000002"]),
    );
    let other = RunFile::read(&other).unwrap();
    assert!(whole.global != other.global);
}

#[test]
fn a_damaged_checkpoint_is_refused_and_the_previous_one_used() {
    let d = dir("damaged");
    let run = d.join("run.mcap");
    run_ok(&["--t-end", "0.001", "-o", s(&run)], &scene_args(&[]));
    run_ok(&["--resume", s(&run), "--t-end", "0.002"], &[]);
    let ckpt = path_for(&run);
    let prev = PathBuf::from(format!("{}.prev", ckpt.display()));
    let good = std::fs::read(&ckpt).unwrap();
    let prev_step = Checkpoint::read(&prev).unwrap().header.step;
    // A flipped byte, a truncation, another format version, not a
    // checkpoint: each is refused with its reason.
    let mut flipped = good.clone();
    flipped[good.len() / 2] ^= 0x10;
    std::fs::write(&ckpt, &flipped).unwrap();
    assert!(matches!(
        Checkpoint::read(&ckpt),
        Err(CheckpointError::Damaged(_))
    ));
    std::fs::write(&ckpt, &good[..good.len() - 100]).unwrap();
    assert!(matches!(
        Checkpoint::read(&ckpt),
        Err(CheckpointError::Damaged(_))
    ));
    let mut versioned = good.clone();
    versioned[8] = 99;
    std::fs::write(&ckpt, &versioned).unwrap();
    let e = Checkpoint::read(&ckpt).unwrap_err();
    assert!(e.to_string().contains("version 99"), "{e}");
    std::fs::write(&ckpt, b"hello").unwrap();
    assert!(matches!(
        Checkpoint::read(&ckpt),
        Err(CheckpointError::NotACheckpoint)
    ));
    // The resume passes over the damaged one and continues from .prev.
    std::fs::write(&ckpt, &flipped).unwrap();
    let text = run_ok(&["--resume", s(&run), "--t-end", "0.003"], &[]);
    assert!(
        text.contains("passing over") && text.contains("damaged"),
        "{text}"
    );
    let resumed = RunFile::read(&run).unwrap();
    assert!(resumed
        .history
        .iter()
        .any(|l| l.contains(&format!("resumed at step {prev_step} "))));
    // Both damaged: the loaded slider's checkpoint is the last resort.
    let loaded = slipfront::io::checkpoint::loaded_path_for(&run);
    let loaded_step = Checkpoint::read(&loaded).unwrap().header.step;
    std::fs::write(path_for(&run), b"SLIPCKPT").unwrap();
    std::fs::write(&prev, b"x").unwrap();
    let text = run_ok(&["--resume", s(&run), "--t-end", "0.003"], &[]);
    assert!(
        text.contains("cut short") && text.contains("not a slipfront checkpoint"),
        "{text}"
    );
    let resumed = RunFile::read(&run).unwrap();
    assert!(resumed
        .history
        .iter()
        .any(|l| l.contains(&format!("resumed at step {loaded_step} "))));
    // None good: refused, naming each.
    std::fs::write(path_for(&run), b"SLIPCKPT").unwrap();
    std::fs::write(&prev, b"x").unwrap();
    std::fs::write(&loaded, &good[..50]).unwrap();
    let err = run_fails(&["--resume", s(&run), "--t-end", "0.004"], &[]);
    for name in [
        ".ckpt`: damaged",
        ".prev`: not a slipfront",
        ".loaded.ckpt`: damaged",
    ] {
        assert!(err.contains(name), "{name}: {err}");
    }
}

#[test]
fn a_branch_with_a_new_velocity_differs_only_after_the_branch_point() {
    let d = dir("branch");
    let parent_whole = uninterrupted(CPU, &d, "f64", "0.004");
    let parent = d.join("parent.mcap");
    run_ok(&["--t-end", "0.002", "-o", s(&parent)], &scene_args(&[]));
    let branch_step = Checkpoint::read(&path_for(&parent)).unwrap().header.step;
    let child = d.join("child.mcap");
    let text = run_ok(
        &[
            "--from",
            s(&path_for(&parent)),
            "--set",
            "loading.drive.velocity=0.3",
            "--t-end",
            "0.004",
            "-o",
            s(&child),
        ],
        &[],
    );
    assert!(
        text.contains("loading.drive.velocity = 0.2 → 0.3"),
        "{text}"
    );
    let child = RunFile::read(&child).unwrap();
    let (before, after): (Vec<_>, Vec<_>) =
        child.global.iter().partition(|g| g.step <= branch_step);
    let parent_before: Vec<_> = parent_whole
        .global
        .iter()
        .filter(|g| g.step <= branch_step)
        .collect();
    assert!(!before.is_empty() && before == parent_before);
    let parent_after: Vec<_> = parent_whole
        .global
        .iter()
        .filter(|g| g.step > branch_step)
        .collect();
    assert_eq!(after.len(), parent_after.len());
    assert!(after.last() != parent_after.last());
    // The side spring goes on from where it was: its force right after the
    // branch is the parent's to within the few steps of faster pulling
    // (without the origin shift it would jump by K·0.1 m/s·2 ms, ~150 %).
    let (a, b) = (after[0], parent_after[0]);
    assert_eq!(a.step, b.step);
    let jump = (a.drive_force - b.drive_force).abs();
    assert!(
        jump < 0.02 * b.drive_force.abs(),
        "{} vs {}",
        a.drive_force,
        b.drive_force
    );
    assert!(child
        .history
        .iter()
        .any(|l| l.starts_with("branched at step")));
}

#[test]
fn a_branch_refuses_keys_the_saved_state_fixes() {
    let d = dir("refuse");
    let parent = d.join("parent.mcap");
    run_ok(&["--t-end", "0.001", "-o", s(&parent)], &scene_args(&[]));
    let from = path_for(&parent);
    let err = run_fails(
        &[
            "--from",
            s(&from),
            "--set",
            "geometry.nx=57",
            "--set",
            "geometry.length=0.14",
            "--set",
            "damping.ratio=0.5",
        ],
        &[],
    );
    for key in ["geometry.nx = 29 → 57", "geometry.length", "damping.ratio"] {
        assert!(err.contains(key), "{key}: {err}");
    }
    assert!(err.contains("fixed by the saved state"), "{err}");
    // A top force growing from the branch point would jump: refused.
    let text = Checkpoint::read(&from).unwrap().header.scenario;
    let mut table: toml::Table = text.parse().unwrap();
    table["loading"]["drive"] =
        toml::Value::Table("mode = \"top_force\"\nforce_rate = 10.0".parse().unwrap());
    let child = d.join("top_force.toml");
    std::fs::write(&child, toml::to_string(&table).unwrap()).unwrap();
    let err = run_fails(&[s(&child), "--from", s(&from)], &[]);
    assert!(err.contains("loading.drive.force_rate"), "{err}");
    let err = run_fails(&["--resume", s(&parent), "--set", "time.seed=3"], &[]);
    assert!(err.contains("--from"), "{err}");
}

/// The engines' own save and load: a state saved after n steps and loaded
/// into a fresh engine steps on with the same bits, on either CPU engine,
/// in every precision, and across the two engines.
#[test]
fn engine_state_round_trips_bit_for_bit() {
    let scenario = slipfront::app::verify::small_scene(&["loading.drive.velocity=0.2"]).unwrap();
    let model = Model::from_scenario(&scenario, false).unwrap();
    let n = model.prep_steps + 2500;
    for precision in [Precision::F64, Precision::F32, Precision::F32Plain] {
        let mut a = cpu_engine(&model, precision, 1).unwrap();
        a.advance(n).unwrap();
        let saved = a.save_state().unwrap();
        a.advance(1500).unwrap();
        let want = a.snapshot().unwrap();
        assert!(
            want.total_ruptures() > 0,
            "the stretch must break junctions"
        );
        for mut b in [
            cpu_engine(&model, precision, 1).unwrap(),
            cpu_reference_engine(&model, precision, 1).unwrap(),
            cpu_engine(&model, precision, 2).unwrap(),
        ] {
            b.load_state(&saved).unwrap();
            assert_eq!(b.save_state().unwrap(), saved, "{}", b.describe());
            b.advance(1500).unwrap();
            assert_eq!(
                b.snapshot().unwrap(),
                want,
                "{} {precision:?}",
                b.describe()
            );
        }
        // Negative control: one velocity off by 1e-9 m/s changes the run.
        let mut off = saved.clone();
        off.vel[model.nx + 3][0] += 1e-9;
        let mut c = cpu_engine(&model, precision, 1).unwrap();
        c.load_state(&off).unwrap();
        c.advance(1500).unwrap();
        assert_ne!(c.snapshot().unwrap(), want, "{precision:?}");
    }
    // A state of another lattice is refused, naming the sizes.
    let other =
        slipfront::app::verify::small_scene(&["geometry.nx=57", "geometry.length=0.14"]).unwrap();
    let other = Model::from_scenario(&other, false).unwrap();
    let mut e = cpu_engine(&other, Precision::F64, 1).unwrap();
    let saved = cpu_engine(&model, Precision::F64, 1)
        .unwrap()
        .save_state()
        .unwrap();
    let err = e.load_state(&saved).unwrap_err().to_string();
    assert!(err.contains("another lattice"), "{err}");
}

/// "N factorisations, M CG iterations" of a run summary.
fn solver_totals(summary: &str) -> String {
    let line = summary
        .lines()
        .find(|l| l.contains("fast-forward"))
        .expect("a fast-forward line");
    let at = line.find("J of ring-down; ").expect("solver totals") + 16;
    let end = line[at..].find(" CG iterations").expect("CG") + at;
    line[at..end].to_string()
}

/// A fast-forwarded run (Table S1 driven 10× faster: one jump, then the
/// first event) stopped during the event and extended: the same records,
/// the jump's included, and the same solver totals (the kept factor comes
/// back with the checkpoint; without it the resumed run would factorise
/// again).
#[test]
fn a_fast_forwarded_run_resumes_exactly() {
    let d = dir("ff");
    let set: Vec<String> = [
        "loading.drive.velocity=4e-3",
        "output.global_interval=1e-5",
        "output.interface_interval=1e-4",
        "output.bulk_interval=0",
    ]
    .iter()
    .flat_map(|s| ["--set".to_string(), s.to_string()])
    .collect();
    let whole = d.join("whole.mcap");
    let ff = ["--fast-forward", "on"];
    let a = run_ok(
        &[&ff[..], &["--t-end", "0.03", "-o", s(&whole)]].concat(),
        &set,
    );
    let part = d.join("part.mcap");
    run_ok(
        &[&ff[..], &["--t-end", "0.021", "-o", s(&part)]].concat(),
        &set,
    );
    let b = run_ok(&["--resume", s(&part), "--t-end", "0.03"], &[]);
    let (whole, part) = (
        RunFile::read(&whole).unwrap(),
        RunFile::read(&part).unwrap(),
    );
    assert_eq!(whole.fast_forward.len(), 1, "the scene has one jump");
    assert_same_records(&whole, &part);
    assert_eq!(solver_totals(&a), solver_totals(&b));
}

#[test]
fn a_resume_in_another_precision_says_so() {
    let d = dir("precision");
    let run = d.join("run.mcap");
    run_ok(&["--t-end", "0.001", "-o", s(&run)], &scene_args(&[]));
    let text = run_ok(
        &[
            "--resume",
            s(&run),
            "--t-end",
            "0.0015",
            "--precision",
            "f32",
        ],
        &[],
    );
    assert!(text.contains("precision changed f64 → f32 mixed"), "{text}");
    let file = RunFile::read(&run).unwrap();
    let line = file.history.last().unwrap();
    assert!(line.contains("precision changed f64 → f32 mixed"), "{line}");
    assert!(file.global.last().unwrap().time > 0.0014);
}

/// The loaded slider (saved one step before driving starts) is the common
/// start of a study: a branch from it with another drive velocity, or with
/// a trigger, is the fresh run of that scene, bit for bit, without its
/// normal-load phase.
#[test]
fn branches_from_the_loaded_slider_equal_fresh_runs() {
    let d = dir("loaded");
    let trigger = [
        "loading.trigger.shear_prestress=0.3",
        "loading.trigger.force_width=0.1",
        "loading.trigger.strip_length=0.005",
        "loading.trigger.strip_prestress=0.7",
    ];
    let base = d.join("base.mcap");
    run_ok(&["--t-end", "0", "-o", s(&base)], &scene_args(&trigger));
    let loaded = slipfront::io::checkpoint::loaded_path_for(&base);
    for (name, changes) in [
        ("velocity", vec!["loading.drive.velocity=0.3"]),
        (
            "trigger",
            vec![
                "loading.trigger.force_width=0.2",
                "loading.trigger.strip_prestress=0.9",
            ],
        ),
    ] {
        let set: Vec<String> = changes
            .iter()
            .flat_map(|c| ["--set".to_string(), c.to_string()])
            .collect();
        let fresh = d.join(format!("fresh-{name}.mcap"));
        let scene = [&trigger[..], &changes[..]].concat();
        run_ok(&["--t-end", "0.002", "-o", s(&fresh)], &scene_args(&scene));
        let branch = d.join(format!("branch-{name}.mcap"));
        let from = ["--from", s(&loaded), "--t-end", "0.002", "-o", s(&branch)];
        run_ok(&from, &set);
        let (a, b) = (
            RunFile::read(&fresh).unwrap(),
            RunFile::read(&branch).unwrap(),
        );
        assert_same_records(&a, &b);
        // Negative control: the parent's own continuation differs.
        let parent = d.join(format!("parent-{name}.mcap"));
        run_ok(
            &["--resume", s(&base), "--t-end", "0.002", "-o", s(&parent)],
            &[],
        );
        assert!(RunFile::read(&parent).unwrap().global != a.global, "{name}");
    }
    // The prestress acts in the normal-load phase too: refused.
    let err = run_fails(
        &[
            "--from",
            s(&loaded),
            "--set",
            "loading.trigger.shear_prestress=0.4",
        ],
        &[],
    );
    assert!(err.contains("normal-load phase"), "{err}");
}

/// The GPU engine too: a finished GPU run extended from its checkpoint
/// writes the records of the longer run, bit for bit (the state is restored
/// exactly, batches are anchored at the same steps whatever the chunks, the
/// device records resume after the last sample and with its fast cadence).
/// Negative control: V × (1 + 1e-6) is flagged.
#[test]
fn a_gpu_run_extended_equals_the_longer_run() {
    let d = dir("gpu-extend");
    let gpu = |args: &[&str], extra: &[String]| {
        let out = Command::new(env!("CARGO_BIN_EXE_slipfront"))
            .args(["run", "--backend", "gpu", "--precision", "f32", "--quiet"])
            .args(args)
            .args(extra)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(
            out.status.success(),
            "a GPU adapter is required (lavapipe in CI): {text}"
        );
    };
    let whole = d.join("whole.mcap");
    gpu(&["--t-end", "0.001", "-o", s(&whole)], &scene_args(&[]));
    let short = d.join("short.mcap");
    gpu(&["--t-end", "0.0005", "-o", s(&short)], &scene_args(&[]));
    gpu(&["--resume", s(&short), "--t-end", "0.001"], &[]);
    let whole = RunFile::read(&whole).unwrap();
    assert_same_records(&whole, &RunFile::read(&short).unwrap());
    let other = d.join("other.mcap");
    gpu(
        &["--t-end", "0.001", "-o", s(&other)],
        &scene_args(&["loading.drive.velocity=0.2000002"]),
    );
    assert!(whole.global != RunFile::read(&other).unwrap().global);
}

/// A rate-and-state run stopped at its end and resumed gives the records
/// of the run that never stopped: the law's state θ travels in the
/// checkpoint (a resume that restarted θ would slip elsewhere).
#[test]
fn a_rate_state_run_resumes_bit_for_bit() {
    let d = dir("rate-state");
    let scene = ["scenarios/rate_state.toml"];
    let args = |more: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = scene.iter().map(|s| s.to_string()).collect();
        v.extend(
            slipfront::app::verify::SMALL_SCENE
                .iter()
                .chain(&["loading.drive.velocity=0.4"])
                .chain(more)
                .flat_map(|s| ["--set".to_string(), s.to_string()]),
        );
        v
    };
    let whole = d.join("whole.mcap");
    run_ok(&["--t-end", "0.002", "-o", s(&whole)], &args(&[]));
    let run = d.join("run.mcap");
    run_ok(&["--t-end", "0.001", "-o", s(&run)], &args(&[]));
    let ckpt = Checkpoint::read(&path_for(&run)).unwrap();
    assert_eq!(ckpt.engine.law_state.len(), 29, "θ of each interface block");
    run_ok(&["--resume", s(&run), "--t-end", "0.002"], &[]);
    let (a, b) = (RunFile::read(&whole).unwrap(), RunFile::read(&run).unwrap());
    assert!(
        a.global.iter().any(|g| g.ruptures > 0),
        "the run must contain slips"
    );
    assert_same_records(&a, &b);
}

/// A checkpoint of format version 1 (before the law state) is still read,
/// with no law state: every law then had none.
#[test]
fn a_version_1_checkpoint_is_still_read() {
    let d = dir("version-1");
    let run = d.join("run.mcap");
    run_ok(&["--t-end", "0.0005", "-o", s(&run)], &scene_args(&[]));
    let path = path_for(&run);
    let now = Checkpoint::read(&path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    // The empty law_state section's count sits after the sections before it.
    let h = &now.header;
    let header_len = u64::from_le_bytes(bytes[12..20].try_into().unwrap()) as usize;
    let (n, nx, nj) = (h.blocks, h.nx, h.junctions);
    let values = [
        2 * 8,
        4 * n * 8,
        2 * n * 8,
        2 * n * 8,
        2 * nx * 8,
        2 * nj * 8,
        nj * 8,
        2 * nj * 4,
        2 * nx * 4,
    ];
    let at = 20 + header_len + values.iter().map(|v| 8 + v).sum::<usize>();
    assert_eq!(&bytes[at..at + 8], &[0u8; 8], "the empty law_state section");
    let mut old = [&bytes[..at], &bytes[at + 8..bytes.len() - 8]].concat();
    old[8..12].copy_from_slice(&1u32.to_le_bytes());
    let sum = slipfront::io::output::fnv1a(&old);
    old.extend_from_slice(&sum.to_le_bytes());
    std::fs::write(&path, &old).unwrap();
    let back = Checkpoint::read(&path).unwrap();
    assert_eq!(back.engine, now.engine);
    assert_eq!(back.header.step, now.header.step);
}
