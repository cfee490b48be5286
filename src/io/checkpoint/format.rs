//! The checkpoint file, byte by byte (docs/checkpoints.md):
//!
//! ```text
//! "SLIPCKPT"                 8 bytes, magic
//! version                    u32 LE (FORMAT_VERSION)
//! header length              u64 LE
//! header                     JSON (`Header`)
//! sections, in SECTIONS order, each:
//!     value count            u64 LE
//!     values                 f64 LE, or u32/i32 LE for the integer arrays
//! checksum                   u64 LE, FNV-1a 64 of every byte before it
//! ```
//!
//! Floats travel as their bits, so a state comes back exactly. The version
//! is read before anything else, so a file of another format version is
//! refused with that reason rather than misread.

use super::{Checkpoint, CheckpointError, Header};
use crate::engines::quasistatic::band::BandCholesky;
use crate::engines::EngineState;
use crate::io::output::fnv1a;

pub const MAGIC: &[u8; 8] = b"SLIPCKPT";
/// Bump on any change of the layout or of the header's meaning. Version 2
/// added `law_state`; version 1 files (no law state: every law then had
/// none) are still read.
pub const FORMAT_VERSION: u32 = 2;
const FIRST_READ_VERSION: u32 = 1;

/// The binary sections, in file order.
pub const SECTIONS: [&str; 12] = [
    "drive_origin",
    "disp",
    "vel",
    "force",
    "contact",
    "anchor",
    "junction_stiffness",
    "junction_state",
    "slide",
    "law_state",
    "solver_factor",
    "end",
];

fn put_u64(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_f64s<'a>(out: &mut Vec<u8>, values: impl ExactSizeIterator<Item = &'a f64>) {
    put_u64(out, values.len() as u64);
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

fn put_u32s(out: &mut Vec<u8>, values: impl ExactSizeIterator<Item = u32>) {
    put_u64(out, values.len() as u64);
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

pub fn encode(c: &Checkpoint) -> Vec<u8> {
    let header = serde_json::to_vec(&c.header).expect("the header serialises");
    let s = &c.engine;
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    put_u64(&mut out, header.len() as u64);
    out.extend_from_slice(&header);
    put_f64s(&mut out, s.drive_origin.iter());
    put_f64s(&mut out, s.disp.as_flattened().as_flattened().iter());
    put_f64s(&mut out, s.vel.as_flattened().iter());
    put_f64s(&mut out, s.force.as_flattened().iter());
    put_f64s(&mut out, s.contact.as_flattened().iter());
    put_f64s(&mut out, s.anchor.as_flattened().iter());
    put_f64s(&mut out, s.junction_stiffness.iter());
    put_u32s(&mut out, s.junction_state.as_flattened().iter().copied());
    put_u32s(&mut out, s.slide.as_flattened().iter().map(|&v| v as u32));
    put_f64s(&mut out, s.law_state.as_flattened().iter());
    let factor = c
        .header
        .runner
        .fast_forward
        .as_ref()
        .and_then(|f| f.factor.as_ref())
        .map_or(&[][..], |f| f.parts().2);
    put_f64s(&mut out, factor.iter());
    put_u64(&mut out, 0);
    let sum = fnv1a(&out);
    put_u64(&mut out, sum);
    out
}

/// Reads sections off the bytes after the header.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| format!("the {what} section runs past the end of the file"))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        let b = self.take(8, what)?;
        Ok(u64::from_le_bytes(b.try_into().expect("8 bytes")))
    }

    /// A section of `width`-byte values, checked against `expected` values
    /// when known.
    fn section(
        &mut self,
        what: &str,
        width: usize,
        expected: Option<usize>,
    ) -> Result<&'a [u8], String> {
        let n = self.u64(what)? as usize;
        if let Some(e) = expected.filter(|&e| e != n) {
            return Err(format!(
                "the {what} section holds {n} values, the header implies {e}"
            ));
        }
        let bytes = n
            .checked_mul(width)
            .ok_or_else(|| format!("the {what} section's length {n} is impossible"))?;
        self.take(bytes, what)
    }

    fn f64s(&mut self, what: &str, expected: Option<usize>) -> Result<Vec<f64>, String> {
        Ok(self
            .section(what, 8, expected)?
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect())
    }

    fn u32s(&mut self, what: &str, expected: Option<usize>) -> Result<Vec<u32>, String> {
        Ok(self
            .section(what, 4, expected)?
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
            .collect())
    }
}

fn pairs<T: Copy>(v: Vec<T>) -> Vec<[T; 2]> {
    v.chunks_exact(2).map(|c| [c[0], c[1]]).collect()
}

pub fn decode(bytes: &[u8]) -> Result<Checkpoint, CheckpointError> {
    let damaged = |why: String| CheckpointError::Damaged(why);
    if bytes.len() < 8 || &bytes[..8] != MAGIC {
        return Err(CheckpointError::NotACheckpoint);
    }
    if bytes.len() < 12 {
        return Err(damaged(format!("it is cut short ({} bytes)", bytes.len())));
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if !(FIRST_READ_VERSION..=FORMAT_VERSION).contains(&version) {
        return Err(CheckpointError::Version(version));
    }
    if bytes.len() < 12 + 8 + 8 {
        return Err(damaged(format!("it is cut short ({} bytes)", bytes.len())));
    }
    let (body, tail) = bytes.split_at(bytes.len() - 8);
    let stored = u64::from_le_bytes(tail.try_into().expect("8 bytes"));
    if fnv1a(body) != stored {
        return Err(damaged(
            "its checksum does not match its content (cut short or overwritten)".into(),
        ));
    }
    let mut c = Cursor {
        bytes: body,
        at: 12,
    };
    let header_len = c.u64("header").map_err(damaged)? as usize;
    let header: Header = serde_json::from_slice(c.take(header_len, "header").map_err(damaged)?)
        .map_err(|e| damaged(format!("its header does not parse: {e}")))?;
    let (n, nx, nj) = (header.blocks, header.nx, header.junctions);
    let read = |c: &mut Cursor| -> Result<(EngineState, Vec<f64>), String> {
        let drive_origin = c.f64s("drive_origin", Some(2))?;
        let disp = c.f64s("disp", Some(4 * n))?;
        let state = EngineState {
            precision: header.precision.clone(),
            step: header.step,
            drive_origin: [drive_origin[0], drive_origin[1]],
            disp: disp
                .chunks_exact(4)
                .map(|c| [[c[0], c[1]], [c[2], c[3]]])
                .collect(),
            vel: pairs(c.f64s("vel", Some(2 * n))?),
            force: pairs(c.f64s("force", Some(2 * n))?),
            contact: pairs(c.f64s("contact", Some(2 * nx))?),
            anchor: pairs(c.f64s("anchor", Some(2 * nj))?),
            junction_stiffness: c.f64s("junction_stiffness", Some(nj))?,
            junction_state: pairs(c.u32s("junction_state", Some(2 * nj))?),
            slide: pairs(
                c.u32s("slide", Some(2 * nx))?
                    .into_iter()
                    .map(|v| v as i32)
                    .collect(),
            ),
            law_state: if version >= 2 {
                pairs(c.f64s("law_state", None)?)
            } else {
                Vec::new()
            },
        };
        let factor = c.f64s("solver_factor", None)?;
        if c.u64("end")? != 0 || c.at != c.bytes.len() {
            return Err("it has bytes after its last section".into());
        }
        Ok((state, factor))
    };
    let (engine, factor) = read(&mut c).map_err(damaged)?;
    let mut header = header;
    let solver_factor = match header.solver_factor_shape {
        Some((size, band)) => Some(
            BandCholesky::from_parts(size, band, factor)
                .ok_or_else(|| damaged("its solver factor does not fit its stated shape".into()))?,
        ),
        None => None,
    };
    if let Some(ff) = header.runner.fast_forward.as_mut() {
        ff.factor = solver_factor;
    }
    Ok(Checkpoint { header, engine })
}
