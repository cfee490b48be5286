//! Faults and hostile inputs (issue 14): each case made small by the test.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("slipfront-hard-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
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

/// A small run with a few hundred messages in several chunks.
fn small_run(at: &Path) {
    let mut args = vec!["run", "--backend", "cpu", "--threads", "1", "--quiet"];
    args.extend(["--t-end", "1e-3", "-o", s(at)]);
    let sets: Vec<String> = slipfront::verify::SMALL_SCENE
        .iter()
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
    let out = slipfront(&["info", s(&bad)], &[]);
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("cut short"),
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
    let before = slipfront::output::reader::RunFile::read(&cut).unwrap();
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
    let after = slipfront::output::reader::RunFile::read(&cut).unwrap();
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
