//! One scene's slice of the engine's buffers: read back as a snapshot or
//! a saved state, and written (a loaded state, a quasi-static jump's
//! kinematics and junctions). Scene k's elements start at k times the
//! per-scene count of each buffer.

use super::arena::Region;
use super::buffers::{
    gpu_junction_springs, Shape, PHASE_CLOCK_BYTES, STATUS_BYTES, WORD_PAIR_BYTES,
};
use super::layout::{GpuJunctionCache, GpuJunctionSpring, GpuStatus};
use super::phase_clocks::{PhaseCycles, PHASE_CLOCK_WORDS};
use super::precision::{Coord, GpuReal, Packed};
use super::readback::{cast_prefix, read_ranges, Range};
use super::GpuEngine;
use crate::engines::{EngineError, EngineState, FrictionState, Snapshot, StateArrays};
use crate::model::real::Coordinate;
use bytemuck::Zeroable;

impl<T: GpuReal> GpuEngine<T> {
    /// Byte range of scene `k`'s slice of a buffer with `per_scene` elements
    /// of `bytes` each.
    pub(super) fn slice<'a>(
        &self,
        array: &'a Region,
        k: usize,
        per_scene: usize,
        bytes: usize,
    ) -> Range<'a> {
        let size = (per_scene * bytes) as u64;
        array.range(k as u64 * size, size)
    }

    /// Scene `k`'s buffers as they are (forces possibly of the previous step).
    pub(super) fn read_raw(&mut self, k: usize) -> Result<RawState<T>, EngineError> {
        self.drain()?;
        let Shape {
            blocks: n,
            nx,
            junctions: nj,
            law_words,
            ..
        } = self.shape;
        let b = &self.buffers;
        let ranges = [
            self.slice(&b.disp[self.current], k, n, Self::DISP_BYTES),
            self.slice(&b.vel[self.current], k, n, Self::REAL_PAIR_BYTES),
            self.slice(&b.force, k, n, Self::REAL_PAIR_BYTES),
            self.slice(&b.contact, k, nx, Self::REAL_PAIR_BYTES),
            self.slice(&b.junction_spring, k, nj, Self::SPRING_BYTES),
            self.slice(&b.junction_state, k, nj, WORD_PAIR_BYTES),
            self.slice(&b.slide, k, nx, WORD_PAIR_BYTES),
            self.slice(&b.law_state, k, law_words, Self::PACKED_BYTES),
        ];
        let raw = read_ranges(&self.ctx, &ranges)?;
        Ok(RawState {
            disp: cast_prefix(&raw[0], n),
            vel: cast_prefix(&raw[1], n),
            force: cast_prefix(&raw[2], n),
            contact: cast_prefix(&raw[3], nx),
            friction: FrictionState {
                junction_spring: cast_prefix::<GpuJunctionSpring<T>>(&raw[4], nj)
                    .into_iter()
                    .map(Into::into)
                    .collect(),
                junction_state: cast_prefix(&raw[5], nj),
                slide: cast_prefix(&raw[6], nx),
                law_state: cast_prefix::<Packed<T>>(&raw[7], law_words)
                    .into_iter()
                    .map(T::unpack)
                    .collect(),
            },
        })
    }

    pub(super) fn read_state(&mut self, k: usize) -> Result<Snapshot, EngineError> {
        let r = self.read_raw(k)?;
        Ok(Snapshot::from_buffers(
            &self.scenes[k].model,
            self.step,
            &r.disp,
            &r.vel,
            &r.force,
            &r.contact,
            &r.friction,
        ))
    }

    /// Writes `bytes` at element `k · per_scene` of a buffer with elements
    /// of `element` bytes (nothing for an empty array).
    pub(super) fn write_scene(
        &self,
        array: &Region,
        k: usize,
        per_scene: usize,
        element: usize,
        bytes: &[u8],
    ) {
        if !bytes.is_empty() {
            let at = (k * per_scene * element) as u64;
            array.write(&self.ctx.queue, at, bytes);
        }
    }

    /// Empties scene `k`'s kept junction sums (`junction_cache`): every
    /// host write of its junctions calls this, so no kernel uses sums of
    /// springs that are no longer there.
    pub(super) fn forget_junction_sums(&self, k: usize) {
        let nx = self.shape.nx;
        let empty = vec![GpuJunctionCache::<T>::zeroed(); nx];
        let bytes = std::mem::size_of::<GpuJunctionCache<T>>();
        self.write_scene(
            &self.buffers.junction_cache,
            k,
            nx,
            bytes,
            bytemuck::cast_slice(&empty),
        );
    }

    /// Interface blocks of scene `k` whose junction sums are kept now (all
    /// their junctions pinned since the sums were made): how much of the
    /// junction phase the kernels skip while nothing breaks.
    pub fn kept_junction_blocks(&mut self, k: usize) -> Result<usize, EngineError> {
        self.drain()?;
        let nx = self.shape.nx;
        let bytes = std::mem::size_of::<GpuJunctionCache<T>>();
        let range = self.slice(&self.buffers.junction_cache, k, nx, bytes);
        let raw = read_ranges(&self.ctx, &[range])?;
        Ok(kept_records::<T>(&raw[0]))
    }

    /// Interface block-steps of scene `k` whose junctions the kernels have
    /// summed rather than kept, since the engine was built (mod 2³²; a
    /// halo block of the tiled kernel counts in each tile that steps it).
    /// Counted only where `GpuOptions::count_summed_junction_blocks` asks.
    pub fn summed_junction_blocks(&mut self, k: usize) -> Result<u32, EngineError> {
        self.drain()?;
        let range = self.slice(&self.buffers.status, k, 1, STATUS_BYTES);
        let raw = read_ranges(&self.ctx, &[range])?;
        let status: GpuStatus = bytemuck::pod_read_unaligned(&raw[0]);
        Ok(status.summed_junction_blocks)
    }

    /// Scene `k`'s phase clock sums since the engine was built: where its
    /// kernels' steps spent their cycles (`GpuOptions::phase_clocks`; all
    /// zero where it is off), its tiles' together.
    pub fn phase_cycles(&mut self, k: usize) -> Result<PhaseCycles, EngineError> {
        let tiles = self.phase_cycles_by_tile(k)?;
        Ok(tiles.iter().sum())
    }

    /// Scene `k`'s phase clock sums, each of its tiles' apart in column
    /// order (the tiled kernel), or the scene's alone (the others).
    pub fn phase_cycles_by_tile(&mut self, k: usize) -> Result<Vec<PhaseCycles>, EngineError> {
        self.drain()?;
        let tiles = self.tiles.as_ref().map_or(1, |t| t.geometry.tiles as usize);
        let range = self.slice(&self.buffers.phase_cycles, k, tiles, PHASE_CLOCK_BYTES);
        let raw = read_ranges(&self.ctx, &[range])?;
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&raw[0]);
        Ok(words
            .chunks(PHASE_CLOCK_WORDS)
            .map(PhaseCycles::from_words)
            .collect())
    }

    /// Kept records of the tiled kernel's halo copies (`junction_sums_slot`
    /// in `junction_tiled.wgsl`), every scene and tile: 0 for the other
    /// kernels, which keep none apart.
    pub fn kept_halo_junction_records(&mut self) -> Result<usize, EngineError> {
        self.drain()?;
        let bytes = std::mem::size_of::<GpuJunctionCache<T>>();
        let owned = (self.scenes.len() * self.shape.nx * bytes) as u64;
        let size = self.buffers.junction_cache.size() - owned;
        if size == 0 {
            return Ok(0);
        }
        let range = self.buffers.junction_cache.range(owned, size);
        let raw = read_ranges(&self.ctx, &[range])?;
        Ok(kept_records::<T>(&raw[0]))
    }

    pub(super) fn snapshot_of(&mut self, k: usize) -> Result<Snapshot, EngineError> {
        self.ready_forces()?;
        self.read_state(k)
    }

    pub(super) fn set_kinematics_of(
        &mut self,
        k: usize,
        disp: &[[f64; 2]],
        vel: &[[f64; 2]],
    ) -> Result<(), EngineError> {
        self.drain()?;
        let disp: Vec<[Coord<T>; 2]> = disp.iter().map(|u| u.map(Coord::<T>::from_f64)).collect();
        let vel: Vec<[T; 2]> = vel.iter().map(|v| v.map(T::from_f64)).collect();
        let (b, n) = (&self.buffers, self.shape.blocks);
        self.write_scene(
            &b.disp[self.current],
            k,
            n,
            Self::DISP_BYTES,
            bytemuck::cast_slice(&disp),
        );
        self.write_scene(
            &b.vel[self.current],
            k,
            n,
            Self::REAL_PAIR_BYTES,
            bytemuck::cast_slice(&vel),
        );
        self.scenes[k].forces_ready = false;
        Ok(())
    }

    pub(super) fn set_junctions_of(
        &mut self,
        k: usize,
        snap: &Snapshot,
    ) -> Result<(), EngineError> {
        self.drain()?;
        let spring = gpu_junction_springs::<T>(&snap.anchor, &snap.junction_stiffness);
        let state: Vec<[u32; 2]> = snap
            .slip_steps_left
            .iter()
            .zip(&snap.ruptures)
            .map(|(l, r)| [*l, *r])
            .collect();
        let (b, nj) = (&self.buffers, self.shape.junctions);
        self.write_scene(
            &b.junction_spring,
            k,
            nj,
            Self::SPRING_BYTES,
            bytemuck::cast_slice(&spring),
        );
        self.write_scene(
            &b.junction_state,
            k,
            nj,
            WORD_PAIR_BYTES,
            bytemuck::cast_slice(&state),
        );
        self.forget_junction_sums(k);
        self.scenes[k].forces_ready = false;
        Ok(())
    }

    /// Starts every scene from its state in `states` (one per scene, all of
    /// one step); the engine moves to that step.
    pub(super) fn start_scenes_from(&mut self, states: &[&EngineState]) -> Result<(), EngineError> {
        if states.len() != self.scenes.len() {
            return Err(EngineError::State(format!(
                "{} states for an ensemble of {} scenes",
                states.len(),
                self.scenes.len()
            )));
        }
        let step = states[0].step;
        if let Some(s) = states.iter().find(|s| s.step != step) {
            return Err(EngineError::State(format!(
                "the scenes of an ensemble start at one step, not at {step} and {}",
                s.step
            )));
        }
        self.drain()?;
        self.step = step;
        for (k, state) in states.iter().enumerate() {
            self.load_state_of(k, state)?;
        }
        Ok(())
    }

    pub(super) fn save_state_of(&mut self, k: usize) -> Result<EngineState, EngineError> {
        self.ready_forces()?;
        let r = self.read_raw(k)?;
        Ok(EngineState::capture(StateArrays {
            step: self.step,
            drive_origin: self.scenes[k].drive_origin,
            disp: &r.disp,
            vel: &r.vel,
            force: &r.force,
            contact: &r.contact,
            friction: &r.friction,
        }))
    }

    /// Replaces scene `k`'s state (at the engine's step: an ensemble's
    /// scenes stand at one step).
    pub(super) fn load_state_of(
        &mut self,
        k: usize,
        state: &EngineState,
    ) -> Result<(), EngineError> {
        state.check_fits(&self.scenes[k].model)?;
        self.drain()?;
        let spring: Vec<GpuJunctionSpring<T>> = state
            .junction_springs_as::<T, Coord<T>>()
            .into_iter()
            .map(Into::into)
            .collect();
        let b = &self.buffers;
        let Shape {
            blocks: n,
            nx,
            junctions: nj,
            law_words,
            ..
        } = self.shape;
        let disp = state.disp_as::<T, Coord<T>>();
        self.write_scene(
            &b.disp[self.current],
            k,
            n,
            Self::DISP_BYTES,
            bytemuck::cast_slice(&disp),
        );
        let vel = state.vel_as::<T>();
        self.write_scene(
            &b.vel[self.current],
            k,
            n,
            Self::REAL_PAIR_BYTES,
            bytemuck::cast_slice(&vel),
        );
        let force = state.force_as::<T>();
        let pair = Self::REAL_PAIR_BYTES;
        self.write_scene(&b.force, k, n, pair, bytemuck::cast_slice(&force));
        let contact = state.contact_as::<T>();
        self.write_scene(&b.contact, k, nx, pair, bytemuck::cast_slice(&contact));
        self.write_scene(
            &b.junction_spring,
            k,
            nj,
            Self::SPRING_BYTES,
            bytemuck::cast_slice(&spring),
        );
        let js = bytemuck::cast_slice(&state.junction_state);
        self.write_scene(&b.junction_state, k, nj, WORD_PAIR_BYTES, js);
        self.forget_junction_sums(k);
        self.write_scene(
            &b.slide,
            k,
            nx,
            WORD_PAIR_BYTES,
            bytemuck::cast_slice(&state.slide),
        );
        let law_state: Vec<Packed<T>> = state
            .law_state
            .iter()
            .map(|&v| T::pack(Coord::<T>::from_parts(v)))
            .collect();
        self.write_scene(
            &b.law_state,
            k,
            law_words,
            Self::PACKED_BYTES,
            bytemuck::cast_slice(&law_state),
        );
        let scene = &mut self.scenes[k];
        scene.drive_origin = state.drive_origin_as::<T, Coord<T>>();
        // The saved forces are those of the saved state.
        scene.forces_ready = true;
        Ok(())
    }
}

/// The state buffers read back, in the kernels' types.
pub(super) struct RawState<T: GpuReal> {
    disp: Vec<[Coord<T>; 2]>,
    vel: Vec<[T; 2]>,
    force: Vec<[T; 2]>,
    contact: Vec<[T; 2]>,
    friction: FrictionState<T, Coord<T>>,
}

/// Records of `junction_cache` bytes that hold kept sums (not empty).
fn kept_records<T: GpuReal>(bytes: &[u8]) -> usize {
    let n = bytes.len() / std::mem::size_of::<GpuJunctionCache<T>>();
    let sums: Vec<GpuJunctionCache<T>> = cast_prefix(bytes, n);
    sums.iter().filter(|s| s.stiffness_max > T::zero()).count()
}
