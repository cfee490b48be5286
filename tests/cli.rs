//! The command line, end to end.

use std::process::Command;

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

#[path = "support/f64_adapter.rs"]
mod f64_adapter;

fn slipfront_cmd() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_slipfront"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn slipfront(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("runs")
}

#[test]
fn check_reports_derived_quantities_as_json() {
    let out = slipfront(&["check", "scenarios/tromborg2014_stick_slip.toml", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["blocks"], serde_json::json!([57, 31]));
    assert!((v["dt_over_period"].as_f64().unwrap() - 0.02).abs() < 1e-12);
    assert_eq!(v["stable"], true);
    let terms: Vec<&str> = v["terms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_str().unwrap())
        .collect();
    assert!(
        terms.contains(&"junctions") && terms.contains(&"side_spring"),
        "{terms:?}"
    );
}

#[test]
fn run_default_scene_briefly_writes_an_mcap_file() {
    let dir = Scratch::new("cli", "run");
    let file = dir.join("run.mcap");
    let out = slipfront(&[
        "run",
        "--backend",
        "cpu",
        "--t-end",
        "2e-4",
        "--quiet",
        "-o",
        file.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("run complete"), "{text}");
    let bytes = std::fs::read(&file).unwrap();
    let n = mcap::MessageStream::new(&bytes).unwrap().count();
    // 2e-4 s at 1e-5 s global cadence and 2e-5 s interface cadence.
    assert!(n >= 25, "{n} messages");
    let out = slipfront(&["info", file.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("/interface") && text.contains("events") && text.contains("precursors"),
        "{text}"
    );
    let out = slipfront(&["plot", file.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // No event in 0.2 ms: the maps and the loading curve, not the event
    // figures (tests/plots.rs covers every kind).
    for name in [
        "run_spacetime.png",
        "run_stress_ratio.png",
        "run_loading.png",
    ] {
        assert!(dir.join(name).exists(), "{name}");
    }
    assert!(!dir.join("run_front_speed.png").exists());
    // An event that is not there is refused before any picture is drawn.
    let other = dir.join("other");
    let out = slipfront(&[
        "plot",
        file.to_str().unwrap(),
        "--event",
        "99",
        "-o",
        other.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--event 99"));
    assert!(!other.join("run_spacetime.png").exists());
    // The event table as CSV: a header naming the columns with units.
    let out = slipfront(&["info", "--csv", file.to_str().unwrap()]);
    let csv = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && csv.starts_with("event,start_s,end_s,kind,rupture_length_m"),
        "{csv}"
    );
    let out = slipfront(&["info", "no_such.mcap"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no_such.mcap"));
    // A file that is not MCAP at all is refused, not read as an empty run.
    let not_mcap = dir.join("scenario.mcap");
    std::fs::write(&not_mcap, "name = \"x\"\n").unwrap();
    let out = slipfront(&["info", not_mcap.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not an MCAP file"));
}

#[test]
fn bad_input_exits_with_a_clear_message() {
    let out = slipfront(&["check", "--set", "material.youngs_modulus=-3"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("material.youngs_modulus = -3"), "{err}");
    let out = slipfront(&["run", "--backend", "cpu", "--set", "time.dt=1e-5"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("stability limit"));
    let out = slipfront(&["run", "missing.toml"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.toml"));
    let out = slipfront(&["info", "--quiet-gap=-1", "run.mcap"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--quiet-gap = -1"));
    // A missing --from names the path given, not a derived one.
    let out = slipfront(&["run", "--from", "nope.ckpt", "-o", "never.mcap"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--from `nope.ckpt`: no such file"), "{err}");
    // A workgroup of no threads, on run and sweep alike.
    for command in ["run", "sweep"] {
        let out = slipfront(&[command, "--gpu-threads", "0"]);
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("'0' for '--gpu-threads"), "{err}");
        assert!(err.contains("not in 1.."), "{err}");
        // Each bad value of a flag: refused (status 2), the value and the
        // flag named, with the allowed range.
        let refused = |flag: &str, bad: &[&str], allowed: &str| {
            for bad in bad {
                let out = slipfront(&[command, &format!("--{flag}={bad}")]);
                assert_eq!(out.status.code(), Some(2));
                let err = String::from_utf8_lossy(&out.stderr);
                assert!(err.contains(&format!("'{bad}' for '--{flag}")), "{err}");
                assert!(err.contains(allowed), "{err}");
            }
        };
        // Batches to run ahead: a count, and a bounded one.
        refused("gpu-run-ahead", &["-1", "65", "four"], "from 0 to 64");
        // A tile shape: WIDTHxHALO, the width at least 1, the halo 1 to 32.
        refused("gpu-tile", &["8x0", "0x4", "8x33", "8"], "1 to 32");
        // Junction lanes a thread: a power of two up to 8.
        refused("gpu-lane-run", &["0", "3", "16", "four"], "[1, 2, 4, 8]");
        // Scenes a persistent workgroup: 1, 2 or 4.
        refused("gpu-group-scenes", &["0", "3", "8", "two"], "[1, 2, 4]");
        // How the kernels' arithmetic is compiled: one of three words.
        refused("gpu-arithmetic", &["exact", "fast"], "leaner, strict, wgpu");
    }
}

#[test]
fn verify_json_lists_every_case_with_its_fields() {
    let out = slipfront(&["verify", "--backend", "cpu", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let cases = v.as_array().unwrap();
    assert!(cases.len() >= 17);
    for c in cases {
        for key in ["name", "measured", "expected", "tolerance", "unit", "pass"] {
            assert!(c.get(key).is_some(), "{key} missing in {c}");
        }
    }
}

/// Output piped into a reader that stops early (`| head`) ends the
/// process quietly instead of panicking on the closed pipe.
#[cfg(unix)]
#[test]
fn a_closed_stdout_pipe_is_not_a_panic() {
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .arg("check")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn check_estimates_the_wall_time_and_fails_when_unstable() {
    let out = slipfront(&["check", "--set", "time.end=0.01"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("wall time") && text.contains("steps/s") && text.contains("cpu f64"),
        "{text}"
    );
    let out = slipfront(&["check", "--set", "time.dt=1e-5"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stdout).contains("UNSTABLE"));
    assert!(String::from_utf8_lossy(&out.stderr).contains("stability limit"));
}

/// `check` times the GPU in the precision `run --backend gpu` takes, f64
/// where the adapter has f64 shaders, as well as in mixed f32 (it timed
/// mixed f32 only, so a GPU run's estimate was of another precision).
#[test]
fn check_times_the_gpu_in_the_precision_a_gpu_run_takes() {
    let out = slipfront(&["check", "--set", "time.end=0.01"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("on gpu f32 mixed"), "{text}");
    if f64_adapter::f64_adapter() {
        assert!(text.contains("on gpu f64,"), "{text}");
    }
}

/// `check` refuses to measure what `run` would refuse (memory), and times a
/// large lattice over a few steps instead of hanging on long calls (it took
/// over a minute on 2000 × 1000 before).
#[test]
fn check_is_bounded_in_memory_and_time() {
    let huge = [
        "check",
        "--set",
        "geometry.nx=65536",
        "--set",
        "geometry.nz=65536",
        "--set",
        "geometry.height=0.14",
    ];
    let out = slipfront(&huge);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("not measured    Cpu F64: a 65536 × 65536 lattice needs about"),
        "{text}"
    );
    let started = std::time::Instant::now();
    let large = [
        "check",
        "--set",
        "geometry.nx=2000",
        "--set",
        "geometry.nz=1000",
        "--set",
        "geometry.height=0.069965",
    ];
    let out = slipfront(&large);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("block-steps/s"), "{text}");
    // A bound on behaviour, not a speed claim: each of three engines is
    // timed for 0.4 s plus one step.
    assert!(started.elapsed().as_secs() < 60, "{:?}", started.elapsed());
}

/// On a big lattice a step takes milliseconds: a signal must still stop
/// the run within a second or so (chunks of steps are sized by wall time,
/// not a fixed step count), exiting 130 with its file closed.
#[test]
fn sigint_stops_a_big_lattice_promptly() {
    let dir = Scratch::new("cli", "big");
    let file = dir.join("big.mcap");
    let mut child = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(["run", "--backend", "cpu", "--threads", "1", "--quiet"])
        .args(["--set", "geometry.nx=300", "--set", "geometry.nz=300"])
        .args([
            "--set",
            "geometry.length=0.14",
            "--set",
            "geometry.height=0.14",
        ])
        .args(["-o", file.to_str().unwrap()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    assert!(child.try_wait().unwrap().is_none());
    let sent = std::time::Instant::now();
    unsafe {
        libc::kill(child.id() as i32, libc::SIGINT);
    }
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if sent.elapsed() > std::time::Duration::from_secs(20) {
            child.kill().unwrap();
            panic!("the run ignored SIGINT for 20 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    assert_eq!(status.code(), Some(130));
    assert!(
        sent.elapsed() < std::time::Duration::from_secs(5),
        "{:?} to stop",
        sent.elapsed()
    );
    let run = slipfront::io::output::reader::RunFile::read(&file).unwrap();
    assert!(!run.truncated);
}

/// Output files: an existing one is kept unless --force (which also
/// removes the old run's checkpoints), an input is never overwritten,
/// absurd thread counts are refused, foreign MCAP files are named as such,
/// and terminal escapes in a run's metadata are not sent to the terminal.
#[test]
fn outputs_inputs_and_foreign_files_are_guarded() {
    let dir = Scratch::new("cli", "guard");
    let file = dir.join("run.mcap");
    let f = file.to_str().unwrap();
    let short = [
        "run",
        "--backend",
        "cpu",
        "--t-end",
        "1e-5",
        "--quiet",
        "-o",
        f,
    ];
    let out = slipfront(&short);
    assert!(out.status.success());
    let out = slipfront(&short);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("exists") && err.contains("--force") && err.contains("--resume"),
        "{err}"
    );
    let stale = dir.join("run.mcap.ckpt");
    assert!(stale.exists());
    std::fs::write(&stale, b"an old run's checkpoint").unwrap();
    let out = slipfront(&[
        "run",
        "--backend",
        "cpu",
        "--t-end",
        "0",
        "--quiet",
        "-o",
        f,
        "--force",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(slipfront::io::checkpoint::Checkpoint::read(&stale).is_ok());
    // The old checkpoint did not survive as the new run's previous one.
    assert!(!dir.join("run.mcap.ckpt.prev").exists());
    // The scenario itself as the output: refused, even with --force.
    let scenario = dir.join("s.toml");
    std::fs::write(&scenario, slipfront::model::scenario::DEFAULT_SCENARIO).unwrap();
    let s = scenario.to_str().unwrap();
    let out = slipfront(&["run", s, "--backend", "cpu", "-o", s, "--force"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("input of this run"));
    assert_eq!(
        std::fs::read_to_string(&scenario).unwrap(),
        slipfront::model::scenario::DEFAULT_SCENARIO
    );
    let out = slipfront(&[
        "run",
        "--backend",
        "cpu",
        "--threads",
        "100000",
        "--t-end",
        "0",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--threads 100000"));
    // An MCAP file that slipfront did not write.
    let foreign = dir.join("foreign.mcap");
    {
        let mut w = mcap::Writer::new(std::io::BufWriter::new(
            std::fs::File::create(&foreign).unwrap(),
        ))
        .unwrap();
        w.finish().unwrap();
    }
    let out = slipfront(&["info", foreign.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a slipfront run file"));
    // A scenario name with an escape sequence is shown escaped.
    let evil = dir.join("evil.mcap");
    let out = slipfront(&[
        "run",
        "--backend",
        "cpu",
        "--t-end",
        "1e-5",
        "--quiet",
        "--set",
        "name=x\u{1b}[2Jy",
        "-o",
        evil.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = slipfront(&["info", evil.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        !text.contains('\u{1b}') && text.contains("x\\u{1b}[2Jy"),
        "{text}"
    );
}

#[test]
fn study_commands_write_their_tables_and_figures() {
    let dir = Scratch::new("cli", "study");
    let out: &std::path::Path = &dir;
    for study in ["front-1d", "single-block", "coulomb-precursors"] {
        let o = slipfront_cmd()
            .args(["study", study, "--quick", "-o"])
            .arg(out)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{study}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let csv = std::fs::read_to_string(out.join("front_speed_1d.csv")).unwrap();
    assert!(csv.starts_with("law,viscosity,alpha,stiffness_ratio,tau_bar,n_blocks,front_speed\n"));
    assert!(
        csv.contains(",inf,0.8,inf,"),
        "a rigid extrapolated row:\n{csv}"
    );
    for f in [
        "front_speed_1d.md",
        "front_speed_1d_viscosity.png",
        "thogersen2014_single_block.md",
        "thogersen2014_friction_vs_speed.png",
        "tromborg2011_coulomb_precursors.md",
        "tromborg2011_coulomb_precursors.png",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // Uniform loading: precursors longer than one block, growing with the load.
    let table = std::fs::read_to_string(out.join("tromborg2011_coulomb_precursors.csv")).unwrap();
    let uniform: Vec<(f64, f64)> = table
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|c| c[0] == "200" && c[3] == "false" && c[5].parse::<f64>().unwrap() > 3.75)
        .map(|c| (c[4].parse().unwrap(), c[5].parse().unwrap()))
        .collect();
    assert!(uniform.len() >= 2, "{table}");
    assert!(
        uniform
            .windows(2)
            .all(|w| w[1].0 > w[0].0 && w[1].1 > w[0].1),
        "{uniform:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn single_block_runs_the_built_in_scene_and_refuses_a_bad_one() {
    let dir = Scratch::new("cli", "block");
    let csv = dir.join("sb.csv");
    let o = slipfront_cmd()
        .args(["single-block", "-o"])
        .arg(&csv)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text
        .starts_with("time_s,position_m,velocity_m_per_s,friction_coefficient,pinned_fraction\n"));
    assert!(text.lines().count() > 1000);
    let bad = dir.join("bad.toml");
    let scene = std::fs::read_to_string("scenarios/thogersen2014_single_block.toml")
        .unwrap()
        .replace("break_stretch = 1.0e-7", "break_stretch = -1.0e-7");
    std::fs::write(&bad, scene).unwrap();
    let o = slipfront_cmd()
        .arg("single-block")
        .arg(&bad)
        .arg("-o")
        .arg(&csv)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("law.break_stretch = -0.0000001") || err.contains("law.break_stretch = -1e-7"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
