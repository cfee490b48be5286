//! MCAP output streamed while the engine runs: metadata, the scenario as an
//! attachment, and one channel per output kind. Messages are protobuf with
//! their FileDescriptorSet as the schema (MCAP well-known encoding), so that
//! Foxglove and the `mcap` Python reader decode numeric arrays; chunks are
//! zstd-compressed and flushed every few seconds so that a killed run leaves
//! a readable file.

pub mod lock;
pub mod messages;
pub mod reader;
pub mod recover;
pub mod scan;

use prost::Message;

use crate::engines::{BulkField, InterfaceRow};
use crate::model::scenario::Scenario;
use crate::model::Model;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;
use std::time::{Duration, Instant};

const FLUSH_EVERY: Duration = Duration::from_secs(1);

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot create `{path}`: {source}")]
    Create {
        path: String,
        source: std::io::Error,
    },
    #[error("MCAP: {0}")]
    Mcap(#[from] mcap::McapError),
    #[error("cannot read `{path}`: {why}")]
    Read { path: String, why: String },
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

pub struct McapSink {
    writer: mcap::Writer<BufWriter<File>>,
    /// The same file, to sync it to disk before a checkpoint.
    file: File,
    global: u16,
    interface: u16,
    bulk: u16,
    fast_forward: u16,
    sequence: u32,
    last_flush: Instant,
    slip_origin: Option<Vec<f64>>,
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
    /// A new run file. `history` (one line per start, resume and branch
    /// of the run) goes to the `slipfront_history` metadata record.
    pub fn create(
        path: &Path,
        model: &Model,
        scenario: &Scenario,
        backend: &str,
        history: &[String],
    ) -> Result<Self, OutputError> {
        let create_error = |source| OutputError::Create {
            path: path.display().to_string(),
            source,
        };
        let file = open_locked(path)?;
        let sync_handle = file.try_clone().map_err(create_error)?;
        let mut writer = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .chunk_size(Some(1 << 20))
            .create(BufWriter::new(file))?;
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
        let g = writer.add_schema("slipfront.Global", "protobuf", &descriptor)?;
        let i = writer.add_schema("slipfront.Interface", "protobuf", &descriptor)?;
        let b = writer.add_schema("slipfront.Bulk", "protobuf", &descriptor)?;
        let none = BTreeMap::new();
        let global = writer.add_channel(g, "/global", "protobuf", &none)?;
        let interface = writer.add_channel(i, "/interface", "protobuf", &none)?;
        let bulk = writer.add_channel(b, "/bulk", "protobuf", &none)?;
        let f = writer.add_schema("slipfront.FastForwardJump", "protobuf", &descriptor)?;
        let fast_forward = writer.add_channel(f, "/fast_forward", "protobuf", &none)?;
        Ok(McapSink {
            writer,
            file: sync_handle,
            global,
            interface,
            bulk,
            fast_forward,
            sequence: 0,
            last_flush: Instant::now(),
            slip_origin: None,
        })
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
        let mut sink = McapSink::create(&partial, model, scenario, backend, history)?;
        let copied = sink.copy_messages(parent, messages)?;
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
        sink.sync()?;
        std::fs::rename(&partial, path).map_err(|source| OutputError::Create {
            path: path.display().to_string(),
            source,
        })?;
        Ok(sink)
    }

    /// Copies the messages with sequence numbers 1..=`upto` of `parent`
    /// (record by record: a file cut short gives what it holds) and
    /// continues the numbering after them. Returns how many it copied.
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
                    let id = match c.topic.as_str() {
                        "/global" => self.global,
                        "/interface" => self.interface,
                        "/bulk" => self.bulk,
                        "/fast_forward" => self.fast_forward,
                        other => return Err(fail(format!("unknown channel `{other}`"))),
                    };
                    ours.insert(c.id, id);
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
        self.sequence = upto;
        Ok(copied)
    }

    /// Everything written so far on disk: the open chunk closed, the
    /// buffers flushed and the file synced (before a checkpoint that counts
    /// on those messages).
    pub fn sync(&mut self) -> Result<(), OutputError> {
        self.writer.flush()?;
        self.last_flush = Instant::now();
        self.file.sync_data().map_err(|e| OutputError::Read {
            path: "the run file".into(),
            why: format!("cannot sync it to disk: {e}"),
        })
    }

    /// (messages written, interface slip origin): the sink's part of a
    /// checkpoint.
    pub fn state(&self) -> (u32, Option<Vec<f64>>) {
        (self.sequence, self.slip_origin.clone())
    }

    /// Continues the numbering and the slip origin of a saved run.
    pub fn restore(&mut self, sequence: u32, slip_origin: Option<Vec<f64>>) {
        self.sequence = sequence;
        self.slip_origin = slip_origin;
    }

    fn write(&mut self, channel: u16, time: f64, data: &[u8]) -> Result<(), OutputError> {
        let t = (time.max(0.0) * 1e9) as u64;
        self.sequence += 1;
        self.writer.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: channel,
                sequence: self.sequence,
                log_time: t,
                publish_time: t,
            },
            data,
        )?;
        if self.last_flush.elapsed() > FLUSH_EVERY {
            self.writer.flush()?;
            self.last_flush = Instant::now();
        }
        Ok(())
    }

    pub fn write_global(&mut self, g: &GlobalSample) -> Result<(), OutputError> {
        let msg = messages::Global {
            time: g.time,
            step: g.step,
            drive_force: g.drive_force,
            drive_ratio: g.drive_ratio,
            friction_force: g.friction_force,
            pinned_fraction: g.pinned_fraction,
            kinetic_energy: g.kinetic_energy,
            ruptures: g.ruptures,
        };
        self.write(self.global, g.time, &msg.encode_to_vec())
    }

    /// Writes an interface row; slip is u_x from the first row written.
    pub fn write_interface(
        &mut self,
        model: &Model,
        step: u64,
        time: f64,
        row: &InterfaceRow,
    ) -> Result<(), OutputError> {
        let area = model.spacing * model.width;
        let origin = self.slip_origin.get_or_insert_with(|| row.ux.clone());
        let slip: Vec<f64> = row
            .ux
            .iter()
            .zip(origin.iter())
            .map(|(u, o)| u - o)
            .collect();
        let shear: Vec<f64> = row.friction.iter().map(|f| -f / area).collect();
        let normal: Vec<f64> = row.normal.iter().map(|p| p / area).collect();
        let msg = messages::Interface {
            time,
            step,
            shear_stress: shear,
            normal_stress: normal,
            pinned_fraction: row.pinned_fraction.clone(),
            slip,
            slip_speed: row.slip_speed.clone(),
        };
        let data = msg.encode_to_vec();
        self.write(self.interface, time, &data)
    }

    pub fn write_bulk(
        &mut self,
        model: &Model,
        step: u64,
        time: f64,
        field: &BulkField,
    ) -> Result<(), OutputError> {
        let msg = messages::Bulk {
            time,
            step,
            nx: model.nx as u32,
            nz: model.nz as u32,
            ux: field.ux.clone(),
            uz: field.uz.clone(),
            vx: field.vx.clone(),
            vz: field.vz.clone(),
        };
        self.write(self.bulk, time, &msg.encode_to_vec())
    }

    pub fn write_fast_forward(
        &mut self,
        r: &crate::engines::quasistatic::JumpRecord,
    ) -> Result<(), OutputError> {
        let index = |v: Option<usize>| v.map_or(-1, |v| v as i32);
        let msg = messages::FastForwardJump {
            start_time: r.start_time,
            end_time: r.end_time,
            start_step: r.start_step,
            end_step: r.end_step,
            drive_start: r.drive_start,
            drive_end: r.drive_end,
            predicted_change: r.predicted_change,
            block: index(r.block),
            junction: index(r.junction),
            dropped_energy: r.dropped_energy,
            work_in: r.work_in,
            damping: r.damping,
            stored_change: r.stored_change,
            ruptures: r.ruptures,
            repins: r.repins,
        };
        self.write(self.fast_forward, r.end_time, &msg.encode_to_vec())
    }

    /// Closes the file; a fast-forwarded run adds its totals as the
    /// `slipfront_fast_forward` metadata record.
    pub fn finish(
        mut self,
        fast_forward: Option<&crate::engines::quasistatic::FastForwardStats>,
    ) -> Result<(), OutputError> {
        if let Some(f) = fast_forward {
            let mut meta = BTreeMap::new();
            meta.insert("jumps".into(), f.jumps.to_string());
            meta.insert("skipped_steps".into(), f.skipped_steps.to_string());
            meta.insert("skipped_time".into(), format!("{:e}", f.skipped_time));
            meta.insert("dropped_energy".into(), format!("{:e}", f.dropped_energy));
            self.writer.write_metadata(&mcap::records::Metadata {
                name: "slipfront_fast_forward".into(),
                metadata: meta,
            })?;
        }
        self.writer.finish()?;
        Ok(())
    }
}

/// FNV-1a 64-bit hash (scenario fingerprint).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}
