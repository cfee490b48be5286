//! The protobuf bytes of the channels with large arrays (`/interface`,
//! `/bulk`), written with each packed array copied whole. prost writes a
//! packed `double` or `float` one value at a time, each with its own
//! bounds check: at 1024 columns that was most of the runner's cost of a
//! sample (`cargo bench --bench output_writer`, BENCHMARKS.md session 51).
//! The bytes are prost's to the byte (tests below): proto3 leaves out a
//! zero scalar and an empty array, and writes the fields in tag order.

use super::messages::{Bulk, Interface};

/// Wire types of the fields written here.
const WIRE_VARINT: u64 = 0;
const WIRE_FIXED64: u64 = 1;
const WIRE_LENGTH_DELIMITED: u64 = 2;

/// `/interface`'s bytes, as `Interface::encode_to_vec` gives them.
pub fn encode_interface(m: &Interface) -> Vec<u8> {
    let arrays = [
        (3, &m.shear_stress),
        (4, &m.normal_stress),
        (5, &m.pinned_fraction),
        (6, &m.slip),
        (7, &m.slip_speed),
    ];
    let mut out =
        Vec::with_capacity(24 + arrays.iter().map(|(_, v)| 12 + 8 * v.len()).sum::<usize>());
    put_double(&mut out, 1, m.time);
    put_uint(&mut out, 2, m.step);
    for (tag, values) in arrays {
        put_packed(&mut out, tag, values);
    }
    out
}

/// `/bulk`'s bytes, as `Bulk::encode_to_vec` gives them.
pub fn encode_bulk(m: &Bulk) -> Vec<u8> {
    let arrays = [(5, &m.ux), (6, &m.uz), (7, &m.vx), (8, &m.vz)];
    let mut out =
        Vec::with_capacity(40 + arrays.iter().map(|(_, v)| 12 + 4 * v.len()).sum::<usize>());
    put_double(&mut out, 1, m.time);
    put_uint(&mut out, 2, m.step);
    put_uint(&mut out, 3, m.nx as u64);
    put_uint(&mut out, 4, m.nz as u64);
    for (tag, values) in arrays {
        put_packed(&mut out, tag, values);
    }
    out
}

fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8 & 0x7f) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

fn put_key(out: &mut Vec<u8>, tag: u64, wire: u64) {
    put_varint(out, tag << 3 | wire);
}

/// A `double` field, left out when zero (as proto3 and prost do: −0.0
/// too, and a NaN is written).
fn put_double(out: &mut Vec<u8>, tag: u64, v: f64) {
    if v != 0.0 {
        put_key(out, tag, WIRE_FIXED64);
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// An unsigned integer field, left out when zero.
fn put_uint(out: &mut Vec<u8>, tag: u64, v: u64) {
    if v != 0 {
        put_key(out, tag, WIRE_VARINT);
        put_varint(out, v);
    }
}

/// A packed array of fixed-width values, left out when empty: the wire
/// bytes are the values' little-endian bytes, on a little-endian machine
/// their memory, copied at once.
fn put_packed<T: bytemuck::Pod>(out: &mut Vec<u8>, tag: u64, values: &[T]) {
    if values.is_empty() {
        return;
    }
    let bytes: &[u8] = bytemuck::cast_slice(values);
    put_key(out, tag, WIRE_LENGTH_DELIMITED);
    put_varint(out, bytes.len() as u64);
    if cfg!(target_endian = "little") {
        out.extend_from_slice(bytes);
    } else {
        for value in bytes.chunks_exact(size_of::<T>()) {
            out.extend(value.iter().rev());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use prost::Message;

    /// Values with the edge cases of the wire format: zero and −0.0 (left
    /// out as scalars), NaN and infinities, subnormals, and lengths whose
    /// varint takes one, two and three bytes.
    fn values(n: usize, seed: u64) -> Vec<f64> {
        let specials = [0.0, -0.0, f64::NAN, f64::INFINITY, -f64::MIN_POSITIVE / 4.0];
        (0..n)
            .map(|i| match i % 7 {
                0 => specials[(i / 7 + seed as usize) % specials.len()],
                k => (seed as f64 + i as f64) * 1.37e-3 * if k % 2 == 0 { 1.0 } else { -1.0 },
            })
            .collect()
    }

    fn interface(n: usize, time: f64, step: u64) -> Interface {
        Interface {
            time,
            step,
            shear_stress: values(n, 1),
            normal_stress: values(n, 2),
            pinned_fraction: values(n / 2, 3),
            slip: values(n, 4),
            slip_speed: values(if n > 0 { n + 3 } else { 0 }, 5),
        }
    }

    #[test]
    fn interface_bytes_are_prosts() {
        for (n, time, step) in [
            (0, 0.0, 0),
            (1, -0.0, 1),
            (15, 2.5e-3, 127),
            (16, f64::NAN, 128),
            (1024, 1.0, 1 << 40),
            (2049, 3.0, u64::MAX),
        ] {
            let m = interface(n, time, step);
            assert_eq!(encode_interface(&m), m.encode_to_vec(), "{n} columns");
        }
    }

    #[test]
    fn bulk_bytes_are_prosts() {
        for (nx, nz, time, step) in [
            (0, 0, 0.0, 0),
            (3, 2, 1e-4, 7),
            (57, 31, -2.0, 300),
            (1024, 64, 1.0, 1 << 33),
        ] {
            let f = |seed| values(nx * nz, seed).iter().map(|&v| v as f32).collect();
            let m = Bulk {
                time,
                step,
                nx: nx as u32,
                nz: nz as u32,
                ux: f(1),
                uz: f(2),
                vx: f(3),
                vz: f(4),
            };
            assert_eq!(encode_bulk(&m), m.encode_to_vec(), "{nx}×{nz}");
        }
    }

    /// The comparison can fail: one value changed changes the bytes.
    #[test]
    fn a_changed_value_changes_the_bytes() {
        let m = interface(64, 1.0, 5);
        let mut other = m.clone();
        other.slip[17] = f64::from_bits(other.slip[17].to_bits() ^ 1);
        assert_ne!(encode_interface(&other), m.encode_to_vec());
    }
}
