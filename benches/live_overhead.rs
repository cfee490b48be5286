//! What the live view costs a run: `slipfront run` on the built-in Table S1
//! scene, with and without `-o`, each plain, with `--live` and no viewer,
//! and with `--live` and one viewer (tests/support/live_client.rs, on this
//! machine, subscribed to every channel and reading all it is sent). The
//! runs are timed in rounds, one of each arm per round, so that a noisy
//! machine affects them alike; the table gives each arm's median wall time
//! (the run's own, from its summary) and the median of its per-round ratio
//! to the plain run.
//!
//! `cargo bench --bench live_overhead [-- T_END ROUNDS]` (defaults 0.05 s
//! of driving, 5 rounds); `BACKEND=gpu` times the GPU engine instead.

#[path = "../tests/support/live_client.rs"]
mod live_client;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::Duration;

#[derive(Clone, Copy, PartialEq)]
enum Live {
    Off,
    NoViewer,
    Viewer,
}

/// One run: its wall seconds (from the summary) and the messages the
/// viewer received.
fn run(t_end: &str, backend: &str, file: Option<&str>, live: Live) -> (f64, usize) {
    let mut args: Vec<&str> = vec![
        "run",
        "--backend",
        backend,
        "--t-end",
        t_end,
        "--progress",
        "none",
    ];
    if let Some(f) = file {
        let _ = std::fs::remove_file(f);
        args.extend(["-o", f, "--force"]);
    }
    match live {
        Live::Off => {}
        Live::NoViewer => args.extend(["--live", ":0"]),
        Live::Viewer => args.extend(["--live", ":0", "--live-wait"]),
    }
    let mut child = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(&args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start slipfront");
    let mut received = 0;
    let stderr = child.stderr.take().unwrap();
    let mut lines = BufReader::new(stderr).lines().map_while(Result::ok);
    if live == Live::Viewer {
        let url = lines
            .by_ref()
            .find_map(|l| {
                l.split("live view at ")
                    .nth(1)
                    .map(|r| r.split_whitespace().next().unwrap().to_string())
            })
            .expect("the live view's address");
        let mut client = live_client::LiveClient::connect(&url);
        let topics = [
            "/global",
            "/interface",
            "/bulk",
            "/fast_forward",
            "/live/stress_ratio",
            "/live/slip",
            "/live/slip_speed",
            "/live/bulk_speed",
        ];
        client.wait_for_channels(&topics, Duration::from_secs(30));
        client.subscribe(&topics);
        let (by_topic, _) = client.collect_until_closed(Duration::from_secs(3600));
        received = by_topic.values().map(Vec::len).sum();
    }
    std::thread::spawn(move || lines.for_each(drop));
    let out = child.wait_with_output().expect("slipfront");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    let wall = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("wall time"))
        .and_then(|v| v.trim().trim_end_matches(" s").parse().ok())
        .expect("the summary's wall time");
    (wall, received)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let t_end = args.first().cloned().unwrap_or_else(|| "0.05".into());
    let rounds: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(5);
    let backend = std::env::var("BACKEND").unwrap_or_else(|_| "cpu".into());
    let dir = std::env::temp_dir().join(format!("slipfront-live-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("run.mcap");
    let file = file.to_str().unwrap();
    println!(
        "live view overhead: Table S1 scene (57×31), {t_end} s of driving, {backend}, {rounds} rounds\n"
    );
    println!(
        "| output | live | wall (median) | ratio to plain (median, min–max) | viewer received |"
    );
    println!("| --- | --- | --- | --- | --- |");
    for with_file in [true, false] {
        let arms = [Live::Off, Live::NoViewer, Live::Viewer];
        let mut walls = vec![Vec::new(); 3];
        let mut received = [0usize; 3];
        for _ in 0..rounds {
            for (k, &live) in arms.iter().enumerate() {
                let (wall, got) = run(&t_end, &backend, with_file.then_some(file), live);
                walls[k].push(wall);
                received[k] = got;
            }
        }
        for (k, name) in ["off", "on, no viewer", "on, one viewer"]
            .iter()
            .enumerate()
        {
            let ratios: Vec<f64> = walls[k].iter().zip(&walls[0]).map(|(a, b)| a / b).collect();
            let (lo, hi) = ratios
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(l, h), &r| (l.min(r), h.max(r)));
            println!(
                "| {} | {name} | {:.2} s | {:.3} ({lo:.3}–{hi:.3}) | {} |",
                if with_file { "-o run.mcap" } else { "none" },
                median(walls[k].clone()),
                median(ratios),
                if k == 2 {
                    format!("{} messages", received[k])
                } else {
                    "—".into()
                }
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
