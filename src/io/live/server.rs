//! The live view's server: Foxglove's WebSocket server in a context of its
//! own, one raw channel per run-file channel (the same protobuf schema) and
//! one foxglove.RawImage channel per picture.

use super::pictures::{bulk_speed, InterfaceHistory, Picture};
use super::{LiveAddress, LiveError, IMAGE_TOPICS};
use crate::io::output::messages::{descriptor_set, Bulk};
use crate::io::output::records::{log_time, Record, Topic};
use foxglove::messages::{RawImage, Timestamp};
use foxglove::websocket::{Capability, ChannelView, Client, ServerListener};
use foxglove::{Channel, Context, PartialMetadata, RawChannel, Schema, WebSocketServerHandle};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Pictures and the time broadcast at most this often (30 Hz).
const FRAME_INTERVAL: Duration = Duration::from_millis(33);

/// Bytes a viewer's queue may hold before its oldest messages are dropped
/// (the server counts messages: the count is this over the largest one).
const QUEUE_BYTES: usize = 128 << 20;

/// How long a closing server keeps sending to its viewers.
const LINGER: Duration = Duration::from_secs(1);

/// How long a viewer's subscriptions must stay unchanged before a run that
/// waits for one starts (one subscribe message lands well within this).
const SETTLE: Duration = Duration::from_millis(300);

/// A live view, shared by the run and its command (clones are handles).
#[derive(Clone)]
pub struct LiveView(Arc<Inner>);

struct Inner {
    /// The server holds its context weakly: kept alive here.
    _context: Arc<Context>,
    handle: Mutex<Option<WebSocketServerHandle>>,
    url: String,
    records: Vec<Arc<RawChannel>>,
    images: Vec<Channel<RawImage>>,
    watch: Arc<Subscriptions>,
    drawing: Mutex<Drawing>,
}

/// What the pictures are drawn from, and when they were last sent.
struct Drawing {
    interface: InterfaceHistory,
    bulk: Option<Bulk>,
    time: f64,
    last_frame: Option<Instant>,
    fresh: bool,
}

/// Counts subscriptions, and notes when they last changed.
#[derive(Default)]
struct Subscriptions {
    count: AtomicUsize,
    changed: Mutex<Option<Instant>>,
}

impl Subscriptions {
    fn note(&self, delta: isize) {
        if delta > 0 {
            self.count.fetch_add(1, Ordering::SeqCst);
        } else {
            let _ = self
                .count
                .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |c| c.checked_sub(1));
        }
        *self.changed.lock().unwrap_or_else(|e| e.into_inner()) = Some(Instant::now());
    }
}

impl ServerListener for Subscriptions {
    fn on_subscribe(&self, _client: Client, _channel: ChannelView) {
        self.note(1);
    }
    fn on_unsubscribe(&self, _client: Client, _channel: ChannelView) {
        self.note(-1);
    }
}

impl LiveView {
    /// Starts the server at `address`. `largest_message` (bytes, the
    /// largest record the run will send) sizes each viewer's queue.
    pub fn start(address: &LiveAddress, largest_message: usize) -> Result<LiveView, LiveError> {
        let context = Context::new();
        let server_error = |e: foxglove::FoxgloveError| LiveError::Server(e.to_string());
        let descriptor = descriptor_set();
        let records = Topic::ALL
            .iter()
            .map(|topic| {
                context
                    .channel_builder(topic.name())
                    .message_encoding("protobuf")
                    .schema(Schema::new(topic.schema(), "protobuf", descriptor.clone()))
                    .build_raw()
                    .map_err(server_error)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let images = IMAGE_TOPICS
            .iter()
            .map(|topic| context.channel_builder(*topic).build::<RawImage>())
            .collect();
        // Pictures come at most 30 times a second: records fill the queue.
        let backlog = (QUEUE_BYTES / largest_message.max(1)).clamp(16, 16384);
        let watch = Arc::new(Subscriptions::default());
        let handle = context
            .websocket_server()
            .name(format!("slipfront {}", env!("CARGO_PKG_VERSION")))
            .bind(address.host.clone(), address.port)
            .capabilities([Capability::Time])
            .listener(watch.clone())
            .message_backlog_size(backlog)
            .start_blocking()
            .map_err(|e| LiveError::Bind {
                address: address.to_string(),
                why: e.to_string(),
            })?;
        let shown = LiveAddress {
            port: handle.port(),
            ..address.clone()
        };
        Ok(LiveView(Arc::new(Inner {
            _context: context,
            handle: Mutex::new(Some(handle)),
            url: format!("ws://{shown}"),
            records,
            images,
            watch,
            drawing: Mutex::new(Drawing {
                interface: InterfaceHistory::default(),
                bulk: None,
                time: 0.0,
                last_frame: None,
                fresh: false,
            }),
        })))
    }

    /// Where viewers connect (`ws://HOST:PORT`, the port the system gave
    /// where 0 was asked for).
    pub fn url(&self) -> &str {
        &self.0.url
    }

    /// Some viewer subscribes to a channel: records are worth building.
    pub fn wanted(&self) -> bool {
        self.0.watch.count.load(Ordering::SeqCst) > 0
    }

    /// Blocks until a viewer has subscribed and its subscriptions have
    /// settled, or `stop()` says to give up (false then).
    pub fn wait_for_viewer(&self, stop: &dyn Fn() -> bool) -> bool {
        loop {
            if stop() {
                return false;
            }
            let changed = *self
                .0
                .watch
                .changed
                .lock()
                .unwrap_or_else(|e| e.into_inner());
            if self.wanted() && changed.is_some_and(|t| t.elapsed() >= SETTLE) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Sends a record (its protobuf bytes as written to the file) to the
    /// viewers of its channel, and draws the pictures from it when due.
    pub fn publish(&self, record: &Record, bytes: &[u8]) {
        let inner = &self.0;
        let t = log_time(record.time());
        inner.records[record.topic().index()]
            .log_with_meta(bytes, PartialMetadata::with_log_time(t));
        let interface_pictures = inner.images[..3].iter().any(|c| c.has_sinks());
        let bulk_picture = inner.images[3].has_sinks();
        if !interface_pictures && !bulk_picture {
            return;
        }
        let mut d = inner.drawing.lock().unwrap_or_else(|e| e.into_inner());
        match record {
            Record::Interface(m) if interface_pictures => d.interface.push(m),
            Record::Bulk(m) if bulk_picture => d.bulk = Some(m.clone()),
            _ => {}
        }
        d.time = d.time.max(record.time());
        d.fresh = true;
        if d.last_frame.is_none_or(|f| f.elapsed() >= FRAME_INTERVAL) {
            self.draw(&mut d);
        }
    }

    /// Tells viewers the run's simulated time (s), at most 30 times a
    /// second (the Foxglove app's clock follows it).
    pub fn show_time(&self, t: f64) {
        let mut d = self.0.drawing.lock().unwrap_or_else(|e| e.into_inner());
        d.time = d.time.max(t);
        if d.last_frame.is_none_or(|f| f.elapsed() >= FRAME_INTERVAL) {
            self.draw(&mut d);
        }
    }

    /// The pictures with something new, and the time.
    fn draw(&self, d: &mut Drawing) {
        let inner = &self.0;
        d.last_frame = Some(Instant::now());
        if let Some(h) = inner
            .handle
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .as_ref()
        {
            h.broadcast_time(log_time(d.time));
        }
        if !d.fresh {
            return;
        }
        d.fresh = false;
        let t = log_time(d.time);
        let send = |channel: &Channel<RawImage>, picture: &dyn Fn() -> Picture| {
            if channel.has_sinks() {
                let p = picture();
                if p.height > 0 {
                    channel.log_with_meta(&raw_image(p, t), PartialMetadata::with_log_time(t));
                }
            }
        };
        if d.interface.rows() > 0 {
            send(&inner.images[0], &|| d.interface.stress_ratio());
            send(&inner.images[1], &|| d.interface.slip());
            send(&inner.images[2], &|| d.interface.slip_speed());
        }
        if let Some(bulk) = &d.bulk {
            send(&inner.images[3], &|| bulk_speed(bulk));
        }
    }

    /// Closes the server: viewers get the last pictures and what is queued for them (for up to
    /// [`LINGER`]: the server cannot say when a queue is empty, and
    /// stopping drops what is left), then a close message. A viewer that
    /// does not read is given up on after another second.
    pub fn close(&self) {
        // The last pictures, whatever the frame rate allowed.
        self.draw(&mut self.0.drawing.lock().unwrap_or_else(|e| e.into_inner()));
        let handle = self
            .0
            .handle
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take();
        if let Some(handle) = handle {
            if handle.client_count() > 0 {
                std::thread::sleep(LINGER);
            }
            let shutdown = handle.stop();
            let (done, wait) = std::sync::mpsc::channel();
            std::thread::spawn(move || {
                shutdown.wait_blocking();
                let _ = done.send(());
            });
            let _ = wait.recv_timeout(Duration::from_secs(1));
        }
    }
}

fn raw_image(p: Picture, t: u64) -> RawImage {
    RawImage {
        timestamp: Some(Timestamp::new(
            (t / 1_000_000_000) as u32,
            (t % 1_000_000_000) as u32,
        )),
        frame_id: p.scale,
        width: p.width,
        height: p.height,
        encoding: "rgb8".into(),
        step: 3 * p.width,
        data: p.rgb.into(),
    }
}

impl Drop for Inner {
    fn drop(&mut self) {
        if let Some(handle) = self
            .handle
            .get_mut()
            .unwrap_or_else(|e| e.into_inner())
            .take()
        {
            handle.stop().detach_all();
        }
    }
}
