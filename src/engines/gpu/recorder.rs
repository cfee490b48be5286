//! Output samples recorded on the device, by the step kernels in their
//! steps (`shaders/record_common.wgsl`): which steps of a batch are
//! samples and where their records go, the copy of a batch's records into
//! a staging buffer read back with the batch's status, and their decoding
//! into `Sample`s. An ensemble's scenes are recorded together: the same
//! steps, each scene in its own region of every record buffer (its plan
//! says where).
//!
//! Which planned samples are due (the fast interface cadence's rule: a
//! sample of the fast cadence only while the sample before it slipped
//! fast) is decided in step order: inside the persistent kernel's loop, and
//! here on the host for the kernels that keep a partial a workgroup
//! (`RecordSite::Steps`, `RecordSite::Tiles`), as the batches are read
//! back. The tiled kernel computes every planned sample; the one-step
//! kernels skip those their fast chain finds cannot be due (the same rule
//! on the device, `shaders/record_step.wgsl`), and the host checks that
//! every due sample was computed.

use super::arena::{Access, Arenas, Region};
use super::batch_sizes::ONE_STEP_BATCH;
use super::context::GpuContext;
use super::layout::{
    AtomicWords8, GpuRecordEntry, GpuRecordPlan, GpuSampleSums, RECORD_BULK, RECORD_BULK_WORDS,
    RECORD_FAST, RECORD_GLOBAL, RECORD_INTERFACE, RECORD_INTERFACE_WORDS,
};
use super::precision::GpuReal;
use crate::engines::{BulkField, InterfaceRow, PlannedAndComputed, Sample, SamplePlan, SampleSums};
use crate::model::{Driver, Model};

/// Record buffers of one batch at most (interface rows and bulk fields);
/// a batch ends early rather than go past it (one bulk field always fits).
const ROWS_BUDGET: u64 = 64 << 20;

/// The partials of one batch's samples at most (all scenes'): a batch of
/// the kernels that keep a partial per workgroup and sample ends early
/// rather than plan more samples than fit (one always does).
const PARTIALS_BUDGET: u64 = 64 << 20;

/// The most samples of a batch of the tiled kernel. At Table S1's cadences
/// (a planned sample every 4 or 5 steps) a batch of `ONE_STEP_BATCH` steps
/// plans about 230.
const TILED_SAMPLES_A_BATCH: u32 = 256;

/// A sample asked for in a batch: in the step dispatch at `offset` (or in
/// the batch's forces-only pass), at global step `step`.
#[derive(Debug, Clone, Copy)]
pub struct Planned {
    pub offset: u64,
    pub step: u64,
    pub entry: GpuRecordEntry,
}

/// A batch's records on their way back: the staging buffer and what is
/// where in it (each scene's records, scene after scene).
pub struct Pending {
    staging: wgpu::Buffer,
    planned: Vec<Planned>,
    interface_slots: u32,
    bulk_slots: u32,
    /// Bytes of one scene's records in the staging buffer.
    scene_bytes: u64,
}

/// The output side of one GPU engine: every scene's samples, in the
/// kernels' precision `T` (sums and rows of `T`).
pub struct Recorder<T: GpuReal> {
    /// The cadences every scene shares (each scene's fast flag is in
    /// `fast`, and on the device in its plan).
    plan: SamplePlan,
    /// Each scene's fast cadence flag after the samples read back so far,
    /// where the host decides which samples are due (`host_rule`).
    fast: Vec<bool>,
    /// The host applies the fast cadence's rule (the sites that record
    /// every planned sample); else the persistent kernel did.
    host_rule: bool,
    /// Scene by scene.
    models: Vec<Model>,
    /// Its arrays, in arenas of their own (`arena`) where the engine packs
    /// its arrays (`GpuOptions::pack_arrays`).
    plans: Region,
    sums: Region,
    rows: Region,
    /// The batch's samples in step order (`GpuRecordEntry`).
    entries: Region,
    /// The one-step kernels' (`RecordSite::Steps`; a placeholder for the
    /// others, never written): the index of each step offset's sample
    /// among the entries (`shaders/record_step.wgsl` step_samples).
    step_samples: Region,
    writes_step_samples: bool,
    max_entries: u32,
    max_interface: u32,
    max_bulk: u32,
    /// Each scene's region: sums (elements) and rows (bytes).
    sums_per_scene: u64,
    rows_per_scene: u64,
    /// Where the bulk fields start in a scene's rows region.
    bulk_offset: u64,
    /// The last step sampled (by the device or by the host).
    pub recorded_through: Option<u64>,
    /// Samples planned so far, all batches: the next one's ordinal (its
    /// fast chain slots, `GpuRecordEntry::ring`).
    ordinal: u64,
    /// Planned samples read back, and those of them the device computed
    /// (all scenes).
    pub read_back: PlannedAndComputed,
    spare: Vec<wgpu::Buffer>,
    precision: std::marker::PhantomData<T>,
}

/// Reals of `T` in `bytes`.
fn words<T>(bytes: u64) -> u64 {
    bytes / size_of::<T>() as u64
}

/// Where a step kernel's output samples are recorded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordSite {
    /// In the one-step kernels' step dispatch of each sample (their
    /// recording variant, `STEP_RECORDS`): a partial per workgroup of the
    /// dispatch (`partials` of them a scene) and sample, added after the
    /// batch (`record_batch_finish`).
    Steps { partials: u32 },
    /// Inside the persistent kernel's loop, which reduces each sample
    /// across its workgroup itself.
    Persistent,
    /// Inside the tiled kernel's steps: a partial per tile (`tiles` a
    /// scene) and sample, added after the batch (`record_batch_finish`).
    Tiles { tiles: u32 },
}

impl RecordSite {
    /// A sample's partials a scene.
    fn partials(self) -> u32 {
        match self {
            RecordSite::Steps { partials } => partials,
            RecordSite::Persistent => 0,
            RecordSite::Tiles { tiles } => tiles,
        }
    }
}

impl<T: GpuReal> Recorder<T> {
    /// The recorder of an engine's scenes (`models`, one lattice) whose
    /// step kernel records at `site`, or why the device cannot hold the
    /// records of one batch.
    pub fn new(
        ctx: &GpuContext,
        models: &[Model],
        plan: &SamplePlan,
        site: RecordSite,
        packed: bool,
    ) -> Result<Recorder<T>, String> {
        let device = &ctx.device;
        let model = &models[0];
        let scenes = models.len() as u64;
        let (n, nx) = (model.n_blocks() as u64, model.nx as u64);
        let real = size_of::<T>() as u64;
        let sums_size = size_of::<GpuSampleSums<T>>() as u64;
        let interface_bytes = nx * RECORD_INTERFACE_WORDS as u64 * real;
        let bulk_bytes = n * RECORD_BULK_WORDS as u64 * real;
        // Each sample of a batch keeps its partials until the batch's end.
        let partials = site.partials() as u64;
        let most = match site {
            RecordSite::Tiles { .. } => TILED_SAMPLES_A_BATCH as u64,
            _ => ONE_STEP_BATCH + 1,
        };
        let max_entries = match partials {
            0 => most,
            p => (PARTIALS_BUDGET / (scenes * p * sums_size)).clamp(1, most),
        } as u32;
        let budget = ROWS_BUDGET / 2 / scenes;
        let max_interface = (budget / interface_bytes).clamp(1, max_entries as u64) as u32;
        let max_bulk = if plan.every_bulk > 0 {
            (budget / bulk_bytes).clamp(1, max_entries as u64) as u32
        } else {
            0
        };
        let bulk_offset = max_interface as u64 * interface_bytes;
        let rows_per_scene = bulk_offset + max_bulk as u64 * bulk_bytes;
        let rows_bytes = (scenes * rows_per_scene).max(16);
        let limit = ctx
            .limits
            .max_storage_buffer_binding_size
            .min(ctx.limits.max_buffer_size);
        if rows_bytes > limit {
            return Err(format!(
                "the records of one batch need {rows_bytes} bytes, {} binds at most {limit}",
                ctx.info.name
            ));
        }
        let sums_per_scene = max_entries as u64 * (1 + partials);
        let sums_bytes = scenes * sums_per_scene * sums_size;
        if sums_bytes > limit {
            return Err(format!(
                "the sums of one batch's samples need {sums_bytes} bytes, {} binds at most {limit}",
                ctx.info.name
            ));
        }
        if words::<T>(rows_bytes) > u32::MAX as u64 || scenes * sums_per_scene > u32::MAX as u64 {
            return Err("the records of one batch need more than 2^32 words".into());
        }
        let gpu_plans: Vec<GpuRecordPlan<T>> = models
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let k = k as u64;
                GpuRecordPlan::<T> {
                    fast: plan.fast as u32,
                    every_fast: plan.every_fast.min(u32::MAX as u64) as u32,
                    fast_slip_speed: T::fast_threshold(plan.fast_slip_speed),
                    fast_bits: T::fast_order_bits(plan.fast_slip_speed),
                    driven_block: match m.driver {
                        Driver::SideSpring { row, .. } => (row * m.nx) as u32,
                        _ => u32::MAX,
                    },
                    top_reaction: matches!(m.driver, Driver::TopVelocity { .. }) as u32,
                    junctions_per_block: (m.n_junctions() / m.nx.max(1)) as u32,
                    partials: partials as u32,
                    step_chain: matches!(site, RecordSite::Steps { .. }) as u32,
                    fast_chain: AtomicWords8::fast_chain(plan.fast),
                    sums_offset: (k * sums_per_scene) as u32,
                    partials_offset: (k * sums_per_scene) as u32 + max_entries,
                    interface_offset: words::<T>(k * rows_per_scene) as u32,
                    bulk_offset: words::<T>(k * rows_per_scene + bulk_offset) as u32,
                }
            })
            .collect();
        let mut arenas = Arenas::default();
        let (rw, ro) = (Access::ReadWrite, Access::ReadOnly);
        let plans = arenas.bytes(rw, bytemuck::cast_slice(&gpu_plans));
        let sums = arenas.zeros(rw, sums_bytes as usize);
        let rows = arenas.zeros(rw, rows_bytes as usize);
        let entries = arenas.zeros(ro, max_entries as usize * size_of::<GpuRecordEntry>());
        // A one-step batch's steps (`GpuEngine::batch_steps`).
        let writes_step_samples = matches!(site, RecordSite::Steps { .. });
        let step_samples = arenas.zeros(
            ro,
            match writes_step_samples {
                true => ONE_STEP_BATCH as usize * 4,
                false => 16,
            },
        );
        let built = arenas.build(device, &ctx.limits, packed);
        Ok(Recorder {
            plan: *plan,
            fast: vec![plan.fast; models.len()],
            host_rule: site != RecordSite::Persistent,
            models: models.to_vec(),
            plans: built.region(plans),
            sums: built.region(sums),
            rows: built.region(rows),
            entries: built.region(entries),
            step_samples: built.region(step_samples),
            writes_step_samples,
            max_entries,
            max_interface,
            max_bulk,
            sums_per_scene,
            rows_per_scene,
            bulk_offset,
            recorded_through: None,
            ordinal: 0,
            read_back: PlannedAndComputed::default(),
            spare: Vec::new(),
            precision: std::marker::PhantomData,
        })
    }

    /// The arrays the step kernels bind, by their names in the shaders:
    /// `plans`, `sums`, `rows`, `record_entries` and `step_samples`.
    pub fn state_bindings(&self) -> [wgpu::BindingResource<'_>; 5] {
        [
            &self.plans,
            &self.sums,
            &self.rows,
            &self.entries,
            &self.step_samples,
        ]
        .map(Region::binding)
    }

    /// Whether `plan` has the cadences this recorder samples at (its fast
    /// flag may differ: each scene keeps its own).
    pub fn samples_like(&self, plan: &SamplePlan) -> bool {
        SamplePlan {
            fast: self.plan.fast,
            ..*plan
        } == self.plan
    }

    /// Takes scene `scene`'s fast cadence state from `plan` (whose
    /// cadences are this recorder's, `samples_like`), into its flag and its
    /// fast chain; only between batches (the engine has drained).
    pub fn set_plan(&mut self, queue: &wgpu::Queue, scene: usize, plan: &SamplePlan) {
        debug_assert!(self.samples_like(plan));
        self.fast[scene] = plan.fast;
        let plan_at = (scene * size_of::<GpuRecordPlan<T>>()) as u64;
        let at = plan_at + std::mem::offset_of!(GpuRecordPlan<T>, fast) as u64;
        self.plans
            .write(queue, at, bytemuck::bytes_of(&(plan.fast as u32)));
        let at = plan_at + std::mem::offset_of!(GpuRecordPlan<T>, fast_chain) as u64;
        let chain = AtomicWords8::fast_chain(plan.fast);
        self.plans.write(queue, at, bytemuck::bytes_of(&chain));
    }

    /// Whether `step` is a sample not yet taken.
    fn wanted(&self, step: u64) -> bool {
        self.recorded_through.is_none_or(|r| step > r) && self.plan.due(step).any()
    }

    /// The samples of a batch of `steps` steps from `first`, and how many
    /// steps the batch may take before its records would overflow
    /// (≤ `steps`).
    pub fn plan_batch(&self, first: u64, steps: u64) -> (Vec<Planned>, u64) {
        let mut planned = Vec::new();
        let (mut interface, mut bulk) = (0u32, 0u32);
        for offset in 0..steps {
            let step = first + offset;
            if !self.wanted(step) {
                continue;
            }
            let due = self.plan.due(step);
            let needs_interface = due.interface || due.fast;
            if planned.len() as u32 == self.max_entries
                || (needs_interface && interface == self.max_interface)
                || (due.bulk && bulk == self.max_bulk)
            {
                return (planned, offset);
            }
            let channels = (due.global as u32 * RECORD_GLOBAL)
                | (due.interface as u32 * RECORD_INTERFACE)
                | (due.bulk as u32 * RECORD_BULK)
                | (due.fast as u32 * RECORD_FAST);
            planned.push(Planned {
                offset,
                step,
                entry: GpuRecordEntry {
                    offset: offset as u32,
                    channels,
                    sums_slot: planned.len() as u32,
                    interface_slot: interface,
                    bulk_slot: bulk,
                    ring: 0,
                },
            });
            interface += needs_interface as u32;
            bulk += due.bulk as u32;
        }
        (planned, steps)
    }

    /// The sample of the current step (after a forces-only pass), if it is
    /// one not yet taken.
    pub fn plan_now(&self, step: u64) -> Vec<Planned> {
        if !self.wanted(step) {
            return Vec::new();
        }
        self.plan_batch(step, 1).0
    }

    /// Writes a batch's entries (before its submit): the samples in step
    /// order, each with its slots in the fast chain, and the sample of each
    /// step offset; marks its samples as taken.
    pub fn write_entries(&mut self, queue: &wgpu::Queue, planned: &[Planned]) {
        let Some(last) = planned.last() else {
            return;
        };
        let entries: Vec<GpuRecordEntry> = planned
            .iter()
            .zip(self.ordinal..)
            .map(|(p, n)| GpuRecordEntry {
                ring: (n % 6) as u32,
                ..p.entry
            })
            .collect();
        self.ordinal += planned.len() as u64;
        self.entries.write(queue, 0, bytemuck::cast_slice(&entries));
        if self.writes_step_samples {
            // Offsets of no sample: no step reads them.
            let mut step_samples = vec![u32::MAX; last.offset as usize + 1];
            for (k, p) in planned.iter().enumerate() {
                step_samples[p.offset as usize] = k as u32;
            }
            self.step_samples
                .write(queue, 0, bytemuck::cast_slice(&step_samples));
        }
        self.recorded_through = Some(last.step);
    }

    /// Copies the batch's records (only the slots it used) into a staging
    /// buffer, after its steps in `encoder`.
    pub fn copy_out(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        planned: Vec<Planned>,
    ) -> Option<Pending> {
        if planned.is_empty() {
            return None;
        }
        let interface_slots = planned
            .iter()
            .filter(|p| p.entry.channels & (RECORD_INTERFACE | RECORD_FAST) != 0)
            .count() as u32;
        let bulk_slots = planned
            .iter()
            .filter(|p| p.entry.channels & RECORD_BULK != 0)
            .count() as u32;
        let sums_size = size_of::<GpuSampleSums<T>>() as u64;
        let sums_bytes = planned.len() as u64 * sums_size;
        let interface_bytes = interface_slots as u64 * self.interface_bytes();
        let bulk_bytes = bulk_slots as u64 * self.bulk_bytes();
        let scene_bytes = sums_bytes + interface_bytes + bulk_bytes;
        let size = scene_bytes * self.models.len() as u64;
        let staging = match self.spare.iter().position(|b| b.size() >= size) {
            Some(k) => self.spare.swap_remove(k),
            None => device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("record readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        };
        for k in 0..self.models.len() as u64 {
            let to = k * scene_bytes;
            let sums_at = k * self.sums_per_scene * sums_size;
            let from = self.sums.range(sums_at, sums_bytes);
            encoder.copy_buffer_to_buffer(from.buffer, from.offset, &staging, to, sums_bytes);
            let rows_at = k * self.rows_per_scene;
            if interface_bytes > 0 {
                let from = self.rows.range(rows_at, interface_bytes);
                encoder.copy_buffer_to_buffer(
                    from.buffer,
                    from.offset,
                    &staging,
                    to + sums_bytes,
                    interface_bytes,
                );
            }
            if bulk_bytes > 0 {
                let from = self.rows.range(rows_at + self.bulk_offset, bulk_bytes);
                encoder.copy_buffer_to_buffer(
                    from.buffer,
                    from.offset,
                    &staging,
                    to + sums_bytes + interface_bytes,
                    bulk_bytes,
                );
            }
        }
        Some(Pending {
            staging,
            planned,
            interface_slots,
            bulk_slots,
            scene_bytes,
        })
    }

    fn interface_bytes(&self) -> u64 {
        self.models[0].nx as u64 * RECORD_INTERFACE_WORDS as u64 * size_of::<T>() as u64
    }

    fn bulk_bytes(&self) -> u64 {
        self.models[0].n_blocks() as u64 * RECORD_BULK_WORDS as u64 * size_of::<T>() as u64
    }

    /// The staging buffer to map once the batch has run.
    pub fn staging(pending: &Pending) -> &wgpu::Buffer {
        &pending.staging
    }

    /// Decodes a mapped batch's records: each scene's samples that were
    /// due, those before its step `before[scene]` only (a blow-up's), in
    /// step order.
    pub fn decode(&mut self, pending: Pending, before: &[u64]) -> Result<Vec<Vec<Sample>>, String> {
        let view = pending
            .staging
            .slice(..)
            .get_mapped_range()
            .map_err(|e| format!("record readback: {e}"))?;
        let sums_bytes = pending.planned.len() * size_of::<GpuSampleSums<T>>();
        let scene_records = |k: usize| {
            let at = (k as u64 * pending.scene_bytes) as usize;
            &view[at..at + pending.scene_bytes as usize]
        };
        // Which samples were due, scene by scene, and (where the host
        // decides) each scene's fast flag after them.
        let due: Vec<Vec<Due>> = (0..self.models.len())
            .map(|k| {
                let sums: &[GpuSampleSums<T>] =
                    bytemuck::cast_slice(&scene_records(k)[..sums_bytes]);
                match self.host_rule {
                    true => fast_rule(&self.plan, &mut self.fast[k], &pending.planned, sums),
                    false => sums
                        .iter()
                        .map(|s| Due {
                            recorded: s.recorded != 0,
                            interface_row: s.interface_row != 0,
                        })
                        .collect(),
                }
            })
            .collect();
        // The one-step kernels compute only the planned samples their
        // chain says may be due (a superset of the host's rule's).
        for (k, due) in due.iter().enumerate() {
            let sums: &[GpuSampleSums<T>] = bytemuck::cast_slice(&scene_records(k)[..sums_bytes]);
            self.read_back.planned += sums.len() as u64;
            self.read_back.computed += sums.iter().filter(|s| s.recorded != 0).count() as u64;
            let skipped = pending
                .planned
                .iter()
                .zip(sums)
                .zip(due)
                .find(|((p, s), d)| d.recorded && s.recorded == 0 && p.step < before[k]);
            if let Some(((p, _), _)) = skipped {
                return Err(format!(
                    "scene {k}: the device skipped the sample of step {}, which the fast \
                     cadence's rule makes due (the kernels' fast chain parts from the host's rule)",
                    p.step
                ));
            }
        }
        let samples = self
            .models
            .iter()
            .zip(before)
            .zip(&due)
            .enumerate()
            .map(|(k, ((m, &before), due))| {
                self.decode_scene(&pending, m, scene_records(k), before, due)
            })
            .collect();
        drop(view);
        pending.staging.unmap();
        self.spare.push(pending.staging);
        Ok(samples)
    }

    /// One scene's samples from its records in the staging buffer, `due`
    /// saying which were.
    fn decode_scene(
        &self,
        pending: &Pending,
        m: &Model,
        records: &[u8],
        before: u64,
        due: &[Due],
    ) -> Vec<Sample> {
        let sums_bytes = pending.planned.len() * size_of::<GpuSampleSums<T>>();
        let sums: &[GpuSampleSums<T>] = bytemuck::cast_slice(&records[..sums_bytes]);
        let reals: &[T] = bytemuck::cast_slice(&records[sums_bytes..]);
        let interface_words = self.interface_bytes() as usize / size_of::<T>();
        let bulk_at = pending.interface_slots as usize * interface_words;
        let bulk_words = self.bulk_bytes() as usize / size_of::<T>();
        debug_assert!(reals.len() >= bulk_at + pending.bulk_slots as usize * bulk_words);
        let mut samples = Vec::new();
        for ((p, s), due) in pending.planned.iter().zip(sums).zip(due) {
            if !due.recorded || p.step >= before {
                continue;
            }
            let interface = due.interface_row.then(|| {
                let at = p.entry.interface_slot as usize * interface_words;
                let row = &reals[at..at + interface_words];
                let col = |k: usize| -> Vec<f64> {
                    row.chunks(RECORD_INTERFACE_WORDS as usize)
                        .map(|b| b[k].as_f64())
                        .collect()
                };
                InterfaceRow {
                    ux: row
                        .chunks(RECORD_INTERFACE_WORDS as usize)
                        .map(|b| b[0].as_f64() + b[1].as_f64())
                        .collect(),
                    friction: col(2),
                    normal: col(3),
                    pinned_fraction: col(4),
                    slip_speed: col(5),
                }
            });
            let bulk = (p.entry.channels & RECORD_BULK != 0).then(|| {
                let at = bulk_at + p.entry.bulk_slot as usize * bulk_words;
                let field = &reals[at..at + bulk_words];
                let col = |k: usize| -> Vec<f32> {
                    field
                        .chunks(RECORD_BULK_WORDS as usize)
                        // The file's bulk fields are f32 (as the host
                        // twin rounds them).
                        .map(|b| b[k].as_f64() as f32)
                        .collect()
                };
                BulkField {
                    ux: col(0),
                    uz: col(1),
                    vx: col(2),
                    vz: col(3),
                }
            });
            samples.push(Sample {
                step: p.step,
                time: m.time_of_step(p.step),
                sums: SampleSums {
                    kinetic_energy: 0.5 * m.mass * s.kinetic.as_f64(),
                    friction: s.friction.as_f64(),
                    pinned_fraction: s.pinned.as_f64() / m.nx.max(1) as f64,
                    min_pinned_fraction: s.min_pinned.as_f64(),
                    max_slip_speed: s.max_slip_speed.as_f64(),
                    ruptures: s.ruptures_lo as u64 | (s.ruptures_hi as u64) << 32,
                    driven_ux: s.driven_ux_hi.as_f64() + s.driven_ux_lo.as_f64(),
                    top_reaction: s.top_reaction.as_f64(),
                },
                interface,
                bulk,
            });
        }
        samples
    }
}

/// Whether a planned sample was due, and with its interface row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Due {
    recorded: bool,
    interface_row: bool,
}

/// The fast interface cadence's rule over a batch's `planned` samples of
/// one scene, in step order, from `fast` (the flag the samples before them
/// left, updated): a sample is due by a fixed cadence, or by the fast one
/// while the flag is on; a due sample sets the flag where its interface
/// slipped faster than the plan's threshold (the host's rule,
/// `runner::outputs::Outputs::emit_sample`).
fn fast_rule<T: GpuReal>(
    plan: &SamplePlan,
    fast: &mut bool,
    planned: &[Planned],
    sums: &[GpuSampleSums<T>],
) -> Vec<Due> {
    planned
        .iter()
        .zip(sums)
        .map(|(p, s)| {
            let channels = p.entry.channels;
            let by_fast = channels & RECORD_FAST != 0 && *fast;
            let recorded =
                channels & (RECORD_GLOBAL | RECORD_INTERFACE | RECORD_BULK) != 0 || by_fast;
            let interface_row = channels & RECORD_INTERFACE != 0 || by_fast;
            if recorded {
                *fast = plan.every_fast > 0 && s.max_slip_speed.as_f64() > plan.fast_slip_speed;
            }
            Due {
                recorded,
                interface_row,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::layout::{FAST_CHAIN_DUE, FAST_CHAIN_FLAG, FAST_CHAIN_MAX};
    use super::*;

    fn planned(offset: u64, channels: u32) -> Planned {
        Planned {
            offset,
            step: offset,
            entry: GpuRecordEntry {
                offset: offset as u32,
                channels,
                sums_slot: offset as u32,
                interface_slot: 0,
                bulk_slot: 0,
                ring: 0,
            },
        }
    }

    fn slipping(speed: f32) -> GpuSampleSums<f32> {
        GpuSampleSums {
            max_slip_speed: speed,
            ..bytemuck::Zeroable::zeroed()
        }
    }

    /// The fast cadence's rule as the host applies it to a batch read
    /// back: a fast-only sample is due only while the due sample before it
    /// slipped faster than the threshold, and a sample that was not due
    /// leaves the flag as it was (however fast its planned sums say the
    /// interface slipped). The flag carries over to the next batch.
    #[test]
    fn the_fast_rule_follows_the_due_samples_in_order() {
        let plan = SamplePlan {
            prep_steps: 0,
            every_global: 10,
            every_interface: 10,
            every_bulk: 0,
            every_fast: 2,
            fast_slip_speed: 0.5,
            fast: false,
        };
        let fixed = RECORD_GLOBAL | RECORD_INTERFACE | RECORD_FAST;
        let batch = [
            (planned(0, RECORD_FAST), slipping(2.0)),
            (planned(2, fixed), slipping(1.0)),
            (planned(4, RECORD_FAST), slipping(0.1)),
            (planned(6, RECORD_FAST), slipping(9.0)),
            (planned(8, RECORD_GLOBAL), slipping(0.7)),
        ];
        let (p, s): (Vec<Planned>, Vec<GpuSampleSums<f32>>) = batch.into_iter().unzip();
        let mut fast = false;
        let due = fast_rule(&plan, &mut fast, &p, &s);
        let (yes, row, no) = (
            Due {
                recorded: true,
                interface_row: true,
            },
            Due {
                recorded: true,
                interface_row: false,
            },
            Due {
                recorded: false,
                interface_row: false,
            },
        );
        // Off at first: the fast-only sample at 0 is not due and does not
        // turn it on; the fixed one at 2 does; 4 is due and turns it off;
        // 6 is not due; 8 (fixed, no row) turns it on again.
        assert_eq!(due, [no, yes, yes, no, row]);
        assert!(fast);
        // The next batch starts from that flag.
        let due = fast_rule(&plan, &mut fast, &p[..1], &s[4..]);
        assert_eq!(due, [yes]);
        assert!(fast);
        // No fast cadence: never on.
        let mut fast = false;
        let never = SamplePlan {
            every_fast: 0,
            ..plan
        };
        let due = fast_rule(&never, &mut fast, &p, &s);
        assert_eq!(due[3], no);
        assert!(!fast);
    }

    /// CPU twin of shaders/record_step.wgsl fast_chain_due, on one scene's
    /// chain words.
    fn fast_chain_due(
        chain: &mut [u32; 8],
        e: &GpuRecordEntry,
        every_fast: u32,
        fast_bits: u32,
        writer: bool,
    ) -> bool {
        let (max, due, flag) = (
            FAST_CHAIN_MAX as usize,
            FAST_CHAIN_DUE as usize,
            FAST_CHAIN_FLAG as usize,
        );
        let n = e.ring as usize;
        let mut fast = chain[flag + n % 2] != 0;
        if chain[due + (n + 1) % 2] != 0 {
            fast = every_fast != 0 && chain[max + (n + 2) % 3] >= fast_bits;
        }
        let fixed = RECORD_GLOBAL | RECORD_INTERFACE | RECORD_BULK;
        let is_due = e.channels & fixed != 0 || (e.channels & RECORD_FAST != 0 && fast);
        if writer {
            chain[flag + (n + 1) % 2] = fast as u32;
            chain[due + n % 2] = is_due as u32;
            chain[max + (n + 1) % 3] = 0;
        }
        is_due
    }

    /// Runs `speeds.len()` samples (the channels of each from `channels`)
    /// through the device's chain, whose computed samples add their speed
    /// (as f32 order bits) to their max, and through the host's rule in
    /// batches of seven; returns (device's, host's) decisions.
    fn chain_and_host<T: GpuReal>(
        plan: &SamplePlan,
        fast_bits: u32,
        channels: &[u32],
        speeds: &[T],
    ) -> (Vec<bool>, Vec<bool>) {
        let mut chain = AtomicWords8::fast_chain(plan.fast).0;
        let every_fast = plan.every_fast as u32;
        let device: Vec<bool> = channels
            .iter()
            .zip(speeds)
            .enumerate()
            .map(|(n, (&c, &v))| {
                let mut e = planned(n as u64, c).entry;
                e.ring = (n % 6) as u32;
                let due = fast_chain_due(&mut chain, &e, every_fast, fast_bits, true);
                if due {
                    let at = FAST_CHAIN_MAX as usize + n % 3;
                    chain[at] = chain[at].max((v.as_f64() as f32).to_bits());
                }
                due
            })
            .collect();
        let mut fast = plan.fast;
        let mut host = Vec::new();
        for (c, v) in channels.chunks(7).zip(speeds.chunks(7)) {
            let p: Vec<Planned> = c.iter().map(|&c| planned(0, c)).collect();
            let s: Vec<GpuSampleSums<T>> = v
                .iter()
                .map(|&v| GpuSampleSums {
                    max_slip_speed: v,
                    ..bytemuck::Zeroable::zeroed()
                })
                .collect();
            host.extend(
                fast_rule(plan, &mut fast, &p, &s)
                    .iter()
                    .map(|d| d.recorded),
            );
        }
        (device, host)
    }

    /// A stick-slip-like run of planned samples: mostly the fast cadence's
    /// alone, speeds in runs, many of them the f32 values next to the
    /// threshold.
    fn chain_run(threshold: f64, count: usize) -> (Vec<u32>, Vec<f64>) {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut near = vec![0.0, 2.0 * threshold + 1.0, threshold, threshold.next_up()];
        let mut x = (threshold as f32).next_down().next_down();
        for _ in 0..5 {
            near.push(x as f64);
            x = x.next_up();
        }
        let mut channels = Vec::new();
        let mut speeds = Vec::new();
        let mut speed = 0.0;
        for _ in 0..count {
            let r = next();
            channels.push(match r % 10 {
                0 => RECORD_GLOBAL | RECORD_FAST,
                1 => RECORD_INTERFACE | RECORD_FAST,
                2 => RECORD_GLOBAL,
                _ => RECORD_FAST,
            });
            if (r >> 8) % 3 == 0 {
                speed = near[((r >> 16) % near.len() as u64) as usize];
            }
            speeds.push(speed);
        }
        (channels, speeds)
    }

    /// The one-step kernels compute the planned samples their fast chain
    /// says may be due: in mixed precision exactly the host rule's due
    /// samples (the threshold's order bits are exact), in f64 every one
    /// of them. The control: order bits one f32 step too high skip due
    /// samples, which the comparison must see.
    #[test]
    fn the_fast_chain_computes_the_samples_the_host_rule_makes_due() {
        for threshold in [0.1, 0.5, 1e-3] {
            for fast in [false, true] {
                let plan = SamplePlan {
                    prep_steps: 0,
                    every_global: 10,
                    every_interface: 10,
                    every_bulk: 0,
                    every_fast: 1,
                    fast_slip_speed: threshold,
                    fast,
                };
                let (channels, speeds) = chain_run(threshold, 3000);
                let mixed: Vec<f32> = speeds.iter().map(|&v| v as f32).collect();
                let bits = f32::fast_order_bits(threshold);
                let (device, host) = chain_and_host(&plan, bits, &channels, &mixed);
                assert_eq!(device, host, "mixed, threshold {threshold}");
                let skipped = host.iter().filter(|&&d| !d).count();
                assert!(
                    skipped > 300,
                    "{skipped} of 3000 skipped: the run tests too little"
                );

                let (device, host) = chain_and_host(&plan, bits + 1, &channels, &mixed);
                let missed = device
                    .iter()
                    .zip(&host)
                    .filter(|(d, h)| **h && !**d)
                    .count();
                assert!(
                    missed > 0,
                    "the control: one step too high must skip a due sample"
                );

                let bits = f64::fast_order_bits(threshold);
                let (device, host) = chain_and_host(&plan, bits, &channels, &speeds);
                for (n, (d, h)) in device.iter().zip(&host).enumerate() {
                    assert!(
                        d | !h,
                        "f64, threshold {threshold}: sample {n} due, not computed"
                    );
                }
            }
        }
    }
}
