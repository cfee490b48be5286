//! The structs the host shares with the WGSL kernels, declared once here:
//! `gpu_struct!` defines the Rust struct and writes its WGSL declaration,
//! and `wgsl_prelude` adds the constants both sides use (flags, PINNED,
//! lanes, stencil). The shaders get these declarations prepended, so a
//! field added here exists on both sides; a naga test checks the offsets.
//! Most structs are generic in the kernels' precision `T` (f32 mixed or
//! f64, `precision::GpuReal`): one definition gives both layouts, with
//! the u32 fields first so that neither has padding.

use super::precision::{Coord, GpuReal, Packed, WgslType};
use crate::engines::step_params::{drive_target_at_anchor, Consts};
use crate::model::lattice::{
    FLAG_DRIVEN, FLAG_FIX_X, FLAG_FIX_Z, FLAG_INTERFACE, FLAG_PRESCRIBED_X, FLAG_TOP, STENCIL,
};
use bytemuck::{Pod, Zeroable};

/// Threads per workgroup of the one-step kernel.
pub const WORKGROUP: u32 = 64;

/// A struct shared with WGSL: its fields, types and byte offsets.
pub trait GpuStruct {
    const NAME: &'static str;
    /// (field, WGSL type, byte offset in the Rust struct).
    fn fields() -> Vec<(&'static str, &'static str, usize)>;
    /// The WGSL declaration.
    fn wgsl() -> String {
        let body: String = Self::fields()
            .iter()
            .map(|(name, ty, _)| format!("    {name}: {ty},\n"))
            .collect();
        format!("struct {} {{\n{body}}}\n", Self::NAME)
    }
}

macro_rules! gpu_struct {
    // Generic in the precision: fields of type T, Coord<T>, Packed<T>.
    ($(#[$meta:meta])* pub struct $name:ident<T> as $wgsl:literal {
        $($(#[$fmeta:meta])* pub $field:ident : $ty:ty),* $(,)?
    }) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Debug, Clone, Copy)]
        pub struct $name<T: GpuReal = f32> {
            $($(#[$fmeta])* pub $field: $ty),*
        }

        // SAFETY: repr(C), every field is Pod (u32, f32, f64, their pairs),
        // and neither precision's layout has padding (asserted below).
        unsafe impl<T: GpuReal> Zeroable for $name<T> {}
        unsafe impl<T: GpuReal> Pod for $name<T> {}
        const _: () = {
            type T = f32;
            assert!(std::mem::size_of::<$name<T>>() == 0 $(+ std::mem::size_of::<$ty>())*);
        };
        const _: () = {
            type T = f64;
            assert!(std::mem::size_of::<$name<T>>() == 0 $(+ std::mem::size_of::<$ty>())*);
        };

        impl<T: GpuReal> GpuStruct for $name<T> {
            const NAME: &'static str = $wgsl;
            fn fields() -> Vec<(&'static str, &'static str, usize)> {
                vec![$((
                    stringify!($field),
                    <$ty as WgslType>::FIELD,
                    std::mem::offset_of!($name<T>, $field),
                )),*]
            }
        }
    };
    ($(#[$meta:meta])* pub struct $name:ident as $wgsl:literal {
        $($(#[$fmeta:meta])* pub $field:ident : $ty:ty),* $(,)?
    }) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Debug, Clone, Copy, Pod, Zeroable)]
        pub struct $name {
            $($(#[$fmeta])* pub $field: $ty),*
        }

        impl GpuStruct for $name {
            const NAME: &'static str = $wgsl;
            fn fields() -> Vec<(&'static str, &'static str, usize)> {
                vec![$((
                    stringify!($field),
                    <$ty as WgslType>::FIELD,
                    std::mem::offset_of!($name, $field),
                )),*]
            }
        }
    };
}

gpu_struct! {
    /// The run constants of a scene (`c`, its copy of `scene_consts[s]`).
    pub struct GpuConsts<T> as "Consts" {
        pub nx: u32,
        pub nz: u32,
        pub junction_count: u32,
        pub seed: u32,
        pub stiffness_normal_load: u32,
        pub n_blocks: u32,
        pub strip_blocks: u32,
        /// 1.0, read at run time: guards the double-single sums against
        /// reassociation (shaders/double_single.wgsl).
        pub one: f32,
        pub spacing: T,
        pub k: T,
        pub eta: T,
        pub k_foundation: T,
        pub mass: T,
        pub inv_mass: T,
        pub dt: T,
        pub mu_s: T,
        pub mu_d: T,
        pub junction_stiffness_value: T,
        pub slip_mean_steps: T,
        pub slip_std_steps: T,
        pub drive_stiffness: T,
        pub speed_limit: T,
        pub top_share_full: T,
        pub top_share_edge: T,
        pub normal_force: T,
        pub normal_slope: T,
        pub inv_ramp_steps: T,
        pub top_prestress_force: T,
        pub top_force_rate: T,
        pub relax_eta: T,
        pub absolute_eta: T,
        pub interface_shear_force: T,
        pub strip_shear_force: T,
        pub drive_velocity: T,
        /// V·dt = hi + lo, hi with 12 significant bits so that i·hi is
        /// exact for the step offsets i < 4096 of a batch.
        pub drive_step_hi: T,
        pub drive_step_lo: T,
        /// The friction law's constants (`Consts::law`): each per-block
        /// law's WGSL names its own.
        pub law0: T,
        pub law1: T,
        pub law2: T,
        pub law3: T,
        pub law4: T,
        pub law5: T,
        pub law6: T,
        pub law7: T,
    }
}

gpu_struct! {
    /// What the kernels need to compute the loads of the steps of one
    /// batch (`shaders/common.wgsl` `loads_at`): steps `first + i`,
    /// i < `steps`. Batches never cross the end of the ramp or of the
    /// normal-load phase, so the phase flags hold for the whole batch.
    pub struct GpuBatch<T> as "Batch" {
        /// The side spring's far end at the first step (a coordinate).
        pub drive_target: Coord<T>,
        /// Driving time of the first step (s).
        pub drive_time: T,
        /// Unused: keeps both precisions free of padding.
        pub reserved_real: T,
        /// Low 32 bits of the first step (used while ramping, < 2²⁴).
        pub first_step: u32,
        pub steps: u32,
        pub preparing: u32,
        pub ramping: u32,
        pub relaxing: u32,
        /// 1: the forces of the first step are already in `force` and
        /// `contact` (a snapshot computed them): skip them.
        pub forces_ready: u32,
        /// 1: compute the forces of the first step only, no update.
        pub forces_only: u32,
        /// Steps per dispatch of the persistent kernel.
        pub steps_per_dispatch: u32,
        /// The state copy (0 or 1) the one-step kernel reads at the first step.
        pub parity: u32,
        /// Steps from the batch's anchor to its first step: `drive_time`
        /// and the drive target are the anchor's (0 while preparing).
        pub anchor_offset: u32,
        /// Output samples the persistent kernel records in this batch.
        pub records: u32,
        /// `LOOP_PROBE_PASSES`: the passes of the persistent kernel's loop
        /// probe, read at run time so that no compiler unrolls the probe.
        pub probe_passes: u32,
    }
}

/// Passes of the persistent kernel's loop probe (`persistent.wgsl`
/// `loop_budget_left`): two, one more than llvmpipe lets any loop run once
/// an invocation has spent its loop budget.
pub const LOOP_PROBE_PASSES: u32 = 2;

pub use crate::engines::step_params::{drive_anchor, DRIVE_ANCHOR_STEPS};

gpu_struct! {
    /// A block's displacement, u_x and u_z: the bytes of the CPU twin's
    /// `[Coord<T>; 2]` ((hi, lo) pairs in mixed precision).
    pub struct GpuDisp<T> as "Disp" {
        pub x: Coord<T>,
        pub z: Coord<T>,
    }
}

gpu_struct! {
    /// A junction's spring (anchor, stiffness): the bytes of the CPU
    /// twin's `JunctionSpring<Coord<T>, T>`.
    pub struct GpuJunctionSpring<T> as "JunctionSpring" {
        pub anchor: Packed<T>,
        pub stiffness: T,
    }
}

gpu_struct! {
    /// What the junction lanes of a block hand back (the CPU twin's
    /// `kernels::junctions::LaneSum`): over the junctions pinned after the
    /// step, Σ k_j·(a_j − r) and Σ k_j (WGSL `force_sum`s), the largest
    /// |k_j·(a_j − r)| and k_j; and the count of slipping junctions.
    pub struct GpuLaneSum<T> as "LaneSum" {
        pub anchored: Coord<T>,
        pub stiffness: Coord<T>,
        pub stretch_max: T,
        pub stiffness_max: T,
        pub slipping: u32,
        /// Unused: keeps both precisions free of padding.
        pub reserved: u32,
    }
}

gpu_struct! {
    /// The sums of an interface block whose junctions are all pinned,
    /// kept from the step that made them (`junction_cache`): while no
    /// junction changes, they are what the lanes would sum again. Valid
    /// where `stiffness_max` > 0 (a zeroed record is empty). The CPU twin
    /// sums anew every step (`kernels::junctions::pinned_friction`).
    pub struct GpuJunctionCache<T> as "JunctionCache" {
        /// Σ k_j·(a_j − r) (a WGSL `force_sum`).
        pub anchored: Coord<T>,
        /// r, junction 0's anchor.
        pub reference: Coord<T>,
        /// Σ k_j, rounded once.
        pub stiffness: T,
        pub stretch_max: T,
        pub stiffness_max: T,
        /// Unused: keeps both precisions free of padding.
        pub reserved: T,
    }
}

gpu_struct! {
    /// An interface block's junction block for its next step, noted in
    /// workgroup memory by the thread that updates the block
    /// (`shaders/noted_blocks.wgsl`: the resident and tiled kernels), so
    /// that its lanes and its next update read it, not work it out again.
    pub struct GpuNotedBlock<T> as "NotedBlock" {
        /// u_x.
        pub ux: Coord<T>,
        /// r, the coordinate the pinned sums are taken about.
        pub reference: Coord<T>,
        /// The normal force a junction.
        pub f_n: T,
        /// 1 where the block keeps its sums (no junction can change), else 0:
        /// a real, so that neither precision's layout has padding.
        pub kept: T,
    }
}

gpu_struct! {
    /// The first blow-up of a batch, written by the kernel that saw it
    /// (non-finite or faster than c_p): read back after every batch.
    /// Its values are f32 in either precision (diagnostics).
    pub struct GpuStatus as "Status" {
        pub flag: u32,
        /// Step offset in the batch of the update that blew up.
        pub step: u32,
        pub block: u32,
        pub ux: f32,
        pub uz: f32,
        pub vx: f32,
        pub vz: f32,
        /// Steps the persistent kernel has run, all dispatches (mod 2³²).
        pub persistent_steps: u32,
        /// The most levels of the junction lane tree a workgroup merged in
        /// subgroups (`lane_shuffle.wgsl`; 0: none, each lane's sum through
        /// storage), over the scene's dispatches.
        pub lane_levels: u32,
        /// A chained tiled kernel's tile that gave up waiting for its
        /// neighbours, plus one (0: none; `tiles::TileChain`).
        pub stalled_tile: u32,
        /// Interface block-steps whose junctions were summed, not kept
        /// (`junction_friction` counts them where
        /// `GpuOptions::count_summed_junction_blocks` asks; 0 otherwise), all
        /// dispatches (mod 2³²): a halo block of the tiled kernel counts in
        /// each tile that steps it.
        pub summed_junction_blocks: u32,
        /// 1 where a subgroup held threads of two scenes of a persistent
        /// workgroup that steps several (`GpuOptions::group_scenes`): its
        /// threads took the subgroup's first scene (`subgroup_uniform`), so
        /// the run is void (0: none). Also keeps the count of words even:
        /// the status copies are followed by 8-byte timestamps.
        pub straddled_subgroup: u32,
    }
}

gpu_struct! {
    /// What the step kernels' sample code (`shaders/record_common.wgsl`) needs besides the
    /// run constants: the fast cadence (its state is updated by the
    /// device), the driver's blocks, and where each region of the record
    /// buffers starts.
    pub struct GpuRecordPlan<T> as "RecordPlan" {
        /// The threshold in `T`, rounded down where it is not a value of
        /// `T` (`GpuReal::fast_threshold`): `|v| > fast_slip_speed` in `T`
        /// is then the host's f64 rule exactly.
        pub fast_slip_speed: T,
        /// 1: the fast interface cadence is on (set by each sample).
        pub fast: u32,
        pub every_fast: u32,
        /// The block the side spring pulls (u32::MAX: none).
        pub driven_block: u32,
        /// 1: the top row's velocity is prescribed (its reaction is summed).
        pub top_reaction: u32,
        pub junctions_per_block: u32,
        /// A sample's partial sums (a workgroup's of the one-step kernels,
        /// a tile's of the tiled kernel; `shaders/record_batch.wgsl`), and
        /// where the batch's go in the sums buffer.
        pub partials: u32,
        /// The one-step kernels' fast chain (`FAST_CHAIN_*`): a sample's
        /// max slip speed may be over the threshold where the order bits
        /// of its f32 rounding are at least these
        /// (`GpuReal::fast_order_bits`).
        pub fast_bits: u32,
        pub partials_offset: u32,
        /// Word offsets of the interface rows and the bulk fields.
        pub interface_offset: u32,
        pub bulk_offset: u32,
        /// Where this scene's samples' sums start in the sums buffer.
        pub sums_offset: u32,
        /// 1: the one-step kernels' chain decides which planned samples
        /// they compute, and partial 0 of a sample says whether they did
        /// (`shaders/record_step.wgsl`; `record_batch_finish` reads it).
        pub step_chain: u32,
        /// The one-step kernels' fast chain, written by the device
        /// (`FAST_CHAIN_*` say where each ring is).
        pub fast_chain: AtomicWords8,
    }
}

/// Eight words the device updates with atomics (WGSL
/// `array<atomic<u32>, 8>`).
#[repr(transparent)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct AtomicWords8(pub [u32; 8]);

impl WgslType for AtomicWords8 {
    const WGSL: &'static str = "array<atomic<u32>, 8>";
}

/// Where `GpuRecordPlan::fast_chain`'s rings start, each indexed by a
/// sample's ordinal (`GpuRecordEntry::ring`, its ordinal mod 6): sample
/// n's max slip speed (order bits, atomicMax) in a ring of three, whether
/// it may be due in a ring of two, and the fast flag after it in a ring of
/// two. Sample n's step reads what sample n − 1's step left and writes
/// none of the words it reads.
pub const FAST_CHAIN_MAX: u32 = 0;
pub const FAST_CHAIN_DUE: u32 = 3;
pub const FAST_CHAIN_FLAG: u32 = 5;

impl AtomicWords8 {
    /// The chain of a scene whose fast flag is `fast` before the next
    /// sample, whatever its ordinal: the sample before it not due (so the
    /// flag stands), both flag slots `fast`, the max slots cleared.
    pub fn fast_chain(fast: bool) -> AtomicWords8 {
        let mut w = [0u32; 8];
        w[FAST_CHAIN_FLAG as usize] = fast as u32;
        w[FAST_CHAIN_FLAG as usize + 1] = fast as u32;
        AtomicWords8(w)
    }
}

gpu_struct! {
    /// One sample the host asks for in a batch: its step, the channels
    /// (`RECORD_*` bits) and its slots.
    pub struct GpuRecordEntry as "RecordEntry" {
        /// The sample's step offset in its batch.
        pub offset: u32,
        pub channels: u32,
        pub sums_slot: u32,
        pub interface_slot: u32,
        pub bulk_slot: u32,
        /// The sample's ordinal among all the engine's samples, mod 6:
        /// its slots in the fast chain's rings (`FAST_CHAIN_*`).
        pub ring: u32,
    }
}

gpu_struct! {
    /// A sample's sums as the device reduced them (in the kernels'
    /// precision; the partial sums of the workgroups have the same layout).
    pub struct GpuSampleSums<T> as "SampleSums" {
        /// Σ |v|² over the blocks (the host multiplies by m/2).
        pub kinetic: T,
        pub friction: T,
        /// Σ of the interface blocks' pinned fractions.
        pub pinned: T,
        pub min_pinned: T,
        pub max_slip_speed: T,
        pub top_reaction: T,
        pub driven_ux_hi: T,
        pub driven_ux_lo: T,
        /// 1: the sample was due (0: a fast-cadence slot while it was off).
        pub recorded: u32,
        /// 1: its interface row was written.
        pub interface_row: u32,
        /// The fast cadence after this sample.
        pub fast: u32,
        pub ruptures_lo: u32,
        pub ruptures_hi: u32,
        /// Unused: keeps both precisions free of padding.
        pub reserved: u32,
    }
}

/// `GpuRecordEntry::channels` bits.
pub const RECORD_GLOBAL: u32 = 1;
pub const RECORD_INTERFACE: u32 = 2;
pub const RECORD_BULK: u32 = 4;
/// A multiple of the fast cadence: recorded if the fast cadence is on.
pub const RECORD_FAST: u32 = 8;
/// Words per interface block of a row: u_x (hi, lo), friction, normal
/// force, pinned fraction, v_x.
pub const RECORD_INTERFACE_WORDS: u32 = 6;
/// Words per block of a bulk field: u_x, u_z, v_x, v_z.
pub const RECORD_BULK_WORDS: u32 = 4;

/// The shared constants and structs in precision `T`, prepended to every
/// shader module: `real`, `coord`, `packed_coord` and `force_sum` name
/// `T`'s types.
pub fn wgsl_prelude<T: GpuReal>() -> String {
    let stencil: Vec<String> = STENCIL
        .iter()
        .map(|b| format!("vec2<i32>({}, {})", b.dx, b.dz))
        .collect();
    let lengths: Vec<String> = STENCIL
        .iter()
        .map(|b| format!("{:?}", T::from_f64(b.length_factor)))
        .collect();
    let stiffness: Vec<String> = STENCIL
        .iter()
        .map(|b| format!("{:?}", T::from_f64(b.stiffness_factor)))
        .collect();
    let mut s =
        String::from("// Generated from src/engines/gpu/layout.rs: do not edit in the shaders.\n");
    s += &format!(
        "alias real = {};\nalias coord = {};\nalias packed_coord = {};\n",
        T::WGSL,
        <Coord<T> as WgslType>::WGSL,
        <Packed<T> as WgslType>::WGSL
    );
    // A block's force sum (`crate::model::real::ForceSum`): a (sum, error) pair in
    // mixed precision, like the coordinate pair; a plain f64 in f64.
    s += &format!("alias force_sum = {};\n", <Coord<T> as WgslType>::WGSL);
    for (name, value) in [
        ("PINNED", crate::model::junction::PINNED),
        ("FLAG_FIX_X", FLAG_FIX_X),
        ("FLAG_FIX_Z", FLAG_FIX_Z),
        ("FLAG_TOP", FLAG_TOP),
        ("FLAG_INTERFACE", FLAG_INTERFACE),
        ("FLAG_DRIVEN", FLAG_DRIVEN),
        ("FLAG_PRESCRIBED_X", FLAG_PRESCRIBED_X),
        ("WORKGROUP", WORKGROUP),
        ("REDUCTION_SLOTS", reduction_slots::<T>()),
        ("RECORD_GLOBAL", RECORD_GLOBAL),
        ("RECORD_INTERFACE", RECORD_INTERFACE),
        ("RECORD_BULK", RECORD_BULK),
        ("RECORD_FAST", RECORD_FAST),
        (
            "RECORD_FIXED",
            RECORD_GLOBAL | RECORD_INTERFACE | RECORD_BULK,
        ),
        ("RECORD_INTERFACE_WORDS", RECORD_INTERFACE_WORDS),
        ("RECORD_BULK_WORDS", RECORD_BULK_WORDS),
        ("FAST_CHAIN_MAX", FAST_CHAIN_MAX),
        ("FAST_CHAIN_DUE", FAST_CHAIN_DUE),
        ("FAST_CHAIN_FLAG", FAST_CHAIN_FLAG),
        (
            "JUNCTION_LANES",
            crate::model::junction::JUNCTION_LANES as u32,
        ),
    ] {
        s += &format!("const {name}: u32 = {value}u;\n");
    }
    s += &status_word_constants();
    s += &super::phase_clocks::phase_constants();
    // The friction laws' kernel codes (`FRICTION_LAW`), from the laws'
    // declarations (crate::model::friction::LAWS).
    for (code, name) in crate::model::friction::kernel_codes() {
        s += &format!("const {name}: u32 = {code}u;\n");
    }
    s += &format!("const REAL_EPSILON: real = {:?};\n", T::epsilon());
    s += &format!(
        "const STENCIL = array<vec2<i32>, 8>({});\n",
        stencil.join(", ")
    );
    s += &format!(
        "const STENCIL_LENGTH = array<real, 8>({});\n",
        lengths.join(", ")
    );
    s += &format!(
        "const STENCIL_STIFFNESS = array<real, 8>({});\n",
        stiffness.join(", ")
    );
    for decl in [
        GpuConsts::<T>::wgsl(),
        GpuBatch::<T>::wgsl(),
        GpuDisp::<T>::wgsl(),
        GpuJunctionSpring::<T>::wgsl(),
        GpuLaneSum::<T>::wgsl(),
        GpuJunctionCache::<T>::wgsl(),
        GpuNotedBlock::<T>::wgsl(),
        GpuStatus::wgsl(),
        GpuRecordPlan::<T>::wgsl(),
        GpuRecordEntry::wgsl(),
        GpuSampleSums::<T>::wgsl(),
    ] {
        s += &decl;
    }
    s
}

/// The status words of a scene, named from `GpuStatus`'s fields: `STATUS_WORDS`
/// (words per scene) and `STATUS_<FIELD>` (a field's word), so the kernels
/// index their counters by name, never by a number that could drift from
/// the struct the host reads.
fn status_word_constants() -> String {
    let word = |offset: usize| offset / std::mem::size_of::<u32>();
    let mut s = format!(
        "const STATUS_WORDS: u32 = {}u;\n",
        word(std::mem::size_of::<GpuStatus>())
    );
    for (name, _, offset) in GpuStatus::fields() {
        s += &format!(
            "const STATUS_{}: u32 = {}u;\n",
            name.to_uppercase(),
            word(offset)
        );
    }
    s
}

/// Threads a sample's sums can be reduced across (`wg_sums` of
/// shaders/record_common.wgsl): a power of two, at most 256, whose sums fit
/// 16 KiB of workgroup memory (WebGPU's minimum limit; f64 sums are larger).
pub fn reduction_slots<T: GpuReal>() -> u32 {
    let fit = (16 * 1024 / std::mem::size_of::<GpuSampleSums<T>>()) as u32;
    1 << fit.min(256).ilog2()
}

impl<T: GpuReal> GpuConsts<T> {
    pub fn new(c: &Consts<T>, speed_limit: T) -> Self {
        GpuConsts {
            nx: c.nx as u32,
            nz: c.nz as u32,
            junction_count: c.junction_count as u32,
            seed: c.seed,
            spacing: c.spacing,
            k: c.k,
            eta: c.eta,
            k_foundation: c.k_foundation,
            mass: c.mass,
            inv_mass: c.inv_mass,
            dt: c.dt,
            mu_s: c.mu_s,
            mu_d: c.mu_d,
            junction_stiffness_value: c.junction_stiffness_value,
            slip_mean_steps: c.slip_mean_steps,
            slip_std_steps: c.slip_std_steps,
            drive_stiffness: c.drive_stiffness,
            speed_limit,
            // Column 1 is interior whenever a full share is used (nx > 2).
            top_share_full: crate::model::laws::top_share(c.nx, c.nz, 1),
            top_share_edge: crate::model::laws::top_share(c.nx, c.nz, 0),
            stiffness_normal_load: c.junction_stiffness_normal_load as u32,
            n_blocks: (c.nx * c.nz) as u32,
            one: 1.0,
            normal_force: c.normal_force,
            normal_slope: c.normal_slope,
            inv_ramp_steps: c.inv_ramp_steps,
            top_prestress_force: c.top_prestress_force,
            top_force_rate: c.top_force_rate,
            relax_eta: c.relax_eta,
            absolute_eta: c.absolute_eta,
            interface_shear_force: c.interface_shear_force,
            strip_shear_force: c.strip_shear_force,
            strip_blocks: c.strip_blocks as u32,
            drive_velocity: c.drive_velocity,
            drive_step_hi: c.drive_step_hi,
            drive_step_lo: c.drive_step_lo,
            law0: c.law[0],
            law1: c.law[1],
            law2: c.law[2],
            law3: c.law[3],
            law4: c.law[4],
            law5: c.law[5],
            law6: c.law[6],
            law7: c.law[7],
        }
    }
}

impl<T: GpuReal> GpuBatch<T> {
    /// The batch of `steps` steps from global step `first`, with the
    /// drive target origin + V·t formed in f64 and rounded to a coordinate.
    pub fn new(c: &Consts<T>, first: u64, steps: u32, drive_origin: Coord<T>) -> Self {
        let p = crate::engines::step_params::step_params(c, first);
        let anchor = drive_anchor(c, first);
        GpuBatch {
            drive_target: drive_target_at_anchor(c, drive_origin, anchor),
            reserved_real: T::zero(),
            first_step: first as u32,
            steps,
            preparing: p.preparing as u32,
            ramping: (first < c.ramp_steps) as u32,
            relaxing: (p.preparing && first >= c.ramp_steps) as u32,
            drive_time: if p.preparing {
                T::zero()
            } else {
                T::from_f64((anchor - c.prep_steps) as f64 * c.dt_exact)
            },
            forces_ready: 0,
            forces_only: 0,
            steps_per_dispatch: steps,
            parity: 0,
            anchor_offset: (first - anchor) as u32,
            records: 0,
            probe_passes: LOOP_PROBE_PASSES,
        }
    }
}

impl<T: GpuReal> From<GpuJunctionSpring<T>>
    for crate::model::junction::JunctionSpring<Coord<T>, T>
{
    fn from(s: GpuJunctionSpring<T>) -> Self {
        crate::model::junction::JunctionSpring {
            anchor: T::unpack(s.anchor),
            stiffness: s.stiffness,
        }
    }
}

impl<T: GpuReal> From<crate::model::junction::JunctionSpring<Coord<T>, T>>
    for GpuJunctionSpring<T>
{
    fn from(s: crate::model::junction::JunctionSpring<Coord<T>, T>) -> Self {
        GpuJunctionSpring {
            anchor: T::pack(s.anchor),
            stiffness: s.stiffness,
        }
    }
}

/// The notes a workgroup holds (`shaders/noted_blocks.wgsl`) for
/// `interface_blocks` interface blocks (the resident kernel's lattice, the
/// tiled kernel's tile) of a scene with `junctions` junctions: one a block,
/// or where the scene has no junctions one, the array's least length,
/// which no kernel reads.
pub fn noted_blocks(interface_blocks: usize, junctions: usize) -> usize {
    if junctions == 0 {
        return 1;
    }
    interface_blocks.max(1)
}

/// Bytes of `notes` notes in precision `T`.
pub fn noted_blocks_bytes<T: GpuReal>(notes: usize) -> u64 {
    (notes * std::mem::size_of::<GpuNotedBlock<T>>()) as u64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::real::{Coordinate, DoubleSingle};
    use crate::model::scenario::{Scenario, DEFAULT_SCENARIO};

    fn table_s1() -> crate::Model {
        let s = Scenario::parse(DEFAULT_SCENARIO, "test", &[]).unwrap();
        crate::Model::from_scenario(&s, false).unwrap()
    }

    /// The kernels add i·(V·dt) to the batch's first drive target as
    /// i·hi + i·lo: after 1e8 and 2³² steps, and 4095 steps into a batch,
    /// the target is still origin + V·t to f64 round-off (a plain f32
    /// would be ~1e-10 m off, a whole creep step).
    #[test]
    fn drive_target_after_1e8_steps_stays_exact() {
        let m = table_s1();
        let c = Consts::<f32>::new(&m);
        let gc = GpuConsts::new(&c, 1.0);
        let origin = DoubleSingle::from_f64(1.234_567e-5);
        for first in [m.prep_steps + 100_000_000, m.prep_steps + (1 << 32) + 7] {
            let b = GpuBatch::new(&c, first, 4096, origin);
            let last = (DRIVE_ANCHOR_STEPS - 1) as u32 - b.anchor_offset;
            for i in [0u32, 1, last] {
                // The kernel's arithmetic (shaders/common.wgsl loads_at).
                let fi = (b.anchor_offset + i) as f32;
                let target = b
                    .drive_target
                    .ds_add(fi * gc.drive_step_hi)
                    .ds_add(fi * gc.drive_step_lo);
                // The CPU engines' target is the kernels' to the bit.
                let cpu = crate::engines::step_params::drive_target(&c, origin, first + i as u64);
                assert_eq!(cpu, target, "step {}", first + i as u64);
                let t = m.time_of_step(first + i as u64);
                let exact = origin.as_f64() + 4.0e-4 * t;
                let got = target.as_f64();
                assert!((got - exact).abs() <= exact * 1e-13, "{got} vs {exact}");
                assert!(((exact as f32) as f64 - exact).abs() > 1e-12);
            }
        }
        let (hi, lo) = crate::engines::step_params::split_drive_step::<f32>(4.0e-4 * m.dt);
        assert_eq!((4095.0 * hi) as f64, 4095.0 * hi as f64);
        assert!(((hi as f64 + lo as f64) / (4.0e-4 * m.dt) - 1.0).abs() < 1e-12);
    }

    /// Every shared struct has, in the WGSL the shaders see, the size and
    /// the field offsets of its Rust twin (naga's layout): a field added,
    /// reordered or misaligned on one side fails here, without a GPU.
    #[test]
    fn wgsl_structs_match_the_rust_layout() {
        check_layouts::<f32>();
        check_layouts::<f64>();
        // Mixed precision reduces across 256 threads as before; f64 sums
        // (88 bytes) fit 128 in 16 KiB.
        assert_eq!(reduction_slots::<f32>(), 256);
        assert_eq!(reduction_slots::<f64>(), 128);
        assert_eq!(size_of::<GpuDisp<f32>>(), size_of::<[DoubleSingle; 2]>());
        assert_eq!(size_of::<GpuDisp<f64>>(), size_of::<[f64; 2]>());
        // Mixed precision keeps its 12-byte junction springs.
        assert_eq!(size_of::<GpuJunctionSpring<f32>>(), 12);
        assert_eq!(
            size_of::<GpuJunctionSpring<f64>>(),
            size_of::<crate::model::junction::JunctionSpring<f64, f64>>()
        );
    }

    fn check_layouts<T: GpuReal>() {
        let src = wgsl_prelude::<T>();
        let module = naga::front::wgsl::parse_str(&src).expect("prelude parses");
        let mut layouter = naga::proc::Layouter::default();
        layouter
            .update(module.to_ctx())
            .expect("layout of the prelude");
        let check = |name: &str, size: usize, fields: Vec<(&str, &str, usize)>| {
            let (handle, ty) = module
                .types
                .iter()
                .find(|(_, t)| t.name.as_deref() == Some(name))
                .unwrap_or_else(|| panic!("struct {name} missing in WGSL"));
            let naga::TypeInner::Struct { members, span } = &ty.inner else {
                panic!("{name} is not a struct");
            };
            assert_eq!(*span as usize, size, "{name}: WGSL size vs Rust size");
            assert_eq!(layouter[handle].size as usize, size);
            assert_eq!(members.len(), fields.len(), "{name}: field count");
            for (m, (field, _, offset)) in members.iter().zip(fields) {
                assert_eq!(m.name.as_deref(), Some(field), "{name}: field order");
                assert_eq!(m.offset as usize, offset, "{name}.{field}: offset");
            }
        };
        check(
            "Consts",
            size_of::<GpuConsts<T>>(),
            GpuConsts::<T>::fields(),
        );
        check("Batch", size_of::<GpuBatch<T>>(), GpuBatch::<T>::fields());
        check("Disp", size_of::<GpuDisp<T>>(), GpuDisp::<T>::fields());
        check(
            "JunctionSpring",
            size_of::<GpuJunctionSpring<T>>(),
            GpuJunctionSpring::<T>::fields(),
        );
        check(
            "LaneSum",
            size_of::<GpuLaneSum<T>>(),
            GpuLaneSum::<T>::fields(),
        );
        check(
            "JunctionCache",
            size_of::<GpuJunctionCache<T>>(),
            GpuJunctionCache::<T>::fields(),
        );
        check(
            "NotedBlock",
            size_of::<GpuNotedBlock<T>>(),
            GpuNotedBlock::<T>::fields(),
        );
        check("Status", size_of::<GpuStatus>(), GpuStatus::fields());
        check(
            "RecordPlan",
            size_of::<GpuRecordPlan<T>>(),
            GpuRecordPlan::<T>::fields(),
        );
        check(
            "RecordEntry",
            size_of::<GpuRecordEntry>(),
            GpuRecordEntry::fields(),
        );
        check(
            "SampleSums",
            size_of::<GpuSampleSums<T>>(),
            GpuSampleSums::<T>::fields(),
        );
        // A whole number of 16-byte rows (the stride of `scene_consts`).
        assert_eq!(size_of::<GpuConsts<T>>() % 16, 0);
    }

    /// The negative control of the layout test: a Rust struct whose
    /// vec2 field sits at a 4-byte offset (WGSL aligns it to 8) is caught.
    #[test]
    fn layout_check_flags_a_misaligned_vec2() {
        gpu_struct! {
            pub struct Misaligned as "Misaligned" {
                pub a: f32,
                pub b: DoubleSingle,
            }
        }
        let module = naga::front::wgsl::parse_str(&Misaligned::wgsl()).unwrap();
        let (_, ty) = module.types.iter().find(|(_, t)| t.name.is_some()).unwrap();
        let naga::TypeInner::Struct { members, .. } = &ty.inner else {
            panic!()
        };
        assert_ne!(members[1].offset as usize, Misaligned::fields()[1].2);
    }
}
