//! The Python examples read slipfront's run files with the `mcap` package:
//! a complete file and a killed one after `slipfront recover`. In CI the
//! packages are installed (.ci/run) and a missing one fails the test;
//! elsewhere the test says what to install and passes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn python(args: &[&str]) -> Output {
    Command::new("python3")
        .args(args)
        .current_dir(root())
        .output()
        .expect("python3 runs")
}

fn have_packages() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import mcap, mcap_protobuf, numpy, matplotlib"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        assert!(
            std::env::var("CI").is_err(),
            "CI: python3 with the packages of examples/requirements.txt is required"
        );
        eprintln!("skipped: pip install -r examples/requirements.txt to run it");
    }
    ok
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn python_reads_complete_and_recovered_run_files() {
    if !have_packages() {
        return;
    }
    let d = Scratch::new("py", "run");
    let run = d.join("run.mcap");
    std::fs::copy(root().join("tests/fuzz/corpus/mcap/small_run.mcap"), &run).unwrap();
    let expected = slipfront::io::output::reader::RunFile::read(&run)
        .unwrap()
        .interface
        .len();
    let out = python(&["examples/read_interface.py", s(&run)]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.starts_with(&format!("{expected} samples")), "{text}");
    // Killed: the chunks on disk, no summary. The package's reader cannot
    // open it (negative control) ...
    let bytes = std::fs::read(&run).unwrap();
    let mut at = 8;
    while bytes[at] != 0x07 {
        at += 9 + u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
    }
    let cut = d.join("cut.mcap");
    std::fs::write(&cut, &bytes[..at + 5]).unwrap();
    let out = python(&["examples/read_interface.py", s(&cut)]);
    assert!(!out.status.success());
    // ... and reads all of it once recovered.
    let rec = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(["recover", s(&cut)])
        .output()
        .unwrap();
    assert!(
        rec.status.success(),
        "{}",
        String::from_utf8_lossy(&rec.stderr)
    );
    let out = python(&["examples/read_interface.py", s(&cut)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).starts_with(&format!("{expected} samples")));
    // The matplotlib space-time map.
    let png = d.join("map.png");
    let out = python(&["examples/spacetime_map.py", s(&run), "-o", s(&png)]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);
}
