//! The engine's storage arrays as ranges of a few buffers (arenas), not a
//! buffer each.
//!
//! Why: wgpu tracks every buffer a dispatch binds, at every dispatch (it
//! merges each bound buffer's usage into the dispatch's scope and works
//! out its barriers), so the host's cost of encoding a dispatch grows with
//! the distinct buffers bound, not with the bindings: 0.63 µs a dispatch
//! with one buffer, 2.51 µs with 28, and 0.68 µs with 28 bindings that are
//! ranges of one buffer (`cargo bench --bench gpu_host`; lavapipe, the
//! 2-core container; BENCHMARKS.md, session 55). The one-step kernels
//! encode a dispatch a step, and on the H200 they were host-bound at
//! Table S1 (session 50). In arenas their host CPU a step halved there
//! (2.8 to 1.5 µs).
//!
//! Each arena holds arrays of one access: a buffer bound read-only in a
//! dispatch may not also be bound read-write in it (wgpu's usage rules),
//! so the read-only bindings get arenas of their own.

use super::readback::Range;
use std::num::NonZeroU64;

/// Bytes an arena holds at most: a larger array gets a buffer of its own.
/// Only small lattices' dispatches are short enough for the host's cost
/// to matter, and their arrays are far below this.
const ARENA_BYTES: u64 = 256 << 20;

/// One storage array: a range of an arena.
#[derive(Debug, Clone)]
pub(super) struct Region {
    buffer: wgpu::Buffer,
    offset: u64,
    size: u64,
}

impl Region {
    pub(super) fn size(&self) -> u64 {
        self.size
    }

    /// The array as a binding (`arrayLength` sees its own elements only).
    pub(super) fn binding(&self) -> wgpu::BindingResource<'_> {
        self.head_binding(self.size)
    }

    /// The array's first `size` bytes as a binding: one with a dynamic
    /// offset, which moves it within the rest of the array.
    pub(super) fn head_binding(&self, size: u64) -> wgpu::BindingResource<'_> {
        assert!(
            size <= self.size,
            "{size} bytes of an array of {}",
            self.size
        );
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.buffer,
            offset: self.offset,
            size: NonZeroU64::new(size),
        })
    }

    /// Bytes `at..at + size` of the array, for a copy or a readback.
    pub(super) fn range(&self, at: u64, size: u64) -> Range<'_> {
        assert!(
            at + size <= self.size,
            "bytes {at}..{} of an array of {}",
            at + size,
            self.size
        );
        Range {
            buffer: &self.buffer,
            offset: self.offset + at,
            size,
        }
    }

    /// Bytes `at..at + size` of the array as an array of its own (a
    /// binding of it starts at `at`, which must be a multiple of the
    /// adapter's storage offset alignment).
    pub(super) fn part(&self, at: u64, size: u64) -> Region {
        assert!(
            at + size <= self.size,
            "bytes {at}..{} of an array of {}",
            at + size,
            self.size
        );
        Region {
            buffer: self.buffer.clone(),
            offset: self.offset + at,
            size,
        }
    }

    /// Writes `bytes` at byte `at` of the array (in queue order).
    pub(super) fn write(&self, queue: &wgpu::Queue, at: u64, bytes: &[u8]) {
        let range = self.range(at, bytes.len() as u64);
        queue.write_buffer(range.buffer, range.offset, bytes);
    }
}

/// How the kernels bind an array: arrays of each access get arenas of
/// their own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Access {
    ReadWrite,
    ReadOnly,
}

/// Where an array will be in the arenas `Arenas::build` makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Slot(usize);

/// What an array holds at first.
enum Contents<'a> {
    Bytes(&'a [u8]),
    /// This many zero bytes (every buffer starts zeroed: wgpu's rule).
    Zeros(usize),
    /// Two copies of these bytes, the second `stride` bytes after the
    /// first, in `2 stride` bytes (written in place: no pair is built on
    /// the host).
    Twice(&'a [u8], usize),
}

impl Contents<'_> {
    fn len(&self) -> usize {
        match self {
            Contents::Bytes(b) => b.len(),
            Contents::Zeros(n) => *n,
            Contents::Twice(_, stride) => 2 * stride,
        }
    }
}

/// The engine's arrays, gathered before their arenas are made.
#[derive(Default)]
pub(super) struct Arenas<'a> {
    arrays: Vec<(Access, Contents<'a>)>,
}

impl<'a> Arenas<'a> {
    /// Adds an array with these initial bytes.
    pub(super) fn bytes(&mut self, access: Access, bytes: &'a [u8]) -> Slot {
        self.add(access, Contents::Bytes(bytes))
    }

    /// Adds an array of two copies of `bytes`, the second at `stride`
    /// (at least `bytes.len()`), `2 stride` bytes long.
    pub(super) fn twice(&mut self, access: Access, bytes: &'a [u8], stride: usize) -> Slot {
        assert!(
            stride >= bytes.len(),
            "{stride} bytes apart, {} long",
            bytes.len()
        );
        self.add(access, Contents::Twice(bytes, stride))
    }

    /// Adds an array of `len` zero bytes.
    pub(super) fn zeros(&mut self, access: Access, len: usize) -> Slot {
        self.add(access, Contents::Zeros(len))
    }

    /// An empty array gets 48 zero bytes (a whole number of every element
    /// size): a binding may not be empty.
    fn add(&mut self, access: Access, contents: Contents<'a>) -> Slot {
        let contents = match contents.len() {
            0 => Contents::Zeros(48),
            _ => contents,
        };
        self.arrays.push((access, contents));
        Slot(self.arrays.len() - 1)
    }

    /// Makes the arenas: each access's arrays in order, each at a multiple
    /// of the adapter's storage offset alignment, a new arena wherever the
    /// next array would take one past `ARENA_BYTES` (or the adapter's
    /// largest buffer). Not `packed`: an arena per array. Returns each
    /// slot's region.
    pub(super) fn build(self, device: &wgpu::Device, limits: &wgpu::Limits, packed: bool) -> Built {
        let align = u64::from(limits.min_storage_buffer_offset_alignment).max(4);
        let cap = match packed {
            true => ARENA_BYTES.min(limits.max_buffer_size),
            false => 0,
        };
        let sizes: Vec<(Access, u64)> = self
            .arrays
            .iter()
            .map(|(access, array)| (*access, array.len() as u64))
            .collect();
        let Layout { arenas, placed } = layout(&sizes, align, cap);
        let buffers: Vec<wgpu::Buffer> = arenas
            .iter()
            .enumerate()
            .map(|(k, &(access, bytes))| {
                let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(match access {
                        Access::ReadWrite => "state arena",
                        Access::ReadOnly => "read-only arena",
                    }),
                    size: bytes.next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT),
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_SRC
                        | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: true,
                });
                {
                    // Mapped at creation: as wgpu's own `create_buffer_init`.
                    let mut view = buffer
                        .get_mapped_range_mut(..)
                        .expect("a buffer mapped at creation maps");
                    let members = placed.iter().enumerate().filter(|(_, p)| p.0 == k);
                    for (i, &(_, at)) in members {
                        let at = at as usize;
                        match self.arrays[i].1 {
                            Contents::Bytes(array) => {
                                view.slice(at..at + array.len()).copy_from_slice(array);
                            }
                            Contents::Twice(array, stride) => {
                                for at in [at, at + stride] {
                                    view.slice(at..at + array.len()).copy_from_slice(array);
                                }
                            }
                            Contents::Zeros(_) => {}
                        }
                    }
                }
                buffer.unmap();
                buffer
            })
            .collect();
        let regions = self
            .arrays
            .iter()
            .zip(&placed)
            .map(|((_, array), &(k, offset))| Region {
                buffer: buffers[k].clone(),
                offset,
                size: array.len() as u64,
            })
            .collect();
        Built { regions }
    }
}

/// Where arrays go: each arena's access and bytes, each array's arena
/// and offset in it.
#[derive(Debug, PartialEq)]
struct Layout {
    arenas: Vec<(Access, u64)>,
    placed: Vec<(usize, u64)>,
}

/// Lays out arrays of these accesses and sizes, in order: each in the last
/// arena of its access at the next multiple of `align`, or at the start of
/// a new one where that would end past `cap` bytes.
fn layout(arrays: &[(Access, u64)], align: u64, cap: u64) -> Layout {
    let mut arenas: Vec<(Access, u64)> = Vec::new();
    let mut placed = Vec::with_capacity(arrays.len());
    for &(access, size) in arrays {
        let last = arenas.iter().rposition(|(a, _)| *a == access);
        match last {
            Some(k) if arenas[k].1.next_multiple_of(align) + size <= cap => {
                let at = arenas[k].1.next_multiple_of(align);
                arenas[k].1 = at + size;
                placed.push((k, at));
            }
            _ => {
                arenas.push((access, size));
                placed.push((arenas.len() - 1, 0));
            }
        }
    }
    Layout { arenas, placed }
}

/// The regions of built arenas, by slot.
pub(super) struct Built {
    regions: Vec<Region>,
}

impl Built {
    pub(super) fn region(&self, slot: Slot) -> Region {
        self.regions[slot.0].clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use Access::{ReadOnly as Ro, ReadWrite as Rw};

    #[test]
    fn arrays_of_one_access_share_an_arena_at_aligned_offsets() {
        let l = layout(
            &[(Rw, 100), (Ro, 8), (Rw, 256), (Rw, 4), (Ro, 48)],
            256,
            1 << 20,
        );
        assert_eq!(l.arenas, vec![(Rw, 516), (Ro, 304)]);
        assert_eq!(l.placed, vec![(0, 0), (1, 0), (0, 256), (0, 512), (1, 256)]);
    }

    #[test]
    fn an_arena_full_to_its_cap_starts_another_and_a_large_array_has_its_own() {
        // 400 bytes at offset 768 would end past 1024: a new arena.
        let l = layout(&[(Rw, 600), (Rw, 400), (Rw, 5000), (Rw, 24)], 256, 1024);
        assert_eq!(l.arenas, vec![(Rw, 600), (Rw, 400), (Rw, 5000), (Rw, 24)]);
        assert_eq!(l.placed, vec![(0, 0), (1, 0), (2, 0), (3, 0)]);
        let l = layout(&[(Rw, 200), (Rw, 300), (Rw, 5000), (Rw, 24)], 256, 1024);
        assert_eq!(l.arenas, vec![(Rw, 556), (Rw, 5000), (Rw, 24)]);
        assert_eq!(l.placed, vec![(0, 0), (0, 256), (1, 0), (2, 0)]);
    }

    #[test]
    fn a_cap_of_zero_gives_each_array_a_buffer() {
        let l = layout(&[(Rw, 8), (Rw, 8), (Ro, 8)], 256, 0);
        assert_eq!(l.arenas, vec![(Rw, 8), (Rw, 8), (Ro, 8)]);
        assert_eq!(l.placed, vec![(0, 0), (1, 0), (2, 0)]);
    }
}
