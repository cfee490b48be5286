//! `slipfront plot` end to end: every kind on a small run with an event,
//! what a run without events gets, sizes and formats, bad options.

use std::path::Path;
use std::process::{Command, Output};

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

fn dir(name: &str) -> Scratch {
    Scratch::new("plots", name)
}

fn slipfront(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("runs")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The small side-driven scene, driven so that it slips from ~0.6 ms on;
/// `t_end` 2 ms holds one full event, 0.3 ms none.
fn small_run(at: &Path, t_end: &str) {
    let mut args = vec!["run", "--backend", "cpu", "--threads", "1", "--quiet"];
    args.extend(["--t-end", t_end, "-o", s(at)]);
    let sets: Vec<String> = slipfront::app::verify::SMALL_SCENE
        .iter()
        .chain(&["loading.drive.velocity=0.2"])
        .flat_map(|s| ["--set".to_string(), s.to_string()])
        .collect();
    let mut c = Command::new(env!("CARGO_BIN_EXE_slipfront"));
    let out = c.args(&args).args(&sets).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn png_size(path: &Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    ));
    let reader = decoder.read_info().unwrap();
    (reader.info().width, reader.info().height)
}

const ALL: [&str; 10] = [
    "spacetime",
    "stress_ratio",
    "slip_speed",
    "loading",
    "front_speed",
    "front_tip",
    "precursors",
    "slip_history",
    "slip_profiles",
    "slip_vs_front",
];

#[test]
fn every_kind_renders_on_a_run_with_an_event() {
    let d = dir("event");
    let run = d.join("run.mcap");
    small_run(&run, "0.002");
    let out = slipfront(&["plot", s(&run), "--event", "0", "--at", "0,35,70"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    for name in ALL {
        assert_eq!(
            png_size(&d.join(format!("run_{name}.png"))),
            (900, 600),
            "{name}"
        );
    }
    for name in ["spacetime", "stress_ratio", "slip_speed", "front_speed"] {
        assert!(d.join(format!("run_event0_{name}.png")).exists(), "{name}");
    }
    // Size and density: 600x400 at 200 dpi is 1200x800 pixels; SVG names
    // its axes in text.
    let big = d.join("big");
    let out = slipfront(&[
        "plot",
        s(&run),
        "--kind",
        "loading",
        "--size",
        "600x400",
        "--dpi",
        "200",
        "-o",
        s(&big),
    ]);
    assert!(out.status.success());
    assert_eq!(png_size(&big.join("run_loading.png")), (1200, 800));
    let out = slipfront(&[
        "plot",
        s(&run),
        "--kind",
        "spacetime,loading",
        "--format",
        "svg",
        "-o",
        s(&big),
    ]);
    assert!(out.status.success());
    let svg = std::fs::read_to_string(big.join("run_spacetime.svg")).unwrap();
    assert!(svg.contains("time t (ms)") && svg.contains("fraction of junctions pinned"));
    assert!(std::fs::read_dir(&big).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .ends_with(".partial")));
}

#[test]
fn a_run_without_events_draws_what_it_can_and_says_why() {
    let d = dir("quiet");
    let run = d.join("quiet.mcap");
    small_run(&run, "3e-4");
    let out = slipfront(&["plot", s(&run)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    for name in [
        "spacetime",
        "stress_ratio",
        "slip_speed",
        "loading",
        "slip_history",
    ] {
        assert!(d.join(format!("quiet_{name}.png")).exists(), "{name}");
    }
    for name in [
        "front_speed",
        "front_tip",
        "precursors",
        "slip_profiles",
        "slip_vs_front",
    ] {
        assert!(!d.join(format!("quiet_{name}.png")).exists(), "{name}");
        assert!(
            err.contains(&format!("{name}: not drawn: the run has no events")),
            "{err}"
        );
    }
    // Asked for by name, a figure that cannot be drawn fails the command.
    let other = d.join("other");
    let out = slipfront(&["plot", s(&run), "--kind", "front-speed", "-o", s(&other)]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no events"));
    assert!(std::fs::read_dir(&other).unwrap().next().is_none());
}

#[test]
fn bad_plot_options_are_refused_naming_them() {
    let d = dir("bad");
    let run = d.join("run.mcap");
    small_run(&run, "3e-4");
    for (args, expect) in [
        (vec!["--size", "10x10"], "--size: width 10 px"),
        (vec!["--size", "big"], "WIDTHxHEIGHT"),
        (vec!["--dpi", "5000"], "--dpi 5000"),
        (vec!["--at", "500"], "--at 500.0000 mm: off the interface"),
        (vec!["--kind", "pie"], "invalid value 'pie'"),
    ] {
        let mut a = vec!["plot", s(&run)];
        a.extend(&args);
        let out = slipfront(&a);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expect), "{args:?}: {err}");
    }
}
