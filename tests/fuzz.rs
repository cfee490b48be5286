//! Fuzzing, bounded so that it runs with the tests: the scenario parser
//! (mutated scenario files, arbitrary text, hostile `--set` values) and the
//! run-file reader with the analysis `info` runs on it (mutated run files).
//! Inputs start from the corpus in tests/fuzz/corpus/ and the shipped
//! scenarios. SLIPFRONT_FUZZ_CASES sets the cases per target (default 200);
//! a failure prints the input that broke it (proptest shrinks it first).

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use slipfront::analysis::events::FRONT_WINDOW;
use slipfront::io::output::reader::RunFile;
use slipfront::{Model, Scenario};
use std::path::{Path, PathBuf};

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

fn cases() -> u32 {
    std::env::var("SLIPFRONT_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(200)
}

fn runner() -> TestRunner {
    TestRunner::new(Config {
        cases: cases(),
        failure_persistence: None,
        ..Config::default()
    })
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn files(dir: &Path, ext: &str) -> Vec<Vec<u8>> {
    let mut out: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .map(|p| (p.clone(), std::fs::read(&p).unwrap()))
        .collect();
    out.sort();
    out.into_iter().map(|(_, b)| b).collect()
}

/// One edit of a byte string; positions are taken modulo its length.
#[derive(Debug, Clone)]
enum Edit {
    Flip(usize, u8),
    Set(usize, u8),
    Insert(usize, Vec<u8>),
    Delete(usize, usize),
    Truncate(usize),
    /// Copies `len` bytes from one place over another.
    Splice(usize, usize, usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), 1u8..=255).prop_map(|(p, b)| Edit::Flip(p, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Edit::Set(p, b)),
        (any::<usize>(), prop::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(p, v)| Edit::Insert(p, v)),
        (any::<usize>(), 1usize..64).prop_map(|(p, n)| Edit::Delete(p, n)),
        any::<usize>().prop_map(Edit::Truncate),
        (any::<usize>(), any::<usize>(), 1usize..64).prop_map(|(a, b, n)| Edit::Splice(a, b, n)),
    ]
}

fn apply(base: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut v = base.to_vec();
    for e in edits {
        let n = v.len().max(1);
        match e {
            Edit::Flip(p, b) => {
                if !v.is_empty() {
                    v[p % n] ^= b;
                }
            }
            Edit::Set(p, b) => {
                if !v.is_empty() {
                    v[p % n] = *b;
                }
            }
            Edit::Insert(p, bytes) => {
                let at = p % (v.len() + 1);
                v.splice(at..at, bytes.iter().copied());
            }
            Edit::Delete(p, len) => {
                let at = p % n;
                let end = (at + len).min(v.len());
                if at < end {
                    v.drain(at..end);
                }
            }
            Edit::Truncate(p) => v.truncate(p % n),
            Edit::Splice(a, b, len) => {
                if !v.is_empty() {
                    let (a, b) = (a % n, b % n);
                    let len = (*len).min(v.len() - a).min(v.len() - b);
                    let piece = v[a..a + len].to_vec();
                    v[b..b + len].copy_from_slice(&piece);
                }
            }
        }
    }
    v
}

/// A parsed scenario must give a model with a finite, positive time step
/// and a step count that fits, or an error; never a panic.
fn check_scenario(result: Result<Scenario, slipfront::model::scenario::ScenarioError>) {
    if let Ok(s) = result {
        if let Ok(m) = Model::from_scenario(&s, false) {
            assert!(m.dt.is_finite() && m.dt > 0.0, "dt = {:e}", m.dt);
            assert!(m.total_steps() < u64::MAX / 2);
            let _ = m.memory_bytes(8, 8);
        }
    }
}

fn scenario_corpus() -> Vec<Vec<u8>> {
    let mut c = files(&root().join("scenarios"), "toml");
    c.extend(files(&root().join("tests/fuzz/corpus/scenario"), "toml"));
    c.push(
        slipfront::model::scenario::DEFAULT_SCENARIO
            .as_bytes()
            .to_vec(),
    );
    c
}

#[test]
fn the_scenario_parser_survives_mutated_files() {
    let corpus = scenario_corpus();
    let strategy = (0..corpus.len(), prop::collection::vec(edit(), 1..6));
    runner()
        .run(&strategy, |(k, edits)| {
            let text = String::from_utf8_lossy(&apply(&corpus[k], &edits)).into_owned();
            check_scenario(Scenario::parse(&text, "fuzz", &[]));
            Ok(())
        })
        .unwrap();
}

#[test]
fn the_scenario_parser_survives_arbitrary_text() {
    runner()
        .run(&"\\PC{0,400}", |text| {
            check_scenario(Scenario::parse(&text, "fuzz", &[]));
            Ok(())
        })
        .unwrap();
}

#[test]
fn hostile_set_values_give_a_model_or_an_error() {
    let seeds =
        std::fs::read_to_string(root().join("tests/fuzz/corpus/scenario/overrides.txt")).unwrap();
    let keys: Vec<&str> = seeds
        .lines()
        .filter_map(|l| l.split_once('=').map(|(k, _)| k))
        .collect();
    let values = prop_oneof![
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("-inf".to_string()),
        Just("1e308".to_string()),
        Just("-1e308".to_string()),
        Just("5e-324".to_string()),
        Just("0".to_string()),
        Just("-0".to_string()),
        Just("18446744073709551616".to_string()),
        any::<f64>().prop_map(|v| format!("{v:e}")),
        any::<i64>().prop_map(|v| v.to_string()),
        "[a-z\"\\[\\]{}=., ]{0,12}",
    ];
    let strategy = prop::collection::vec((0..keys.len(), values), 1..4);
    runner()
        .run(&strategy, |sets| {
            let set: Vec<String> = sets
                .iter()
                .map(|(k, v)| format!("{}={v}", keys[*k]))
                .collect();
            check_scenario(Scenario::parse(
                slipfront::model::scenario::DEFAULT_SCENARIO,
                "fuzz",
                &set,
            ));
            Ok(())
        })
        .unwrap();
    // The seeds themselves, each alone.
    for line in seeds.lines() {
        check_scenario(Scenario::parse(
            slipfront::model::scenario::DEFAULT_SCENARIO,
            "fuzz",
            &[line.to_string()],
        ));
    }
}

/// What `info` does with a file it could read.
fn analyse(run: &RunFile) {
    let series = run.interface_series();
    let events = series.events_separated_by(1e-3);
    for e in &events {
        let _ = series.resolved_front_speeds(e, FRONT_WINDOW);
        let _ = series.front_kind(e, FRONT_WINDOW);
        let _ = series.front_tip(e);
        let _ = run.drive_ratio_at(e.start);
    }
    let _ = series.slip_front_pairs(&events, FRONT_WINDOW);
}

#[test]
fn the_run_file_reader_survives_mutated_files() {
    let corpus = files(&root().join("tests/fuzz/corpus/mcap"), "mcap");
    assert!(!corpus.is_empty());
    let dir = Scratch::new("fuzz", "run");
    let path = dir.join("case.mcap");
    // Most edits land in the compressed chunks; a few in the headers
    // (the first 2 KiB hold the header, metadata and the first chunk's).
    let edits = prop::collection::vec(
        prop_oneof![
            3 => edit(),
            1 => (0usize..2048, 1u8..=255).prop_map(|(p, b)| Edit::Flip(p, b)),
        ],
        1..5,
    );
    let strategy = (0..corpus.len(), edits);
    let read_ok = std::cell::Cell::new(0u32);
    runner()
        .run(&strategy, |(k, edits)| {
            std::fs::write(&path, apply(&corpus[k], &edits)).unwrap();
            if let Ok(run) = RunFile::read(&path) {
                analyse(&run);
                read_ok.set(read_ok.get() + 1);
            }
            Ok(())
        })
        .unwrap();
    // Negative control: the unmutated corpus reads and has messages, so the
    // cases above exercised a real reader, not an early refusal.
    for bytes in &corpus {
        std::fs::write(&path, bytes).unwrap();
        let run = RunFile::read(&path).unwrap();
        assert!(!run.interface.is_empty() && !run.truncated);
        analyse(&run);
    }
    eprintln!("{} of {} mutated run files read", read_ok.get(), cases());
}

/// `recover` on run files cut at any offset or with a byte flipped
/// anywhere: it ends with a clear error or with a file every reader opens
/// whole, holding only records of the original (a damaged chunk is dropped,
/// never re-signed under a fresh CRC), in the original's order.
#[test]
fn recover_keeps_only_good_records_of_cut_or_flipped_files() {
    use slipfront::io::output::recover::rewrite;
    let corpus = files(&root().join("tests/fuzz/corpus/mcap"), "mcap");
    let dir = Scratch::new("fuzz", "recover");
    let (case, out) = (dir.join("case.mcap"), dir.join("out.mcap"));
    let originals: Vec<RunFile> = corpus
        .iter()
        .map(|bytes| {
            std::fs::write(&case, bytes).unwrap();
            RunFile::read(&case).unwrap()
        })
        .collect();
    let damage = prop_oneof![
        any::<usize>().prop_map(Edit::Truncate),
        (any::<usize>(), 1u8..=255).prop_map(|(p, b)| Edit::Flip(p, b)),
    ];
    let strategy = (0..corpus.len(), prop::collection::vec(damage, 1..3));
    let (recovered, kept) = (std::cell::Cell::new(0u32), std::cell::Cell::new(0usize));
    runner()
        .run(&strategy, |(k, edits)| {
            std::fs::write(&case, apply(&corpus[k], &edits)).unwrap();
            let _ = std::fs::remove_file(&out);
            if rewrite(&case, &out).is_err() {
                return Ok(());
            }
            let run = RunFile::read(&out)
                .map_err(|e| TestCaseError::fail(format!("{edits:?}: unreadable: {e}")))?;
            prop_assert!(
                !run.truncated && run.damage.is_none(),
                "{edits:?}: {:?}",
                run.damage
            );
            // Every record is the original's, in order: a subsequence.
            let original = &originals[k].global;
            let mut at = 0;
            for g in &run.global {
                match original[at..].iter().position(|o| o == g) {
                    Some(i) => at += i + 1,
                    None => {
                        return Err(TestCaseError::fail(format!(
                            "{edits:?}: a record not in the original: {g:?}"
                        )))
                    }
                }
            }
            prop_assert!(run
                .interface
                .iter()
                .all(|r| originals[k].interface.contains(r)));
            recovered.set(recovered.get() + 1);
            kept.set(kept.get() + run.global.len());
            Ok(())
        })
        .unwrap();
    // The control: an undamaged file comes back with every record.
    std::fs::write(&case, &corpus[0]).unwrap();
    rewrite(&case, &out).unwrap();
    assert!(RunFile::read(&out).unwrap().global == originals[0].global);
    eprintln!(
        "{} of {} damaged files recovered, {} /global records kept",
        recovered.get(),
        cases(),
        kept.get()
    );
}
