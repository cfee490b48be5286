//! The host side of the tiled kernel (temporal blocking, `shaders/tiled.wgsl`):
//! how a lattice is cut into column tiles, what each tile holds in
//! workgroup memory and in its scratch buffers, whether a scene fits, and
//! where each dispatch of a batch ends.

use super::batch_sizes::ONE_STEP_BATCH;
use super::loop_budget::{lane_loop_iterations, SOFTWARE_LOOP_BUDGET};
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
/// The tiled kernel's own workgroup words (its plan, its chain, its next
/// sample, the sample reduction's flag), rounded up.
const TILE_OWN_BYTES: u64 = 64;
/// Tile widths `auto` times beside the default, at the default halo
/// (`kernel_choice::search_tile_shapes`): narrower tiles spread a small
/// lattice over more multiprocessors, wider ones redo less halo work.
pub const WIDTHS_SEARCHED: [u32; 2] = [4, 16];
/// Halos (steps per dispatch) `auto` then times at the fastest width:
/// fewer dispatches a step against more redundant halo work.
pub const HALOS_SEARCHED: [u32; 2] = [2, 8];
/// Halos `auto` times chained at the chained launch's width where chaining
/// beat the unchained launch (smaller ones than its own only): a chained
/// round costs a neighbour's wait, not a dispatch, so less redundant halo
/// work may win there.
pub const CHAINED_HALOS_SEARCHED: [u32; 2] = [1, 2];
/// Widths `auto` then times chained at the fastest chained halo (narrower
/// ones than its own only), on hardware: a narrower tile spreads a scene
/// over more multiprocessors, each stepping fewer blocks, and chained its
/// rounds cost waits on neighbours rather than dispatches. Software
/// adapters run only as many workgroups at once as they have threads, so
/// a scene of many tiles would stall its chain there.
pub const CHAINED_WIDTHS_SEARCHED: [u32; 2] = [2, 4];

/// A tile's shape: the columns it owns and its halo columns each side,
/// the most steps one dispatch runs. Written `16x4` (width x halo) in
/// launch names and on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TileShape {
    pub width: u32,
    pub halo: u32,
}

impl TileShape {
    /// The default shape (`TILE_WIDTH`, `TILE_HALO`).
    pub const DEFAULT: TileShape = TileShape {
        width: TILE_WIDTH,
        halo: TILE_HALO,
    };

    /// `16x4`.
    pub fn name(self) -> String {
        format!("{}x{}", self.width, self.halo)
    }

    /// The inverse of `name`; an error naming the value and the allowed
    /// ranges (those of `check`).
    pub fn parse(text: &str) -> Result<TileShape, String> {
        let bad = || {
            format!(
                "tile shape {text:?}: expected WIDTHxHALO, e.g. 8x4 (columns a tile owns, at \
                 least 1; halo columns each side, the most steps a dispatch runs, 1 to \
                 {MAX_TILE_HALO})"
            )
        };
        let (w, h) = text.split_once('x').ok_or_else(bad)?;
        let width: u32 = w.parse().map_err(|_| bad())?;
        let halo: u32 = h.parse().map_err(|_| bad())?;
        let shape = TileShape { width, halo };
        shape.check().map_err(|_| bad())?;
        Ok(shape)
    }

    /// The allowed ranges, in one place: a width of at least 1 column, a
    /// halo of 1 to `MAX_TILE_HALO` (the most steps a dispatch runs); an
    /// error naming the value and its range.
    pub fn check(self) -> Result<(), String> {
        if self.width == 0 {
            return Err("tile width 0: a tile owns at least 1 column".to_string());
        }
        if self.halo == 0 || self.halo > MAX_TILE_HALO {
            return Err(format!(
                "tile halo {}: halo columns each side, the most steps a dispatch of the tiled \
                 kernel runs, are 1 to {MAX_TILE_HALO}",
                self.halo
            ));
        }
        Ok(())
    }
}

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
    /// Tiles of `shape` over `model`'s lattice; an error naming the value
    /// and the allowed range (`TileShape::check`).
    pub fn new(model: &Model, shape: TileShape) -> Result<TileGeometry, String> {
        shape.check()?;
        let TileShape { width, halo } = shape;
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
    /// blocks' u, v and force, its columns' junction-block notes, the slots of the
    /// samples it records and the kernel's own words.
    pub fn workgroup_bytes<T: GpuReal>(&self) -> u64 {
        let per_block = std::mem::size_of::<[Coord<T>; 2]>() + 2 * std::mem::size_of::<[T; 2]>();
        // A note a column: the tiled kernel steps junctions or no friction,
        // and counts the notes of the second too (a few hundred bytes).
        let noted = super::layout::noted_blocks_bytes::<T>(self.span as usize);
        // The sample reduction's slots, and of each own interface block
        // what a sample reads (u, v, force, friction, normal) and its part.
        let sums = std::mem::size_of::<super::layout::GpuSampleSums<T>>() as u64;
        // (`InterfaceInputs`: u's two coordinates, then four reals and
        // two vec2s, laid out at a vec2<real>'s alignment.)
        let vec2 = std::mem::size_of::<[T; 2]>() as u64;
        let inputs = (std::mem::size_of::<[Coord<T>; 2]>() + 6 * std::mem::size_of::<T>()) as u64;
        let slots = super::batch_sizes::workgroup_state_reduction_width::<T>() as u64 * sums
            + self.width as u64 * (sums + inputs.next_multiple_of(vec2));
        self.blocks as u64 * per_block as u64 + noted + slots + TILE_OWN_BYTES
    }

    /// Elements of each scratch array per scene of `blocks` blocks, `nx`
    /// columns, `ns` junctions per interface block and `lanes` lanes.
    pub fn scratch_per_scene(
        &self,
        blocks: usize,
        nx: usize,
        ns: usize,
        lanes: usize,
    ) -> TileScratch {
        let tiles = self.tiles as usize;
        let span = self.span as usize;
        TileScratch {
            published_blocks: 2 * blocks,
            published_junctions: 2 * nx * ns,
            published_sums: 2 * nx,
            halo_junctions: tiles * span * ns,
            lane_sums: tiles * span * lanes,
        }
    }
}

/// Elements per scene of what the tiled kernel keeps beside the state
/// (`shaders/state_tiled.wgsl`, `shaders/junction_tiled.wgsl`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TileScratch {
    /// Two published copies of the blocks (`pub_disp`, `pub_vel`).
    pub published_blocks: usize,
    /// Two published copies of the junctions (`tile_junction_state`,
    /// `tile_junction_spring`).
    pub published_junctions: usize,
    /// Two published copies of the interface blocks' kept junction sums
    /// (`tile_junction_cache`).
    pub published_sums: usize,
    /// Each tile's private copy of its halo's junctions: the junction
    /// arrays' tail, after every scene's own junctions.
    pub halo_junctions: usize,
    /// The lane sums of each tile's held interface blocks (`lane_partial`).
    pub lane_sums: usize,
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

/// The most loop iterations one invocation of `threads` runs in a tiled
/// dispatch of `geometry.halo` steps on `model` (counted as the persistent
/// kernel's are: 10 a block for its bonds, a junction lane's junctions,
/// eight lane sums a round, and a sample's tally and reduction), with
/// loading and publishing the tile.
pub fn loop_iterations(
    model: &Model,
    geometry: &TileGeometry,
    threads: u32,
    lane_run: u32,
) -> usize {
    let t = threads.max(1) as usize;
    let span = geometry.span as usize;
    let (ns, lanes) = match model.junctions {
        Some(j)
            if !model.law.is_per_block()
                && model.law != crate::model::scenario::FrictionLaw::None =>
        {
            (j.count, crate::model::junction::JUNCTION_LANES.min(j.count))
        }
        _ => (0, 0),
    };
    let blocks = (span * model.nz).div_ceil(t);
    let lane_loops = lane_loop_iterations(span, lanes, ns, t, lane_run);
    let merges = span.div_ceil(t) * lanes.div_ceil(8).max(1);
    // A sample in the step: an interface block's junction tally (16 a
    // round), the threads folded into the slots, the tree.
    let slots = super::batch_sizes::WORKGROUP_STATE_REDUCTION_WIDTH as usize;
    let sample = ns.div_ceil(16) + 1 + t.div_ceil(slots) + slots.ilog2() as usize;
    let per_step = 3 + blocks * 10 + lane_loops + merges + sample;
    // Loading and publishing the tile, and the search for its first sample.
    let tile = 2 * blocks + 2 * (span * ns).div_ceil(t) + 12;
    geometry.halo as usize * per_step + tile
}

/// On a software adapter, whether a tiled dispatch stays within the loop
/// budget; an error naming the count and what to change where not.
pub fn software_fit(
    model: &Model,
    geometry: &TileGeometry,
    threads: u32,
    lane_run: u32,
) -> Result<(), String> {
    let n = loop_iterations(model, geometry, threads, lane_run);
    if n > SOFTWARE_LOOP_BUDGET {
        return Err(format!(
            "a tiled dispatch of {} steps with {threads} threads would run about {n} loop \
             iterations per thread, and software adapters end a shader's loops after 65535 \
             (this engine keeps to {SOFTWARE_LOOP_BUDGET}): use fewer steps per dispatch, more \
             threads or --gpu-path one-step",
            geometry.halo
        ));
    }
    Ok(())
}

/// A chained tiled dispatch (`GpuOptions::chained_tiles`): the most rounds
/// it runs, and the most polls each tile makes for its neighbours in it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TileChain {
    /// Rounds (dispatches of the unchained kernel) one dispatch runs at
    /// most; the batch's end ends one anyway.
    pub rounds: usize,
    /// Polls a tile makes in one dispatch before it gives up
    /// (`CHAIN_POLLS`; `GpuStatus::stalled_tile`).
    pub polls: u32,
    /// Each poll waits at 256 workgroup barriers (`CHAIN_POLL_PAUSE`):
    /// on a software adapter a barrier takes time and no loop iteration,
    /// so a tile's loop budget waits longer.
    pub pause: bool,
}

/// Rounds a chained dispatch runs at most on a software adapter: few, so
/// that the polls of its waits keep most of the loop budget.
pub const SOFTWARE_CHAINED_ROUNDS: usize = 4;

/// Polls a tile makes in a chained dispatch on hardware before it gives up:
/// about a second at a microsecond a poll (two L2 loads and a barrier).
/// That is far past any wait of a scene whose tiles are all on the GPU (a
/// neighbour's round: microseconds), and past a wait for a slot freed by a
/// scene before it (a batch: milliseconds). A GPU that cannot run a
/// scene's tiles at once then costs `auto` about a second, not ten, when it
/// times the chained kernel (once a wave of stalled workgroups).
pub const HARDWARE_CHAIN_POLLS: u32 = 1 << 20;

impl TileChain {
    /// The chain of `model`'s tiles of `geometry` at `threads` threads: a
    /// whole batch's rounds a dispatch on hardware; on a software adapter
    /// `SOFTWARE_CHAINED_ROUNDS`, with the rest of the loop budget for
    /// polls (each a loop round and one per tile it reads), or an error
    /// where no poll is left.
    pub fn new(
        model: &Model,
        geometry: &TileGeometry,
        threads: u32,
        lane_run: u32,
        software: bool,
    ) -> Result<TileChain, String> {
        if !software {
            return Ok(TileChain {
                rounds: ONE_STEP_BATCH as usize,
                polls: HARDWARE_CHAIN_POLLS,
                pause: false,
            });
        }
        let per_round = loop_iterations(model, geometry, threads, lane_run);
        let rounds = SOFTWARE_CHAINED_ROUNDS;
        // The loop round, and where a halo reaches past the tiles either
        // side, a round per tile it reaches (`neighbours_finished`).
        let per_poll = match geometry.halo <= geometry.width {
            true => 1,
            false => 2 * geometry.halo.div_ceil(geometry.width) as usize + 2,
        };
        let left = SOFTWARE_LOOP_BUDGET.saturating_sub(rounds * per_round) / per_poll;
        if left < 64 {
            return Err(format!(
                "chained tiles of {} steps with {threads} threads would leave {left} polls of a \
                 software adapter's loop budget for the tiles' waits: use fewer steps per \
                 dispatch, more threads, or the tiled kernel unchained",
                geometry.halo
            ));
        }
        Ok(TileChain {
            rounds,
            polls: left as u32,
            pause: true,
        })
    }
}

/// The step after the last of the dispatch that starts at step `first` of
/// a batch of `steps` steps: after `halo` steps, at the batch's end, and
/// after the batch's first step (whose forces may be a snapshot's). A
/// sample ends none: the kernel records it in its step (tiled.wgsl). The
/// engine writes a batch's ends to the kernel's `tile_ends`.
pub fn dispatch_end(first: u64, steps: u64, halo: u64) -> u64 {
    if first == 0 { 1 } else { first + halo }.min(steps)
}

/// The step after the last of each dispatch of a batch on `kernel`: one
/// step each for the one-step kernels, `dispatch_end` for the tiled one.
pub fn dispatch_ends(kernel: Kernel, steps: u64, halo: u64) -> Vec<u64> {
    let mut ends = Vec::new();
    let mut first = 0;
    while first < steps {
        let end = match kernel {
            Kernel::Tiled => dispatch_end(first, steps, halo),
            _ => first + 1,
        };
        ends.push(end);
        first = end;
    }
    ends
}

/// The bit of a `tile_ends` word that marks the round ending its dispatch
/// (`ROUND_ENDS_DISPATCH` in tiled.wgsl).
pub const ROUND_ENDS_DISPATCH: u32 = 0x8000_0000;

/// Whether each round of a batch (its end steps `ends`, from
/// `dispatch_ends`) ends its dispatch: every round unchained; chained
/// (`chain`), the batch's last, and any that would make a dispatch longer
/// than `chain.rounds`.
pub fn rounds_ending_dispatches(ends: &[u64], chain: Option<TileChain>) -> Vec<bool> {
    let Some(chain) = chain else {
        return vec![true; ends.len()];
    };
    let mut run = 0;
    ends.iter()
        .enumerate()
        .map(|(d, _)| {
            run += 1;
            let last = d + 1 == ends.len() || run == chain.rounds;
            if last {
                run = 0;
            }
            last
        })
        .collect()
}

/// The `tile_ends` words of a batch: each round's end step, with
/// `ROUND_ENDS_DISPATCH` where it ends its dispatch.
pub fn tile_end_words(ends: &[u64], ending: &[bool]) -> Vec<u32> {
    ends.iter()
        .zip(ending)
        .map(|(&end, &last)| end as u32 | if last { ROUND_ENDS_DISPATCH } else { 0 })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped Table S1 scene (57 × 31).
    fn table_s1() -> Model {
        let s = crate::model::scenario::Scenario::parse(
            crate::model::scenario::built_in("tromborg2014_precursors").unwrap(),
            "s1",
            &[] as &[String],
        )
        .unwrap();
        Model::from_scenario(&s, false).unwrap()
    }

    /// Table S1 at the defaults is far inside llvmpipe's loop budget;
    /// one thread and a 32-step halo on a tall lattice is past it, and is
    /// refused with the count.
    #[test]
    fn a_dispatch_past_the_software_loop_budget_is_refused() {
        let m = table_s1();
        let defaults = TileGeometry::new(&m, TileShape::DEFAULT).unwrap();
        let n = loop_iterations(&m, &defaults, 256, 1);
        assert!(n < SOFTWARE_LOOP_BUDGET / 10, "{n}");
        assert!(software_fit(&m, &defaults, 256, 1).is_ok());
        let wide = TileGeometry::new(
            &m,
            TileShape {
                width: 16,
                halo: MAX_TILE_HALO,
            },
        )
        .unwrap();
        let err = software_fit(&m, &wide, 1, 1).unwrap_err();
        assert!(err.contains("loop iterations per thread"), "{err}");
        assert!(loop_iterations(&m, &wide, 1, 1) > SOFTWARE_LOOP_BUDGET);
    }

    /// A tile of no columns, or a halo past the most steps a dispatch may
    /// take, is refused with the value and the range.
    #[test]
    fn a_tile_of_no_columns_or_too_wide_a_halo_is_refused() {
        let s = crate::model::scenario::Scenario::parse(
            crate::model::scenario::DEFAULT_SCENARIO,
            "s1",
            &[] as &[String],
        )
        .unwrap();
        let m = Model::from_scenario(&s, false).unwrap();
        let err = TileGeometry::new(
            &m,
            TileShape {
                width: 0,
                halo: TILE_HALO,
            },
        )
        .unwrap_err();
        assert!(
            err.contains("tile width 0") && err.contains("at least 1"),
            "{err}"
        );
        let err = TileGeometry::new(
            &m,
            TileShape {
                width: TILE_WIDTH,
                halo: MAX_TILE_HALO + 1,
            },
        )
        .unwrap_err();
        assert!(err.contains(&format!("1 to {MAX_TILE_HALO}")), "{err}");
    }

    /// Shapes read back from their names; anything else is refused with
    /// the value and the ranges.
    #[test]
    fn tile_shapes_read_back_and_bad_ones_are_refused() {
        for shape in [TileShape::DEFAULT, TileShape { width: 16, halo: 2 }] {
            assert_eq!(TileShape::parse(&shape.name()), Ok(shape));
        }
        assert_eq!(TileShape::DEFAULT.name(), "8x4");
        for bad in [
            "8", "0x4", "8x0", "8x33", "x4", "8x", "ax4", "8x4x2", "-8x4",
        ] {
            let err = TileShape::parse(bad).unwrap_err();
            assert!(err.contains(bad) && err.contains("1 to 32"), "{err}");
        }
    }

    /// A sample ends no dispatch: the tiled kernel records it in its step.
    #[test]
    fn a_dispatch_ends_after_its_halo_the_first_step_or_the_batch() {
        assert_eq!(
            dispatch_ends(Kernel::Tiled, 20, 4),
            vec![1, 5, 9, 13, 17, 20]
        );
        assert_eq!(dispatch_ends(Kernel::Tiled, 1, 4), vec![1]);
        assert_eq!(dispatch_ends(Kernel::Tiled, 9, 4), vec![1, 5, 9]);
        assert_eq!(dispatch_ends(Kernel::OneStep, 3, 4), vec![1, 2, 3]);
        assert_eq!(dispatch_ends(Kernel::Tiled, 6, 8), vec![1, 6]);
    }

    /// Chained, a dispatch runs rounds up to the batch's end or its most
    /// rounds; unchained, a round is a dispatch.
    #[test]
    fn a_chained_dispatch_ends_at_the_batch_or_its_most_rounds() {
        let ends = dispatch_ends(Kernel::Tiled, 30, 4);
        assert_eq!(ends, vec![1, 5, 9, 13, 17, 21, 25, 29, 30]);
        let chain = TileChain {
            rounds: 3,
            polls: 1,
            pause: false,
        };
        let ending = rounds_ending_dispatches(&ends, Some(chain));
        let t = true;
        let f = false;
        assert_eq!(ending, vec![f, f, t, f, f, t, f, f, t]);
        assert!(rounds_ending_dispatches(&ends, None).iter().all(|&e| e));
        let words = tile_end_words(&ends, &ending);
        assert_eq!(words[0], 1);
        assert_eq!(words[2], 9 | ROUND_ENDS_DISPATCH);
    }

    /// Table S1 on a software adapter leaves its chained tiles polls to
    /// spare; on hardware a dispatch chains a whole batch.
    #[test]
    fn chained_tiles_keep_polls_within_a_software_loop_budget() {
        let m = table_s1();
        let g = TileGeometry::new(&m, TileShape::DEFAULT).unwrap();
        let soft = TileChain::new(&m, &g, 256, 1, true).unwrap();
        assert_eq!(soft.rounds, SOFTWARE_CHAINED_ROUNDS);
        assert!(soft.pause);
        // Halo 4 within tiles of 8: a loop round a poll.
        let used = soft.rounds * loop_iterations(&m, &g, 256, 1) + soft.polls as usize;
        assert!(used <= SOFTWARE_LOOP_BUDGET, "{used}");
        assert!(soft.polls > 10_000, "{soft:?}");
        let hard = TileChain::new(&m, &g, 256, 1, false).unwrap();
        assert_eq!(hard.polls, HARDWARE_CHAIN_POLLS);
        assert!(!hard.pause);
        let wide = TileGeometry::new(
            &m,
            TileShape {
                width: 16,
                halo: MAX_TILE_HALO,
            },
        )
        .unwrap();
        let err = TileChain::new(&m, &wide, 1, 1, true).unwrap_err();
        assert!(err.contains("polls"), "{err}");
    }
}
