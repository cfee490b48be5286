//! MCAP output streamed while the engine runs: metadata, the scenario as an
//! attachment, and one channel per output kind. Messages are protobuf with
//! their FileDescriptorSet as the schema (MCAP well-known encoding), so that
//! Foxglove and the `mcap` Python reader decode numeric arrays; chunks are
//! zstd-compressed (unless the file is scratch, `ChunkCompression`) on the
//! file's own writing thread (`writer`) and flushed every second so that a
//! killed run leaves a readable file.

pub mod lock;
pub mod messages;
mod packed;
pub mod reader;
pub mod records;
pub mod recover;
pub mod scan;
mod writer;

use crate::model::scenario::Scenario;
use crate::model::Model;
use records::Topic;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;
use writer::WriterThread;

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot create `{path}`: {source}")]
    Create {
        path: String,
        source: std::io::Error,
    },
    #[error("MCAP: {}", mcap_cause(.0))]
    Mcap(#[from] mcap::McapError),
    #[error("cannot read `{path}`: {why}")]
    Read { path: String, why: String },
    #[error("writing the run file: {0}")]
    Writing(String),
}

/// The MCAP error with its I/O cause ("No space left on device"), which
/// the crate's own message leaves out.
fn mcap_cause(e: &mcap::McapError) -> String {
    match e {
        mcap::McapError::Io(io) => format!("{e}: {io}"),
        other => other.to_string(),
    }
}

/// How a run file's chunks are stored.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum ChunkCompression {
    /// zstd: what a file that is kept gets.
    #[default]
    Zstd,
    /// Uncompressed, for a scratch file read back once and deleted (a
    /// sweep point that keeps no file): the stick-slip scenes' fast
    /// interface samples compress only 1.45×, and compressing them took
    /// 7–17 % of such a run's CPU (measured, BENCHMARKS.md "CPU sweeps:
    /// lane trees without their empty subtrees").
    None,
}

impl ChunkCompression {
    fn mcap(self) -> Option<mcap::Compression> {
        match self {
            ChunkCompression::Zstd => Some(mcap::Compression::Zstd),
            ChunkCompression::None => None,
        }
    }
}

/// The zstd level of a run file's chunks: the fastest. On a large lattice
/// the writing thread's compression is what an output file costs (at 1024
/// columns, 41 KB a fast `/interface` sample every 4–5 steps): level 1
/// wrote 1.5× faster than zstd's default level 3 on slipping rows and
/// 1.2× on stuck ones (medians of paired runs), for files 2 % and 0.3 %
/// larger (`cargo bench --bench output_writer`, BENCHMARKS.md session
/// 50). Readers see no difference.
const ZSTD_LEVEL: u32 = 1;

/// Uncompressed bytes of one zstd job at `ZSTD_LEVEL`: zstd's
/// multithreaded compressor (the `mcap` crate gives it a worker per
/// physical core) cuts its input into jobs of 2^(windowLog + 2) bytes,
/// windowLog 19 at level 1, and compresses the jobs on its workers side by
/// side. A chunk of one job or less is compressed by one worker while the
/// writing thread waits for it.
const ZSTD_JOB_BYTES: u64 = 2 << 20;

/// zstd jobs a chunk holds: the writing thread fills the next job while
/// the workers compress the ones before, and waits only for the last one
/// at the chunk's end. On a 41 KB-a-sample `/interface` stream (1024
/// columns, slipping) the writing thread took 46–62 µs a message with
/// chunks of 4 jobs against 69–93 µs with chunks of 1 MB, on 2 cores
/// (`cargo bench --bench output_writer`, BENCHMARKS.md session 51); 8 jobs
/// were no faster there. A chunk is also cut at every flush (at least
/// once a second, `writer`), so a slow run's chunks stay small.
const CHUNK_JOBS: u64 = 4;

/// Target uncompressed size of a chunk.
pub const CHUNK_BYTES: u64 = CHUNK_JOBS * ZSTD_JOB_BYTES;

/// How a run file's chunks are laid out: their compression and their
/// target uncompressed size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChunkLayout {
    pub compression: ChunkCompression,
    pub bytes: u64,
}

impl ChunkLayout {
    /// Chunks of `CHUNK_BYTES`, compressed as `compression` says: what
    /// every run file slipfront writes gets.
    pub fn of(compression: ChunkCompression) -> ChunkLayout {
        ChunkLayout {
            compression,
            bytes: CHUNK_BYTES,
        }
    }
}

/// The `mcap` writer's options for `layout`, at `ZSTD_LEVEL`.
fn write_options(layout: ChunkLayout) -> mcap::WriteOptions {
    mcap::WriteOptions::new()
        .compression(layout.compression.mcap())
        .compression_level(ZSTD_LEVEL)
        .chunk_size(Some(layout.bytes))
}

/// One sample of the global series.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct GlobalSample {
    pub time: f64,
    pub step: u64,
    pub drive_force: f64,
    pub drive_ratio: f64,
    pub friction_force: f64,
    pub pinned_fraction: f64,
    pub kinetic_energy: f64,
    pub ruptures: u64,
}

/// The run file being written: messages go to its writing thread.
pub struct McapSink {
    writer: WriterThread,
    /// Channel ids, by [`Topic::index`].
    channels: [u16; 4],
    sequence: u32,
}

/// A run file opened, its header written, not yet handed to its thread
/// (a continued run first copies its parent's messages in here).
struct Opened {
    writer: mcap::Writer<BufWriter<File>>,
    /// The same file, to sync it to disk before a checkpoint.
    file: File,
    channels: [u16; 4],
}

/// Opens `path` for writing as the only writer: created if missing, locked
/// (flock, held while the file is open) and only then emptied, so that a
/// second run aimed at the same file is refused instead of both writing it.
fn open_locked(path: &Path) -> Result<File, OutputError> {
    let create_error = |source| OutputError::Create {
        path: path.display().to_string(),
        source,
    };
    let file = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false)
        .open(path)
        .map_err(create_error)?;
    #[cfg(unix)]
    {
        use std::os::unix::io::AsRawFd;
        // SAFETY: flock on a descriptor this function owns.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
            return Err(create_error(std::io::Error::other(
                "another slipfront run is writing this file",
            )));
        }
    }
    file.set_len(0).map_err(create_error)?;
    Ok(file)
}

impl McapSink {
    /// A new run file, its chunks laid out as `layout` says (runs take
    /// `ChunkLayout::of`; the benches compare layouts). `history` (one
    /// line per start, resume and branch of the run) goes to the
    /// `slipfront_history` metadata record.
    pub fn create(
        path: &Path,
        model: &Model,
        scenario: &Scenario,
        backend: &str,
        history: &[String],
        layout: ChunkLayout,
    ) -> Result<Self, OutputError> {
        let opened = Opened::create(path, model, scenario, backend, history, layout)?;
        Ok(opened.spawn(0))
    }

    /// A run file that continues `parent` (or, with `parent` = `path`,
    /// the same file): its first `messages` messages are copied from
    /// `parent` into `path.partial`, which then takes `path`'s name, so a
    /// crash before that leaves `parent` as it was. Fails when `parent` no
    /// longer holds them all.
    #[allow(clippy::too_many_arguments)]
    pub fn continue_from(
        path: &Path,
        parent: &Path,
        messages: u32,
        model: &Model,
        scenario: &Scenario,
        backend: &str,
        history: &[String],
    ) -> Result<Self, OutputError> {
        let mut partial = path.as_os_str().to_owned();
        partial.push(".partial");
        let partial = std::path::PathBuf::from(partial);
        let mut opened = Opened::create(
            &partial,
            model,
            scenario,
            backend,
            history,
            ChunkLayout::of(ChunkCompression::Zstd),
        )?;
        let copied = opened.copy_messages(parent, messages)?;
        if copied != messages {
            let _ = std::fs::remove_file(&partial);
            return Err(OutputError::Read {
                path: parent.display().to_string(),
                why: format!(
                    "it holds {copied} of the {messages} messages written before the \
                     checkpoint: it was damaged or replaced after it"
                ),
            });
        }
        opened.sync()?;
        std::fs::rename(&partial, path).map_err(|source| OutputError::Create {
            path: path.display().to_string(),
            source,
        })?;
        Ok(opened.spawn(messages))
    }

    /// Everything written so far on disk: the open chunk closed, the
    /// buffers flushed and the file synced (before a checkpoint that counts
    /// on those messages).
    pub fn sync(&mut self) -> Result<(), OutputError> {
        self.writer.sync()
    }

    /// Messages written so far: the sink's part of a checkpoint.
    pub fn sequence(&self) -> u32 {
        self.sequence
    }

    /// Continues the numbering of a saved run.
    pub fn restore(&mut self, sequence: u32) {
        self.sequence = sequence;
    }

    /// Queues one message of `topic`, its protobuf bytes, logged at
    /// simulated time `time` (s). An error of the writing thread (a full
    /// disk) comes back from a later call.
    pub fn write(&mut self, topic: Topic, time: f64, data: Vec<u8>) -> Result<(), OutputError> {
        let t = records::log_time(time);
        self.sequence += 1;
        let header = mcap::records::MessageHeader {
            channel_id: self.channels[topic.index()],
            sequence: self.sequence,
            log_time: t,
            publish_time: t,
        };
        self.writer.write(header, data)
    }

    /// Closes the file, waiting for everything queued; a fast-forwarded
    /// run adds its totals as the `slipfront_fast_forward` metadata record.
    pub fn finish(
        self,
        fast_forward: Option<&crate::engines::quasistatic::FastForwardStats>,
    ) -> Result<(), OutputError> {
        let last = fast_forward.map(|f| {
            let mut meta = BTreeMap::new();
            meta.insert("jumps".into(), f.jumps.to_string());
            meta.insert("skipped_steps".into(), f.skipped_steps.to_string());
            meta.insert("skipped_time".into(), format!("{:e}", f.skipped_time));
            meta.insert("dropped_energy".into(), format!("{:e}", f.dropped_energy));
            mcap::records::Metadata {
                name: "slipfront_fast_forward".into(),
                metadata: meta,
            }
        });
        self.writer.finish(last)
    }
}

impl Opened {
    fn create(
        path: &Path,
        model: &Model,
        scenario: &Scenario,
        backend: &str,
        history: &[String],
        layout: ChunkLayout,
    ) -> Result<Self, OutputError> {
        let create_error = |source| OutputError::Create {
            path: path.display().to_string(),
            source,
        };
        let file = open_locked(path)?;
        let sync_handle = file.try_clone().map_err(create_error)?;
        let mut writer = write_options(layout).create(BufWriter::new(file))?;
        let toml = scenario.to_toml();
        let mut meta = BTreeMap::new();
        meta.insert("slipfront_version".into(), env!("CARGO_PKG_VERSION").into());
        meta.insert(
            "git_commit".into(),
            option_env!("SLIPFRONT_GIT_COMMIT")
                .unwrap_or("unknown")
                .into(),
        );
        meta.insert("scenario".into(), scenario.name.clone());
        meta.insert(
            "scenario_hash".into(),
            format!("{:016x}", fnv1a(toml.as_bytes())),
        );
        meta.insert("backend".into(), backend.into());
        meta.insert("seed".into(), model.seed.to_string());
        meta.insert("dt".into(), format!("{:e}", model.dt));
        meta.insert("nx".into(), model.nx.to_string());
        meta.insert("nz".into(), model.nz.to_string());
        meta.insert("spacing".into(), format!("{:e}", model.spacing));
        meta.insert("normal_force".into(), format!("{:e}", model.normal_force));
        writer.write_metadata(&mcap::records::Metadata {
            name: "slipfront".into(),
            metadata: meta,
        })?;
        if !history.is_empty() {
            writer.write_metadata(&mcap::records::Metadata {
                name: "slipfront_history".into(),
                metadata: history
                    .iter()
                    .enumerate()
                    .map(|(k, line)| (format!("{k:04}"), line.clone()))
                    .collect(),
            })?;
        }
        writer.attach(&mcap::Attachment {
            log_time: 0,
            create_time: 0,
            name: "scenario.toml".into(),
            media_type: "application/toml".into(),
            data: std::borrow::Cow::Owned(toml.into_bytes()),
        })?;
        let descriptor = messages::descriptor_set();
        let none = BTreeMap::new();
        let mut channels = [0; 4];
        for topic in Topic::ALL {
            let schema = writer.add_schema(topic.schema(), "protobuf", &descriptor)?;
            channels[topic.index()] =
                writer.add_channel(schema, topic.name(), "protobuf", &none)?;
        }
        Ok(Opened {
            writer,
            file: sync_handle,
            channels,
        })
    }

    /// Hands the file to its writing thread; `sequence`: messages in it.
    fn spawn(self, sequence: u32) -> McapSink {
        let file = self.file;
        McapSink {
            writer: WriterThread::spawn(
                self.writer,
                move || file.sync_data(),
                writer::MAX_IN_FLIGHT,
            ),
            channels: self.channels,
            sequence,
        }
    }

    /// Closes the open chunk, flushes and syncs the file to disk.
    fn sync(&mut self) -> Result<(), OutputError> {
        let file = &self.file;
        writer::flush_to_disk(&mut self.writer, || file.sync_data())
    }

    /// Copies the messages with sequence numbers 1..=`upto` of `parent`
    /// (record by record: a file cut short gives what it holds). Returns
    /// how many it copied.
    fn copy_messages(&mut self, parent: &Path, upto: u32) -> Result<u32, OutputError> {
        use mcap::records::Record;
        let fail = |why: String| OutputError::Read {
            path: parent.display().to_string(),
            why,
        };
        let mut ours = std::collections::HashMap::new();
        let mut copied = 0;
        let ending = scan::scan(parent, fail, |record| {
            match record {
                Record::Channel(c) => {
                    let topic = Topic::from_name(&c.topic)
                        .ok_or_else(|| fail(format!("unknown channel `{}`", c.topic)))?;
                    ours.insert(c.id, self.channels[topic.index()]);
                }
                Record::Message { header, data } if header.sequence <= upto => {
                    let channel_id = *ours.get(&header.channel_id).ok_or_else(|| {
                        fail(format!("message {} has no channel", header.sequence))
                    })?;
                    self.writer.write_to_known_channel(
                        &mcap::records::MessageHeader {
                            channel_id,
                            ..header
                        },
                        &data,
                    )?;
                    copied += 1;
                }
                _ => {}
            }
            Ok(scan::Flow::Continue)
        })?;
        // A damaged file would be continued with a hole in it: refused.
        if let scan::Ending::Damaged(why) = ending {
            return Err(fail(format!(
                "it is damaged ({why}); run `slipfront recover` on it first"
            )));
        }
        Ok(copied)
    }
}

/// FNV-1a 64-bit hash (scenario fingerprint).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}
