//! The host side of the tiled kernel (temporal blocking, `shaders/tiled.wgsl`):
//! how a lattice is cut into column tiles, what each tile holds in
//! workgroup memory and in its scratch buffers, whether a scene fits, and
//! where each dispatch of a batch ends.

use super::precision::{Coord, GpuReal};
use super::shaders::Kernel;
use crate::model::Model;

/// Columns a tile owns by default.
pub const TILE_WIDTH: u32 = 8;
/// Halo columns each side, and so the most steps per dispatch, by default.
pub const TILE_HALO: u32 = 4;
/// The most halo columns (steps per dispatch) asked for: llvmpipe counts a
/// dispatch's loop iterations against 65535, and the redundant halo work
/// grows with it.
pub const MAX_TILE_HALO: u32 = 32;
/// The tiled kernel's own workgroup words (its plan), rounded up.
const TILE_OWN_BYTES: u64 = 64;

/// The tiles of one lattice (`shaders/state_tiled.wgsl`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TileGeometry {
    /// Columns each tile owns (the last may own fewer).
    pub width: u32,
    /// Halo columns each side: the most steps one dispatch runs.
    pub halo: u32,
    /// Tiles across the lattice: workgroups per scene.
    pub tiles: u32,
    /// Slots per tile: (width + 2 halo) columns of every row.
    pub blocks: u32,
    /// Columns of the slots: width + 2 halo.
    pub span: u32,
}

impl TileGeometry {
    /// Tiles of `width` columns with `halo` columns of halo over `model`'s
    /// lattice; an error naming the value and the allowed range.
    pub fn new(model: &Model, width: u32, halo: u32) -> Result<TileGeometry, String> {
        if width == 0 {
            return Err("tile width 0: a tile owns at least 1 column".to_string());
        }
        if halo == 0 || halo > MAX_TILE_HALO {
            return Err(format!(
                "tile halo {halo}: the steps per dispatch of the tiled kernel are 1 to \
                 {MAX_TILE_HALO}"
            ));
        }
        let span = width + 2 * halo;
        Ok(TileGeometry {
            width,
            halo,
            tiles: (model.nx as u32).div_ceil(width),
            blocks: span * model.nz as u32,
            span,
        })
    }

    /// Bytes of workgroup memory a tile holds in precision `T`: its
    /// blocks' u, v and force, and the kernel's own words.
    pub fn workgroup_bytes<T: GpuReal>(&self) -> u64 {
        let per_block = std::mem::size_of::<[Coord<T>; 2]>() + 2 * std::mem::size_of::<[T; 2]>();
        self.blocks as u64 * per_block as u64 + TILE_OWN_BYTES
    }

    /// Elements of each scratch buffer per scene of `blocks` blocks, `nx`
    /// columns, `ns` junctions per interface block and `lanes` lanes: the
    /// published blocks (two copies); the published junctions (two copies)
    /// and then each tile's private halo junctions; the lane sums.
    pub fn scratch_per_scene(
        &self,
        blocks: usize,
        nx: usize,
        ns: usize,
        lanes: usize,
    ) -> [usize; 3] {
        let tiles = self.tiles as usize;
        let span = self.span as usize;
        [
            2 * blocks,
            2 * nx * ns + tiles * span * ns,
            tiles * span * lanes,
        ]
    }
}

/// Whether the tiled kernel can step `model` in precision `T` on an
/// adapter with `limits`: a junction law or none (a per-block law's state
/// would be raced on by the halos), and the tile in workgroup memory.
pub fn tiled_fit<T: GpuReal>(
    model: &Model,
    geometry: &TileGeometry,
    limits: &wgpu::Limits,
) -> Result<u64, String> {
    if model.law.is_per_block() {
        return Err(format!(
            "the tiled kernel steps junction friction or none: {} keeps per-block state its \
             halos would race on: use --gpu-path one-step-lanes or resident",
            model.law.name()
        ));
    }
    let bytes = geometry.workgroup_bytes::<T>();
    let allowed = limits.max_compute_workgroup_storage_size as u64;
    if bytes > allowed {
        return Err(format!(
            "the tiled kernel holds a tile of {} columns and {} halo columns each side in \
             workgroup memory: {} blocks in {} need {bytes} bytes, the adapter allows {allowed}: \
             use a narrower tile, a smaller halo, or --gpu-path one-step-lanes",
            geometry.width,
            geometry.halo,
            geometry.blocks,
            T::NAME
        ));
    }
    Ok(bytes)
}

/// The step after the last of the dispatch that starts at step `first` of
/// a batch of `steps` steps with samples at `sample_offsets` (ascending):
/// after `halo` steps, at the batch's end, after the batch's first step
/// (whose forces may be a snapshot's) and after a sample's step. The
/// kernel computes the same (`tile_dispatch_end` in `shaders/tiled.wgsl`).
pub fn dispatch_end(first: u64, steps: u64, halo: u64, sample_offsets: &[u64]) -> u64 {
    let mut end = if first == 0 { 1 } else { first + halo }.min(steps);
    if let Some(&sample) = sample_offsets.iter().find(|&&o| o >= first) {
        end = end.min(sample + 1);
    }
    end
}

/// The step after the last of each dispatch of a batch on `kernel`: one
/// step each for the one-step kernels, `dispatch_end` for the tiled one.
pub fn dispatch_ends(kernel: Kernel, steps: u64, halo: u64, sample_offsets: &[u64]) -> Vec<u64> {
    let mut ends = Vec::new();
    let mut first = 0;
    while first < steps {
        let end = match kernel {
            Kernel::Tiled => dispatch_end(first, steps, halo, sample_offsets),
            _ => first + 1,
        };
        ends.push(end);
        first = end;
    }
    ends
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dispatch_ends_after_its_halo_the_first_step_a_sample_or_the_batch() {
        let ends = dispatch_ends(Kernel::Tiled, 20, 4, &[6, 7, 15]);
        assert_eq!(ends, vec![1, 5, 7, 8, 12, 16, 20]);
        assert_eq!(dispatch_ends(Kernel::Tiled, 1, 4, &[]), vec![1]);
        assert_eq!(dispatch_ends(Kernel::Tiled, 9, 4, &[]), vec![1, 5, 9]);
        assert_eq!(dispatch_ends(Kernel::OneStep, 3, 4, &[1]), vec![1, 2, 3]);
        // A sample at the first step ends the first dispatch anyway.
        assert_eq!(dispatch_ends(Kernel::Tiled, 6, 8, &[0, 5]), vec![1, 6]);
    }
}
