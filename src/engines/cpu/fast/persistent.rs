//! Several bands stepped together by the threads of a pool: each thread
//! keeps its band for a whole `advance` call and the threads meet at one
//! barrier per step, instead of a fork-join per step. The state is double
//! buffered; at step k every thread reads buffer k mod 2 whole and writes
//! its own rows of the other one, so no row is written by two threads or
//! read while written (the barrier orders one step's writes before the
//! next step's reads).

use super::chunk::{self, Band, Isa, Scratch};
use super::rows::RowView;
use super::step::{Advance, Fixed, Interface, InterfaceArrays, Shared, StateView};
use super::State;
use crate::model::real::{Coordinate, Real};
use std::ops::Range;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;

/// One `advance` call's work.
pub struct Run<'a, T: Real, C> {
    pub fixed: &'a Fixed<T>,
    pub drive_origin: C,
    pub first_step: u64,
    pub steps: u64,
    pub bands: &'a [Range<usize>],
    pub isa: Isa,
}

/// A state buffer's arrays as raw pointers, so that threads can hold
/// disjoint row ranges of it between barriers.
struct RawState<T, C> {
    ux: *mut C,
    uz: *mut C,
    vx: *mut T,
    vz: *mut T,
    fx: *mut T,
    fz: *mut T,
    contact: *mut [T; 2],
    blocks: usize,
    nx: usize,
}

// SAFETY: the pointers are only dereferenced under the access discipline
// of the module comment (whole-buffer reads and disjoint row writes
// separated by barriers).
unsafe impl<T: Send, C: Send> Send for RawState<T, C> {}
unsafe impl<T: Sync, C: Sync> Sync for RawState<T, C> {}

impl<T: Real, C: Coordinate<T>> RawState<T, C> {
    fn of(s: &mut State<T, C>) -> Self {
        RawState {
            blocks: s.fx.len(),
            nx: s.contact.len(),
            ux: s.kin.ux.as_mut_ptr(),
            uz: s.kin.uz.as_mut_ptr(),
            vx: s.kin.vx.as_mut_ptr(),
            vz: s.kin.vz.as_mut_ptr(),
            fx: s.fx.as_mut_ptr(),
            fz: s.fz.as_mut_ptr(),
            contact: s.contact.as_mut_ptr(),
        }
    }

    /// The whole buffer, read-only.
    ///
    /// # Safety
    /// No thread writes this buffer while the view lives.
    unsafe fn view<'b>(&self) -> StateView<'b, T, C> {
        use std::slice::from_raw_parts as slice;
        let n = self.blocks;
        StateView {
            kin: RowView {
                ux: slice(self.ux, n),
                uz: slice(self.uz, n),
                vx: slice(self.vx, n),
                vz: slice(self.vz, n),
            },
            force: [slice(self.fx, n), slice(self.fz, n)],
            contact: slice(self.contact, self.nx),
        }
    }

    /// Rows `rows` of the buffer, writable, with the interface arrays for
    /// the band holding row 0.
    ///
    /// # Safety
    /// No other thread reads or writes these rows (or, with `interface`,
    /// the contact array) while the band lives.
    unsafe fn band<'b>(
        &self,
        rows: Range<usize>,
        interface: Option<InterfaceArrays<'b, T, C>>,
    ) -> Band<'b, T, C> {
        use std::slice::from_raw_parts_mut as slice;
        let (first, len) = (rows.start * self.nx, rows.len() * self.nx);
        Band {
            ux: slice(self.ux.add(first), len),
            uz: slice(self.uz.add(first), len),
            vx: slice(self.vx.add(first), len),
            vz: slice(self.vz.add(first), len),
            fx: slice(self.fx.add(first), len),
            fz: slice(self.fz.add(first), len),
            interface: interface.map(|arrays| Interface::new(slice(self.contact, self.nx), arrays)),
            rows,
        }
    }
}

/// A barrier that spins briefly, then yields: a step of a small lattice
/// takes tens of microseconds, less than a sleeping barrier's wake-up.
struct SpinBarrier {
    arrived: AtomicUsize,
    generation: AtomicUsize,
    parties: usize,
}

impl SpinBarrier {
    fn new(parties: usize) -> Self {
        SpinBarrier {
            arrived: AtomicUsize::new(0),
            generation: AtomicUsize::new(0),
            parties,
        }
    }

    fn wait(&self) {
        let generation = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.parties {
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::Release);
            return;
        }
        let mut spins = 0u32;
        while self.generation.load(Ordering::Acquire) == generation {
            if spins < 1 << 14 {
                std::hint::spin_loop();
                spins += 1;
            } else {
                std::thread::yield_now();
            }
        }
    }
}

impl<T: Real, C: Coordinate<T>> Run<'_, T, C> {
    /// Steps `buffers[0]` (the current state) on the pool's threads, one
    /// band each. Returns the steps taken (the newest state is in
    /// `buffers[steps % 2]`), the first block that blew up in the last of
    /// them, and each band's working time (s, barrier waits excluded).
    pub fn go(
        &self,
        pool: &rayon::ThreadPool,
        buffers: [&mut State<T, C>; 2],
        scratch: &mut [Scratch<T, C>],
        interface: InterfaceArrays<'_, T, C>,
    ) -> (u64, Option<usize>, Vec<f64>) {
        assert_eq!(pool.current_num_threads(), self.bands.len());
        let [a, b] = buffers;
        let raw = [RawState::of(a), RawState::of(b)];
        let scratch: Vec<Mutex<&mut Scratch<T, C>>> = scratch.iter_mut().map(Mutex::new).collect();
        let interface = Mutex::new(Some(interface));
        let barrier = SpinBarrier::new(self.bands.len());
        let blocks = raw[0].blocks as u64;
        // Step · blocks + block of the earliest blow-up (u64::MAX: none).
        let blown = AtomicU64::new(u64::MAX);
        let done = AtomicU64::new(self.steps);
        let busy: Vec<AtomicU64> = self.bands.iter().map(|_| AtomicU64::new(0)).collect();
        pool.broadcast(|ctx| {
            let t = ctx.index();
            let mut working = std::time::Duration::ZERO;
            let mut scratch = scratch[t].lock().expect("scratch");
            let mut interface = (t == 0).then(|| interface.lock().expect("interface"));
            for k in 0..self.steps {
                let started = std::time::Instant::now();
                let (now, next) = (&raw[(k % 2) as usize], &raw[1 - (k % 2) as usize]);
                // SAFETY: in step k, buffer k mod 2 is only read and each
                // thread writes only its band's rows of the other (the
                // contact array: band 0 alone); the barrier below ends the
                // step for every thread before any starts the next.
                let bad = unsafe {
                    let shared = Shared::new(
                        self.fixed,
                        self.drive_origin,
                        self.first_step + k,
                        now.view(),
                        Advance::Leapfrog,
                        true,
                    );
                    let arrays = interface
                        .as_mut()
                        .and_then(|g| g.as_mut())
                        .map(|(s, j, l, w)| (&mut **s, &mut **j, &mut **l, &mut **w));
                    let band = next.band(self.bands[t].clone(), arrays);
                    chunk::sweep_band(self.isa, &shared, band, &mut scratch)
                };
                if let Some(i) = bad {
                    blown.fetch_min(k * blocks + i as u64, Ordering::AcqRel);
                }
                working += started.elapsed();
                if k + 1 == self.steps {
                    busy[t].store(working.as_nanos() as u64, Ordering::Relaxed);
                }
                barrier.wait();
                // Every thread sees this step's blow-ups (a later step's
                // have a larger key), so all stop after the same step.
                let first = blown.load(Ordering::Acquire);
                if first != u64::MAX && first / blocks <= k {
                    if t == 0 {
                        done.store(k + 1, Ordering::Relaxed);
                    }
                    busy[t].store(working.as_nanos() as u64, Ordering::Relaxed);
                    return;
                }
            }
        });
        let first = blown.load(Ordering::Acquire);
        let bad = (first != u64::MAX).then(|| (first % blocks) as usize);
        let busy = busy
            .iter()
            .map(|b| b.load(Ordering::Relaxed) as f64 * 1e-9)
            .collect();
        (done.load(Ordering::Relaxed), bad, busy)
    }
}

/// New band boundaries for `nz` rows from the bands' rows and working
/// times: each band gets rows in proportion to its measured rows per
/// second (the interface band also carries the junctions), moved halfway
/// there to damp noise. Bands keep at least one row. Any split gives the
/// same bits, so this only changes the speed.
pub fn rebalance(bands: &[Range<usize>], busy: &[f64]) -> Vec<Range<usize>> {
    let nz = bands.last().map_or(0, |b| b.end);
    let rates: Vec<f64> = bands
        .iter()
        .zip(busy)
        .map(|(b, &t)| b.len() as f64 / t.max(1e-9))
        .collect();
    let total: f64 = rates.iter().sum();
    if !(total.is_finite() && total > 0.0) || bands.len() < 2 {
        return bands.to_vec();
    }
    let mut out = Vec::with_capacity(bands.len());
    let mut start = 0usize;
    let mut target = 0.0;
    for (i, (b, rate)) in bands.iter().zip(&rates).enumerate() {
        let left = bands.len() - i - 1;
        target += 0.5 * (b.len() as f64 + nz as f64 * rate / total);
        let end = if left == 0 {
            nz
        } else {
            (target.round() as usize).clamp(start + 1, nz - left)
        };
        out.push(start..end);
        start = end;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::rebalance;

    #[test]
    fn rebalance_moves_rows_away_from_the_slow_band_and_keeps_every_row() {
        // Band 0 took twice as long per row: it should shrink, halfway.
        let bands = rebalance(&[0..100, 100..200], &[2.0, 1.0]);
        assert_eq!(bands, vec![0..83, 83..200]);
        // Balanced bands stay; one-row bands survive.
        assert_eq!(
            rebalance(&[0..50, 50..100], &[1.0, 1.0]),
            vec![0..50, 50..100]
        );
        assert_eq!(
            rebalance(&[0..1, 1..3, 3..4], &[100.0, 1.0, 1.0]),
            vec![0..1, 1..3, 3..4]
        );
    }
}
