//! Rewriting a run file that was cut short (a killed run, a full disk)
//! with its summary and footer, so that any MCAP reader, not only one that
//! reads from the start, opens it.

use super::scan::{scan, Ending, Flow};
use super::{ChunkCompression, OutputError};
use mcap::records::Record;
use std::collections::{BTreeMap, HashMap};
use std::io::BufWriter;
use std::path::Path;

/// What a recovery kept.
#[derive(Debug, Clone, PartialEq)]
pub struct Recovered {
    pub messages: u64,
    /// Time of the last message kept (s), if any.
    pub last_time: Option<f64>,
    /// How the original ended.
    pub ending: Ending,
}

/// Copies every readable record of `cut` into a new complete MCAP file at
/// `out` (schemas, channels, messages with their sequence numbers and
/// times, metadata, attachments), closed with a summary.
pub fn rewrite(cut: &Path, out: &Path) -> Result<Recovered, OutputError> {
    let fail = |why: String| OutputError::Read {
        path: cut.display().to_string(),
        why,
    };
    let file = std::fs::File::create(out).map_err(|source| OutputError::Create {
        path: out.display().to_string(),
        source,
    })?;
    let mut writer = super::write_options(super::ChunkLayout::of(ChunkCompression::Zstd))
        .create(BufWriter::new(file))?;
    let mut schemas: HashMap<u16, u16> = HashMap::new();
    let mut channels: HashMap<u16, u16> = HashMap::new();
    let mut messages = 0u64;
    let mut last_time = None;
    let mut a_run = false;
    let ending = scan(cut, fail, |record| {
        match record {
            Record::Schema { header, data } => {
                let id = writer.add_schema(&header.name, &header.encoding, &data)?;
                schemas.insert(header.id, id);
            }
            Record::Channel(c) => {
                let schema = *schemas.get(&c.schema_id).unwrap_or(&0);
                let metadata: BTreeMap<String, String> = c.metadata;
                let id = writer.add_channel(schema, &c.topic, &c.message_encoding, &metadata)?;
                channels.insert(c.id, id);
            }
            Record::Message { header, data } => {
                if let Some(&channel_id) = channels.get(&header.channel_id) {
                    writer.write_to_known_channel(
                        &mcap::records::MessageHeader {
                            channel_id,
                            ..header
                        },
                        &data,
                    )?;
                    messages += 1;
                    last_time = Some(header.log_time as f64 * 1e-9);
                }
            }
            Record::Metadata(m) => {
                a_run |= m.name == "slipfront";
                writer.write_metadata(&m)?
            }
            Record::Attachment { header, data, .. } => writer.attach(&mcap::Attachment {
                log_time: header.log_time,
                create_time: header.create_time,
                name: header.name,
                media_type: header.media_type,
                data,
            })?,
            _ => {}
        }
        Ok(Flow::Continue)
    })?;
    // Without its metadata record no reader takes the file for a run:
    // nothing is written rather than a file `info` would refuse.
    if !a_run {
        return Err(fail(
            "nothing of a slipfront run survives in it (no `slipfront` metadata record before \
             the cut or the damage): nothing to recover"
                .into(),
        ));
    }
    writer.finish()?;
    Ok(Recovered {
        messages,
        last_time,
        ending,
    })
}
