//! Output samples recorded on the device (`shaders/record.wgsl`): which
//! steps of a batch are samples and where their records go, the two
//! dispatches that write them, the copy of a batch's records into a staging
//! buffer read back with the batch's status, and their decoding into
//! `Sample`s. Only the channels due are written and copied. An ensemble's
//! scenes are recorded together: the same steps, one dispatch for all
//! (workgroup row z is scene z), each scene in its own region of every
//! record buffer (its plan says where).

use super::compile::ShaderChecks;
use super::context::GpuContext;
use super::layout::{
    GpuRecordEntry, GpuRecordPlan, GpuSampleSums, RECORD_BULK, RECORD_BULK_WORDS, RECORD_FAST,
    RECORD_GLOBAL, RECORD_INTERFACE, RECORD_INTERFACE_WORDS, WORKGROUP,
};
use super::options::ONE_STEP_BATCH;
use super::precision::GpuReal;
use super::record_pipelines::{RecordPipelines, RECORD_SMALL_BLOCKS};
use crate::engines::{BulkField, InterfaceRow, Sample, SamplePlan, SampleSums};
use crate::model::{Driver, Model};
use wgpu::util::DeviceExt;

/// Record buffers of one batch at most (interface rows and bulk fields);
/// a batch ends early rather than go past it (one bulk field always fits).
const ROWS_BUDGET: u64 = 64 << 20;

/// The most samples of a batch of the tiled kernel, which keeps a partial
/// per tile for each: a batch ends early rather than plan more. At
/// Table S1's cadences (a planned sample every 4 or 5 steps) a batch of
/// `ONE_STEP_BATCH` steps plans about 230; a quarter of the other kernels'
/// room keeps an ensemble's partials a quarter as large.
const TILED_SAMPLES_A_BATCH: u32 = 256;

/// The state buffers the output kernels read.
pub struct StateBuffers<'a> {
    pub consts: &'a wgpu::Buffer,
    pub disp: &'a [wgpu::Buffer; 2],
    pub vel: &'a [wgpu::Buffer; 2],
    pub force: &'a wgpu::Buffer,
    pub flags: &'a wgpu::Buffer,
    pub contact: &'a wgpu::Buffer,
    pub junction_state: &'a wgpu::Buffer,
    pub slide: &'a wgpu::Buffer,
}

/// A sample asked for in a batch: after the step dispatch at `offset` (or
/// after the batch's forces-only pass), at global step `step`.
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
    /// The cadences every scene shares (each scene's fast flag is on the
    /// device, in its plan).
    plan: SamplePlan,
    /// Scene by scene.
    models: Vec<Model>,
    pipelines: std::sync::Arc<RecordPipelines>,
    plan_buffer: wgpu::Buffer,
    sums: wgpu::Buffer,
    rows: wgpu::Buffer,
    entries: wgpu::Buffer,
    group: wgpu::BindGroup,
    entry_group: wgpu::BindGroup,
    /// Bytes between entries: the dynamic-offset alignment for the output
    /// kernels, the entry's size for the persistent kernel (an array).
    stride: u64,
    /// Workgroups of `record_sample` (x, y); None: one `record_small`, or
    /// no output kernel (the persistent and tiled kernels record in their
    /// steps). With them, the step dispatch of a sample sums each
    /// partial's kinetic energy (the one-step kernels' recording variant):
    /// then a sample without a bulk field takes `record_special` over
    /// these partials, not `record_sample`.
    groups: Option<(u32, u32)>,
    special_count: u32,
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
    spare: Vec<wgpu::Buffer>,
    precision: std::marker::PhantomData<T>,
}

/// Reals of `T` in `bytes`.
fn words<T>(bytes: u64) -> u64 {
    bytes / size_of::<T>() as u64
}

/// How a sample's partials split a lattice: each holds `WORKGROUP`
/// consecutive blocks, or `WORKGROUP` items of the one-step kernels'
/// patched threads (`shaders/patch_items.wgsl`: interface block t below
/// nx, then the 2×2 patches of the rows above, ⌈nx/2⌉ a row).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Partials {
    nx: u32,
    nz: u32,
    by_patches: bool,
}

impl Partials {
    pub fn of(m: &Model, by_patches: bool) -> Partials {
        Partials {
            nx: m.nx as u32,
            nz: m.nz as u32,
            by_patches,
        }
    }

    /// Blocks, or items.
    fn items(self) -> u32 {
        if self.by_patches {
            self.nx + self.nx.div_ceil(2) * (self.nz - 1).div_ceil(2)
        } else {
            self.nx * self.nz
        }
    }

    pub fn count(self) -> u32 {
        self.items().div_ceil(WORKGROUP)
    }

    /// The partial that holds the block at `column` and `row`.
    fn holding(self, column: u32, row: u32) -> u32 {
        let item = if !self.by_patches || row == 0 {
            row * self.nx + column
        } else {
            self.nx + (row - 1) / 2 * self.nx.div_ceil(2) + column / 2
        };
        item / WORKGROUP
    }

    /// The partials of any of the scenes that hold a block adding more
    /// than kinetic energy to a sample: the interface row, the top row
    /// where the top reaction is summed, the driven block. In increasing
    /// order, each once (`record_special`).
    fn special(self, models: &[Model]) -> Vec<u32> {
        let (nx, nz) = (self.nx, self.nz);
        let mut groups: Vec<u32> = (0..=self.holding(nx - 1, 0)).collect();
        for m in models {
            match m.driver {
                Driver::TopVelocity { .. } => {
                    groups.extend(self.holding(0, nz - 1)..=self.holding(nx - 1, nz - 1))
                }
                Driver::SideSpring { row, .. } => groups.push(self.holding(0, row as u32)),
                _ => {}
            }
        }
        groups.sort_unstable();
        groups.dedup();
        groups
    }
}

/// Where a step kernel's output samples are recorded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordSite {
    /// By the output kernels, after a sample's step dispatch (the one-step
    /// kernels, whose recording variant `RECORD_KINETIC` a large lattice's
    /// samples then use). `stride`: the dynamic-offset alignment of the
    /// entries; `partials`: how the partials split the lattice (as the
    /// step kernel's workgroups do).
    Dispatches { stride: u64, partials: Partials },
    /// Inside the persistent kernel's loop, which reads the entries as an
    /// array.
    Persistent,
    /// Inside the tiled kernel's steps: a partial per tile (`tiles` a
    /// scene) and sample, added after the batch (`tile_record_finish`).
    Tiles { tiles: u32 },
}

impl<T: GpuReal> Recorder<T> {
    /// The recorder of an engine's scenes (`models`, one lattice) whose
    /// step kernel records at `site`, or why the device cannot hold the
    /// records of one batch. `checks`: the run-time checks of the output
    /// kernels' module, as the step kernel's.
    pub fn new(
        ctx: &GpuContext,
        models: &[Model],
        state: StateBuffers,
        plan: &SamplePlan,
        site: RecordSite,
        checks: ShaderChecks,
    ) -> Result<Recorder<T>, String> {
        // The others read the entries as an array.
        let (stride, layout) = match site {
            RecordSite::Dispatches { stride, partials } => (stride, partials),
            _ => (
                size_of::<GpuRecordEntry>() as u64,
                Partials::of(&models[0], false),
            ),
        };
        let device = &ctx.device;
        let model = &models[0];
        let scenes = models.len() as u64;
        let (n, nx) = (model.n_blocks() as u64, model.nx as u64);
        let real = size_of::<T>() as u64;
        let interface_bytes = nx * RECORD_INTERFACE_WORDS as u64 * real;
        let bulk_bytes = n * RECORD_BULK_WORDS as u64 * real;
        let max_entries = match site {
            RecordSite::Tiles { .. } => TILED_SAMPLES_A_BATCH,
            _ => ONE_STEP_BATCH as u32 + 1,
        };
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
        // The output kernels' partials, or the tiled kernel's: a tile's
        // each of a batch's samples.
        let (partials, groups) = match site {
            RecordSite::Dispatches { .. } => {
                let partials = layout.count();
                let groups = (model.n_blocks() > RECORD_SMALL_BLOCKS)
                    .then(|| super::step_kernel::groups_for(partials));
                (partials, groups)
            }
            RecordSite::Persistent => (0, None),
            RecordSite::Tiles { tiles } => (max_entries * tiles, None),
        };
        let special = layout.special(models);
        let special_groups = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("record special groups"),
            contents: bytemuck::cast_slice(&special),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let sums_per_scene = (max_entries + partials) as u64;
        let sums_bytes = scenes * sums_per_scene * size_of::<GpuSampleSums<T>>() as u64;
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
                    fast_slip_speed: T::from_f64(plan.fast_slip_speed),
                    driven_block: match m.driver {
                        Driver::SideSpring { row, .. } => (row * m.nx) as u32,
                        _ => u32::MAX,
                    },
                    top_reaction: matches!(m.driver, Driver::TopVelocity { .. }) as u32,
                    junctions_per_block: (m.n_junctions() / m.nx.max(1)) as u32,
                    partials,
                    partials_by_patches: layout.by_patches as u32,
                    reserved: 0,
                    sums_offset: (k * sums_per_scene) as u32,
                    partials_offset: (k * sums_per_scene) as u32 + max_entries,
                    interface_offset: words::<T>(k * rows_per_scene) as u32,
                    bulk_offset: words::<T>(k * rows_per_scene + bulk_offset) as u32,
                }
            })
            .collect();
        let plan_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("record plans"),
            contents: bytemuck::cast_slice(&gpu_plans),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        });
        let storage = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | usage,
                mapped_at_creation: false,
            })
        };
        let sums = storage("record sums", sums_bytes, wgpu::BufferUsages::COPY_SRC);
        let rows = storage("record rows", rows_bytes, wgpu::BufferUsages::COPY_SRC);
        let entries = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("record entries"),
            size: max_entries as u64 * stride.max(size_of::<GpuRecordEntry>() as u64),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let pipelines = ctx.record_pipelines::<T>(checks);
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("record"),
            layout: &pipelines.group,
            entries: &pipelines.bindings.entries(
                0,
                &[
                    ("scene_consts", state.consts),
                    ("disp_a", &state.disp[0]),
                    ("vel_a", &state.vel[0]),
                    ("disp_b", &state.disp[1]),
                    ("vel_b", &state.vel[1]),
                    ("force", state.force),
                    ("flags", state.flags),
                    ("contact", state.contact),
                    ("junction_state", state.junction_state),
                    ("slide", state.slide),
                    ("plans", &plan_buffer),
                    ("sums", &sums),
                    ("rows", &rows),
                    ("special_groups", &special_groups),
                ]
                .map(|(name, buffer)| (name, buffer.as_entire_binding())),
            ),
        });
        let entry_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("record entry"),
            layout: &pipelines.entry,
            entries: &pipelines.bindings.entries(
                1,
                &[(
                    super::record_pipelines::RECORD_ENTRY,
                    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &entries,
                        offset: 0,
                        size: wgpu::BufferSize::new(size_of::<GpuRecordEntry>() as u64),
                    }),
                )],
            ),
        });
        Ok(Recorder {
            plan: *plan,
            models: models.to_vec(),
            pipelines,
            plan_buffer,
            sums,
            rows,
            entries,
            group,
            entry_group,
            stride,
            groups,
            special_count: special.len() as u32,
            max_entries,
            max_interface,
            max_bulk,
            sums_per_scene,
            rows_per_scene,
            bulk_offset,
            recorded_through: None,
            spare: Vec::new(),
            precision: std::marker::PhantomData,
        })
    }

    /// The buffers the step kernels bind: the persistent kernel at 13
    /// (plan), 14 (sums), 15 (rows) and 16 (entries); the one-step kernels'
    /// recording variant plans and sums.
    pub fn state_bindings(&self) -> [&wgpu::Buffer; 4] {
        [&self.plan_buffer, &self.sums, &self.rows, &self.entries]
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
    /// cadences are this recorder's, `samples_like`); only between batches
    /// (the engine has drained).
    pub fn set_plan(&mut self, queue: &wgpu::Queue, scene: usize, plan: &SamplePlan) {
        debug_assert!(self.samples_like(plan));
        let at =
            scene * size_of::<GpuRecordPlan<T>>() + std::mem::offset_of!(GpuRecordPlan<T>, fast);
        queue.write_buffer(
            &self.plan_buffer,
            at as u64,
            bytemuck::bytes_of(&(plan.fast as u32)),
        );
    }

    /// Whether `step` is a sample not yet taken.
    fn wanted(&self, step: u64) -> bool {
        self.recorded_through.is_none_or(|r| step > r) && self.plan.due(step).any()
    }

    /// The samples of a batch of `steps` steps from `first` whose first
    /// step reads state copy `parity`, and how many steps the batch may
    /// take before its records would overflow (≤ `steps`).
    pub fn plan_batch(&self, first: u64, steps: u64, parity: usize) -> (Vec<Planned>, u64) {
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
                    copy: ((parity as u64 + offset) & 1) as u32,
                    channels,
                    sums_slot: planned.len() as u32,
                    interface_slot: interface,
                    bulk_slot: bulk,
                },
            });
            interface += needs_interface as u32;
            bulk += due.bulk as u32;
        }
        (planned, steps)
    }

    /// The sample of the current step (after a forces-only pass), if it is
    /// one not yet taken.
    pub fn plan_now(&self, step: u64, copy: usize) -> Vec<Planned> {
        if !self.wanted(step) {
            return Vec::new();
        }
        let mut v = self.plan_batch(step, 1, copy).0;
        // No step dispatch runs: the copy is the current one.
        if let Some(p) = v.first_mut() {
            p.entry.copy = copy as u32;
        }
        v
    }

    /// Writes a batch's entries (before its submit) and marks its samples
    /// as taken.
    pub fn write_entries(&mut self, queue: &wgpu::Queue, planned: &[Planned]) {
        if planned.is_empty() {
            return;
        }
        let mut table = vec![0u8; planned.len() * self.stride as usize];
        for (k, p) in planned.iter().enumerate() {
            let at = k * self.stride as usize;
            table[at..at + size_of::<GpuRecordEntry>()]
                .copy_from_slice(bytemuck::bytes_of(&p.entry));
        }
        queue.write_buffer(&self.entries, 0, &table);
        self.recorded_through = planned.last().map(|p| p.step);
    }

    /// Whether the step dispatch of sample `entry` is to sum each
    /// partial's kinetic energy (the one-step kernels' recording variant,
    /// `RECORD_KINETIC`): lattices recorded in two dispatches, when no
    /// bulk field is due (`record_sample` writes every partial then).
    pub fn kinetic_in_step(&self, entry: &GpuRecordEntry) -> bool {
        self.kinetic_in_steps() && entry.channels & RECORD_BULK == 0
    }

    /// Whether any sample's step dispatch may sum kinetic energy (the
    /// engine then builds the recording variant of its step kernel).
    pub fn kinetic_in_steps(&self) -> bool {
        self.groups.is_some()
    }

    /// Records sample `k` of the batch, `entry`, (one or two dispatches)
    /// in `pass`, calling `after_each` after each dispatch (the dispatch
    /// timing's marks); the caller sets its own pipeline and groups again
    /// afterwards. Returns the dispatches.
    pub fn encode(
        &self,
        pass: &mut wgpu::ComputePass,
        k: usize,
        entry: &GpuRecordEntry,
        after_each: &mut dyn FnMut(&mut wgpu::ComputePass),
    ) -> u64 {
        let offset = (k as u64 * self.stride) as u32;
        pass.set_bind_group(0, &self.group, &[]);
        pass.set_bind_group(1, &self.entry_group, &[offset]);
        let scenes = self.models.len() as u32;
        match self.groups {
            None => {
                pass.set_pipeline(&self.pipelines.small);
                pass.dispatch_workgroups(1, 1, scenes);
                after_each(pass);
                1
            }
            Some((x, y)) => {
                if self.kinetic_in_step(entry) {
                    pass.set_pipeline(&self.pipelines.special);
                    pass.dispatch_workgroups(self.special_count, 1, scenes);
                } else {
                    pass.set_pipeline(&self.pipelines.sample);
                    pass.dispatch_workgroups(x, y, scenes);
                }
                after_each(pass);
                pass.set_pipeline(&self.pipelines.finish);
                pass.dispatch_workgroups(1, 1, scenes);
                after_each(pass);
                2
            }
        }
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
            encoder.copy_buffer_to_buffer(&self.sums, sums_at, &staging, to, sums_bytes);
            let rows_at = k * self.rows_per_scene;
            if interface_bytes > 0 {
                encoder.copy_buffer_to_buffer(
                    &self.rows,
                    rows_at,
                    &staging,
                    to + sums_bytes,
                    interface_bytes,
                );
            }
            if bulk_bytes > 0 {
                encoder.copy_buffer_to_buffer(
                    &self.rows,
                    rows_at + self.bulk_offset,
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
        let samples = self
            .models
            .iter()
            .zip(before)
            .enumerate()
            .map(|(k, (m, &before))| {
                let at = (k as u64 * pending.scene_bytes) as usize;
                let records = &view[at..at + pending.scene_bytes as usize];
                self.decode_scene(&pending, m, records, before)
            })
            .collect();
        drop(view);
        pending.staging.unmap();
        self.spare.push(pending.staging);
        Ok(samples)
    }

    /// One scene's samples from its records in the staging buffer.
    fn decode_scene(
        &self,
        pending: &Pending,
        m: &Model,
        records: &[u8],
        before: u64,
    ) -> Vec<Sample> {
        let sums_bytes = pending.planned.len() * size_of::<GpuSampleSums<T>>();
        let sums: &[GpuSampleSums<T>] = bytemuck::cast_slice(&records[..sums_bytes]);
        let reals: &[T] = bytemuck::cast_slice(&records[sums_bytes..]);
        let interface_words = self.interface_bytes() as usize / size_of::<T>();
        let bulk_at = pending.interface_slots as usize * interface_words;
        let bulk_words = self.bulk_bytes() as usize / size_of::<T>();
        debug_assert!(reals.len() >= bulk_at + pending.bulk_slots as usize * bulk_words);
        let mut samples = Vec::new();
        for (p, s) in pending.planned.iter().zip(sums) {
            if s.recorded == 0 || p.step >= before {
                continue;
            }
            let interface = (s.interface_row != 0).then(|| {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The first block (column, row) of the one-step kernels' patch item
    /// `t` ≥ nx on a lattice `nx` wide (`shaders/patch_items.wgsl`, the
    /// same name; the host needs only its inverse, `Partials::holding`);
    /// its row is nz or more past the last patch.
    fn patch_item_origin(t: u32, nx: u32) -> (u32, u32) {
        let columns = nx.div_ceil(2);
        let p = t - nx;
        (2 * (p % columns), 1 + 2 * (p / columns))
    }

    /// Every block of odd and even lattices lies in one item of the
    /// patched layout (patch_item_origin), and `Partials::holding` names
    /// that item's partial; the plain layout holds WORKGROUP consecutive
    /// blocks.
    #[test]
    fn partials_by_patches_hold_each_block_once() {
        for (nx, nz) in [(57, 31), (256, 128), (15, 8), (130, 1), (3, 2)] {
            let by_patches = Partials {
                nx,
                nz,
                by_patches: true,
            };
            let mut seen = vec![0u32; (nx * nz) as usize];
            let mut partial_of = vec![u32::MAX; (nx * nz) as usize];
            for t in 0..by_patches.items() {
                let blocks: Vec<(u32, u32)> = if t < nx {
                    vec![(t, 0)]
                } else {
                    let (x0, z0) = patch_item_origin(t, nx);
                    [(0, 0), (1, 0), (0, 1), (1, 1)]
                        .iter()
                        .map(|&(dx, dz)| (x0 + dx, z0 + dz))
                        .filter(|&(x, z)| x < nx && z < nz)
                        .collect()
                };
                assert!(!blocks.is_empty(), "{nx}×{nz}: item {t} is empty");
                for (x, z) in blocks {
                    seen[(z * nx + x) as usize] += 1;
                    partial_of[(z * nx + x) as usize] = t / WORKGROUP;
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{nx}×{nz}: {seen:?}");
            for z in 0..nz {
                for x in 0..nx {
                    assert_eq!(by_patches.holding(x, z), partial_of[(z * nx + x) as usize]);
                }
            }
            assert!(by_patches.count() * WORKGROUP >= by_patches.items());
            let plain = Partials {
                by_patches: false,
                ..by_patches
            };
            assert_eq!(plain.holding(nx - 1, nz - 1), (nx * nz - 1) / WORKGROUP);
            assert_eq!(plain.count(), (nx * nz).div_ceil(WORKGROUP));
        }
    }
}
