//! The device time of each batch: timestamps at the start and end of its
//! compute pass (where the adapter has timestamp queries), read back with
//! the batch's status. Summed, they say how long the device was busy
//! stepping and recording, against the wall time a run took: what output
//! costs on the device, apart from what it costs the host.
//!
//! On request (`GpuEngine::time_each_dispatch`) the passes also take
//! timestamps inside the pass: around each sample's step dispatch of the
//! one-step kernels (their recording variant) and before the batch's
//! record finish, which split the pass's time between plain steps, the
//! samples' steps and the finish (`DispatchTimes`).

use super::context::GpuContext;

/// Query slots (two timestamps each), used in turn: more than the batches
/// that can be in flight at once (`MAX_RUN_AHEAD_BATCHES` + 1), so a slot
/// is read back before it is written again.
const SLOTS: u32 = 80;

/// Bytes a batch's pass timestamps take in its status staging buffer.
pub const TIMESTAMP_BYTES: u64 = 16;

/// Query sets of the dispatch timing, used batch by batch in turn, so that
/// a batch's queries are reset only after the batches just before it have
/// resolved theirs.
const INSIDE_SETS: usize = 4;

/// Timestamps one batch may take inside its pass: the pass's two, two a
/// sample at most (`ONE_STEP_BATCH` + 1 samples) and one before the finish.
const INSIDE_QUERIES: u32 = wgpu::QUERY_SET_MAX_QUERIES;

/// Where the device time of the timed batches went, by dispatch kind.
/// Each interval between two timestamps goes to the dispatches between
/// them, so the parts add up to the passes' time.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DispatchTimes {
    /// Step dispatches of no sample (forces-only ones included), and
    /// their seconds.
    pub steps: u64,
    pub step_seconds: f64,
    /// Step dispatches of samples (the one-step kernels' recording
    /// variant, `STEP_RECORDS`) and their seconds.
    pub sample_steps: u64,
    pub sample_step_seconds: f64,
    /// The batches' record finishes (`record_batch_finish`, one a batch
    /// with samples) and their seconds.
    pub finishes: u64,
    pub finish_seconds: f64,
}

impl DispatchTimes {
    /// Seconds in all.
    pub fn total_seconds(&self) -> f64 {
        self.step_seconds + self.sample_step_seconds + self.finish_seconds
    }

    fn add(&mut self, t: &DispatchTimes) {
        self.steps += t.steps;
        self.step_seconds += t.step_seconds;
        self.sample_steps += t.sample_steps;
        self.sample_step_seconds += t.sample_step_seconds;
        self.finishes += t.finishes;
        self.finish_seconds += t.finish_seconds;
    }
}

impl std::fmt::Display for DispatchTimes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let each = |s: f64, n: u64| if n == 0 { 0.0 } else { s / n as f64 * 1e6 };
        write!(
            f,
            "steps {:.3} s ({} dispatches, {:.2} µs each); steps of samples {:.3} s ({}, \
             {:.2} µs each); record finish {:.3} s ({}, {:.2} µs each)",
            self.step_seconds,
            self.steps,
            each(self.step_seconds, self.steps),
            self.sample_step_seconds,
            self.sample_steps,
            each(self.sample_step_seconds, self.sample_steps),
            self.finish_seconds,
            self.finishes,
            each(self.finish_seconds, self.finishes),
        )
    }
}

/// What a timed batch's pass held: its step dispatches, in order its
/// samples, and whether a finish ended it.
#[derive(Debug, Clone, Default)]
pub struct BatchMarks {
    steps: u64,
    samples: Vec<SampleMarks>,
    /// A timestamp before the batch's record finish (the pass's end
    /// closes it).
    finish: bool,
    set: usize,
    /// Timestamps written so far (the pass's two first).
    written: u32,
    /// Step dispatches since the last timestamp.
    unmarked: u64,
}

/// A sample's timestamps: one before its step dispatch where steps of no
/// sample came since the last timestamp (else the last one stands for it),
/// and one after it. At most 3 + 2 × 1025 in a batch of 1024 steps.
#[derive(Debug, Clone, Copy)]
struct SampleMarks {
    offset: u64,
    step_marked: bool,
}

/// The query sets of the dispatch timing.
struct Inside {
    sets: Vec<(wgpu::QuerySet, wgpu::Buffer)>,
    next: usize,
    times: DispatchTimes,
}

pub struct DeviceTimer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    next: u32,
    period_ns: f64,
    busy_ns: f64,
    inside: Option<Inside>,
}

/// Where a batch's pass timestamps go: a slot of the pass timing, or a
/// query set of the dispatch timing.
#[derive(Debug, Clone, Copy)]
pub enum BatchSlot {
    Pass(u32),
    Inside(usize),
}

impl DeviceTimer {
    /// A timer, where the context's adapter has timestamp queries.
    pub fn new(ctx: &GpuContext) -> Option<DeviceTimer> {
        let period_ns = ctx.timestamp_period_ns?;
        let queries = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("batch timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * SLOTS,
        });
        let resolved = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("batch timestamps"),
            size: SLOTS as u64 * wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Some(DeviceTimer {
            queries,
            resolved,
            next: 0,
            period_ns,
            busy_ns: 0.0,
            inside: None,
        })
    }

    /// Turns on the timing of each dispatch, where the device has
    /// timestamps inside passes; whether it has.
    pub fn time_each_dispatch(&mut self, ctx: &GpuContext) -> bool {
        if !ctx
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES)
        {
            return false;
        }
        if self.inside.is_none() {
            let sets = (0..INSIDE_SETS)
                .map(|_| {
                    let queries = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                        label: Some("dispatch timestamps"),
                        ty: wgpu::QueryType::Timestamp,
                        count: INSIDE_QUERIES,
                    });
                    let resolved = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("dispatch timestamps"),
                        size: INSIDE_QUERIES as u64 * 8,
                        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                        mapped_at_creation: false,
                    });
                    (queries, resolved)
                })
                .collect();
            self.inside = Some(Inside {
                sets,
                next: 0,
                times: DispatchTimes::default(),
            });
        }
        true
    }

    /// Bytes a batch's timestamps take in its status staging buffer.
    pub fn staging_bytes(&self) -> u64 {
        match self.inside {
            Some(_) => INSIDE_QUERIES as u64 * 8,
            None => TIMESTAMP_BYTES,
        }
    }

    /// The next slot, for one batch's pass.
    pub fn take_slot(&mut self) -> BatchSlot {
        if let Some(inside) = self.inside.as_mut() {
            let set = inside.next;
            inside.next = (inside.next + 1) % INSIDE_SETS;
            return BatchSlot::Inside(set);
        }
        let slot = self.next;
        self.next = (self.next + 1) % SLOTS;
        BatchSlot::Pass(slot)
    }

    /// The pass's timestamp writes into `slot`.
    pub fn pass_writes(&self, slot: BatchSlot) -> wgpu::ComputePassTimestampWrites<'_> {
        let (query_set, first) = match slot {
            BatchSlot::Pass(k) => (&self.queries, 2 * k),
            BatchSlot::Inside(set) => (&self.inside_set(set).0, 0),
        };
        wgpu::ComputePassTimestampWrites {
            query_set,
            beginning_of_pass_write_index: Some(first),
            end_of_pass_write_index: Some(first + 1),
        }
    }

    fn inside_set(&self, set: usize) -> &(wgpu::QuerySet, wgpu::Buffer) {
        &self.inside.as_ref().expect("dispatch timing is on").sets[set]
    }

    /// The marks of a batch timed dispatch by dispatch (None for a pass
    /// timed as a whole).
    pub fn marks(slot: BatchSlot) -> Option<BatchMarks> {
        match slot {
            BatchSlot::Pass(_) => None,
            BatchSlot::Inside(set) => Some(BatchMarks {
                set,
                written: 2,
                ..BatchMarks::default()
            }),
        }
    }

    /// In a batch timed dispatch by dispatch: a timestamp after the
    /// dispatches so far (around a sample's step dispatch, and before the
    /// batch's finish).
    pub fn mark(&self, pass: &mut wgpu::ComputePass, marks: &mut BatchMarks) {
        pass.write_timestamp(&self.inside_set(marks.set).0, marks.written);
        marks.written += 1;
        marks.unmarked = 0;
    }

    /// After the pass: its timestamps into `staging` at `at`.
    pub fn copy_out(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: BatchSlot,
        marks: Option<&BatchMarks>,
        staging: &wgpu::Buffer,
        at: u64,
    ) {
        match slot {
            BatchSlot::Pass(slot) => {
                let from = slot as u64 * wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT;
                encoder.resolve_query_set(
                    &self.queries,
                    2 * slot..2 * slot + 2,
                    &self.resolved,
                    from,
                );
                encoder.copy_buffer_to_buffer(&self.resolved, from, staging, at, TIMESTAMP_BYTES);
            }
            BatchSlot::Inside(set) => {
                let count = marks.map_or(2, BatchMarks::queries);
                let (queries, resolved) = self.inside_set(set);
                encoder.resolve_query_set(queries, 0..count, resolved, 0);
                encoder.copy_buffer_to_buffer(resolved, 0, staging, at, count as u64 * 8);
            }
        }
    }

    /// Adds a retired batch's pass time, from its timestamps as read back
    /// (a pair out of order, as a driver may give across a clock change,
    /// counts nothing), and with `marks` its dispatches' times.
    pub fn add(&mut self, bytes: &[u8], marks: Option<&BatchMarks>) {
        let stamps: [u64; 2] = bytemuck::pod_read_unaligned(&bytes[..TIMESTAMP_BYTES as usize]);
        if stamps[1] > stamps[0] {
            self.busy_ns += (stamps[1] - stamps[0]) as f64 * self.period_ns;
        }
        let (Some(marks), Some(inside)) = (marks, self.inside.as_mut()) else {
            return;
        };
        let count = marks.queries() as usize;
        let stamps: Vec<u64> = bytes[..count * 8]
            .chunks_exact(8)
            .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
            .collect();
        if let Some(times) = marks.split(&stamps, self.period_ns) {
            inside.times.add(&times);
        }
    }

    /// Seconds the device spent in the retired batches' passes.
    pub fn busy_seconds(&self) -> f64 {
        self.busy_ns * 1e-9
    }

    /// The dispatches' times so far, where they are timed.
    pub fn dispatch_times(&self) -> Option<DispatchTimes> {
        self.inside.as_ref().map(|i| i.times)
    }
}

impl BatchMarks {
    /// The batch has `steps` step dispatches.
    pub fn set_steps(&mut self, steps: u64) {
        self.steps = steps;
    }

    /// A step dispatch was encoded.
    pub fn step_dispatched(&mut self) {
        self.unmarked += 1;
    }

    /// Whether a sample's step dispatch needs a timestamp before it:
    /// steps of no sample came since the last one.
    pub fn marks_before_step(&self) -> bool {
        self.unmarked > 0
    }

    /// A sample at step `offset` whose timestamps were written: before its
    /// step dispatch if `step_marked`, and after it.
    pub fn push_sample(&mut self, offset: u64, step_marked: bool) {
        self.samples.push(SampleMarks {
            offset,
            step_marked,
        });
    }

    /// A timestamp was written before the batch's record finish.
    pub fn finish_marked(&mut self) {
        self.finish = true;
    }

    /// Queries the batch wrote.
    fn queries(&self) -> u32 {
        debug_assert_eq!(
            self.written as u64,
            2 + self
                .samples
                .iter()
                .map(|m| m.step_marked as u64 + 1)
                .sum::<u64>()
                + self.finish as u64
        );
        self.written
    }

    /// The pass's time split between its dispatches, from its timestamps
    /// (begin, end, then the marks in order); None where any interval runs
    /// backwards.
    fn split(&self, stamps: &[u64], period_ns: f64) -> Option<DispatchTimes> {
        let seconds = |a: u64, b: u64| (b >= a).then(|| (b - a) as f64 * period_ns * 1e-9);
        let mut times = DispatchTimes::default();
        let (begin, end) = (stamps[0], stamps[1]);
        let mut at = begin;
        let mut next_step = 0u64;
        let mut k = 2;
        for m in &self.samples {
            if m.step_marked {
                times.step_seconds += seconds(at, stamps[k])?;
                times.steps += m.offset - next_step;
                at = stamps[k];
                k += 1;
            }
            times.sample_step_seconds += seconds(at, stamps[k])?;
            times.sample_steps += 1;
            at = stamps[k];
            next_step = m.offset + 1;
            k += 1;
        }
        // The steps after the last sample, then the finish.
        let steps_end = if self.finish { stamps[k] } else { end };
        times.step_seconds += seconds(at, steps_end)?;
        times.steps += self.steps - next_step;
        if self.finish {
            times.finish_seconds += seconds(steps_end, end)?;
            times.finishes += 1;
        }
        Some(times)
    }
}
