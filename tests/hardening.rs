//! Faults and hostile inputs (issue 14): each case made small by the test.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

fn dir(name: &str) -> Scratch {
    Scratch::new("hard", name)
}

fn slipfront(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_slipfront"));
    c.args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("runs")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A small run with a few hundred messages.
fn small_run(at: &Path) {
    small_run_with(at, "1e-3", &[]);
}

/// The small scene for `t_end` seconds with extra `--set`s.
fn small_run_with(at: &Path, t_end: &str, extra: &[&str]) {
    let mut args = vec!["run", "--backend", "cpu", "--threads", "1", "--quiet"];
    args.extend(["--t-end", t_end, "-o", s(at)]);
    // The extra settings after the small scene's: the last --set wins.
    let sets: Vec<String> = slipfront::app::verify::SMALL_SCENE
        .iter()
        .chain(extra)
        .flat_map(|s| ["--set".to_string(), s.to_string()])
        .collect();
    let out = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(&args)
        .args(&sets)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Offset of the first record with `opcode` after the magic.
fn first_record(bytes: &[u8], opcode: u8) -> usize {
    let mut at = 8;
    while at + 9 <= bytes.len() {
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        if bytes[at] == opcode {
            return at;
        }
        at += 9 + len;
    }
    panic!("no record {opcode:#x}");
}

#[test]
fn a_corrupted_chunk_length_is_damage_not_an_allocation() {
    let d = dir("chunk");
    let run = d.join("run.mcap");
    small_run(&run);
    let mut bytes = std::fs::read(&run).unwrap();
    // Chunk: opcode 0x06, u64 length, then start, end, uncompressed_size.
    let chunk = first_record(&bytes, 0x06);
    let size_field = chunk + 9 + 16;
    bytes[size_field..size_field + 8].copy_from_slice(&4_000_000_000_000_000_000u64.to_le_bytes());
    let bad = d.join("bad.mcap");
    std::fs::write(&bad, &bytes).unwrap();
    for cmd in ["info", "plot"] {
        let out = slipfront(
            &[cmd, s(&bad), "-o", s(&d)][..if cmd == "info" { 2 } else { 4 }],
            &[],
        );
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        // An answer, not an abort (signal 6 has no exit code).
        assert!(out.status.code().is_some(), "{cmd}: {text}");
        assert!(!text.contains("memory allocation"), "{cmd}: {text}");
    }
    // The chunk is all there but its header is impossible: damage.
    let out = slipfront(&["info", s(&bad)], &[]);
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("DAMAGED"),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    // Negative control: the undamaged file reads whole.
    let out = slipfront(&["info", s(&run)], &[]);
    assert!(out.status.success());
    assert!(!String::from_utf8_lossy(&out.stdout).contains("cut short"));
}

#[test]
fn a_read_that_would_not_fit_in_memory_is_refused() {
    let d = dir("budget");
    let run = d.join("run.mcap");
    small_run(&run);
    let out = slipfront(&["info", s(&run)], &[("SLIPFRONT_READ_MEMORY", "20000")]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("need more than") && err.contains("SLIPFRONT_READ_MEMORY"),
        "{err}"
    );
    let out = slipfront(&["info", s(&run)], &[("SLIPFRONT_READ_MEMORY", "1e9")]);
    assert!(out.status.success());
}

#[test]
fn a_lattice_larger_than_the_machine_is_refused_before_allocating() {
    let big = [
        "run",
        "--backend",
        "cpu",
        "--quiet",
        "--set",
        "geometry.nx=65536",
        "--set",
        "geometry.nz=65536",
        "--set",
        "geometry.height=0.14",
    ];
    let out = slipfront(&big, &[]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("65536 × 65536") && err.contains("GiB") && err.contains("--no-memory-check"),
        "{err}"
    );
}

#[test]
fn a_cut_short_file_is_recovered_whole() {
    let d = dir("recover");
    let run = d.join("run.mcap");
    small_run(&run);
    let bytes = std::fs::read(&run).unwrap();
    // As a kill leaves it: the chunks written, then the file ends inside
    // the records that follow them (message indexes), without summary or
    // footer.
    let cut = d.join("cut.mcap");
    let after_chunks = first_record(&bytes, 0x07) + 5;
    std::fs::write(&cut, &bytes[..after_chunks]).unwrap();
    let before = slipfront::io::output::reader::RunFile::read(&cut).unwrap();
    assert!(before.truncated && !before.interface.is_empty());
    // A reader that needs the summary finds none (negative control).
    assert!(mcap::Summary::read(&std::fs::read(&cut).unwrap())
        .unwrap_or(None)
        .is_none());
    let out = slipfront(&["recover", s(&cut)], &[]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("ended before its summary") && text.contains("messages kept"),
        "{text}"
    );
    assert!(d.join("cut.mcap.cut").exists());
    let after = slipfront::io::output::reader::RunFile::read(&cut).unwrap();
    assert!(!after.truncated);
    assert_eq!(after.global, before.global);
    assert_eq!(after.interface, before.interface);
    assert_eq!(after.metadata, before.metadata);
    assert_eq!(after.scenario, before.scenario);
    let summary = mcap::Summary::read(&std::fs::read(&cut).unwrap())
        .unwrap()
        .expect("a summary");
    let counted: u64 = summary
        .stats
        .expect("statistics")
        .channel_message_counts
        .values()
        .sum();
    assert_eq!(
        counted as usize,
        before.global.len() + before.interface.len() + before.bulk.len()
    );
    // A complete file is left alone; a second recovery would overwrite
    // the kept .cut copy, so it is refused.
    let out = slipfront(&["recover", s(&run)], &[]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("nothing to do"));
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let out = slipfront(&["recover", s(&cut)], &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cut.mcap.cut"));
}

/// A slipfront-looking run file written by hand: `interface` rows and
/// `global` times as given.
fn crafted(at: &Path, rows: &[Vec<f64>], global_times: &[f64]) {
    use prost::Message;
    use slipfront::io::output::messages::{Global, Interface};
    let file = std::io::BufWriter::new(std::fs::File::create(at).unwrap());
    let mut w = mcap::WriteOptions::new().create(file).unwrap();
    let meta = [
        ("nx".to_string(), "4".to_string()),
        ("spacing".to_string(), "1e-3".to_string()),
    ]
    .into_iter()
    .collect();
    w.write_metadata(&mcap::records::Metadata {
        name: "slipfront".into(),
        metadata: meta,
    })
    .unwrap();
    let none = Default::default();
    let g = w.add_channel(0, "/global", "protobuf", &none).unwrap();
    let i = w.add_channel(0, "/interface", "protobuf", &none).unwrap();
    let mut seq = 0;
    let mut put = |w: &mut mcap::Writer<_>, channel, t: f64, data: Vec<u8>| {
        seq += 1;
        w.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: channel,
                sequence: seq,
                log_time: (t.max(0.0) * 1e9) as u64,
                publish_time: (t.max(0.0) * 1e9) as u64,
            },
            &data,
        )
        .unwrap();
    };
    for (k, &t) in global_times.iter().enumerate() {
        let m = Global {
            time: t,
            step: k as u64,
            ..Default::default()
        };
        put(&mut w, g, t, m.encode_to_vec());
    }
    for (k, row) in rows.iter().enumerate() {
        let m = Interface {
            time: k as f64 * 1e-6,
            step: k as u64,
            shear_stress: row.clone(),
            normal_stress: row.clone(),
            pinned_fraction: row.clone(),
            slip: row.clone(),
            slip_speed: row.clone(),
        };
        put(&mut w, i, k as f64 * 1e-6, m.encode_to_vec());
    }
    w.finish().unwrap();
}

#[test]
fn ragged_rows_and_time_running_backwards_are_damage_not_a_panic_or_a_hang() {
    let d = dir("crafted");
    let good = d.join("good.mcap");
    crafted(&good, &[vec![1.0; 4], vec![1.0; 4]], &[0.0, 1e-5, 2e-5]);
    let ragged = d.join("ragged.mcap");
    crafted(&ragged, &[vec![1.0; 4], vec![1.0; 7]], &[0.0, 1e-5]);
    let backwards = d.join("backwards.mcap");
    crafted(&backwards, &[vec![1.0; 4]], &[0.0, 1e-5, 5e-6, 3e-5]);
    // Negative control: the consistent file reads.
    let out = slipfront(&["info", s(&good)], &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (file, expect) in [
        (
            &ragged,
            "/interface message 1 (t = 1e-6 s) has rows of lengths [7, 7, 7, 7, 7]",
        ),
        (
            &backwards,
            "/global message 2 is at t = 5e-6 s, after one at 1e-5 s",
        ),
    ] {
        for cmd in ["info", "plot"] {
            let started = std::time::Instant::now();
            let out = slipfront(&[cmd, s(file)], &[]);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(
                out.status.code(),
                Some(2),
                "{cmd} {}: {err}",
                file.display()
            );
            assert!(
                err.contains(expect) && err.contains("damaged"),
                "{cmd}: {err}"
            );
            assert!(started.elapsed().as_secs() < 20);
        }
    }
}

#[test]
fn inputs_whose_products_leave_f64_or_the_lattice_are_refused() {
    for (set, expect) in [
        ("geometry.width=1e308", "derived block mass = inf"),
        ("material.density=1e308", "|V| < 5.9580e-150 m/s"),
        ("geometry.nx=1", "geometry.length = 0.14 m with nx = 1"),
        ("geometry.nz=1", "geometry.height = 0.075 m with nz = 1"),
        ("time.end=1e-9", "shorter than one time step"),
    ] {
        let out = slipfront(&["check", "--set", set], &[]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{set}: {err}");
        assert!(err.contains(expect), "{set}: {err}");
    }
    // Negative control: a consistent chain, one block high, is accepted.
    let out = slipfront(
        &[
            "check",
            "tests/fuzz/corpus/scenario/single_junction_chain.toml",
        ],
        &[],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn probing_the_gpu_without_a_runtime_dir_prints_no_mesa_warning() {
    let out = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(["check", "scenarios/triggered_front.toml"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("XDG_RUNTIME_DIR"), "{err}");
}

#[test]
fn hostile_files_and_times_get_bounded_clear_errors() {
    let d = dir("files");
    let big = d.join("big.toml");
    std::fs::write(&big, vec![b'a'; 2 << 20]).unwrap();
    let long = d.join("long.toml");
    std::fs::write(&long, vec![b'a'; 900_000]).unwrap();
    for (args, expect, most) in [
        (vec!["check", "/dev/zero"], "not a regular file", 400),
        (vec!["check", s(&big)], "more than a scenario can be", 400),
        (vec!["check", s(&long)], "TOML parse error", 1000),
        (
            vec!["run", "--t-end", "nan"],
            "--t-end = nan: expected a time",
            400,
        ),
        (
            vec!["check", "--set", "time.end=1e300"],
            "time.end = 1e300 s is out of range",
            400,
        ),
    ] {
        let out = slipfront(&args, &[]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(err.len() < most, "{args:?}: {} bytes of stderr", err.len());
        assert!(!err.contains("--set time.end"), "{args:?}: {err}");
    }
}

#[test]
fn two_runs_cannot_write_one_file() {
    let d = dir("lock");
    let out = d.join("run.mcap");
    let sets: Vec<String> = slipfront::app::verify::SMALL_SCENE
        .iter()
        .flat_map(|s| ["--set".to_string(), s.to_string()])
        .collect();
    let start = |force: bool| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_slipfront"));
        c.args(["run", "--backend", "cpu", "--threads", "1", "--quiet"])
            .args(["--t-end", "0.2", "-o", s(&out)])
            .args(&sets);
        if force {
            c.arg("--force");
        }
        c
    };
    let mut first = start(false)
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Until the first run has its file.
    let t0 = std::time::Instant::now();
    while !out.exists() && t0.elapsed().as_secs() < 30 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    let second = start(true).output().unwrap();
    let err = String::from_utf8_lossy(&second.stderr);
    let still_running = first.try_wait().unwrap().is_none();
    assert_eq!(second.status.code(), Some(2), "{err}");
    assert!(
        err.contains("another slipfront run is writing this file"),
        "{err}"
    );
    assert!(
        still_running,
        "the first run ended before the test could race it"
    );
    assert!(first.wait().unwrap().success());
    let run = slipfront::io::output::reader::RunFile::read(&out).unwrap();
    assert!(!run.truncated && run.global.last().unwrap().time > 0.19);
}

#[test]
fn sigterm_closes_the_file_and_exits_143() {
    let d = dir("term");
    let out = d.join("run.mcap");
    let sets: Vec<String> = slipfront::app::verify::SMALL_SCENE
        .iter()
        .flat_map(|s| ["--set".to_string(), s.to_string()])
        .collect();
    let mut child = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(["run", "--backend", "cpu", "--threads", "1", "--quiet"])
        .args(["--t-end", "5", "-o", s(&out)])
        .args(&sets)
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    // SAFETY: a signal to the child this test started.
    unsafe { libc::kill(child.id() as i32, libc::SIGTERM) };
    let t0 = std::time::Instant::now();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(143));
    assert!(
        t0.elapsed().as_secs_f64() < 5.0,
        "stopped after {:?}",
        t0.elapsed()
    );
    let run = slipfront::io::output::reader::RunFile::read(&out).unwrap();
    assert!(!run.truncated, "the file was closed with its summary");
    assert!(!run.global.is_empty());
}

#[test]
fn errors_name_the_path_and_say_their_cause_once() {
    let out = slipfront(
        &[
            "run",
            "--backend",
            "cpu",
            "--t-end",
            "1e-4",
            "--quiet",
            "-o",
            "/proc/no/x.mcap",
        ],
        &[],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("/proc/no/x.mcap"), "{err}");
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
    let run = root_file("tests/fuzz/corpus/mcap/small_run.mcap");
    let out = slipfront(&["plot", &run, "-o", "/proc/no/dir"], &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cannot create the folder `/proc/no/dir`"),
        "{err}"
    );
    // More threads than rows: said, not silently dropped.
    let d = dir("threads");
    let o = d.join("t.mcap");
    let mut args = vec!["run", "scenarios/triggered_front.toml", "--backend", "cpu"];
    args.extend(["--threads", "4", "--quiet"]);
    args.extend(["--t-end", "1e-4", "-o", s(&o)]);
    // A chain one block high.
    // Three rows of blocks.
    args.extend(["--set", "geometry.nz=3", "--set", "geometry.height=0.005"]);
    let out = slipfront(&args, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("this lattice has 3 rows, so 3 threads work on it"),
        "{err}"
    );
}

#[test]
fn a_run_without_driving_plots_nothing_and_says_why() {
    let d = dir("zero");
    let run = d.join("zero.mcap");
    let mut args = vec!["run", "--backend", "cpu", "--threads", "1", "--quiet"];
    args.extend(["--t-end", "0", "-o", s(&run)]);
    let sets: Vec<String> = slipfront::app::verify::SMALL_SCENE
        .iter()
        .flat_map(|s| ["--set".to_string(), s.to_string()])
        .collect();
    args.extend(sets.iter().map(String::as_str));
    assert!(slipfront(&args, &[]).status.success());
    let out = slipfront(&["plot", s(&run)], &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("no /interface messages, nothing to plot"),
        "{err}"
    );
    assert!(!err.contains("Zero width"), "{err}");
    assert!(!d.join("zero_spacetime.png").exists());
}

fn root_file(rel: &str) -> String {
    format!("{}/{rel}", env!("CARGO_MANIFEST_DIR"))
}

/// kill -9 loses at most about a second of output: while a run goes, its
/// file on disk grows at least every second or so.
#[test]
fn the_run_file_on_disk_lags_the_run_by_about_a_second_at_most() {
    let d = dir("lag");
    let out = d.join("run.mcap");
    // Sparse output, so that chunks do not fill within seconds: only the
    // flush puts records on disk.
    let sparse = [
        "output.global_interval=1e-4",
        "output.interface_interval=1e-4",
        "output.fast_interval=1e-4",
    ];
    let sets: Vec<String> = slipfront::app::verify::SMALL_SCENE
        .iter()
        .chain(&sparse)
        .flat_map(|s| ["--set".to_string(), s.to_string()])
        .collect();
    let mut child = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(["run", "--backend", "cpu", "--threads", "1", "--quiet"])
        .args(["--t-end", "5", "-o", s(&out)])
        .args(&sets)
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    let mut last_size = 0;
    let mut growths = Vec::new();
    while start.elapsed().as_secs_f64() < 5.0 {
        let size = std::fs::metadata(&out).map_or(0, |m| m.len());
        if size != last_size {
            growths.push(start.elapsed().as_secs_f64());
            last_size = size;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    // From the first chunk on (the normal-load phase writes none).
    let gaps: Vec<f64> = growths.windows(2).map(|w| w[1] - w[0]).collect();
    let worst = gaps.iter().copied().fold(0.0, f64::max);
    assert!(gaps.len() >= 2, "the file grew at {growths:?}");
    assert!(
        worst < 1.75,
        "the file grew at {growths:?}: a gap of {worst:.2} s"
    );
    let run = slipfront::io::output::reader::RunFile::read(&out).unwrap();
    assert!(run.truncated && !run.global.is_empty());
}

/// Offsets of every record with `opcode` after the magic.
fn records(bytes: &[u8], opcode: u8) -> Vec<(usize, usize)> {
    let mut at = 8;
    let mut found = Vec::new();
    while at + 9 <= bytes.len() {
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        if bytes[at] == opcode {
            found.push((at, len));
        }
        at += 9 + len;
    }
    found
}

/// A flipped byte inside a chunk fails its CRC: `info` says which chunk and
/// which times are lost, `recover` drops that chunk, keeps the ones after
/// it and never re-signs the damaged data, and a resume refuses the file.
/// A file cut inside its closing magic is cut, not complete.
#[test]
fn damaged_chunks_are_found_by_their_crc_and_dropped() {
    let d = dir("crc");
    let run = d.join("run.mcap");
    // Dense samples: several chunks (`CHUNK_BYTES` each, 8 MiB).
    small_run_with(
        &run,
        "1.2e-2",
        &[
            "output.interface_interval=1e-6",
            "output.global_interval=1e-6",
        ],
    );
    let bytes = std::fs::read(&run).unwrap();
    let chunks = records(&bytes, 0x06);
    assert!(chunks.len() >= 3, "{} chunks", chunks.len());
    let (at, len) = chunks[1];
    let mut flipped = bytes.clone();
    flipped[at + 9 + len / 2] ^= 0x10;
    let bad = d.join("bad.mcap");
    std::fs::write(&bad, &flipped).unwrap();
    let out = slipfront(&["info", s(&bad)], &[]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("DAMAGED: 1 damaged chunk(s)"), "{text}");
    assert!(text.contains("chunk 2 (messages from t ="), "{text}");
    let whole = slipfront::io::output::reader::RunFile::read(&run).unwrap();
    let read = slipfront::io::output::reader::RunFile::read(&bad).unwrap();
    assert!(read.damage.is_some() && read.truncated);
    let (n_whole, n_read) = (
        whole.global.len() + whole.interface.len(),
        read.global.len() + read.interface.len(),
    );
    assert!(n_read < n_whole && n_read > 0, "{n_read} of {n_whole}");
    // The chunks after the damaged one are kept: the last sample is there.
    assert_eq!(
        read.global.last().map(|g| g.time),
        whole.global.last().map(|g| g.time)
    );
    // A resume does not continue a damaged file.
    std::fs::copy(
        slipfront::io::checkpoint::path_for(&run),
        slipfront::io::checkpoint::path_for(&bad),
    )
    .unwrap();
    let out = slipfront(&["run", "--resume", s(&bad), "--t-end", "1.2e-2"], &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_ne!(out.status.code(), Some(0), "{err}");
    assert!(err.contains("recover"), "{err}");
    // Recovered: what was read, under valid CRCs, and no damage left.
    let out = slipfront(&["recover", s(&bad)], &[]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("was damaged"),
        "{text}"
    );
    let recovered = slipfront::io::output::reader::RunFile::read(&bad).unwrap();
    assert!(recovered.damage.is_none() && !recovered.truncated);
    assert_eq!(recovered.global, read.global);
    assert_eq!(recovered.interface, read.interface);
    // Cut inside the closing magic: cut short, not complete.
    for cut in [1, 4, 8] {
        let short = d.join(format!("short{cut}.mcap"));
        std::fs::write(&short, &bytes[..bytes.len() - cut]).unwrap();
        let read = slipfront::io::output::reader::RunFile::read(&short).unwrap();
        assert!(read.truncated && read.damage.is_none(), "cut {cut}");
        let out = slipfront(&["recover", s(&short)], &[]);
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains("ended before its summary"),
            "cut {cut}: {text}"
        );
    }
    // Negative control: the file as written reads complete.
    assert!(!whole.truncated && whole.damage.is_none());
}

/// A checkpoint of another scene beside a run file (copied over, or the
/// file replaced) is refused by a resume, naming both scenes, before the
/// file is touched; the run's own checkpoint still resumes.
#[test]
fn a_resume_refuses_a_checkpoint_of_another_scene() {
    let d = dir("foreign-ckpt");
    let run = d.join("run.mcap");
    small_run(&run);
    let other = d.join("other.mcap");
    small_run_with(
        &other,
        "1e-3",
        &["geometry.nx=9", "geometry.nz=5", "geometry.height=0.035"],
    );
    let ckpt = slipfront::io::checkpoint::path_for(&run);
    let own = std::fs::read(&ckpt).unwrap();
    std::fs::copy(slipfront::io::checkpoint::path_for(&other), &ckpt).unwrap();
    let before = std::fs::read(&run).unwrap();
    let out = slipfront(&["run", "--resume", s(&run), "--t-end", "2e-3"], &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("is of another scene"), "{err}");
    assert!(
        err.contains("29 × 16 blocks") && err.contains("9 × 5 blocks"),
        "{err}"
    );
    assert_eq!(std::fs::read(&run).unwrap(), before, "the file was touched");
    // Negative control: with its own checkpoint back, the run resumes.
    std::fs::write(&ckpt, own).unwrap();
    let out = slipfront(&["run", "--resume", s(&run), "--t-end", "2e-3"], &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `slipfront run` of the small scene to `t_end` into `out`, with extra
/// `--set`s after the small scene's.
fn small_command(out: &Path, t_end: &str, extra: &[&str]) -> Command {
    let sets: Vec<String> = slipfront::app::verify::SMALL_SCENE
        .iter()
        .chain(extra)
        .flat_map(|s| ["--set".to_string(), s.to_string()])
        .collect();
    let mut c = Command::new(env!("CARGO_BIN_EXE_slipfront"));
    c.args(["run", "--backend", "cpu", "--threads", "1", "--quiet"])
        .args(["--t-end", t_end, "-o", s(out)])
        .args(&sets);
    c
}

/// A run of the small scene to `t_end`, started in the background.
fn spawn_run(out: &Path, t_end: &str, extra: &[&str]) -> std::process::Child {
    small_command(out, t_end, extra)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap()
}

fn wait_for(what: &str, mut done: impl FnMut() -> bool) {
    let t0 = std::time::Instant::now();
    while !done() {
        assert!(t0.elapsed().as_secs() < 60, "timed out waiting for {what}");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// /global is whole: from the start of driving to `t_end`, no record
/// missing (no gap over 1.5 output intervals).
fn assert_whole(out: &Path, t_end: f64) {
    let run = slipfront::io::output::reader::RunFile::read(out).unwrap();
    assert!(!run.truncated, "the file is cut short");
    let times: Vec<f64> = run.global.iter().map(|g| g.time).collect();
    assert!(*times.last().unwrap() > 0.95 * t_end, "{:?}", times.last());
    let gap = times.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    assert!(gap < 1.5e-5, "a gap of {gap} s in /global");
}

/// A resume or a `recover` of a file that a run is still writing is
/// refused before it touches the file, naming the run that holds it; the
/// run goes on and ends whole (case 1–2: the run's data ended in `.cut`).
#[test]
fn a_file_being_written_cannot_be_resumed_or_recovered() {
    let d = dir("held");
    let out = d.join("run.mcap");
    let mut first = spawn_run(&out, "0.1", &[]);
    wait_for("the run's file", || out.exists());
    std::thread::sleep(std::time::Duration::from_millis(300));
    let holder = format!("held by slipfront run, pid {}", first.id());
    let resume = slipfront(&["run", "--resume", s(&out)], &[]);
    let recover = slipfront(&["recover", s(&out)], &[]);
    let running = first.try_wait().unwrap().is_none();
    for (what, o) in [("resume", resume), ("recover", recover)] {
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{what} must be refused: {err}");
        assert!(err.contains(&holder), "{what}: {err}");
    }
    assert!(running, "the run ended before the test could race it");
    assert!(first.wait().unwrap().success());
    assert!(!d.join("run.mcap.cut").exists());
    assert_whole(&out, 0.1);
}

/// Two resumes of one killed run, the second started while the first is
/// under way: one continues the run, the other is refused naming it, and
/// the file ends whole (case 1: one kept only 0–67 of 199 records).
#[test]
fn two_resumes_of_one_file_leave_it_whole() {
    let d = dir("two-resumes");
    let out = d.join("run.mcap");
    let mut run = spawn_run(&out, "0.1", &["output.checkpoint_interval=0.2"]);
    let ckpt = slipfront::io::checkpoint::path_for(&out);
    let prev = PathBuf::from(format!("{}.prev", ckpt.display()));
    wait_for("a checkpoint in the driving phase", || {
        prev.exists()
            && slipfront::io::checkpoint::Checkpoint::read(&ckpt).is_ok_and(|c| c.header.time > 0.0)
    });
    run.kill().unwrap();
    run.wait().unwrap();
    let resume = || {
        Command::new(env!("CARGO_BIN_EXE_slipfront"))
            .args(["run", "--resume", s(&out), "--quiet"])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap()
    };
    let first = resume();
    std::thread::sleep(std::time::Duration::from_millis(150));
    let second = resume().wait_with_output().unwrap();
    let first = first.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    assert!(!second.status.success(), "the second resume ran too: {err}");
    assert!(err.contains("held by slipfront resume, pid"), "{err}");
    assert_whole(&out, 0.1);
}

/// A tmpfs of `kib` KiB mounted at a fresh folder, unmounted on drop
/// (then the folder is removed).
struct SmallDisk(Scratch);

impl SmallDisk {
    /// None when this process may not mount (it needs root, and a
    /// container may withhold the capability): the full-disk cases need a
    /// real full file system.
    fn mount(name: &str, kib: u32) -> Option<SmallDisk> {
        let d = dir(name);
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={kib}k"), "tmpfs", s(&d)])
            .status()
            .is_ok_and(|st| st.success());
        if !ok {
            return None;
        }
        Some(SmallDisk(d))
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

/// A full disk is named with the OS's own error (it showed as "attempted
/// another write after a write method failed"), and a checkpoint that did
/// not fit leaves no `.ckpt.tmp` behind (case 8).
#[test]
fn a_full_disk_is_named_and_leaves_no_temporary() {
    for (kib, what) in [(300, "output: MCAP"), (120, "checkpoint: cannot write")] {
        let Some(disk) = SmallDisk::mount(&format!("full-{kib}"), kib) else {
            eprintln!("cannot mount a tmpfs here: the full-disk case was not run");
            return;
        };
        let out = disk.0.join("r.mcap");
        let o = small_command(&out, "0.01", &[]).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(what), "{kib} KiB: {err}");
        assert!(err.contains("No space left on device"), "{kib} KiB: {err}");
        assert!(!err.contains("attempted another write"), "{err}");
        let left: Vec<String> = std::fs::read_dir(&disk.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(!left.iter().any(|n| n.ends_with(".tmp")), "{left:?}");
    }
}

/// Without a normal load F/F_N has no meaning: /global's drive_ratio is
/// the documented 0 beside the drive force, and the summary says why
/// instead of printing a ratio (case 8).
#[test]
fn without_a_normal_load_the_drive_ratio_is_documented_not_invented() {
    let d = dir("no-normal-load");
    let out = d.join("r.mcap");
    let extra = ["loading.normal.force=0", "loading.drive.velocity=0.4"];
    let o = small_command(&out, "2e-3", &extra).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("none: no normal load (F_N = 0)"), "{text}");
    assert!(!text.contains("peak F/F_N"), "{text}");
    let run = slipfront::io::output::reader::RunFile::read(&out).unwrap();
    assert!(run.global.iter().any(|g| g.drive_force != 0.0));
    assert!(run.global.iter().all(|g| g.drive_ratio == 0.0));
}

/// Kill, resume and recover interleaved at random (a fixed sequence of
/// seeds, so a failure repeats): whatever order the lock lets through, a
/// last resume ends the run with its file whole. Each round kills a run
/// at a random moment, then starts two resumes and a recover at random
/// delays, all at once.
#[test]
fn random_interleavings_of_kill_resume_and_recover_lose_no_record() {
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut next = |below: u64| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed % below
    };
    for round in 0..4 {
        let d = dir(&format!("interleave-{round}"));
        let out = d.join("run.mcap");
        let mut run = spawn_run(&out, "0.05", &["output.checkpoint_interval=0.1"]);
        wait_for("the run's loaded checkpoint", || {
            d.join("run.mcap.loaded.ckpt").exists()
        });
        std::thread::sleep(std::time::Duration::from_millis(100 + next(700)));
        let _ = run.kill();
        run.wait().unwrap();
        let resume: &[&str] = &["run", "--resume", s(&out), "--quiet"];
        let recover: &[&str] = &["recover", s(&out), "--force"];
        // Which goes first changes from round to round.
        let mut order = [resume, resume, recover];
        order.rotate_left(next(3) as usize);
        let ops: Vec<std::process::Child> = order
            .iter()
            .map(|args| {
                std::thread::sleep(std::time::Duration::from_millis(next(300)));
                Command::new(env!("CARGO_BIN_EXE_slipfront"))
                    .args(*args)
                    .stdout(std::process::Stdio::null())
                    .stderr(std::process::Stdio::piped())
                    .spawn()
                    .unwrap()
            })
            .collect();
        let mut errors = Vec::new();
        let mut succeeded = 0;
        for op in ops {
            let o = op.wait_with_output().unwrap();
            if o.status.success() {
                succeeded += 1;
            } else {
                errors.push(String::from_utf8_lossy(&o.stderr).into_owned());
            }
        }
        assert!(succeeded > 0, "round {round}: none ran: {errors:?}");
        eprintln!("round {round}: {succeeded} of 3 ran; refused: {errors:?}");
        // A refused operation says why: the lock's holder, or a state
        // that is already what it asked for.
        for e in &errors {
            assert!(
                e.contains("held by slipfront") || e.contains("already reached its end"),
                "round {round}: {e}"
            );
        }
        // Whatever happened, one more resume finishes the run.
        let last = slipfront(&["run", "--resume", s(&out), "--quiet"], &[]);
        let err = String::from_utf8_lossy(&last.stderr);
        assert!(
            last.status.success() || err.contains("already reached its end"),
            "round {round}: {err}"
        );
        assert_whole(&out, 0.05);
    }
}
