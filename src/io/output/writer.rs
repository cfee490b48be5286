//! The run file's writing thread. Chunks are zstd-compressed and written
//! beside the engine, so a run that waits on its GPU (or an ensemble's
//! scenes, which all wait at the same step) does not also wait for the
//! compressor and the disk. Messages keep the order they were sent in.
//! - At most `MAX_IN_FLIGHT` bytes wait at once: a large lattice's bulk
//!   fields would otherwise pile up in memory.
//! - The thread takes messages in batches: woken by the first message after
//!   it idled, it waits `BATCH_WAIT` for the rest of the burst. A wake-up per
//!   message cost the runner as much as the compression it handed off
//!   (a futex call and a task switch each, measured with perf).
//! - The file is flushed at least every `FLUSH_EVERY`, busy or idle, so that
//!   a killed run leaves a readable file.

use super::OutputError;
use mcap::records::{MessageHeader, Metadata};
use std::collections::VecDeque;
use std::io::{Seek, Write};
use std::sync::mpsc;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

const FLUSH_EVERY: Duration = Duration::from_secs(1);

/// How long the thread lets a burst of messages gather after the first.
const BATCH_WAIT: Duration = Duration::from_millis(5);

/// Bytes of messages that may wait for the writing thread; a sender blocks
/// beyond it (one message larger than this still goes, alone).
pub(super) const MAX_IN_FLIGHT: usize = 64 << 20;

enum Command {
    Message {
        header: MessageHeader,
        data: Vec<u8>,
    },
    /// Everything so far on disk, then an answer.
    Sync(mpsc::Sender<Result<(), OutputError>>),
    /// The last metadata record, if any, then the file's summary and end.
    Finish(Option<Metadata>),
}

/// What the writing thread is doing, so that a sender wakes it only when
/// it must.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Writer {
    Busy,
    /// Waiting for a first command (or a flush that is due).
    Idle,
    /// Letting a burst gather: woken early only by something urgent.
    Gathering,
}

struct Queue {
    commands: VecDeque<Command>,
    /// Bytes of messages queued or being written.
    bytes: usize,
    writer: Writer,
    /// A sync, the end, or a sender waiting for room: no gathering.
    urgent: bool,
    /// The sink is gone (finished or dropped).
    senders_gone: bool,
    /// The thread has ended: nobody will make room.
    closed: bool,
}

struct Shared {
    queue: Mutex<Queue>,
    /// The writing thread waits here for commands.
    work: Condvar,
    /// Senders wait here for room.
    room: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Queue> {
        self.queue.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Queues `command` and wakes the thread if it idles, or if the
    /// command is urgent and the thread is gathering.
    fn push(&self, command: Command, bytes: usize, limit: usize) -> bool {
        let urgent = !matches!(command, Command::Message { .. });
        let mut q = self.lock();
        while q.bytes > 0 && q.bytes + bytes > limit && !q.closed {
            q.urgent = true;
            if q.writer != Writer::Busy {
                self.work.notify_one();
            }
            q = self.room.wait(q).unwrap_or_else(|p| p.into_inner());
        }
        if q.closed {
            return false;
        }
        q.bytes += bytes;
        q.commands.push_back(command);
        q.urgent |= urgent;
        if q.writer == Writer::Idle || (q.urgent && q.writer == Writer::Gathering) {
            self.work.notify_one();
        }
        true
    }

    /// The thread's wait for commands: at most `timeout`, if one is given.
    fn wait<'a>(
        &self,
        q: MutexGuard<'a, Queue>,
        timeout: Option<Duration>,
    ) -> MutexGuard<'a, Queue> {
        match timeout {
            None => self.work.wait(q).unwrap_or_else(|p| p.into_inner()),
            Some(t) => {
                self.work
                    .wait_timeout(q, t)
                    .unwrap_or_else(|p| p.into_inner())
                    .0
            }
        }
    }

    fn senders_gone(&self) {
        self.lock().senders_gone = true;
        self.work.notify_one();
    }
}

/// Marks the queue closed when the thread ends, by any path, and frees
/// every sender that waits for room.
struct CloseOnExit(Arc<Shared>);

impl Drop for CloseOnExit {
    fn drop(&mut self) {
        self.0.lock().closed = true;
        self.0.room.notify_all();
    }
}

/// The sending side: owned by the run's sink.
pub(super) struct WriterThread {
    shared: Arc<Shared>,
    limit: usize,
    worker: Option<JoinHandle<Result<(), OutputError>>>,
}

impl WriterThread {
    /// Starts the thread that owns `writer`; `sync` puts what was flushed
    /// on disk (the file's `sync_data`).
    pub(super) fn spawn<W, S>(writer: mcap::Writer<W>, sync: S, limit: usize) -> Self
    where
        W: Write + Seek + Send + 'static,
        S: FnMut() -> std::io::Result<()> + Send + 'static,
    {
        let shared = Arc::new(Shared {
            queue: Mutex::new(Queue {
                commands: VecDeque::new(),
                bytes: 0,
                writer: Writer::Busy,
                urgent: false,
                senders_gone: false,
                closed: false,
            }),
            work: Condvar::new(),
            room: Condvar::new(),
        });
        let closing = CloseOnExit(shared.clone());
        let worker = std::thread::Builder::new()
            .name("slipfront-mcap".into())
            .spawn(move || {
                let closing = closing;
                work(writer, sync, &closing.0)
            })
            .expect("spawning the run file's writing thread");
        WriterThread {
            shared,
            limit,
            worker: Some(worker),
        }
    }

    /// Queues one message; fails with the thread's error once it stopped.
    pub(super) fn write(
        &mut self,
        header: MessageHeader,
        data: Vec<u8>,
    ) -> Result<(), OutputError> {
        let bytes = data.len();
        if self
            .shared
            .push(Command::Message { header, data }, bytes, self.limit)
        {
            Ok(())
        } else {
            Err(self.stopped())
        }
    }

    /// Waits until everything queued is on disk.
    pub(super) fn sync(&mut self) -> Result<(), OutputError> {
        let (answer, answered) = mpsc::channel();
        if !self.shared.push(Command::Sync(answer), 0, self.limit) {
            return Err(self.stopped());
        }
        match answered.recv() {
            Ok(result) => result,
            Err(_) => Err(self.stopped()),
        }
    }

    /// Writes `last` (a metadata record) and closes the file; waits for it.
    pub(super) fn finish(mut self, last: Option<Metadata>) -> Result<(), OutputError> {
        self.shared.push(Command::Finish(last), 0, self.limit);
        self.join()
    }

    /// The thread's own error, once it has stopped.
    fn stopped(&mut self) -> OutputError {
        self.shared.senders_gone();
        self.join().err().unwrap_or_else(|| {
            OutputError::Writing("its writing thread had already stopped".into())
        })
    }

    /// Waits for the thread to end: its outcome.
    fn join(&mut self) -> Result<(), OutputError> {
        match self.worker.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(OutputError::Writing("its writing thread panicked".into())),
            None => Err(OutputError::Writing(
                "its writing thread had already stopped".into(),
            )),
        }
    }
}

impl Drop for WriterThread {
    /// A sink dropped without `finish` (an error path, a panic) still
    /// closes its file, as the writer itself would: waited for, so that the
    /// process does not end before the file's summary is written.
    fn drop(&mut self) {
        self.shared.senders_gone();
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

/// The thread: takes what comes in batches, writes it in order, flushes at
/// least every `FLUSH_EVERY`; the sink gone with nothing queued finishes
/// the file.
fn work<W: Write + Seek>(
    mut writer: mcap::Writer<W>,
    mut sync: impl FnMut() -> std::io::Result<()>,
    shared: &Shared,
) -> Result<(), OutputError> {
    let mut last_flush = Instant::now();
    let mut unflushed = false;
    loop {
        let mut q = shared.lock();
        if q.commands.is_empty() {
            if q.senders_gone {
                drop(q);
                writer.finish()?;
                return Ok(());
            }
            q.writer = Writer::Idle;
            q = shared.wait(q, flush_due_in(unflushed, last_flush.elapsed()));
            if !q.commands.is_empty() && !q.urgent {
                q.writer = Writer::Gathering;
                q = shared.wait(q, Some(BATCH_WAIT));
            }
        }
        q.writer = Writer::Busy;
        q.urgent = false;
        let batch = std::mem::take(&mut q.commands);
        drop(q);
        let mut written = 0;
        let mut outcome = Ok(());
        for command in batch {
            match command {
                Command::Message { header, data } => {
                    written += data.len();
                    if let Err(e) = writer.write_to_known_channel(&header, &data) {
                        outcome = Err(e.into());
                        break;
                    }
                    unflushed = true;
                }
                Command::Sync(answer) => {
                    let done = flush_to_disk(&mut writer, &mut sync);
                    last_flush = Instant::now();
                    unflushed = false;
                    let failed = done.as_ref().err().map(|e| e.to_string());
                    let _ = answer.send(done);
                    if let Some(why) = failed {
                        outcome = Err(OutputError::Writing(why));
                        break;
                    }
                }
                Command::Finish(last) => {
                    if let Some(meta) = last {
                        writer.write_metadata(&meta)?;
                    }
                    writer.finish()?;
                    return Ok(());
                }
            }
        }
        {
            let mut q = shared.lock();
            q.bytes = q.bytes.saturating_sub(written);
            shared.room.notify_all();
        }
        outcome?;
        if unflushed && last_flush.elapsed() >= FLUSH_EVERY {
            writer.flush()?;
            last_flush = Instant::now();
            unflushed = false;
        }
    }
}

/// How long the thread may wait for a command before it must flush: None
/// (wait for the next command, however long) when nothing is unflushed. A
/// timeout there would be zero once a second had passed since the last
/// flush, and the idle thread would spin (it did: a 4-scene ensemble on
/// lavapipe took 2.3× as long, its writers busy doing nothing).
fn flush_due_in(unflushed: bool, since_flush: Duration) -> Option<Duration> {
    unflushed.then(|| FLUSH_EVERY.saturating_sub(since_flush))
}

/// Closes the open chunk, flushes the writer and puts the file on disk
/// (`sync`: its `sync_data`).
pub(super) fn flush_to_disk<W: Write + Seek>(
    writer: &mut mcap::Writer<W>,
    mut sync: impl FnMut() -> std::io::Result<()>,
) -> Result<(), OutputError> {
    writer.flush()?;
    sync().map_err(|e| OutputError::Writing(format!("cannot sync it to disk: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;
    use std::io::Cursor;

    /// A disk that takes `room` bytes and then fails every write.
    struct FullAfter {
        inner: Cursor<Vec<u8>>,
        room: usize,
    }

    impl Write for FullAfter {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if self.inner.get_ref().len() + buf.len() > self.room {
                return Err(std::io::Error::other("no space left on the test disk"));
            }
            self.inner.write(buf)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    impl Seek for FullAfter {
        fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
            self.inner.seek(pos)
        }
    }

    fn header(channel_id: u16, sequence: u32) -> MessageHeader {
        MessageHeader {
            channel_id,
            sequence,
            log_time: sequence as u64,
            publish_time: sequence as u64,
        }
    }

    fn writer_with_channel<W: Write + Seek>(w: W) -> (mcap::Writer<W>, u16) {
        let mut writer = mcap::WriteOptions::new()
            .compression(None)
            .chunk_size(Some(4096))
            .create(w)
            .unwrap();
        let schema = writer.add_schema("x", "jsonschema", b"{}").unwrap();
        let channel = writer
            .add_channel(schema, "/x", "json", &BTreeMap::new())
            .unwrap();
        (writer, channel)
    }

    /// An idle thread with nothing to flush waits for its next command
    /// without a timeout, however long since the last flush; with
    /// something unflushed it wakes when the flush is due.
    #[test]
    fn an_idle_writer_waits_without_spinning() {
        for since in [0.0, 0.5, 1.0, 5.0, 3600.0] {
            let since = Duration::from_secs_f64(since);
            assert_eq!(flush_due_in(false, since), None, "{since:?}");
            assert_eq!(
                flush_due_in(true, since),
                Some(FLUSH_EVERY.saturating_sub(since))
            );
        }
        assert_eq!(flush_due_in(true, Duration::ZERO), Some(FLUSH_EVERY));
    }

    /// Messages arrive whole and in order, through the budget, past a tiny
    /// limit that makes the sender wait for the thread.
    #[test]
    fn every_message_is_written_in_order_through_a_small_budget() {
        let path = std::env::temp_dir().join(format!("writer-order-{}.mcap", std::process::id()));
        let file = std::fs::File::create(&path).unwrap();
        let (writer, channel) = writer_with_channel(std::io::BufWriter::new(file));
        let mut thread = WriterThread::spawn(writer, || Ok(()), 1000);
        for k in 1..=500u32 {
            let data = format!("{{\"k\":{k},\"pad\":\"{}\"}}", "x".repeat(300)).into_bytes();
            thread.write(header(channel, k), data).unwrap();
        }
        thread.sync().unwrap();
        thread
            .finish(Some(Metadata {
                name: "end".into(),
                metadata: BTreeMap::new(),
            }))
            .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let seen: Vec<u32> = mcap::MessageStream::new(&bytes)
            .unwrap()
            .map(|m| m.unwrap().sequence)
            .collect();
        assert_eq!(seen, (1..=500).collect::<Vec<u32>>());
        let _ = std::fs::remove_file(&path);
    }

    /// A sink dropped without `finish` (an error path) still leaves a
    /// whole file, summary and all, by the time the drop returns.
    /// Control: the same file cut short has no summary.
    #[test]
    fn a_dropped_writer_leaves_a_whole_file() {
        let path = std::env::temp_dir().join(format!("writer-drop-{}.mcap", std::process::id()));
        let file = std::fs::File::create(&path).unwrap();
        let (writer, channel) = writer_with_channel(std::io::BufWriter::new(file));
        let mut thread = WriterThread::spawn(writer, || Ok(()), MAX_IN_FLIGHT);
        for k in 1..=50u32 {
            thread.write(header(channel, k), vec![b'1'; 100]).unwrap();
        }
        drop(thread);
        let bytes = std::fs::read(&path).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
        assert_eq!(summary.stats.map(|s| s.message_count), Some(50));
        let cut = &bytes[..bytes.len() - 40];
        assert!(!matches!(mcap::Summary::read(cut), Ok(Some(_))));
        let _ = std::fs::remove_file(&path);
    }

    /// A full disk shows as an error from a later write or from finish,
    /// with the cause; nothing hangs (the budget is released on exit) and
    /// nothing panics. Control: with room, the same messages go through.
    #[test]
    fn a_failing_disk_is_an_error_not_a_hang() {
        for room in [usize::MAX, 20_000] {
            let w = FullAfter {
                inner: Cursor::new(Vec::new()),
                room,
            };
            let (writer, channel) = writer_with_channel(w);
            let mut thread = WriterThread::spawn(writer, || Ok(()), 2000);
            let mut first_error = None;
            for k in 1..=400u32 {
                let data = vec![b'7'; 500];
                if let Err(e) = thread.write(header(channel, k), data) {
                    first_error = Some(e.to_string());
                    break;
                }
            }
            let end = thread.finish(None);
            if room == usize::MAX {
                assert!(
                    first_error.is_none() && end.is_ok(),
                    "{first_error:?} {end:?}"
                );
            } else {
                let why = first_error.unwrap_or_else(|| end.unwrap_err().to_string());
                assert!(why.contains("no space left on the test disk"), "{why}");
            }
        }
    }
}
