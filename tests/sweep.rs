//! Sweeps: every point validated and run, one row each; a killed sweep
//! rerun finishes with the table of one that never stopped; shards (local
//! and as a real Slurm job array) collect into the same table.

use slipfront::engines::gpu::kernel_choice::Launch;
use slipfront::engines::gpu::GpuPath;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

fn dir(name: &str) -> Scratch {
    Scratch::new("sweep", name)
}

/// Eight points of the small side-driven scene (junctions break from
/// 0.6 ms): two μs, two spring stiffnesses (a log range), two seeds.
fn sweep_file(d: &Path, extra_axis: &str) -> PathBuf {
    sweep_file_with_seeds(d, extra_axis, 2, 0.0025)
}

/// The same points with one seed: the GPU sweeps (lavapipe steps this
/// scene at about 1 ms a step, so every point costs seconds).
fn gpu_sweep_file(d: &Path, extra_axis: &str) -> PathBuf {
    gpu_sweep_file_ending(d, extra_axis, 0.0025)
}

fn gpu_sweep_file_ending(d: &Path, extra_axis: &str, end: f64) -> PathBuf {
    sweep_file_with_seeds(d, extra_axis, 1, end)
}

fn sweep_file_with_seeds(d: &Path, extra_axis: &str, seeds: usize, end: f64) -> PathBuf {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/tromborg2014_stick_slip.toml");
    let text = format!(
        r#"base = "{}"
seeds = {seeds}

[set]
"geometry.nx" = 29
"geometry.nz" = 16
"geometry.length" = 0.07
"geometry.height" = 0.0375
"loading.normal.ramp_time" = 2e-4
"loading.normal.relax_time" = 3e-4
"loading.drive.velocity" = 0.2
"time.end" = {end:?}

[axes]
"friction.static_coefficient" = [0.35, 0.4]
"loading.drive.stiffness" = {{ from = 2e6, to = 8e6, count = 2, scale = "log" }}
{extra_axis}
"#,
        base.display()
    );
    let path = d.join("sweep.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn slipfront(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(args)
        .output()
        .unwrap()
}

fn ok(args: &[&str]) -> String {
    let out = slipfront(args);
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "slipfront {args:?}: {text}");
    text
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The table without its wall-time column (the only one that may differ).
/// `sweep FILE -o OUT --backend gpu --precision f32`.
fn gpu_f32_sweep<'a>(file: &'a Path, out: &'a Path) -> Vec<&'a str> {
    vec![
        "sweep",
        s(file),
        "-o",
        s(out),
        "--backend",
        "gpu",
        "--precision",
        "f32",
    ]
}

fn table(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut rows: Vec<Vec<String>> = text
        .lines()
        .map(slipfront::app::sweeps::table::split)
        .collect();
    let wall = rows[0].iter().position(|h| h == "wall_s").unwrap();
    for r in &mut rows {
        r.remove(wall);
    }
    rows
}

fn column<'a>(rows: &'a [Vec<String>], name: &str) -> Vec<&'a str> {
    let k = rows[0].iter().position(|h| h == name).unwrap();
    rows[1..].iter().map(|r| r[k].as_str()).collect()
}

#[test]
fn a_sweep_runs_every_point_once_and_a_killed_one_finishes_the_same() {
    let d = dir("local");
    let file = sweep_file(&d, "");
    let text = ok(&["sweep", s(&file), "--dry-run"]);
    assert!(text.contains("8 points"), "{text}");
    let whole = d.join("whole");
    let text = ok(&["sweep", s(&file), "-o", s(&whole), "--quiet"]);
    assert!(text.contains("8 run now (0 not ok)"), "{text}");
    let rows = table(&whole.join("summary.csv"));
    assert_eq!(rows.len(), 9);
    assert_eq!(
        column(&rows, "point"),
        ["0", "1", "2", "3", "4", "5", "6", "7"]
    );
    assert!(column(&rows, "status").iter().all(|s| *s == "ok"));
    // Every point breaks the interface: a first full event, an F/F_N.
    assert!(column(&rows, "first_full_time_s")
        .iter()
        .all(|t| !t.is_empty()));
    // The axes are as written, the log range's ends exact.
    assert_eq!(
        column(&rows, "loading.drive.stiffness")[..2],
        ["2000000.0"; 2]
    );
    // Stiffer springs load faster: the first event comes earlier.
    let t: Vec<f64> = column(&rows, "first_full_time_s")
        .iter()
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(t[2] < t[0] && t[6] < t[4], "{t:?}");
    // A rerun skips every finished point.
    let text = ok(&["sweep", s(&file), "-o", s(&whole), "--quiet"]);
    assert!(
        text.contains("0 run now") && text.contains("8 already done"),
        "{text}"
    );

    // Killed after two rows, rerun: the table of the sweep that never
    // stopped.
    let cut = d.join("cut");
    let mut child = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args([
            "sweep",
            s(&file),
            "-o",
            s(&cut),
            "--threads",
            "1",
            "--quiet",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let summary = cut.join("summary.csv");
    let started = Instant::now();
    loop {
        let rows = std::fs::read_to_string(&summary).map_or(0, |t| t.lines().count());
        if rows >= 3 {
            break;
        }
        assert!(child.try_wait().unwrap().is_none(), "the sweep ended first");
        assert!(started.elapsed() < Duration::from_secs(120));
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let partial = std::fs::read_to_string(&summary).unwrap().lines().count() - 1;
    assert!((2..8).contains(&partial), "{partial} rows");
    let text = ok(&["sweep", s(&file), "-o", s(&cut), "--quiet"]);
    assert!(text.contains(&format!("{partial} already done")), "{text}");
    assert_eq!(table(&summary), rows);
}

#[test]
fn shards_collect_into_the_local_table_and_bad_points_are_named() {
    let d = dir("shards");
    let file = sweep_file(&d, "");
    let local = d.join("local");
    ok(&["sweep", s(&file), "-o", s(&local), "--quiet"]);
    let sharded = d.join("sharded");
    for shard in ["0/3", "1/3", "2/3"] {
        ok(&[
            "sweep",
            s(&file),
            "-o",
            s(&sharded),
            "--shard",
            shard,
            "--quiet",
        ]);
    }
    ok(&["sweep", "collect", s(&sharded)]);
    assert_eq!(
        table(&sharded.join("summary.csv")),
        table(&local.join("summary.csv"))
    );
    // The points share one normal-load phase (they differ in μs, the
    // drive and the seed): run once, and each point started from it gives
    // the bits of running its own.
    let own = d.join("own");
    let text = ok(&[
        "sweep",
        s(&file),
        "-o",
        s(&own),
        "--quiet",
        "--no-shared-loading",
    ]);
    assert!(text.contains("0 shared normal-load phases"), "{text}");
    let text = ok(&["sweep", s(&file), "-o", s(&d.join("again")), "--quiet"]);
    assert!(text.contains("1 shared normal-load phases"), "{text}");
    assert_eq!(
        table(&own.join("summary.csv")),
        table(&local.join("summary.csv"))
    );
    // A point that fails validation is named, and nothing runs.
    let bad = sweep_file(&d, "\"material.density\" = [1200.0, -1.0]");
    let out = slipfront(&["sweep", s(&bad), "-o", s(&d.join("bad"))]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("point 2 (")
            && err.contains("material.density=-1.0")
            && err.contains("material.density = -1"),
        "{err}"
    );
    assert!(!d.join("bad").join("summary.csv").exists());
}

/// The Slurm test: a real one-node cluster (`../shared/slurm`), the sweep
/// submitted as a 3-task job array, collected, equal to the local table.
/// Skips with its reason outside CI when no cluster can be started; fails
/// under CI=true.
#[test]
fn a_slurm_job_array_gives_the_local_table() {
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    let start = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/slurm/start-local.sh");
    let started = start.exists()
        && Command::new("bash")
            .arg(&start)
            .output()
            .is_ok_and(|o| o.status.success());
    if !started {
        assert!(
            !ci,
            "CI=true: no Slurm cluster could be started with {}",
            start.display()
        );
        eprintln!(
            "skipped: no Slurm cluster ({} missing or failed)",
            start.display()
        );
        return;
    }
    let d = dir("slurm");
    let file = sweep_file(&d, "");
    let array = d.join("array");
    let text = ok(&[
        "sweep",
        s(&file),
        "-o",
        s(&array),
        "--slurm",
        "--array-size",
        "3",
    ]);
    let script = array.join("sweep.sbatch");
    assert!(text.contains("sweep.sbatch"), "{text}");
    let out = Command::new("sbatch").arg(&script).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let job = String::from_utf8_lossy(&out.stdout)
        .split_whitespace()
        .last()
        .unwrap()
        .to_string();
    let t0 = Instant::now();
    loop {
        let q = Command::new("squeue")
            .args(["-h", "-j", &job])
            .output()
            .unwrap();
        if String::from_utf8_lossy(&q.stdout).trim().is_empty() {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(300),
            "job {job} still queued"
        );
        std::thread::sleep(Duration::from_millis(500));
    }
    let text = ok(&["sweep", "collect", s(&array)]);
    assert!(text.contains("8 rows"), "{text}");
    for task in 0..3 {
        assert!(array
            .join(format!("summary.shard-{task}-of-3.csv"))
            .exists());
    }
    let local = d.join("local");
    ok(&["sweep", s(&file), "-o", s(&local), "--quiet"]);
    assert_eq!(
        table(&array.join("summary.csv")),
        table(&local.join("summary.csv"))
    );
}

/// Nonsense in the new options and files is refused, naming the field.
#[test]
fn bad_sweep_input_is_refused_with_the_field_named() {
    let d = dir("bad");
    let file = sweep_file(&d, "");
    let f = s(&file);
    for (args, expect) in [
        (vec!["sweep", f, "--shard", "3/2"], "--shard 3/2"),
        (vec!["sweep", f, "--mcap", "some"], "--mcap some"),
        (
            vec!["sweep", f, "--backend", "gpu", "--precision", "f32-plain"],
            "--precision f32-plain: the GPU engine computes in mixed f32 or in f64",
        ),
        (
            vec!["run", "--set", "output.checkpoint_interval=-1"],
            "output.checkpoint_interval",
        ),
    ] {
        let out = slipfront(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(expect), "{args:?}: {err}");
    }
    let bad = d.join("bad.toml");
    for (text, expect) in [
        ("colour = 1\n[axes]\n\"time.seed\" = [1]\n", "unknown field `colour`"),
        (
            "[axes]\n\"loading.drive.velocity\" = { from = 0.0, to = 1.0, count = 3, scale = \"log\" }\n",
            "axes.\"loading.drive.velocity\": a log range needs from > 0",
        ),
        (
            "combine = \"zip\"\n[axes]\n\"time.seed\" = [1, 2]\n\"time.end\" = [0.1]\n",
            "combine = \"zip\" needs axes of one length",
        ),
    ] {
        std::fs::write(&bad, text).unwrap();
        let out = slipfront(&["sweep", s(&bad), "--dry-run"]);
        assert_eq!(out.status.code(), Some(2), "{text}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(expect), "{text}: {err}");
    }
}

/// On the GPU, points of one lattice run as one ensemble (one dispatch
/// for all) and give the table of the same points run one at a time; a
/// point that cannot join (its own lattice) runs alone. In mixed f32 and
/// in f64 (lavapipe has SHADER_F64).
#[test]
fn a_gpu_ensemble_sweep_gives_the_table_of_points_run_one_at_a_time() {
    for precision in ["f32", "f64"] {
        gpu_ensemble_sweep_matches_points_run_alone(precision);
    }
}

fn gpu_ensemble_sweep_matches_points_run_alone(precision: &str) {
    let d = dir(&format!("ensemble_{precision}"));
    let file = gpu_sweep_file(&d, "\"loading.normal.force\" = [1800.0, 1920.0]");
    let together = d.join("together");
    let text = ok(&[
        "sweep",
        s(&file),
        "-o",
        s(&together),
        "--backend",
        "gpu",
        "--precision",
        precision,
        "--ensemble",
        "4",
    ]);
    assert!(text.contains("8 run now (0 not ok)"), "{text}");
    assert!(text.contains("ensembles of 4, 4"), "{text}");
    // The two normal-load phases run as one ensemble too; the table below
    // equals the one whose loadings ran alone.
    assert!(
        text.contains("2 shared normal-load phases run as GPU ensembles"),
        "{text}"
    );
    let apart = d.join("apart");
    let text = ok(&[
        "sweep",
        s(&file),
        "-o",
        s(&apart),
        "--backend",
        "gpu",
        "--precision",
        precision,
        "--ensemble",
        "1",
        "--quiet",
    ]);
    assert!(text.contains("8 run now (0 not ok)"), "{text}");
    let (a, b) = (
        table(&together.join("summary.csv")),
        table(&apart.join("summary.csv")),
    );
    let software = slipfront::engines::gpu::context::shared()
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
        .is_software();
    if software && precision == "f32" {
        // The one-step kernel: an ensemble's scenes are bit for bit their
        // solo runs.
        assert_eq!(a, b);
    } else {
        // Persistent kernel, or f64 (lavapipe folds a solo run's uniform
        // constants, not an ensemble's per-scene records, and rounds the
        // last bit differently): the same events, and in f64 every number
        // to round-off.
        for name in ["status", "events", "full_events", "precursors"] {
            assert_eq!(column(&a, name), column(&b, name), "{name}");
        }
        if precision == "f64" {
            for (ra, rb) in a.iter().zip(&b).skip(1) {
                for (x, y) in ra.iter().zip(rb) {
                    match (x.parse::<f64>(), y.parse::<f64>()) {
                        (Ok(x), Ok(y)) => {
                            assert!((x - y).abs() <= 1e-12 * x.abs().max(y.abs()), "{x} {y}")
                        }
                        _ => assert_eq!(x, y),
                    }
                }
            }
        }
    }
    // Negative control: the table tells the two normal loads apart.
    let force = column(&a, "loading.normal.force");
    let first = column(&a, "first_full_time_s");
    let of = |f: &str| -> Vec<&str> {
        force
            .iter()
            .zip(&first)
            .filter(|(force, _)| **force == f)
            .map(|(_, first)| *first)
            .collect()
    };
    assert_ne!(of("1800.0"), of("1920.0"));
}

/// `--gpu-path measure` (and `auto` on hardware) times the kernels on an
/// ensemble of the sweep's own lattice, recording the points' samples,
/// once, caches the choice under the ensemble's key and runs every point
/// on it: the table is the one of the
/// same sweep naming that kernel with its points run one at a time. The
/// timed ensemble does not follow --ensemble (so neither does the table).
#[test]
fn a_measured_sweep_runs_every_point_on_the_kernel_timed_on_its_ensemble() {
    let d = dir("gpu_measure");
    let file = gpu_sweep_file(&d, "");
    let cache = d.join("cache");
    let run = |name: &str, extra: &[&str]| {
        let out = d.join(name);
        let mut args = gpu_f32_sweep(&file, &out);
        args.extend(extra);
        let got = Command::new(env!("CARGO_BIN_EXE_slipfront"))
            .args(&args)
            .env("SLIPFRONT_CACHE_DIR", &cache)
            .output()
            .unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&got.stdout),
            String::from_utf8_lossy(&got.stderr)
        );
        assert!(got.status.success(), "{text}");
        assert!(text.contains("4 run now (0 not ok)"), "{text}");
        (table(&out.join("summary.csv")), text)
    };
    let (measured, text) = run("measured", &["--gpu-path", "measure", "--ensemble", "2"]);
    let line = text
        .lines()
        .find(|l| l.starts_with("sweep: GPU kernel for 29x16"))
        .unwrap_or_else(|| panic!("the choice is printed: {text}"));
    assert!(
        line.contains("measured now on an ensemble of 4 scenes"),
        "{line}"
    );
    // Every point writes its run file, so the launches were timed
    // recording the samples on the device, as the points record them
    // (where the load phase took more than its budget to step, as on a
    // busy machine here, they were timed before any sample was due).
    assert!(
        line.contains("recording the run's output on the device (")
            || line.contains("with the run's output cadences but no sample in the timed steps"),
        "{line}"
    );
    let chosen = line
        .split("chose ")
        .nth(1)
        .and_then(|rest| rest.split(':').next())
        .unwrap()
        .to_string();
    // The single-workgroup kernels are timed at several threads.
    for kernel in [
        "one-step ",
        "one-step-lanes ",
        "persistent/256 ",
        "resident/256 ",
    ] {
        assert!(line.contains(kernel), "{kernel} timed: {line}");
    }
    let cached = std::fs::read_to_string(cache.join("gpu-kernels.tsv")).unwrap();
    assert!(cached.contains("| ensemble of 4 |"), "{cached}");
    // `resident/512/bond-patches` is `--gpu-path resident --gpu-threads
    // 512 --gpu-bond-patches` (a tile shape is `--gpu-tile`, lanes in
    // storage `--gpu-lanes-in-storage`).
    let launch = Launch::named(&chosen).unwrap_or_else(|| panic!("a launch's name: {chosen}"));
    let path = GpuPath::of(launch.kernel).name();
    let threads = launch.threads.map(|t| t.to_string());
    let tile = launch.tile.map(|t| t.name());
    let mut named_args = vec!["--ensemble", "1", "--quiet", "--gpu-path", &path];
    if let Some(threads) = &threads {
        named_args.extend(["--gpu-threads", threads]);
    }
    if let Some(tile) = &tile {
        named_args.extend(["--gpu-tile", tile]);
    }
    if launch.bond_patches {
        named_args.push("--gpu-bond-patches");
    }
    if launch.lanes_in_storage {
        named_args.push("--gpu-lanes-in-storage");
    }
    let (named, _) = run("named", &named_args);
    assert_eq!(measured, named, "every point ran {chosen}");
    // Not vacuous: the points differ.
    let first = column(&named, "first_full_time_s");
    assert!(first.iter().any(|t| *t != first[0]), "{first:?}");
}

/// GPU points make their samples on the device, alone (`--ensemble 1`,
/// several at once) or as one ensemble (every scene recorded in one
/// dispatch): the table is the one whose samples were host snapshots
/// taken one point at a time.
#[test]
fn gpu_points_with_device_records_alone_or_as_an_ensemble_give_the_host_snapshot_table() {
    let d = dir("gpu_device_records");
    // Ended 0.45 ms after the last first event (at 1.03 ms), the slip and
    // the ringing after it included: three sweeps of these points on
    // lavapipe's one-step-lanes kernel are CI's costliest test at 2.5 ms.
    let file = gpu_sweep_file_ending(&d, "", 0.0015);
    let run = |name: &str, extra: &[&str]| {
        let out = d.join(name);
        let mut args = gpu_f32_sweep(&file, &out);
        args.extend(["--gpu-path", "one-step-lanes", "--quiet"]);
        args.extend(extra);
        let text = ok(&args);
        assert!(text.contains("4 run now (0 not ok)"), "{text}");
        table(&out.join("summary.csv"))
    };
    let alone = ["--ensemble", "1"];
    let host = run(
        "host",
        &[&alone[..], &["--gpu-output", "host", "--threads", "1"]].concat(),
    );
    let device = run(
        "device",
        &[&alone[..], &["--gpu-output", "device", "--threads", "2"]].concat(),
    );
    assert_eq!(host, device);
    let ensemble = run("ensemble", &["--ensemble", "4", "--gpu-output", "device"]);
    assert_eq!(host, ensemble);
    // Not vacuous: the points slip, and differently.
    let events = column(&host, "events");
    assert!(events.iter().any(|e| *e != "0"), "{events:?}");
    let first = column(&host, "first_full_time_s");
    assert!(first.iter().any(|t| *t != first[0]), "{first:?}");
}
