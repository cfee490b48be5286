//! The engine's device buffers: every scene's state, scene-major (scene
//! s's element i at s times the per-scene count plus i), the kernels'
//! scratch, and group 0's bind group over them.

use super::batch_sizes::ONE_STEP_BATCH;
use super::layout::{GpuConsts, GpuJunctionCache, GpuJunctionSpring, GpuLaneSum, GpuStatus};
use super::precision::{Coord, GpuReal, Packed};
use super::shaders::Kernel;
use super::tiles::TileGeometry;
use super::{GpuContext, GpuEngine};
use crate::engines::step_params::Consts;
use crate::model::lattice::{block_flags, initial_displacement};
use crate::model::real::Coordinate;
use crate::model::Model;
use bytemuck::Zeroable;
use wgpu::util::DeviceExt;

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
/// What the persistent kernel's unused record bindings hold at least (the
/// plan of either precision, an entry, a word of rows); the sums need
/// `GpuEngine::SUMS_BYTES`.
pub(super) const PLACEHOLDER_BYTES: usize = 128;
const _: () = assert!(
    std::mem::size_of::<super::layout::GpuRecordPlan<f64>>() <= PLACEHOLDER_BYTES
        && std::mem::size_of::<super::layout::GpuRecordPlan<f32>>() <= PLACEHOLDER_BYTES
);

pub(super) struct Buffers {
    /// The run constants: one record per scene.
    pub(super) consts: wgpu::Buffer,
    /// Two copies of u and v: the one-step kernel reads one, writes the other.
    pub(super) disp: [wgpu::Buffer; 2],
    pub(super) vel: [wgpu::Buffer; 2],
    pub(super) force: wgpu::Buffer,
    /// One lattice: shared by the scenes of an ensemble.
    pub(super) flags: wgpu::Buffer,
    pub(super) contact: wgpu::Buffer,
    pub(super) junction_spring: wgpu::Buffer,
    pub(super) junction_state: wgpu::Buffer,
    /// Per interface block, the sums of its junctions while none changes
    /// (`GpuJunctionCache`); zeroed wherever the host writes junctions.
    pub(super) junction_cache: wgpu::Buffer,
    pub(super) slide: wgpu::Buffer,
    /// The friction law's state (`Shape::law_words` per scene).
    pub(super) law_state: wgpu::Buffer,
    pub(super) status: wgpu::Buffer,
    pub(super) lane_partial: wgpu::Buffer,
    /// What the step kernels bind for the record buffers until they
    /// record output samples (never read then).
    pub(super) record_placeholders: [wgpu::Buffer; 5],
    /// The tiled kernel's: two published copies of the blocks (u, v), of
    /// the junctions (state, spring; then each tile's private halo
    /// junctions), the ends of a batch's dispatches and each tile's rounds
    /// done; placeholders for the other kernels.
    pub(super) tile_scratch: [wgpu::Buffer; 6],
}

impl Buffers {
    /// The buffers of `models` (one lattice `shape`, scene-major), in their
    /// initial state; the tiled kernel's scratch where `geometry` is given.
    pub(super) fn new<T: GpuReal>(
        device: &wgpu::Device,
        models: &[Model],
        shape: Shape,
        geometry: Option<TileGeometry>,
    ) -> Buffers {
        let model = &models[0];
        let s = models.len();
        let (n, nj) = (shape.blocks, shape.junctions);
        let storage = |label: &str, bytes: &[u8]| {
            // Zero-sized bindings are invalid: pad empty arrays to one element.
            let padded;
            let contents = if bytes.is_empty() {
                padded = vec![0u8; 48]; // a whole number of every element size
                &padded[..]
            } else {
                bytes
            };
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
            })
        };
        let disp: Vec<[Coord<T>; 2]> = models
            .iter()
            .flat_map(initial_displacement)
            .map(|u| u.map(Coord::<T>::from_f64))
            .collect();
        let zeros2 = |len: usize| vec![[T::zero(); 2]; len];
        let gpu_consts: Vec<GpuConsts<T>> = models
            .iter()
            .map(|m| {
                let speed_limit = T::from_f64(m.pressure_wave_speed());
                GpuConsts::new(&Consts::<T>::new(m), speed_limit)
            })
            .collect();
        // The tiled kernel's scratch per scene (`TileGeometry::scratch_per_scene`);
        // the lane sums of the others.
        let scratch = geometry.map_or([0, 0, shape.nx * shape.lanes], |g| {
            g.scratch_per_scene(n, shape.nx, nj / shape.nx.max(1), shape.lanes)
        });
        Buffers {
            consts: storage("scene consts", bytemuck::cast_slice(&gpu_consts)),
            disp: [
                storage("disp 0", bytemuck::cast_slice(&disp)),
                storage("disp 1", bytemuck::cast_slice(&disp)),
            ],
            vel: [
                storage("vel 0", bytemuck::cast_slice(&zeros2(s * n))),
                storage("vel 1", bytemuck::cast_slice(&zeros2(s * n))),
            ],
            force: storage("force", bytemuck::cast_slice(&zeros2(s * n))),
            flags: storage("flags", bytemuck::cast_slice(&block_flags(model))),
            contact: storage("contact", bytemuck::cast_slice(&zeros2(s * shape.nx))),
            junction_spring: storage(
                "junction_spring",
                bytemuck::cast_slice(
                    &models
                        .iter()
                        .flat_map(|m| {
                            gpu_junction_springs::<T>(
                                &crate::model::lattice::initial_anchors(m),
                                &vec![0.0; nj],
                            )
                        })
                        .collect::<Vec<_>>(),
                ),
            ),
            junction_state: storage(
                "junction_state",
                bytemuck::cast_slice(&vec![[crate::model::junction::PINNED, 0u32]; s * nj]),
            ),
            junction_cache: storage(
                "junction sums kept",
                // Each scene's interface blocks, then (tiled kernel) each
                // tile's private records of its halo columns.
                bytemuck::cast_slice(&vec![
                    GpuJunctionCache::<T>::zeroed();
                    s * (shape.nx
                        + geometry
                            .map_or(0, |g| (g.tiles * g.span) as usize))
                ]),
            ),
            slide: storage(
                "slide",
                bytemuck::cast_slice(&vec![[0i32; 2]; s * shape.nx]),
            ),
            law_state: storage(
                "law_state",
                bytemuck::cast_slice(
                    &models
                        .iter()
                        .flat_map(crate::engines::friction_state::initial_law_state::<T, Coord<T>>)
                        .map(T::pack)
                        .collect::<Vec<Packed<T>>>(),
                ),
            ),
            status: storage(
                "status",
                bytemuck::cast_slice(&vec![GpuStatus::zeroed(); s]),
            ),
            lane_partial: storage(
                "lane partial sums",
                // One WGSL `LaneSum` per lane (of each tile's held blocks
                // for the tiled kernel).
                bytemuck::cast_slice(&vec![GpuLaneSum::<T>::zeroed(); s * scratch[2]]),
            ),
            tile_scratch: {
                let zeros = |len: usize, bytes: usize| vec![0u8; s * len * bytes];
                let ends = geometry.map_or(0, |_| ONE_STEP_BATCH as usize);
                [
                    storage(
                        "published disp",
                        &zeros(scratch[0], GpuEngine::<T>::DISP_BYTES),
                    ),
                    storage(
                        "published vel",
                        &zeros(scratch[0], GpuEngine::<T>::REAL_PAIR_BYTES),
                    ),
                    storage("tile junction state", &zeros(scratch[1], WORD_PAIR_BYTES)),
                    storage(
                        "tile junction spring",
                        &zeros(scratch[1], GpuEngine::<T>::SPRING_BYTES),
                    ),
                    storage("tile dispatch ends", &vec![0u8; ends * 4]),
                    // Each tile's rounds done (chained tiles).
                    storage(
                        "tile progress",
                        &vec![0u8; s * geometry.map_or(0, |g| g.tiles as usize) * 4],
                    ),
                ]
            },
            // One element of the largest record struct in this precision.
            record_placeholders: std::array::from_fn(|_| {
                storage(
                    "no records",
                    &vec![0u8; PLACEHOLDER_BYTES.max(GpuEngine::<T>::SUMS_BYTES)],
                )
            }),
        }
    }
}

/// Group 0 of `kernel`: the state buffers and the record buffers `[plan,
/// sums, rows, entries, step samples]` (`Recorder::state_bindings`, or
/// placeholders), bound by the names the kernel's module declares
/// (`bindings::Bindings`).
pub(super) fn state_group(
    ctx: &GpuContext,
    kernel: Kernel,
    b: &Buffers,
    records: [&wgpu::Buffer; 5],
) -> wgpu::BindGroup {
    let [plan, sums, rows, entries, step_samples] = records;
    let resources = [
        ("scene_consts", &b.consts),
        // The one-step kernels' ping-pong copies; the persistent kernel's
        // state in place.
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
        ("lane_partial", &b.lane_partial),
        ("pub_disp", &b.tile_scratch[0]),
        ("pub_vel", &b.tile_scratch[1]),
        ("tile_junction_state", &b.tile_scratch[2]),
        ("tile_junction_spring", &b.tile_scratch[3]),
        ("tile_ends", &b.tile_scratch[4]),
        ("tile_progress", &b.tile_scratch[5]),
        ("plans", plan),
        ("sums", sums),
        ("rows", rows),
        ("record_entries", entries),
        ("step_samples", step_samples),
    ]
    .map(|(name, buffer)| (name, buffer.as_entire_binding()));
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(kernel.entry_point()),
        layout: ctx.state_layout(kernel),
        entries: &ctx.bindings(kernel).entries(0, &resources),
    })
}

/// The step offsets 0..ONE_STEP_BATCH, one per dynamic-offset stride (a
/// dispatch's offset into it says which step of the batch it runs), and
/// that stride.
pub(super) fn step_offsets(device: &wgpu::Device, limits: &wgpu::Limits) -> (wgpu::Buffer, u64) {
    let offset_stride = (limits.min_storage_buffer_offset_alignment as u64).max(4);
    let mut table = vec![0u8; (offset_stride * ONE_STEP_BATCH) as usize];
    for i in 0..ONE_STEP_BATCH {
        let at = (i * offset_stride) as usize;
        table[at..at + 4].copy_from_slice(&(i as u32).to_le_bytes());
    }
    let offsets = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("step offsets"),
        contents: &table,
        usage: wgpu::BufferUsages::STORAGE,
    });
    (offsets, offset_stride)
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
