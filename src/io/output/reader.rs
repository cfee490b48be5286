//! Reading a run back: metadata, the scenario, and every channel decoded.
//! Reads record by record, so a file cut short by a killed run yields
//! everything up to its last complete chunk.

use super::messages::{Bulk, FastForwardJump, Global, Interface};
use super::records::{Record as ChannelRecord, Topic};
use super::scan::{scan, Ending, Flow};
use super::OutputError;
use crate::analysis::events::InterfaceSeries;
use mcap::records::Record;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// A run file, decoded.
#[derive(Debug, Default, Clone)]
pub struct RunFile {
    pub metadata: BTreeMap<String, String>,
    pub scenario: Option<String>,
    pub global: Vec<Global>,
    pub interface: Vec<Interface>,
    pub bulk: Vec<Bulk>,
    /// Quasi-static jumps (fast-forwarded runs).
    pub fast_forward: Vec<FastForwardJump>,
    /// Totals of the fast-forward (`slipfront_fast_forward` metadata).
    pub fast_forward_totals: BTreeMap<String, String>,
    /// One line per start, resume and branch (`slipfront_history`).
    pub history: Vec<String>,
    /// The file ended before its summary (the run was killed), or was
    /// damaged (below).
    pub truncated: bool,
    /// Why the read stopped early, where a record or chunk was damaged
    /// (a chunk failing its CRC: which, and the time range lost).
    pub damage: Option<String>,
}

/// Where a read puts the messages of the channels: [`RunFile`] keeps them
/// decoded message by message ([`Messages`]); a columnar reader (the Python
/// package's) can decode them straight into its columns.
pub trait ChannelSink {
    /// One message of `topic`, its protobuf bytes; an error is why it does
    /// not decode. (Channels of other names are not read.)
    fn message(&mut self, topic: Topic, data: &[u8]) -> Result<(), String>;
    /// After the last message: every /interface row as long as the
    /// interface (`nx` blocks when the metadata says), and no channel's
    /// time going backwards. A file that breaks either is damaged.
    fn check(&self, nx: Option<usize>) -> Result<(), String>;
}

/// The channels' messages, decoded.
#[derive(Debug, Default, Clone)]
pub struct Messages {
    pub global: Vec<Global>,
    pub interface: Vec<Interface>,
    pub bulk: Vec<Bulk>,
    pub fast_forward: Vec<FastForwardJump>,
}

impl ChannelSink for Messages {
    fn message(&mut self, topic: Topic, data: &[u8]) -> Result<(), String> {
        match ChannelRecord::decode(topic, data).map_err(|e| e.to_string())? {
            ChannelRecord::Global(m) => self.global.push(m),
            ChannelRecord::Interface(m) => self.interface.push(m),
            ChannelRecord::Bulk(m) => self.bulk.push(m),
            ChannelRecord::FastForward(m) => self.fast_forward.push(m),
        }
        Ok(())
    }

    fn check(&self, nx: Option<usize>) -> Result<(), String> {
        let nx = nx.or_else(|| self.interface.first().map(|m| m.pinned_fraction.len()));
        for (k, m) in self.interface.iter().enumerate() {
            let lengths = [
                m.shear_stress.len(),
                m.normal_stress.len(),
                m.pinned_fraction.len(),
                m.slip.len(),
                m.slip_speed.len(),
            ];
            if let Some(nx) = nx.filter(|&nx| lengths.iter().any(|&l| l != nx)) {
                return Err(format!(
                    "damaged: /interface message {k} (t = {:e} s) has rows of lengths \
                     {lengths:?}, the interface has {nx} blocks",
                    m.time
                ));
            }
        }
        times_go_forward("/global", self.global.iter().map(|m| m.time))?;
        times_go_forward("/interface", self.interface.iter().map(|m| m.time))?;
        times_go_forward("/bulk", self.bulk.iter().map(|m| m.time))
    }
}

/// Err naming the first message of channel `name` whose time is not
/// finite or is before the one before it.
pub fn times_go_forward(name: &str, times: impl Iterator<Item = f64>) -> Result<(), String> {
    let mut last = f64::NEG_INFINITY;
    for (k, t) in times.enumerate() {
        if !t.is_finite() || t < last {
            return Err(format!(
                "damaged: {name} message {k} is at t = {t:e} s, after one at {last:e} s"
            ));
        }
        last = t;
    }
    Ok(())
}

const GIB: f64 = (1u64 << 30) as f64;

/// How many bytes of decoded messages a read may hold: SLIPFRONT_READ_MEMORY
/// if set, else half the memory available now (the analysis copies the
/// interface rows once more).
pub fn memory_budget() -> u64 {
    if let Some(v) = std::env::var("SLIPFRONT_READ_MEMORY")
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|v| *v > 0.0)
    {
        return v as u64;
    }
    crate::engines::memory::available_bytes().map_or(8 << 30, |b| b / 2)
}

impl RunFile {
    /// The run file's `slipfront` metadata and scenario text, read from its
    /// head only (they are written before any message): what a resume
    /// checks its checkpoint against.
    pub fn read_head(
        path: &Path,
    ) -> Result<(BTreeMap<String, String>, Option<String>), OutputError> {
        let fail = |why: String| OutputError::Read {
            path: path.display().to_string(),
            why,
        };
        let (mut metadata, mut scenario) = (BTreeMap::new(), None);
        scan(path, fail, |record| {
            match record {
                Record::Metadata(m) if m.name == "slipfront" => metadata = m.metadata,
                Record::Attachment { header, data, .. } if header.name == "scenario.toml" => {
                    scenario = Some(String::from_utf8_lossy(&data).into_owned());
                    return Ok(Flow::Stop);
                }
                Record::Message { .. } => return Ok(Flow::Stop),
                _ => {}
            }
            Ok(Flow::Continue)
        })?;
        Ok((metadata, scenario))
    }

    pub fn read(path: &Path) -> Result<RunFile, OutputError> {
        RunFile::read_within(path, memory_budget())
    }

    /// Reads `path` record by record from disk ([`super::scan`]), stopping
    /// with an error once the decoded messages would pass `budget` bytes.
    pub fn read_within(path: &Path, budget: u64) -> Result<RunFile, OutputError> {
        let mut messages = Messages::default();
        let mut run = RunFile::read_with(path, budget, &mut messages)?;
        run.global = messages.global;
        run.interface = messages.interface;
        run.bulk = messages.bulk;
        run.fast_forward = messages.fast_forward;
        Ok(run)
    }

    /// Reads `path` as [`RunFile::read_within`] does, its channels' messages
    /// going to `sink`: the RunFile returned holds the rest (metadata,
    /// scenario, history, whether the file was cut short or damaged).
    pub fn read_with(
        path: &Path,
        budget: u64,
        sink: &mut dyn ChannelSink,
    ) -> Result<RunFile, OutputError> {
        let fail = |why: String| OutputError::Read {
            path: path.display().to_string(),
            why,
        };
        let size = std::fs::metadata(path).map_err(|e| fail(e.to_string()))?;
        if !size.is_file() {
            return Err(fail("not a regular file".into()));
        }
        let mut run = RunFile::default();
        let mut topics: HashMap<u16, Topic> = HashMap::new();
        let mut saw_slipfront = false;
        let mut decoded: u64 = 0;
        let ending = scan(path, fail, |record| {
            match record {
                Record::Channel(c) => {
                    if let Some(topic) = Topic::from_name(&c.topic) {
                        topics.insert(c.id, topic);
                    }
                }
                Record::Metadata(m) if m.name == "slipfront" => {
                    saw_slipfront = true;
                    run.metadata = m.metadata
                }
                Record::Metadata(m) if m.name == "slipfront_history" => {
                    run.history = m.metadata.into_values().collect()
                }
                Record::Metadata(m) if m.name == "slipfront_fast_forward" => {
                    run.fast_forward_totals = m.metadata
                }
                Record::Attachment { header, data, .. } if header.name == "scenario.toml" => {
                    run.scenario = Some(String::from_utf8_lossy(&data).into_owned())
                }
                Record::Message { header, data } => {
                    // Decoded, a message takes about as many bytes as it
                    // has on disk, plus its vectors' headers.
                    decoded += data.len() as u64 + 128;
                    if decoded > budget {
                        return Err(fail(format!(
                            "its messages need more than {:.2} GiB of memory once decoded, \
                             the most this machine can give now ({} bytes on disk); set \
                             SLIPFRONT_READ_MEMORY=BYTES to allow more",
                            budget as f64 / GIB,
                            size.len()
                        )));
                    }
                    if let Some(&topic) = topics.get(&header.channel_id) {
                        sink.message(topic, &data)
                            .map_err(|e| fail(format!("message {}: {e}", header.sequence)))?;
                    }
                }
                _ => {}
            }
            Ok(Flow::Continue)
        })?;
        let saw_footer = ending == Ending::Complete;
        run.truncated |= !saw_footer;
        if let Ending::Damaged(why) = ending {
            run.damage = Some(why);
        }
        if !saw_slipfront {
            return Err(fail(
                "not a slipfront run file (an MCAP file without the `slipfront` metadata \
                 record)"
                    .into(),
            ));
        }
        let nx = run.metadata.get("nx").and_then(|v| v.parse::<usize>().ok());
        sink.check(nx).map_err(fail)?;
        Ok(run)
    }

    /// F/F_N of the global sample nearest to time `t` (NaN without one).
    pub fn drive_ratio_at(&self, t: f64) -> f64 {
        let k = self.global.partition_point(|g| g.time < t);
        [k.checked_sub(1), Some(k)]
            .into_iter()
            .flatten()
            .filter_map(|i| self.global.get(i))
            .min_by(|a, b| (a.time - t).abs().total_cmp(&(b.time - t).abs()))
            .map_or(f64::NAN, |g| g.drive_ratio)
    }

    /// Lattice spacing from the metadata (m).
    pub fn spacing(&self) -> f64 {
        self.metadata
            .get("spacing")
            .and_then(|s| s.parse().ok())
            .unwrap_or(1.0)
    }

    /// The interface channel as a series for the event analysis.
    pub fn interface_series(&self) -> InterfaceSeries {
        InterfaceSeries {
            time: self.interface.iter().map(|m| m.time).collect(),
            spacing: self.spacing(),
            pinned: self
                .interface
                .iter()
                .map(|m| m.pinned_fraction.clone())
                .collect(),
            slip: self.interface.iter().map(|m| m.slip.clone()).collect(),
            slip_speed: self
                .interface
                .iter()
                .map(|m| m.slip_speed.clone())
                .collect(),
        }
    }
}
