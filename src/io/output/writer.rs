//! The run file's writing thread. Chunks are zstd-compressed and written
//! beside the engine, so a run that waits on its GPU (or an ensemble's
//! scenes, which all wait at the same step) does not also wait for the
//! compressor and the disk. Messages keep the order they were sent in;
//! at most `MAX_IN_FLIGHT` bytes wait at once (a large lattice's bulk
//! fields would otherwise pile up in memory), and the file is flushed at
//! least every `FLUSH_EVERY`, busy or idle, so that a killed run leaves a
//! readable file.

use super::OutputError;
use mcap::records::{MessageHeader, Metadata};
use std::collections::BTreeMap;
use std::io::{Seek, Write};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

pub(super) const FLUSH_EVERY: Duration = Duration::from_secs(1);

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

/// Bytes sent and not yet written; `closed` once the thread has ended, so
/// that no sender waits for it.
#[derive(Default)]
struct Budget {
    state: Mutex<(usize, bool)>,
    freed: Condvar,
}

impl Budget {
    fn lock(&self) -> std::sync::MutexGuard<'_, (usize, bool)> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn acquire(&self, bytes: usize, limit: usize) {
        let mut s = self.lock();
        while s.0 > 0 && s.0 + bytes > limit && !s.1 {
            s = self.freed.wait(s).unwrap_or_else(|p| p.into_inner());
        }
        s.0 += bytes;
    }

    fn release(&self, bytes: usize) {
        let mut s = self.lock();
        s.0 = s.0.saturating_sub(bytes);
        self.freed.notify_all();
    }

    fn close(&self) {
        self.lock().1 = true;
        self.freed.notify_all();
    }
}

/// Closes the budget when the thread ends, by any path.
struct CloseOnExit(Arc<Budget>);

impl Drop for CloseOnExit {
    fn drop(&mut self) {
        self.0.close();
    }
}

/// The sending side: owned by the run's sink.
pub(super) struct WriterThread {
    queue: Option<mpsc::Sender<Command>>,
    budget: Arc<Budget>,
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
        let (queue, commands) = mpsc::channel();
        let budget = Arc::new(Budget::default());
        let closing = CloseOnExit(budget.clone());
        let worker = std::thread::Builder::new()
            .name("slipfront-mcap".into())
            .spawn(move || {
                let _closing = closing;
                work(writer, sync, &commands, &_closing.0)
            })
            .expect("spawning the run file's writing thread");
        WriterThread {
            queue: Some(queue),
            budget,
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
        self.budget.acquire(data.len(), self.limit);
        let sent = match &self.queue {
            Some(q) => q.send(Command::Message { header, data }).is_ok(),
            None => false,
        };
        if sent {
            Ok(())
        } else {
            Err(self.stopped())
        }
    }

    /// Waits until everything queued is on disk.
    pub(super) fn sync(&mut self) -> Result<(), OutputError> {
        let (answer, answered) = mpsc::channel();
        let sent = match &self.queue {
            Some(q) => q.send(Command::Sync(answer)).is_ok(),
            None => false,
        };
        if !sent {
            return Err(self.stopped());
        }
        match answered.recv() {
            Ok(result) => result,
            Err(_) => Err(self.stopped()),
        }
    }

    /// Writes `last` (a metadata record) and closes the file; waits for it.
    pub(super) fn finish(mut self, last: Option<Metadata>) -> Result<(), OutputError> {
        if let Some(q) = self.queue.take() {
            let _ = q.send(Command::Finish(last));
        }
        match self.worker.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(OutputError::Writing("its writing thread panicked".into())),
            None => Err(OutputError::Writing(
                "its writing thread had already stopped".into(),
            )),
        }
    }

    /// The thread's own error, once it has stopped.
    fn stopped(&mut self) -> OutputError {
        self.queue = None;
        match self.worker.take().map(JoinHandle::join) {
            Some(Ok(Err(e))) => e,
            Some(Err(_)) => OutputError::Writing("its writing thread panicked".into()),
            _ => OutputError::Writing("its writing thread had already stopped".into()),
        }
    }
}

impl Drop for WriterThread {
    /// A sink dropped without `finish` (an error path, a panic) still
    /// closes its file, as the writer itself would: waited for, so that the
    /// process does not end before the file's summary is written.
    fn drop(&mut self) {
        self.queue = None;
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

/// The thread: writes what comes, in order, flushing at least every
/// `FLUSH_EVERY`; a closed queue (the sink dropped) finishes the file.
fn work<W: Write + Seek>(
    mut writer: mcap::Writer<W>,
    mut sync: impl FnMut() -> std::io::Result<()>,
    commands: &mpsc::Receiver<Command>,
    budget: &Budget,
) -> Result<(), OutputError> {
    let mut last_flush = Instant::now();
    let mut unflushed = false;
    loop {
        let wait = FLUSH_EVERY.saturating_sub(last_flush.elapsed());
        match commands.recv_timeout(wait) {
            Ok(Command::Message { header, data }) => {
                let written = writer.write_to_known_channel(&header, &data);
                budget.release(data.len());
                written?;
                unflushed = true;
            }
            Ok(Command::Sync(answer)) => {
                let done = writer.flush().map_err(OutputError::from).and_then(|()| {
                    sync().map_err(|e| OutputError::Writing(format!("cannot sync it to disk: {e}")))
                });
                last_flush = Instant::now();
                unflushed = false;
                let failed = done.as_ref().err().map(|e| e.to_string());
                let _ = answer.send(done);
                if let Some(why) = failed {
                    return Err(OutputError::Writing(why));
                }
            }
            Ok(Command::Finish(last)) => {
                if let Some(meta) = last {
                    writer.write_metadata(&meta)?;
                }
                writer.finish()?;
                return Ok(());
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => {
                writer.finish()?;
                return Ok(());
            }
        }
        if unflushed && last_flush.elapsed() >= FLUSH_EVERY {
            writer.flush()?;
            last_flush = Instant::now();
            unflushed = false;
        }
    }
}

/// A metadata record from its entries.
pub(super) fn metadata(name: &str, entries: BTreeMap<String, String>) -> Metadata {
    Metadata {
        name: name.into(),
        metadata: entries,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
            .finish(Some(metadata("end", BTreeMap::new())))
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
