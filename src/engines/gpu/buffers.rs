//! The engine's storage arrays, each a range of a few arenas (`arena`):
//! every scene's state, scene-major (scene s's element i at s times the
//! per-scene count plus i), the kernels' scratch, the batches and step
//! offsets, and group 0's bind group over them.

use super::arena::{Access, Arenas, Region};
use super::batch_sizes::ONE_STEP_BATCH;
use super::layout::{
    GpuBatch, GpuConsts, GpuJunctionCache, GpuJunctionSpring, GpuLaneSum, GpuStatus,
};
use super::precision::{Coord, GpuReal, Packed};
use super::shaders::Kernel;
use super::tiles::{TileGeometry, TileScratch};
use super::{GpuContext, GpuEngine};
use crate::engines::step_params::Consts;
use crate::model::lattice::{block_flags, initial_displacement};
use crate::model::real::Coordinate;
use crate::model::Model;

/// Elements of one scene in each buffer; scene s's slice starts at s times
/// these (scene-major, `shaders/scene.wgsl`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Shape {
    pub(super) blocks: usize,
    pub(super) nx: usize,
    pub(super) junctions: usize,
    pub(super) lanes: usize,
    /// Reals of friction-law state: `block_state_words` per interface block.
    pub(super) law_words: usize,
}

impl Shape {
    pub(super) fn of(model: &Model) -> Shape {
        let lanes =
            crate::model::junction::JUNCTION_LANES.min(model.junctions.map_or(0, |j| j.count));
        Shape {
            blocks: model.n_blocks(),
            nx: model.nx,
            junctions: model.n_junctions(),
            lanes,
            law_words: model.nx * model.law.declaration().block_state_words,
        }
    }
}

/// Bytes per element of the state buffers that do not depend on the
/// precision (`GpuEngine::DISP_BYTES` and others do).
pub(super) const WORD_PAIR_BYTES: usize = std::mem::size_of::<[u32; 2]>();
pub(super) const STATUS_BYTES: usize = std::mem::size_of::<GpuStatus>();
/// A scene's phase clock sums (`phase_clocks::PHASE_CLOCK_WORDS` words).
pub(super) const PHASE_CLOCK_BYTES: usize =
    super::phase_clocks::PHASE_CLOCK_WORDS * std::mem::size_of::<u32>();
/// What the persistent kernel's unused record bindings hold at least (the
/// plan of either precision, an entry, a word of rows); the sums need
/// `GpuEngine::SUMS_BYTES`.
pub(super) const PLACEHOLDER_BYTES: usize = 128;
const _: () = assert!(
    std::mem::size_of::<super::layout::GpuRecordPlan<f64>>() <= PLACEHOLDER_BYTES
        && std::mem::size_of::<super::layout::GpuRecordPlan<f32>>() <= PLACEHOLDER_BYTES
);

/// The engine's storage arrays, each a region of the arenas
/// (`arena`): the read-write ones share arenas, the read-only ones
/// (`scene_consts`, `flags`, `tile_ends`, the batches, the step offsets,
/// and the record entries' and step samples' placeholders) have their own.
pub(super) struct Buffers {
    /// The run constants: one record per scene.
    pub(super) consts: Region,
    /// Two copies of u and v: the one-step kernel reads one, writes the
    /// other. Each pair is the two halves of one array (`disp_copies`,
    /// `vel_copies`), which the one-step kernels bind whole.
    pub(super) disp: [Region; 2],
    pub(super) vel: [Region; 2],
    pub(super) disp_copies: Region,
    pub(super) vel_copies: Region,
    pub(super) force: Region,
    /// One lattice: shared by the scenes of an ensemble.
    pub(super) flags: Region,
    pub(super) contact: Region,
    /// Every scene's junctions, then (tiled kernel) each tile's private
    /// copy of its halo's (`TileScratch::halo_junctions`).
    pub(super) junction_spring: Region,
    pub(super) junction_state: Region,
    /// Per interface block, the sums of its junctions while none changes
    /// (`GpuJunctionCache`); zeroed wherever the host writes junctions.
    pub(super) junction_cache: Region,
    pub(super) slide: Region,
    /// The friction law's state (`Shape::law_words` per scene).
    pub(super) law_state: Region,
    pub(super) status: Region,
    /// Each scene's phase clock sums (`phase_clocks::PhaseCycles`): zeros
    /// unless `GpuOptions::phase_clocks` asks.
    pub(super) phase_cycles: Region,
    pub(super) lane_partial: Region,
    /// What the step kernels bind for the record buffers `[plan, sums,
    /// rows, entries, step samples]` until they record output samples
    /// (never read then).
    pub(super) record_placeholders: [Region; 5],
    /// The tiled kernel's: two published copies of the blocks (u, v), of
    /// the junctions (state, spring), the ends of a batch's dispatches and each tile's rounds
    /// done; placeholders for the other kernels.
    pub(super) tile_scratch: [Region; 7],
    /// Group 1: each scene's batch (`GpuBatch`), written before each batch.
    pub(super) batches: Region,
    /// Group 1: the step offsets 0..ONE_STEP_BATCH, one per dynamic-offset
    /// stride (a dispatch's offset into it says which step of the batch it
    /// runs), and that stride.
    pub(super) step_offsets: Region,
    pub(super) offset_stride: u64,
    /// Whether the arrays are in arenas (`GpuOptions::pack_arrays`): a
    /// recorder made later packs its own alike.
    pub(super) packed: bool,
}

impl Buffers {
    /// The buffers of `models` (one lattice `shape`, scene-major), in their
    /// initial state; the tiled kernel's scratch where `geometry` is given;
    /// in a few arenas where `packed` (`GpuOptions::pack_arrays`), else a
    /// buffer each.
    pub(super) fn new<T: GpuReal>(
        device: &wgpu::Device,
        limits: &wgpu::Limits,
        models: &[Model],
        shape: Shape,
        geometry: Option<TileGeometry>,
        packed: bool,
    ) -> Buffers {
        let model = &models[0];
        let s = models.len();
        let (n, nj) = (shape.blocks, shape.junctions);
        let disp: Vec<[Coord<T>; 2]> = models
            .iter()
            .flat_map(initial_displacement)
            .map(|u| u.map(Coord::<T>::from_f64))
            .collect();
        let gpu_consts: Vec<GpuConsts<T>> = models
            .iter()
            .map(|m| {
                let speed_limit = T::from_f64(m.pressure_wave_speed());
                GpuConsts::new(&Consts::<T>::new(m), speed_limit)
            })
            .collect();
        let flags = block_flags(model);
        // The tiled kernel's scratch per scene (`TileGeometry::scratch_per_scene`);
        // the lane sums of the others.
        let scratch = geometry.map_or(
            TileScratch {
                published_blocks: 0,
                published_junctions: 0,
                published_sums: 0,
                halo_junctions: 0,
                lane_sums: shape.nx * shape.lanes,
            },
            |g| g.scratch_per_scene(n, shape.nx, nj / shape.nx.max(1), shape.lanes),
        );
        // Every scene's junctions, then (tiled kernel) each tile's private
        // copy of its halo's, which a dispatch fills before it reads them.
        let halo_junctions = s * scratch.halo_junctions;
        let springs: Vec<GpuJunctionSpring<T>> = models
            .iter()
            .flat_map(|m| {
                gpu_junction_springs::<T>(
                    &crate::model::lattice::initial_anchors(m),
                    &vec![0.0; nj],
                )
            })
            .chain(std::iter::repeat_n(
                bytemuck::Zeroable::zeroed(),
                halo_junctions,
            ))
            .collect();
        let junction_state = vec![[crate::model::junction::PINNED, 0u32]; s * nj + halo_junctions];
        let law_state: Vec<Packed<T>> = models
            .iter()
            .flat_map(crate::engines::friction_state::initial_law_state::<T, Coord<T>>)
            .map(T::pack)
            .collect();
        let pairs = |len: usize| s * len * GpuEngine::<T>::REAL_PAIR_BYTES;
        // Both copies of u in one array, and of v in another: each copy
        // padded to the storage offset alignment, so that each is also an
        // array of its own (`disp`, `vel`) and the one-step kernels index
        // the pair (`state_one_step.wgsl`).
        let disp_bytes: &[u8] = bytemuck::cast_slice(&disp);
        let copy = CopyPair::new(limits, disp_bytes.len());
        let vel_copy = CopyPair::new(limits, pairs(n));
        let mut arenas = Arenas::default();
        let (rw, ro) = (Access::ReadWrite, Access::ReadOnly);
        let consts = arenas.bytes(ro, bytemuck::cast_slice(&gpu_consts));
        let disp_copies = arenas.twice(rw, disp_bytes, copy.stride);
        let vel_copies = arenas.zeros(rw, 2 * vel_copy.stride);
        let force = arenas.zeros(rw, pairs(n));
        let flags = arenas.bytes(ro, bytemuck::cast_slice(&flags));
        let contact = arenas.zeros(rw, pairs(shape.nx));
        let junction_spring = arenas.bytes(rw, bytemuck::cast_slice(&springs));
        let junction_state = arenas.bytes(rw, bytemuck::cast_slice(&junction_state));
        // Each scene's interface blocks, then (tiled kernel) each tile's
        // private records of its halo columns.
        let halo_records = geometry.map_or(0, |g| (g.tiles * g.span) as usize);
        let junction_cache = arenas.zeros(
            rw,
            s * (shape.nx + halo_records) * std::mem::size_of::<GpuJunctionCache<T>>(),
        );
        let slide = arenas.zeros(rw, s * shape.nx * WORD_PAIR_BYTES);
        let law_state = arenas.bytes(rw, bytemuck::cast_slice(&law_state));
        let status = arenas.zeros(rw, s * STATUS_BYTES);
        // A slot a scene, or a tile's own for the tiled kernel.
        let phase_slots = s * geometry.map_or(1, |g| g.tiles as usize);
        let phase_cycles = arenas.zeros(rw, phase_slots * PHASE_CLOCK_BYTES);
        // One WGSL `LaneSum` per lane (of each tile's held blocks for the
        // tiled kernel).
        let lane_partial = arenas.zeros(
            rw,
            s * scratch.lane_sums * std::mem::size_of::<GpuLaneSum<T>>(),
        );
        let ends = geometry.map_or(0, |_| ONE_STEP_BATCH as usize);
        let tile_scratch = [
            // Published u and v.
            arenas.zeros(
                rw,
                s * scratch.published_blocks * GpuEngine::<T>::DISP_BYTES,
            ),
            arenas.zeros(rw, pairs(scratch.published_blocks)),
            // Published junction state and springs.
            arenas.zeros(rw, s * scratch.published_junctions * WORD_PAIR_BYTES),
            arenas.zeros(
                rw,
                s * scratch.published_junctions * GpuEngine::<T>::SPRING_BYTES,
            ),
            // The dispatches' ends (read-only in the kernels).
            arenas.zeros(ro, ends * 4),
            // Each tile's rounds done (chained tiles).
            arenas.zeros(rw, s * geometry.map_or(0, |g| g.tiles as usize) * 4),
            // Published kept junction sums (empty records: zeros).
            arenas.zeros(
                rw,
                s * scratch.published_sums * std::mem::size_of::<GpuJunctionCache<T>>(),
            ),
        ];
        // One element of the largest record struct in this precision; the
        // entries and step samples are read-only bindings.
        let placeholder = PLACEHOLDER_BYTES.max(GpuEngine::<T>::SUMS_BYTES);
        let record_placeholders = [rw, rw, rw, ro, ro].map(|a| arenas.zeros(a, placeholder));
        let batches = arenas.zeros(ro, s * std::mem::size_of::<GpuBatch<T>>());
        let (table, offset_stride) = step_offsets(limits);
        let step_offsets = arenas.bytes(ro, &table);
        let built = arenas.build(device, limits, packed);
        Buffers {
            consts: built.region(consts),
            disp: copy.halves(&built.region(disp_copies)),
            vel: vel_copy.halves(&built.region(vel_copies)),
            disp_copies: built.region(disp_copies),
            vel_copies: built.region(vel_copies),
            force: built.region(force),
            flags: built.region(flags),
            contact: built.region(contact),
            junction_spring: built.region(junction_spring),
            junction_state: built.region(junction_state),
            junction_cache: built.region(junction_cache),
            slide: built.region(slide),
            law_state: built.region(law_state),
            status: built.region(status),
            phase_cycles: built.region(phase_cycles),
            lane_partial: built.region(lane_partial),
            record_placeholders: record_placeholders.map(|p| built.region(p)),
            tile_scratch: tile_scratch.map(|t| built.region(t)),
            batches: built.region(batches),
            step_offsets: built.region(step_offsets),
            offset_stride,
            packed,
        }
    }
}

/// Two copies of one state array in one array: each `size` bytes long, the
/// second at `stride` (a multiple of the storage offset alignment), and
/// the pair `2 stride` bytes, so that `arrayLength / 2` is the stride.
struct CopyPair {
    size: usize,
    stride: usize,
}

impl CopyPair {
    fn new(limits: &wgpu::Limits, size: usize) -> CopyPair {
        let align = (limits.min_storage_buffer_offset_alignment as usize).max(4);
        CopyPair {
            size,
            stride: size.max(1).next_multiple_of(align),
        }
    }

    /// The two copies as arrays of their own.
    fn halves(&self, pair: &Region) -> [Region; 2] {
        [
            pair.part(0, self.size as u64),
            pair.part(self.stride as u64, self.size as u64),
        ]
    }
}

/// Group 0 of `kernel`: the state buffers and the record buffers `[plan,
/// sums, rows, entries, step samples]` (`Recorder::state_bindings`, or
/// placeholders' regions), bound by the names the kernel's module declares
/// (`bindings::Bindings`).
pub(super) fn state_group(
    ctx: &GpuContext,
    kernel: Kernel,
    b: &Buffers,
    records: [wgpu::BindingResource<'_>; 5],
) -> wgpu::BindGroup {
    let [plan, sums, rows, entries, step_samples] = records;
    let state = [
        ("scene_consts", &b.consts),
        // The one-step kernels' ping-pong copies; the persistent kernel's
        // state in place.
        ("disp_copies", &b.disp_copies),
        ("vel_copies", &b.vel_copies),
        ("disp_a", &b.disp[0]),
        ("vel_a", &b.vel[0]),
        ("disp_b", &b.disp[1]),
        ("vel_b", &b.vel[1]),
        ("disp", &b.disp[0]),
        ("vel", &b.vel[0]),
        ("force", &b.force),
        ("flags", &b.flags),
        ("contact", &b.contact),
        ("junction_spring", &b.junction_spring),
        ("junction_state", &b.junction_state),
        ("junction_cache", &b.junction_cache),
        ("slide", &b.slide),
        ("law_state", &b.law_state),
        ("status", &b.status),
        ("phase_cycles", &b.phase_cycles),
        ("lane_partial", &b.lane_partial),
        ("pub_disp", &b.tile_scratch[0]),
        ("pub_vel", &b.tile_scratch[1]),
        ("tile_junction_state", &b.tile_scratch[2]),
        ("tile_junction_spring", &b.tile_scratch[3]),
        ("tile_ends", &b.tile_scratch[4]),
        ("tile_progress", &b.tile_scratch[5]),
        ("tile_junction_cache", &b.tile_scratch[6]),
    ]
    .map(|(name, region)| (name, region.binding()));
    let records = [
        ("plans", plan),
        ("sums", sums),
        ("rows", rows),
        ("record_entries", entries),
        ("step_samples", step_samples),
    ];
    let resources: Vec<_> = state.into_iter().chain(records).collect();
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(kernel.entry_point()),
        layout: ctx.state_layout(kernel),
        entries: &ctx.bindings(kernel).entries(0, &resources),
    })
}

/// The step offsets 0..ONE_STEP_BATCH, one per dynamic-offset stride,
/// and that stride.
fn step_offsets(limits: &wgpu::Limits) -> (Vec<u8>, u64) {
    let offset_stride = (limits.min_storage_buffer_offset_alignment as u64).max(4);
    let mut table = vec![0u8; (offset_stride * ONE_STEP_BATCH) as usize];
    for i in 0..ONE_STEP_BATCH {
        let at = (i * offset_stride) as usize;
        table[at..at + 4].copy_from_slice(&(i as u32).to_le_bytes());
    }
    (table, offset_stride)
}

/// The `junction_spring` buffer's records: anchors as coordinates,
/// stiffnesses in `T`.
pub(super) fn gpu_junction_springs<T: GpuReal>(
    anchors: &[f64],
    stiffness: &[f64],
) -> Vec<GpuJunctionSpring<T>> {
    anchors
        .iter()
        .zip(stiffness)
        .map(|(a, k)| GpuJunctionSpring {
            anchor: T::pack(Coord::<T>::from_f64(*a)),
            stiffness: T::from_f64(*k),
        })
        .collect()
}
