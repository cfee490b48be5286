//! Reading an MCAP file record by record from disk: the file is never held
//! in memory (one chunk at a time, `CHUNK_BYTES` as written), no length field
//! becomes an allocation larger than [`RECORD_LIMIT`], a file cut short (a
//! killed run) yields every record before the cut, and a chunk whose
//! records fail their CRC (or do not decompress or parse) is skipped and
//! reported, the chunks after it kept.
//!
//! (The mcap crate's readers either need the whole file in memory or, given
//! a chunk whose stated uncompressed size exceeds its data, loop forever.)

use mcap::records::Record;
use std::io::{BufReader, Read};
use std::path::Path;

/// The longest record a run file may hold (bytes): the writer's chunks are
/// `CHUNK_BYTES` (8 MiB), an attachment is a scenario. A longer length
/// field is damage.
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
    let mut chunks = 0u64;
    // Chunks that are all there but do not read are skipped (their records
    // lost, the later ones kept) and reported in the ending.
    let mut damaged: Vec<String> = Vec::new();
    let ending = loop {
        let Some((opcode, len)) = (match header(&mut r) {
            Ok(h) => h,
            Err(_) => break Ending::CutShort,
        }) else {
            break Ending::CutShort;
        };
        if opcode == OP_CHUNK && len == u64::MAX {
            // A chunk the writer had begun: its length is written when it
            // closes, so a killed run's file ends in one.
            break Ending::CutShort;
        }
        if len > RECORD_LIMIT {
            break Ending::Damaged(format!(
                "record of {len} bytes (opcode {opcode:#04x}), more than {RECORD_LIMIT}"
            ));
        }
        if opcode == OP_CHUNK {
            chunks += 1;
            match chunk(&mut r, len, chunks, &mut each)? {
                ChunkEnd::Read(Flow::Stop) => break Ending::Complete,
                ChunkEnd::Read(Flow::Continue) => continue,
                ChunkEnd::Cut => break Ending::CutShort,
                ChunkEnd::Damaged(why) => {
                    damaged.push(why);
                    continue;
                }
            }
        }
        body.clear();
        if (&mut r).take(len).read_to_end(&mut body).is_err() || body.len() as u64 != len {
            break Ending::CutShort;
        }
        if opcode == OP_FOOTER {
            // Complete only with the closing magic whole and nothing after
            // it: a file cut inside its last 8 bytes is unreadable to
            // other readers.
            let mut tail = Vec::new();
            if r.read_to_end(&mut tail).is_err() || tail != mcap::MAGIC {
                break Ending::CutShort;
            }
            break Ending::Complete;
        }
        match mcap::parse_record(opcode, &body) {
            Ok(record) => {
                if let Flow::Stop = each(record)? {
                    break Ending::Complete;
                }
            }
            Err(e) => break Ending::Damaged(format!("opcode {opcode:#04x}: {e}")),
        }
    };
    Ok(match (damaged.first(), ending) {
        (None, ending) => ending,
        (Some(first), ending) => Ending::Damaged(format!(
            "{} damaged chunk(s), their records lost and the rest kept; the first: {first}{}",
            damaged.len(),
            match ending {
                Ending::Damaged(then) => format!("; then: {then}"),
                Ending::CutShort => "; then the file is cut short".to_string(),
                Ending::Complete => String::new(),
            }
        )),
    })
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

/// How reading one chunk ended.
enum ChunkEnd {
    /// Its records were passed on; what `each` said last.
    Read(Flow),
    /// The file ends inside it (the records before were passed on).
    Cut,
    /// It is all there but does not read: its CRC fails, it does not
    /// decompress, or a record in it is malformed. None of its records is
    /// passed on (damaged data is neither read nor rewritten).
    Damaged(String),
}

/// Reads chunk number `index`, a record of `len` bytes, and, if it is whole
/// and its records match their CRC (when the writer stored one), passes
/// them to `each`.
fn chunk<E>(
    r: &mut impl Read,
    len: u64,
    index: u64,
    each: &mut impl FnMut(Record<'_>) -> Result<Flow, E>,
) -> Result<ChunkEnd, E> {
    // The record whole first (len ≤ RECORD_LIMIT; the writer's chunks are
    // `CHUNK_BYTES`): a chunk the file ends inside is a cut, one that is all there
    // but does not read is damage.
    let mut raw = Vec::new();
    if r.take(len).read_to_end(&mut raw).is_err() || (raw.len() as u64) < len {
        // Cut inside the chunk: no CRC to check, so every whole record
        // that decompresses before the cut is passed on, as a reader of a
        // killed run expects.
        let records = cut_chunk_records(&raw);
        let (spans, _) = record_spans(&records);
        if let Some(stop) = pass_on(&records, &spans, each)? {
            return Ok(stop);
        }
        return Ok(ChunkEnd::Cut);
    }
    match chunk_records(&raw) {
        Ok((records, spans)) => {
            Ok(pass_on(&records, &spans, each)?.unwrap_or(ChunkEnd::Read(Flow::Continue)))
        }
        Err(why) => Ok(ChunkEnd::Damaged(format!("chunk {index} {why}"))),
    }
}

/// Where the records of a chunk's decompressed bytes lie: (opcode, byte
/// range of its body) of each whole record that parses, in order, up to the
/// first that does not; and whether every byte was such a record.
fn record_spans(records: &[u8]) -> (Vec<(u8, std::ops::Range<usize>)>, bool) {
    let mut spans = Vec::new();
    let mut at = 0;
    while at < records.len() {
        let mut inner = &records[at..];
        let Ok(Some((opcode, len))) = header(&mut inner) else {
            return (spans, false);
        };
        let body = at + 9;
        if len > (records.len() - body) as u64 {
            return (spans, false);
        }
        let end = body + len as usize;
        if mcap::parse_record(opcode, &records[body..end]).is_err() {
            return (spans, false);
        }
        spans.push((opcode, body..end));
        at = end;
    }
    (spans, true)
}

/// Passes the records at `spans` to `each`; `Some` if it said stop.
fn pass_on<E>(
    records: &[u8],
    spans: &[(u8, std::ops::Range<usize>)],
    each: &mut impl FnMut(Record<'_>) -> Result<Flow, E>,
) -> Result<Option<ChunkEnd>, E> {
    for (opcode, span) in spans {
        let record =
            mcap::parse_record(*opcode, &records[span.clone()]).expect("parsed by record_spans");
        if let Flow::Stop = each(record)? {
            return Ok(Some(ChunkEnd::Read(Flow::Stop)));
        }
    }
    Ok(None)
}

/// The records of a chunk cut short, decompressed as far as the data goes
/// (never more than the chunk says it holds).
fn cut_chunk_records(raw: &[u8]) -> Vec<u8> {
    let mut records = Vec::new();
    let Some(fixed) = raw.get(..32) else {
        return records;
    };
    let uncompressed = u64::from_le_bytes(fixed[16..24].try_into().expect("8 bytes"));
    let name_len = u32::from_le_bytes(fixed[28..32].try_into().expect("4 bytes")) as usize;
    if name_len > 64 || uncompressed > RECORD_LIMIT {
        return records;
    }
    let (Some(name), Some(compressed)) = (raw.get(32..32 + name_len), raw.get(40 + name_len..))
    else {
        return records;
    };
    let mut buf = [0u8; 1 << 16];
    let mut read_all = |mut decoded: Box<dyn Read + '_>| {
        let mut decoded = (&mut decoded).take(uncompressed);
        // Whatever decodes before the cut (the decoder's error at the cut
        // ends it).
        while let Ok(n) = decoded.read(&mut buf) {
            if n == 0 {
                break;
            }
            records.extend_from_slice(&buf[..n]);
        }
    };
    match name {
        b"" => read_all(Box::new(compressed)),
        b"zstd" => {
            if let Ok(d) = zstd::stream::read::Decoder::new(compressed) {
                read_all(Box::new(d))
            }
        }
        _ => {}
    }
    records
}

/// A whole chunk record's records, decompressed and checked (CRC, lengths,
/// every record parses), or why not.
#[allow(clippy::type_complexity)]
fn chunk_records(raw: &[u8]) -> Result<(Vec<u8>, Vec<(u8, std::ops::Range<usize>)>), String> {
    // start time, end time, uncompressed size (u64 each), CRC (u32),
    // compression name length (u32).
    let fixed = raw.get(..32).ok_or("is shorter than its header")?;
    let word = |k: usize| u64::from_le_bytes(fixed[k..k + 8].try_into().expect("8 bytes"));
    let (start_ns, end_ns, uncompressed) = (word(0), word(8), word(16));
    let span = format!(
        "(messages from t = {:.6e} s to {:.6e} s)",
        start_ns as f64 * 1e-9,
        end_ns as f64 * 1e-9
    );
    let stored = u32::from_le_bytes(fixed[24..28].try_into().expect("4 bytes"));
    let name_len = u32::from_le_bytes(fixed[28..32].try_into().expect("4 bytes")) as usize;
    if name_len > 64 || uncompressed > RECORD_LIMIT {
        return Err(format!("{span} has a malformed header"));
    }
    let name = raw
        .get(32..32 + name_len)
        .ok_or_else(|| format!("{span} has a malformed header"))?;
    let records_len = raw
        .get(32 + name_len..40 + name_len)
        .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
        .ok_or_else(|| format!("{span} has a malformed header"))?;
    let compressed = raw
        .get(40 + name_len..)
        .and_then(|rest| rest.get(..usize::try_from(records_len).ok()?))
        .ok_or_else(|| format!("{span}: its records run past its end"))?;
    let mut records = Vec::new();
    let decoded = match name {
        b"" => compressed.take(uncompressed).read_to_end(&mut records),
        b"zstd" => zstd::stream::read::Decoder::new(compressed)
            .and_then(|d| d.take(uncompressed).read_to_end(&mut records)),
        other => {
            return Err(format!(
                "{span}: unknown compression `{}`",
                String::from_utf8_lossy(other)
            ))
        }
    };
    if decoded.is_err() || records.len() as u64 != uncompressed {
        return Err(format!("{span} does not decompress to its stated size"));
    }
    if stored != 0 {
        let computed = crc32fast::hash(&records);
        if computed != stored {
            return Err(format!(
                "{span} fails its CRC (stored {stored:#010x}, computed {computed:#010x})"
            ));
        }
    }
    // Every record whole and parsed before any is used.
    match record_spans(&records) {
        (spans, true) => Ok((records, spans)),
        (_, false) => Err(format!("{span}: a record is cut or malformed")),
    }
}
