//! Reading an MCAP file record by record from disk, chunks decompressed as
//! a stream: the file is never held in memory, no length field becomes an
//! allocation larger than [`RECORD_LIMIT`], and a file cut short (a killed
//! run) or damaged yields every record before the cut.
//!
//! (The mcap crate's readers either need the whole file in memory or, given
//! a chunk whose stated uncompressed size exceeds its data, loop forever.)

use mcap::records::Record;
use std::io::{BufReader, Read};
use std::path::Path;

/// The longest record a run file may hold (bytes): the writer's chunks are
/// 1 MiB, an attachment is a scenario. A longer length field is damage.
pub const RECORD_LIMIT: u64 = 256 << 20;

const OP_FOOTER: u8 = 0x02;
const OP_CHUNK: u8 = 0x06;

/// How a scan ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Ending {
    /// The footer was read: the file is complete.
    Complete,
    /// The file ends before its footer (a killed run).
    CutShort,
    /// A record could not be read; the reason.
    Damaged(String),
}

/// Whether to go on after a record.
pub enum Flow {
    Continue,
    Stop,
}

/// Calls `each` with every record of the MCAP file at `path` in order,
/// the records inside chunks flattened, until the footer, the end of the
/// file, damage, or `Flow::Stop`. Errors of `each` are returned as they
/// are; failing to open the file or a missing magic is an `Err(why)` from
/// `io`.
pub fn scan<E>(
    path: &Path,
    io: impl Fn(String) -> E,
    mut each: impl FnMut(Record<'_>) -> Result<Flow, E>,
) -> Result<Ending, E> {
    let file = std::fs::File::open(path).map_err(|e| io(e.to_string()))?;
    let size = file.metadata().map_err(|e| io(e.to_string()))?.len();
    let mut r = BufReader::with_capacity(1 << 16, file);
    let mut magic = [0u8; 8];
    if r.read_exact(&mut magic).is_err() || !magic.starts_with(mcap::MAGIC) {
        return Err(io(format!(
            "not an MCAP file ({size} bytes, no MCAP magic at the start)"
        )));
    }
    let mut body = Vec::new();
    loop {
        let Some((opcode, len)) = (match header(&mut r) {
            Ok(h) => h,
            Err(_) => return Ok(Ending::CutShort),
        }) else {
            return Ok(Ending::CutShort);
        };
        if len > RECORD_LIMIT {
            return Ok(Ending::Damaged(format!(
                "record of {len} bytes (opcode {opcode:#04x}), more than {RECORD_LIMIT}"
            )));
        }
        if opcode == OP_CHUNK {
            match chunk(&mut r, len, &mut each)? {
                Some(Flow::Stop) => return Ok(Ending::Complete),
                Some(Flow::Continue) => continue,
                None => return Ok(Ending::CutShort),
            }
        }
        body.clear();
        if (&mut r).take(len).read_to_end(&mut body).is_err() || body.len() as u64 != len {
            return Ok(Ending::CutShort);
        }
        if opcode == OP_FOOTER {
            return Ok(Ending::Complete);
        }
        match mcap::parse_record(opcode, &body) {
            Ok(record) => {
                if let Flow::Stop = each(record)? {
                    return Ok(Ending::Complete);
                }
            }
            Err(e) => return Ok(Ending::Damaged(format!("opcode {opcode:#04x}: {e}"))),
        }
    }
}

/// Opcode and length of the next record; None at a clean end of file.
fn header(r: &mut impl Read) -> std::io::Result<Option<(u8, u64)>> {
    let mut h = [0u8; 9];
    let mut got = 0;
    while got < h.len() {
        match r.read(&mut h[got..])? {
            0 if got == 0 => return Ok(None),
            0 => return Err(std::io::ErrorKind::UnexpectedEof.into()),
            n => got += n,
        }
    }
    Ok(Some((
        h[0],
        u64::from_le_bytes(h[1..].try_into().expect("8 bytes")),
    )))
}

/// Reads a chunk record of `len` bytes and passes its records to `each`.
/// None when the chunk is cut short or damaged (the records before that
/// have been passed on).
fn chunk<E>(
    r: &mut impl Read,
    len: u64,
    each: &mut impl FnMut(Record<'_>) -> Result<Flow, E>,
) -> Result<Option<Flow>, E> {
    let mut chunk = r.take(len);
    // start time, end time, uncompressed size (u64 each), CRC (u32),
    // compression name length (u32).
    let mut fixed = [0u8; 32];
    if chunk.read_exact(&mut fixed).is_err() {
        return Ok(None);
    }
    let uncompressed = u64::from_le_bytes(fixed[16..24].try_into().expect("8 bytes"));
    let name_len = u32::from_le_bytes(fixed[28..32].try_into().expect("4 bytes")) as u64;
    if name_len > 64 || uncompressed > RECORD_LIMIT {
        return Ok(None);
    }
    let mut name = vec![0u8; name_len as usize];
    let mut records_len = [0u8; 8];
    if chunk.read_exact(&mut name).is_err() || chunk.read_exact(&mut records_len).is_err() {
        return Ok(None);
    }
    let records_len = u64::from_le_bytes(records_len);
    {
        let compressed = (&mut chunk).take(records_len);
        let decoded: Box<dyn Read + '_> = match name.as_slice() {
            b"" => Box::new(compressed),
            b"zstd" => match zstd::stream::read::Decoder::new(compressed) {
                Ok(d) => Box::new(d),
                Err(_) => return Ok(None),
            },
            _ => return Ok(None),
        };
        // The records, never more than the chunk says it holds.
        let mut inner = decoded.take(uncompressed);
        let mut body = Vec::new();
        loop {
            let (opcode, len) = match header(&mut inner) {
                Ok(Some(h)) => h,
                Ok(None) => break,
                Err(_) => return Ok(None),
            };
            if len > RECORD_LIMIT {
                return Ok(None);
            }
            body.clear();
            if (&mut inner).take(len).read_to_end(&mut body).is_err() || body.len() as u64 != len {
                return Ok(None);
            }
            match mcap::parse_record(opcode, &body) {
                Ok(record) => {
                    if let Flow::Stop = each(record)? {
                        return Ok(Some(Flow::Stop));
                    }
                }
                Err(_) => return Ok(None),
            }
        }
    }
    // Padding after the records, up to the chunk's end.
    if std::io::copy(&mut chunk, &mut std::io::sink()).is_err() || chunk.limit() != 0 {
        return Ok(None);
    }
    Ok(Some(Flow::Continue))
}
