//! `slipfront replay RUN.mcap`: serves a finished (or cut-short) run to
//! live viewers as `run --live` serves a running one, paced in simulated
//! time; and the start of a live view, shared with `run`.

use slipfront::app::runner::{interrupted, stopping_signal, watch_stop_signals};
use slipfront::io::live::{largest_record, LiveAddress, LiveView};
use slipfront::io::output::reader::RunFile;
use slipfront::io::output::records::{Record, Topic};
use slipfront::io::output::scan::{scan, Ending, Flow};
use slipfront::model::scenario::Scenario;
use std::collections::HashMap;
use std::path::Path;
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Wall seconds a replay takes by default, whatever the run's length.
const DEFAULT_REPLAY_SECONDS: f64 = 60.0;

/// Starts a live view at `address` and says where; with `wait`, returns
/// once a viewer has subscribed (or a stop signal came).
pub fn start_live(
    address: &LiveAddress,
    largest_record: usize,
    wait: bool,
) -> anyhow::Result<LiveView> {
    let live = LiveView::start(address, largest_record)?;
    eprintln!(
        "slipfront: live view at {} (Foxglove: Open connection → Foxglove WebSocket; \
         layout docs/foxglove-layout.json)",
        live.url()
    );
    if wait {
        watch_stop_signals();
        eprintln!("slipfront: waiting for a viewer to subscribe (Ctrl-C stops)");
        live.wait_for_viewer(&interrupted);
    }
    Ok(live)
}

pub struct ReplayArgs<'a> {
    pub file: &'a Path,
    pub live: &'a LiveAddress,
    /// Simulated seconds per wall second; None: the run in a minute; 0: as
    /// fast as the viewers' queues take them.
    pub speed: Option<f64>,
    pub wait: bool,
}

pub fn replay(a: ReplayArgs) -> anyhow::Result<ExitCode> {
    let (metadata, scenario) = RunFile::read_head(a.file)?;
    if metadata.is_empty() {
        anyhow::bail!(
            "`{}` is not a slipfront run file (no `slipfront` metadata record)",
            a.file.display()
        );
    }
    let number = |key: &str| metadata.get(key).and_then(|v| v.parse::<usize>().ok());
    let (nx, nz) = (number("nx").unwrap_or(1), number("nz").unwrap_or(1));
    let span = scenario
        .as_deref()
        .and_then(|text| Scenario::parse(text, "the run file's scenario", &[]).ok())
        .map_or(1.0, |s| s.time.end);
    let speed = a.speed.unwrap_or(span / DEFAULT_REPLAY_SECONDS);
    let live = start_live(a.live, largest_record(nx, nz, true), a.wait)?;
    if speed > 0.0 {
        eprintln!(
            "slipfront: replaying `{}` at {speed:.3e} s of simulated time per second \
             ({:.0} s for {span} s; --speed changes it)",
            a.file.display(),
            span / speed
        );
    }
    watch_stop_signals();
    let started = Instant::now();
    let mut first_time = None;
    let mut topics: HashMap<u16, Topic> = HashMap::new();
    let mut sent = 0u64;
    let fail = |why: String| anyhow::anyhow!("cannot read `{}`: {why}", a.file.display());
    let ending = scan(a.file, fail, |record| {
        use mcap::records::Record as McapRecord;
        match record {
            McapRecord::Channel(c) => {
                if let Some(topic) = Topic::from_name(&c.topic) {
                    topics.insert(c.id, topic);
                }
            }
            McapRecord::Message { header, data } => {
                let Some(&topic) = topics.get(&header.channel_id) else {
                    return Ok(Flow::Continue);
                };
                let message = Record::decode(topic, &data).map_err(|e| {
                    anyhow::anyhow!("message {} does not decode: {e}", header.sequence)
                })?;
                let t = message.time();
                let t0 = *first_time.get_or_insert(t);
                if speed > 0.0 {
                    let due = started + Duration::from_secs_f64(((t - t0) / speed).max(0.0));
                    while Instant::now() < due && !interrupted() {
                        let left = due.saturating_duration_since(Instant::now());
                        std::thread::sleep(left.min(Duration::from_millis(50)));
                    }
                }
                if interrupted() {
                    return Ok(Flow::Stop);
                }
                live.publish(&message, &data);
                live.show_time(t);
                sent += 1;
            }
            _ => {}
        }
        Ok(Flow::Continue)
    });
    live.close();
    let ending = ending?;
    eprintln!(
        "slipfront: replayed {sent} records in {:.1} s{}",
        started.elapsed().as_secs_f64(),
        match ending {
            _ if interrupted() => " (stopped)".to_string(),
            Ending::Complete => String::new(),
            Ending::CutShort => " (the file was cut short: all it holds)".to_string(),
            Ending::Damaged(why) => format!(" (the file is damaged: {why})"),
        }
    );
    Ok(if interrupted() {
        ExitCode::from(128 + stopping_signal().unwrap_or(2) as u8)
    } else {
        ExitCode::SUCCESS
    })
}
