//! The live view end to end: `slipfront run --live` and `slipfront replay`
//! serve a real WebSocket client (tests/support/live_client.rs), whose
//! messages, decoded with the schemas the server advertises, must equal
//! the run file's messages decoded with the file's own schemas. A client
//! that stops reading must not stall the run, a bad address is refused
//! clearly, and Ctrl-C closes the server and the file.

#![cfg(feature = "live")]

#[path = "support/live_client.rs"]
mod live_client;
#[path = "support/scratch.rs"]
mod scratch;

use live_client::{decode, Event, LiveClient, Received};
use scratch::Scratch;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

const RECORD_TOPICS: [&str; 4] = ["/global", "/interface", "/bulk", "/fast_forward"];
const IMAGE_TOPICS: [&str; 4] = [
    "/live/stress_ratio",
    "/live/slip",
    "/live/slip_speed",
    "/live/bulk_speed",
];

fn scene(name: &str) -> String {
    format!("{}/scenarios/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// A slipfront process serving a live view, and its stderr so far.
struct Served {
    child: Child,
    url: String,
    stderr: mpsc::Receiver<String>,
}

impl Served {
    fn start(args: &[&str]) -> Served {
        let mut child = Command::new(env!("CARGO_BIN_EXE_slipfront"))
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start slipfront");
        let (lines, stderr) = mpsc::channel();
        let err = child.stderr.take().unwrap();
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().map_while(Result::ok) {
                let _ = lines.send(line);
            }
        });
        let mut seen = String::new();
        let deadline = Instant::now() + Duration::from_secs(60);
        let url = loop {
            let line = stderr
                .recv_timeout(deadline.saturating_duration_since(Instant::now()))
                .unwrap_or_else(|_| panic!("no live view announced; stderr:\n{seen}"));
            if let Some(rest) = line.split("live view at ").nth(1) {
                break rest.split_whitespace().next().unwrap().to_string();
            }
            seen += &line;
            seen.push('\n');
        };
        Served { child, url, stderr }
    }

    /// Waits for the process (at most `timeout`): its exit code, stdout and
    /// the rest of its stderr.
    fn finish(mut self, timeout: Duration) -> (i32, String, String) {
        let started = Instant::now();
        let status = loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                break status;
            }
            if started.elapsed() > timeout {
                let _ = self.child.kill();
                panic!("slipfront did not finish within {timeout:?}");
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        let mut out = String::new();
        use std::io::Read;
        self.child
            .stdout
            .take()
            .unwrap()
            .read_to_string(&mut out)
            .unwrap();
        let err: Vec<String> = self.stderr.try_iter().collect();
        (status.code().unwrap_or(-1), out, err.join("\n"))
    }
}

/// A client subscribed to every channel of the live view at `url`.
fn subscribed_client(url: &str) -> LiveClient {
    let mut client = LiveClient::connect(url);
    let all: Vec<&str> = RECORD_TOPICS.iter().chain(&IMAGE_TOPICS).copied().collect();
    client.wait_for_channels(&all, Duration::from_secs(10));
    client.subscribe(&all);
    client
}

/// A run file's messages by topic, in order: (log time, bytes), and each
/// topic's schema, read with the mcap crate.
struct FileMessages {
    by_topic: BTreeMap<String, Vec<(u64, Vec<u8>)>>,
    schemas: BTreeMap<String, prost_reflect::MessageDescriptor>,
}

fn file_messages(path: &Path) -> FileMessages {
    let bytes = std::fs::read(path).unwrap();
    let mut by_topic: BTreeMap<String, Vec<(u64, Vec<u8>)>> = BTreeMap::new();
    let mut schemas = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).expect("an MCAP file") {
        let m = m.expect("a message");
        let topic = m.channel.topic.clone();
        if !schemas.contains_key(&topic) {
            let schema = m.channel.schema.as_ref().expect("a schema");
            let pool = prost_reflect::DescriptorPool::decode(&schema.data[..]).unwrap();
            schemas.insert(
                topic.clone(),
                pool.get_message_by_name(&schema.name).unwrap(),
            );
        }
        by_topic
            .entry(topic)
            .or_default()
            .push((m.log_time, m.data.into_owned()));
    }
    FileMessages { by_topic, schemas }
}

/// Err naming the first difference between what the client received on
/// the record channels and the file's messages: counts, log times, bytes,
/// and the messages decoded (the client's with the advertised schema, the
/// file's with its own).
fn compare(
    client: &LiveClient,
    live: &BTreeMap<String, Vec<Received>>,
    file: &FileMessages,
) -> Result<usize, String> {
    let mut compared = 0;
    for topic in RECORD_TOPICS {
        let got = live.get(topic).map_or(&[][..], Vec::as_slice);
        let want = file.by_topic.get(topic).map_or(&[][..], Vec::as_slice);
        if got.len() != want.len() {
            return Err(format!(
                "{topic}: {} messages live, {} in the file",
                got.len(),
                want.len()
            ));
        }
        if want.is_empty() {
            continue;
        }
        let advertised = client.channel(topic);
        if advertised.encoding != "protobuf" {
            return Err(format!("{topic}: encoding {}", advertised.encoding));
        }
        let (live_type, file_type) = (advertised.descriptor(), &file.schemas[topic]);
        for (k, (g, (t, data))) in got.iter().zip(want).enumerate() {
            if g.log_time != *t {
                return Err(format!(
                    "{topic} message {k}: log time {} against {t}",
                    g.log_time
                ));
            }
            let (a, b) = (
                fields(&decode(&live_type, &g.data)),
                fields(&decode(file_type, data)),
            );
            if let Some(((name, x), (_, y))) = a.iter().zip(&b).find(|(x, y)| x != y) {
                return Err(format!(
                    "{topic} message {k}: {name} is {x:?} live, {y:?} in the file"
                ));
            }
            if a.len() != b.len() {
                return Err(format!("{topic} message {k}: fields differ"));
            }
            if g.data != *data {
                return Err(format!("{topic} message {k}: bytes differ"));
            }
            compared += 1;
        }
    }
    Ok(compared)
}

/// A decoded message's fields by name (the values as decoded, each
/// schema's own).
fn fields(m: &prost_reflect::DynamicMessage) -> Vec<(String, prost_reflect::Value)> {
    m.fields()
        .map(|(f, v)| (f.name().to_string(), v.clone()))
        .collect()
}

/// The pictures are RGB images of the interface (one column per block) as
/// foxglove.RawImage decodes them.
fn check_pictures(client: &LiveClient, live: &BTreeMap<String, Vec<Received>>, nx: u64) {
    for topic in ["/live/stress_ratio", "/live/slip", "/live/slip_speed"] {
        let images = live
            .get(topic)
            .unwrap_or_else(|| panic!("no {topic} image"));
        let channel = client.channel(topic);
        assert_eq!(channel.schema_name, "foxglove.RawImage");
        let last = decode(&channel.descriptor(), &images.last().unwrap().data);
        let field = |name: &str| last.get_field_by_name(name).unwrap().into_owned();
        let (w, h) = (
            field("width").as_u32().unwrap(),
            field("height").as_u32().unwrap(),
        );
        assert_eq!(w as u64, nx, "{topic}: a column per block");
        assert!((1..=256).contains(&h), "{topic}: {h} rows");
        assert_eq!(field("encoding").as_str(), Some("rgb8"));
        assert_eq!(field("data").as_bytes().unwrap().len() as u32, 3 * w * h);
    }
}

const SMALL: [&str; 4] = ["--t-end", "0.03", "--progress", "none"];

#[test]
fn live_run_streams_what_it_writes_with_or_without_a_file() {
    let dir = Scratch::new("live", "streams");
    let file = dir.join("run.mcap");
    let scene = scene("small_stick_slip.toml");
    let mut args = vec!["run", &scene, "--backend", "cpu", "--threads", "1"];
    args.extend(SMALL);
    let f = file.to_str().unwrap();
    let with_file: Vec<&str> = args
        .iter()
        .copied()
        .chain(["-o", f, "--live", "127.0.0.1:0", "--live-wait"])
        .collect();
    let served = Served::start(&with_file);
    let mut client = subscribed_client(&served.url);
    let (live, times) = client.collect_until_closed(Duration::from_secs(120));
    let (code, out, err) = served.finish(Duration::from_secs(30));
    assert_eq!(code, 0, "{out}\n{err}");
    let messages = file_messages(&file);
    let n = compare(&client, &live, &messages).unwrap();
    assert!(n > 1000, "{n} messages compared");
    assert!(messages.by_topic["/bulk"].len() >= 2);
    check_pictures(&client, &live, 15);
    assert!(!times.is_empty(), "the server's clock was broadcast");
    let name = client.server_info.as_ref().unwrap()["name"]
        .as_str()
        .unwrap();
    assert!(name.starts_with("slipfront"), "{name}");

    // Negative controls: the comparison flags a value changed in its last
    // digit, and a message missing.
    let mut perturbed = live.clone();
    let row = &mut perturbed.get_mut("/interface").unwrap()[7].data;
    let last = row.len() - 1;
    row[last - 3] ^= 1;
    assert!(compare(&client, &perturbed, &messages).is_err());
    let mut short = live.clone();
    short.get_mut("/global").unwrap().remove(3);
    let e = compare(&client, &short, &messages).unwrap_err();
    assert!(e.contains("/global"), "{e}");

    // Without -o the same records stream (this engine is deterministic).
    let without: Vec<&str> = args
        .iter()
        .copied()
        .chain(["--live", ":0", "--live-wait"])
        .collect();
    let served = Served::start(&without);
    let mut client = subscribed_client(&served.url);
    let (live, _) = client.collect_until_closed(Duration::from_secs(120));
    let (code, out, err) = served.finish(Duration::from_secs(30));
    assert_eq!(code, 0, "{out}\n{err}");
    assert_eq!(compare(&client, &live, &messages), Ok(n));

    // And a replay of the file serves it the same way.
    let served = Served::start(&["replay", f, "--live", ":0", "--live-wait", "--speed", "0"]);
    let mut client = subscribed_client(&served.url);
    let (live, _) = client.collect_until_closed(Duration::from_secs(120));
    let (code, out, err) = served.finish(Duration::from_secs(30));
    assert_eq!(code, 0, "{out}\n{err}");
    assert_eq!(compare(&client, &live, &messages), Ok(n));
    check_pictures(&client, &live, 15);
    assert!(err.contains(&format!("replayed {n} records")), "{err}");
}

#[test]
fn replay_is_paced_in_simulated_time() {
    let dir = Scratch::new("live", "paced");
    let file = dir.join("paced.mcap");
    let f = file.to_str().unwrap();
    let scene = scene("small_stick_slip.toml");
    let run = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args([
            "run",
            &scene,
            "--t-end",
            "0.01",
            "--progress",
            "none",
            "-o",
            f,
        ])
        .output()
        .unwrap();
    assert!(run.status.success());
    // 0.01 s of driving at 0.01 s per second: about one second.
    let started = Instant::now();
    let served = Served::start(&["replay", f, "--live", ":0", "--speed", "0.01"]);
    let (code, _, err) = served.finish(Duration::from_secs(30));
    let wall = started.elapsed().as_secs_f64();
    assert_eq!(code, 0, "{err}");
    assert!((0.9..10.0).contains(&wall), "replay took {wall} s");
}

#[test]
fn gpu_run_streams_its_device_records() {
    let dir = Scratch::new("live", "gpu");
    let file = dir.join("gpu.mcap");
    let f = file.to_str().unwrap();
    let scene = scene("small_stick_slip.toml");
    let served = Served::start(&[
        "run",
        &scene,
        "--backend",
        "gpu",
        "--t-end",
        "0.01",
        "--progress",
        "none",
        "-o",
        f,
        "--live",
        ":0",
        "--live-wait",
    ]);
    let mut client = subscribed_client(&served.url);
    let (live, _) = client.collect_until_closed(Duration::from_secs(300));
    let (code, out, err) = served.finish(Duration::from_secs(30));
    assert_eq!(
        code, 0,
        "a GPU adapter (lavapipe in CI) is needed:\n{out}\n{err}"
    );
    assert!(out.contains("gpu"), "{out}");
    let n = compare(&client, &live, &file_messages(&file)).unwrap();
    assert!(n > 300, "{n}");
}

#[test]
fn a_client_that_stops_reading_does_not_stall_the_run() {
    // The Table S1 scene with its bulk field every microsecond: about
    // 10^4 fields of 28 KB in 0.01 s, far more than a socket holds.
    let served = Served::start(&[
        "run",
        "--backend",
        "cpu",
        "--t-end",
        "0.01",
        "--progress",
        "none",
        "--set",
        "output.bulk_interval=1e-6",
        "--live",
        ":0",
        "--live-wait",
    ]);
    let mut client = subscribed_client(&served.url);
    // The client reads nothing from here until the run has ended.
    let (code, out, err) = served.finish(Duration::from_secs(120));
    assert_eq!(code, 0, "{out}\n{err}");
    let mut bulk = 0;
    client.set_read_timeout(Duration::from_secs(2));
    loop {
        match client.next() {
            Event::Message(m) if m.topic == "/bulk" => bulk += 1,
            Event::Closed => break,
            Event::Idle => break,
            _ => {}
        }
    }
    // The run made ~10^4 fields; the stuck client got those its socket
    // held and lost the rest (dropped, not waited for).
    assert!(
        (1..8000).contains(&bulk),
        "{bulk} bulk fields reached the stuck client"
    );
}

#[test]
fn a_bad_or_taken_address_is_refused_clearly() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port();
    let run = |live: &str| {
        Command::new(env!("CARGO_BIN_EXE_slipfront"))
            .args([
                "run",
                "--t-end",
                "1e-4",
                "--progress",
                "none",
                "--live",
                live,
            ])
            .output()
            .unwrap()
    };
    let out = run(&format!("127.0.0.1:{port}"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains(&format!(
            "live view at 127.0.0.1:{port}: cannot listen there"
        )) && err.contains("in use"),
        "{err}"
    );
    for bad in ["localhost:http", "127.0.0.1:99999"] {
        let out = run(bad);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains(&format!("`{bad}`")) && err.contains("HOST:PORT"),
            "{err}"
        );
    }
    for speed in ["--speed=-1", "--speed=nan", "--speed=fast"] {
        let out = Command::new(env!("CARGO_BIN_EXE_slipfront"))
            .args(["replay", "run.mcap", speed])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains("--speed = ") && err.contains("0 or more"),
            "{err}"
        );
    }
    let out = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(["replay", "/nonexistent/run.mcap", "--live", ":0"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("/nonexistent/run.mcap"),
        "{err}"
    );
}

#[cfg(unix)]
#[test]
fn ctrl_c_closes_the_server_and_the_file() {
    let dir = Scratch::new("live", "stopped");
    let file = dir.join("stopped.mcap");
    let f = file.to_str().unwrap();
    let served = Served::start(&[
        "run",
        "--backend",
        "cpu",
        "--progress",
        "none",
        "-o",
        f,
        "--live",
        ":0",
        "--live-wait",
    ]);
    let port: u16 = served.url.rsplit(':').next().unwrap().parse().unwrap();
    let mut client = subscribed_client(&served.url);
    let mut received = 0;
    while received < 200 {
        if let Event::Message(_) = client.next() {
            received += 1;
        }
    }
    // SAFETY: a signal to the child this test started.
    unsafe { libc::kill(served.child.id() as i32, libc::SIGINT) };
    let (code, out, err) = served.finish(Duration::from_secs(60));
    assert_eq!(code, 130, "{out}\n{err}");
    assert!(out.contains("run INTERRUPTED"), "{out}");
    // The client was told the server closed.
    let started = Instant::now();
    loop {
        match client.next() {
            Event::Closed => break,
            _ => assert!(started.elapsed() < Duration::from_secs(10), "not closed"),
        }
    }
    // The port is free again, and the file is whole (it has its footer).
    std::net::TcpListener::bind(("127.0.0.1", port)).expect("the port is free");
    let info = Command::new(env!("CARGO_BIN_EXE_slipfront"))
        .args(["info", f])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(info.status.success() && text.contains("/global"), "{text}");
    assert!(!text.contains("cut short"), "{text}");
    assert!(!file_messages(&file).by_topic["/global"].is_empty());
}

/// Every panel of the shipped Foxglove layout shows a channel the live
/// view serves: plot paths name a field of the channel's schema, image
/// panels an image channel.
#[test]
fn the_layout_names_only_channels_and_fields_that_exist() {
    let text = std::fs::read_to_string(format!(
        "{}/docs/foxglove-layout.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let layout: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let pool = prost_reflect::DescriptorPool::decode(
        &slipfront::io::output::messages::descriptor_set()[..],
    )
    .unwrap();
    let schema_of = |topic: &str| match topic {
        "/global" => "slipfront.Global",
        "/interface" => "slipfront.Interface",
        "/bulk" => "slipfront.Bulk",
        "/fast_forward" => "slipfront.FastForwardJump",
        other => panic!("the layout plots `{other}`, which is not a record channel"),
    };
    let check = |path: &str| -> Result<(), String> {
        let (topic, field) = path.split_once('.').ok_or(format!("`{path}`: no field"))?;
        let message = pool.get_message_by_name(schema_of(topic)).unwrap();
        message.get_field_by_name(field).map(|_| ()).ok_or(format!(
            "`{path}`: {} has no field `{field}`",
            message.full_name()
        ))
    };
    let panels = layout["configById"].as_object().unwrap();
    let (mut plots, mut images) = (0, Vec::new());
    for (id, config) in panels {
        if id.starts_with("Plot!") {
            for p in config["paths"].as_array().unwrap() {
                check(p["value"].as_str().unwrap()).unwrap();
                plots += 1;
            }
        } else if id.starts_with("Image!") {
            let topic = config["imageMode"]["imageTopic"].as_str().unwrap();
            assert!(IMAGE_TOPICS.contains(&topic), "{id}: {topic}");
            images.push(topic);
        }
        assert!(
            text.matches(&format!("\"{id}\"")).count() == 2,
            "{id} is not placed"
        );
    }
    assert!(plots >= 3);
    images.sort();
    let mut all = IMAGE_TOPICS.to_vec();
    all.sort();
    assert_eq!(images, all, "an image panel per picture");
    // Negative controls: the check flags a misspelt field and channel.
    assert!(check("/global.drive_ration").is_err());
    assert!(std::panic::catch_unwind(|| check("/globl.drive_ratio")).is_err());
}
