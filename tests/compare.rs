//! `slipfront compare A B` on sweep tables written here: the library call
//! and the command line, for ensembles that agree, differ in location or
//! in mode occupancy, and for bad input.

use slipfront::app::sweeps::compare::compare_tables;
use slipfront::app::sweeps::table;
use std::path::Path;
use std::process::Command;

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

fn dir(name: &str) -> Scratch {
    Scratch::new("compare", name)
}

/// One run's outcomes as the sweep writes them.
struct Run {
    status: &'static str,
    first_full: Option<f64>,
    precursors: usize,
    events: u64,
}

fn ok(first_full: Option<f64>, precursors: usize, events: u64) -> Run {
    Run {
        status: "ok",
        first_full,
        precursors,
        events,
    }
}

/// Writes `DIR/summary.csv` with the sweep's header (one perturbed axis).
fn write_sweep(dir: &Path, runs: &[Run]) {
    let axes = vec!["loading.drive.velocity".to_string()];
    let header = table::header(&axes);
    let mut text = table::line(&header);
    for (k, r) in runs.iter().enumerate() {
        let lengths: Vec<String> = (1..=r.precursors)
            .map(|i| format!("{:e}", 1e-3 * i as f64 + 1e-5 * k as f64))
            .collect();
        let number = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:e}"));
        let value = |name: &str| -> String {
            match name {
                "point" => k.to_string(),
                "id" => format!("{k:016x}"),
                "seed" => "1".into(),
                "loading.drive.velocity" => format!("{:e}", 1e-3 * (1.0 + 1e-6 * k as f64)),
                "status" => r.status.into(),
                "message" if r.status != "ok" => "blew up at step 12, time 1e-5 s".into(),
                _ if r.status != "ok" => String::new(),
                "first_full_time_s" => number(r.first_full),
                "first_full_drive_ratio" => number(r.first_full.map(|t| 0.2 + 0.1 * t)),
                "events" => r.events.to_string(),
                "full_events" => u64::from(r.first_full.is_some()).to_string(),
                "precursors" => r.precursors.to_string(),
                "precursor_lengths_m" => lengths.join(";"),
                "precursor_max_length_m" => lengths.last().cloned().unwrap_or_default(),
                "mean_slip_m" => format!("{:e}", 1e-6 * (1.0 + 0.01 * (k % 7) as f64)),
                "steps" => "1000".into(),
                "wall_s" => "0.5".into(),
                _ => "0".into(),
            }
        };
        let row: Vec<String> = header.iter().map(|h| value(h)).collect();
        text.push_str(&table::line(&row));
    }
    std::fs::write(dir.join("summary.csv"), text).unwrap();
}

/// n runs with first full events spread evenly over t0 .. t0 + 0.1 s.
fn ensemble(n: usize, t0: f64) -> Vec<Run> {
    (0..n)
        .map(|k| {
            // A stride coprime with n: the same values, in another order
            // than the run index.
            let u = ((k * 7) % n) as f64 / n as f64;
            ok(Some(t0 + 0.1 * u), 1 + k % 3, 2 + (k % 2) as u64)
        })
        .collect()
}

fn slipfront(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("runs")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn ensembles_of_one_distribution_do_not_differ() {
    let (a, b) = (dir("same-a"), dir("same-b"));
    let mut runs = ensemble(60, 1.0);
    runs.push(Run {
        status: "blew_up",
        first_full: None,
        precursors: 0,
        events: 0,
    });
    write_sweep(&a, &runs);
    write_sweep(&b, &ensemble(60, 1.0));
    let c = compare_tables(&a, &b).unwrap();
    assert_eq!((c.runs_a, c.runs_b), (60, 60));
    assert_eq!(c.dropped_a.get("blew_up"), Some(&1));
    assert!(!c.differs(0.01), "{:?}", c.differing(0.01));

    let out = slipfront(&[
        "compare",
        s(&a),
        s(&b),
        "--label-a",
        "f64",
        "--label-b",
        "f32",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(
        text.contains("f64: 60 ok runs (1 blew_up left out)"),
        "{text}"
    );
    assert!(text.contains("no outcome differs at p < 0.01"), "{text}");
    assert!(
        !text
            .lines()
            .any(|l| l.contains(" differs") && !l.starts_with("smallest p")),
        "{text}"
    );
}

#[test]
fn a_shifted_first_event_is_flagged_in_text_json_and_exit_status() {
    let (a, b) = (dir("shift-a"), dir("shift-b"));
    write_sweep(&a, &ensemble(60, 1.0));
    write_sweep(&b, &ensemble(60, 1.05));
    let c = compare_tables(&a.join("summary.csv"), &b).unwrap();
    assert!(c.differs(0.01));
    let min = c.min_p().unwrap();
    assert!(min.p < 1e-4, "{min:?}");
    assert!(min.outcome.starts_with("first_full"), "{min:?}");

    let figure = a.join("compare.svg");
    let out = slipfront(&["compare", s(&a), s(&b), "-o", s(&figure)]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(
        text.contains("DIFFERS at p < 0.01: first_full_time_s ks"),
        "{text}"
    );
    let svg = std::fs::read_to_string(&figure).unwrap();
    assert!(
        svg.contains("first_full_time_s: KS p ="),
        "the figure's panel"
    );

    let out = slipfront(&["compare", s(&a), s(&b), "--json", "--alpha", "1e-9"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // At a level below every p-value nothing differs: exit 0.
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(v["differs"], false);
    assert!(v["min_p"]["p"].as_f64().unwrap() < 1e-4);
    assert_eq!(v["continuous"][0]["name"], "first_full_time_s");
    assert_eq!(v["continuous"][0]["a"]["summary"]["n"], 60);
}

#[test]
fn a_different_mode_occupancy_is_flagged() {
    // The same first events where there is one, but half of B's runs end
    // without a full event.
    let (a, b) = (dir("modes-a"), dir("modes-b"));
    write_sweep(&a, &ensemble(40, 1.0));
    let mut runs = ensemble(40, 1.0);
    for r in runs.iter_mut().step_by(2) {
        r.first_full = None;
    }
    write_sweep(&b, &runs);
    let c = compare_tables(&a, &b).unwrap();
    let first = &c.continuous[0];
    let none = first.modes.last().unwrap();
    assert_eq!(
        (none.label.as_str(), none.a, none.b),
        ("no full event", 0, 20)
    );
    assert!(first.modes_test.unwrap().p < 0.01);
    assert!(first.ks.unwrap().p > 0.01, "the runs that have one agree");
    let out = slipfront(&["compare", s(&a), s(&b), "--json"]);
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let differing = v["differing"].as_array().unwrap();
    assert!(differing
        .iter()
        .any(|d| d["outcome"] == "first_full_time_s" && d["test"] == "modes"));
}

#[test]
fn bad_input_exits_2_naming_the_path() {
    let good = dir("bad-good");
    write_sweep(&good, &ensemble(10, 1.0));
    let missing = good.join("no-such-sweep");
    let failed = dir("bad-failed");
    write_sweep(
        &failed,
        &[Run {
            status: "failed",
            first_full: None,
            precursors: 0,
            events: 0,
        }],
    );
    let other = dir("bad-columns");
    std::fs::write(other.join("summary.csv"), "point,id,status\n0,a,ok\n").unwrap();
    let garbled = dir("bad-number");
    write_sweep(&garbled, &ensemble(3, 1.0));
    let text = std::fs::read_to_string(garbled.join("summary.csv")).unwrap();
    std::fs::write(
        garbled.join("summary.csv"),
        text.replacen(",1e0,", ",soon,", 1),
    )
    .unwrap();
    for (bad, says) in [
        (missing.as_path(), "cannot read the sweep table"),
        (&failed, "no row with status ok (1 failed)"),
        (&other, "has no column `first_full_time_s`"),
        (
            &garbled,
            "line 2: first_full_time_s = `soon` is not a finite number",
        ),
    ] {
        let out = slipfront(&["compare", s(&good), s(bad)]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(s(bad)), "{err}");
        assert!(err.contains(says), "{err}");
        assert!(compare_tables(bad, &good).unwrap_err().contains(says));
    }
    let out = slipfront(&["compare", s(&good), s(&good), "-o", "figure.pdf"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains(".png or .svg"));
}

/// Rewrites column `name` of `dir`'s table, row k to `value(k)`, or
/// drops the column with None.
fn set_column(dir: &Path, name: &str, value: Option<&dyn Fn(usize) -> String>) {
    let path = dir.join("summary.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    let header = table::split(lines.next().unwrap());
    let c = header.iter().position(|h| h == name).unwrap();
    let edit = |mut fields: Vec<String>, k: Option<usize>| {
        match (value, k) {
            (Some(v), Some(k)) => fields[c] = v(k),
            (Some(_), None) => {}
            (None, _) => {
                fields.remove(c);
            }
        }
        table::line(&fields)
    };
    let mut out = edit(header.clone(), None);
    for (k, l) in lines.enumerate() {
        out.push_str(&edit(table::split(l), Some(k)));
    }
    std::fs::write(path, out).unwrap();
}

#[test]
fn slow_front_speeds_are_compared_and_tables_without_them_still_read() {
    let (a, b) = (dir("slow-a"), dir("slow-b"));
    write_sweep(&a, &ensemble(40, 1.0));
    write_sweep(&b, &ensemble(40, 1.0));
    let speed = |base: f64| move |k: usize| format!("{:e}", base + 0.05 * (k % 10) as f64);
    set_column(&a, "slow_front_speed_m_per_s", Some(&speed(10.0)));
    set_column(&b, "slow_front_speed_m_per_s", Some(&speed(10.0)));
    let same = compare_tables(&a, &b).unwrap();
    assert!(!same.differs(0.01), "{:?}", same.differing(0.01));
    // Slow fronts 10 % faster on one side: flagged.
    set_column(&b, "slow_front_speed_m_per_s", Some(&speed(11.0)));
    let c = compare_tables(&a, &b).unwrap();
    let flagged: Vec<&str> = c.differing(0.01).iter().map(|p| p.outcome).collect();
    assert_eq!(
        flagged.first(),
        Some(&"slow_front_speed_m_per_s"),
        "{flagged:?}"
    );
    // A table written before these columns existed reads, without them.
    for name in [
        "first_event_time_s",
        "first_event_length_m",
        "slow_front_speed_m_per_s",
        "slow_slip_speed_m_per_s",
    ] {
        set_column(&a, name, None);
        set_column(&b, name, None);
    }
    let old = compare_tables(&a, &b).unwrap();
    assert!(old.continuous.iter().all(|o| !o.name.starts_with("slow_")));
    assert!(!old.differs(0.01), "{:?}", old.differing(0.01));
}

/// Adds the column a `perturb` sweep writes, run k perturbed by
/// (start + k)·1e-6.
fn add_perturbation(dir: &Path, start: usize) {
    let path = dir.join("summary.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut out = String::new();
    for (k, l) in text.lines().enumerate() {
        let value = match k {
            0 => "perturb(loading.drive.velocity)".to_string(),
            k => format!("{:e}", (start + k - 1) as f64 * 1e-6),
        };
        out.push_str(&format!("{l},{value}\n"));
    }
    std::fs::write(path, out).unwrap();
}

#[test]
fn members_choose_the_outcomes_of_one_corrected_verdict() {
    // First full events 5 % later on B: what two disjoint ranges of a
    // short run's perturbation can give by construction.
    let (a, b) = (dir("members-a"), dir("members-b"));
    write_sweep(&a, &ensemble(60, 1.0));
    write_sweep(&b, &ensemble(60, 1.05));
    add_perturbation(&a, 0);
    add_perturbation(&b, 60);
    // Each test alone: the first event differs.
    assert_eq!(slipfront(&["compare", s(&a), s(&b)]).status.code(), Some(1));
    // Disjoint members: the whole-run outcomes agree.
    let out = slipfront(&["compare", s(&a), s(&b), "--members", "disjoint"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    let last = text.lines().last().unwrap();
    assert!(
        last.starts_with("verdict (disjoint members")
            && last.contains("do not differ at corrected p < 0.01"),
        "{last}"
    );
    assert!(!last.contains("first_full"), "{last}");
    // The same members claimed for disjoint ones is refused.
    let out = slipfront(&["compare", s(&a), s(&b), "--members", "same"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--members same: 0 of A's 60 ok runs have a perturbation that B has"),
        "{err}"
    );

    // The same members: every outcome, and the shift is flagged.
    let c = dir("members-c");
    write_sweep(&c, &ensemble(60, 1.05));
    add_perturbation(&c, 0);
    let out = slipfront(&["compare", s(&a), s(&c), "--members", "same", "--json"]);
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let verdict = &v["verdict"];
    assert_eq!(verdict["members"], "same");
    assert!(verdict["smallest"]["outcome"]
        .as_str()
        .unwrap()
        .starts_with("first_full"));
    let (p, tests) = (
        verdict["smallest"]["p"].as_f64().unwrap(),
        verdict["tests"].as_f64().unwrap(),
    );
    assert_eq!(verdict["corrected"].as_f64().unwrap(), (p * tests).min(1.0));
    assert_eq!(tests, v["tests"].as_f64().unwrap());
    assert_eq!(v["differs"], true);

    // Tables without a perturbation column cannot be the same members.
    let (d, e) = (dir("members-d"), dir("members-e"));
    write_sweep(&d, &ensemble(20, 1.0));
    write_sweep(&e, &ensemble(20, 1.0));
    let out = slipfront(&["compare", s(&d), s(&e), "--members", "same"]);
    assert_eq!(out.status.code(), Some(2));
    let out = slipfront(&["compare", s(&d), s(&e), "--members", "disjoint"]);
    assert_eq!(out.status.code(), Some(0));
}
