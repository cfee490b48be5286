//! Where a kernel's steps spend their time on the device, phase by phase
//! (`GpuOptions::phase_clocks`, `shaders/phase_clocks.wgsl`): thread 0 of
//! each workgroup reads its multiprocessor's cycle counter at the barriers
//! between phases, and each scene's sums come back in one buffer. The
//! phases, their words and the host's reading of them are defined here,
//! once: the kernels take the constants from the prelude
//! (`phase_constants`).

/// The phases a persistent, resident or tiled kernel marks, in the order
/// of their words.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// The dispatch's start: its plan and the state entered (workgroup
    /// memory filled), up to the first step or round.
    Enter,
    /// A step's first phase: bulk forces and junction lanes.
    Forces,
    /// A step's second: junction blocks, lane merges, updates, samples.
    Updates,
    /// The persistent kernels' stop check (every 16 steps); a tiled
    /// round's plan.
    Checks,
    /// A tiled round's start: its tile and halo loaded into workgroup
    /// memory, its first step's junction blocks noted.
    Load,
    /// A tiled round's end: its edges published, and its counter.
    Publish,
    /// A chained tiled round's wait for its neighbours' publication.
    Wait,
    /// The dispatch's end: the state left (stored), steps counted.
    Leave,
}

impl Phase {
    pub const ALL: [Phase; 8] = [
        Phase::Enter,
        Phase::Forces,
        Phase::Updates,
        Phase::Checks,
        Phase::Load,
        Phase::Publish,
        Phase::Wait,
        Phase::Leave,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Phase::Enter => "enter",
            Phase::Forces => "forces",
            Phase::Updates => "updates",
            Phase::Checks => "checks",
            Phase::Load => "load",
            Phase::Publish => "publish",
            Phase::Wait => "wait",
            Phase::Leave => "leave",
        }
    }

    /// Its place in `ALL` and in the words: the order of declaration.
    fn index(self) -> usize {
        self as usize
    }
}

/// Words a phase takes: its cycles (low, high), thread 0's own (low,
/// high), its marks, the slowest warp's cycles (low, high), and a spare
/// (in workgroup memory: the latest arrival's clock).
pub const PHASE_WORDS: usize = 8;
/// Words before the first phase's: the workgroup-dispatches flushed and a
/// spare (in workgroup memory: the last mark's clock and the last
/// arrival's).
pub const PHASE_FIRST_WORD: usize = 2;
/// Words a scene's sums take in the `phase_cycles` buffer (and a
/// workgroup's in workgroup memory, where the clocks are on).
pub const PHASE_CLOCK_WORDS: usize = PHASE_FIRST_WORD + Phase::ALL.len() * PHASE_WORDS;

/// The WGSL constants of the phases' words and indices (the prelude,
/// `layout::wgsl_prelude`).
pub fn phase_constants() -> String {
    let mut s = String::new();
    for (name, value) in [
        ("PHASE_COUNT", Phase::ALL.len()),
        ("PHASE_WORDS", PHASE_WORDS),
        ("PHASE_FIRST_WORD", PHASE_FIRST_WORD),
        ("PHASE_CLOCK_WORDS", PHASE_CLOCK_WORDS),
    ] {
        s += &format!("const {name}: u32 = {value}u;\n");
    }
    for phase in Phase::ALL {
        s += &format!(
            "const PHASE_{}: u32 = {}u;\n",
            phase.name().to_uppercase(),
            phase.index()
        );
    }
    s
}

/// One phase's sums over a scene's workgroups and dispatches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PhaseSum {
    /// Cycles from the mark before to this phase's (past its barrier).
    pub cycles: u64,
    /// Thread 0's own cycles in it: to its arrival at the barrier.
    pub own_cycles: u64,
    /// The slowest warp's cycles in it: to the latest arrival at the
    /// barrier of the threads that sample it (a warp's first on NVIDIA).
    /// `cycles` less these is what the barrier took.
    pub slowest_cycles: u64,
    /// Times the phase was marked.
    pub marks: u32,
}

/// A scene's phase sums as its kernels left them in `phase_cycles`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct PhaseCycles {
    /// Workgroup-dispatches that added their sums (a tiled scene's tiles
    /// each count).
    pub flushes: u32,
    /// Each phase's sums, in `Phase::ALL`'s order (`get`).
    pub phases: [PhaseSum; Phase::ALL.len()],
}

impl PhaseCycles {
    /// Decodes one scene's `PHASE_CLOCK_WORDS` words.
    pub fn from_words(words: &[u32]) -> PhaseCycles {
        assert_eq!(words.len(), PHASE_CLOCK_WORDS, "a scene's phase words");
        let pair = |w: usize| u64::from(words[w]) | (u64::from(words[w + 1]) << 32);
        let phases = Phase::ALL.map(|phase| {
            let w = PHASE_FIRST_WORD + phase.index() * PHASE_WORDS;
            PhaseSum {
                cycles: pair(w),
                own_cycles: pair(w + 2),
                marks: words[w + 4],
                slowest_cycles: pair(w + 5),
            }
        });
        PhaseCycles {
            flushes: words[0],
            phases,
        }
    }

    pub fn get(&self, phase: Phase) -> PhaseSum {
        self.phases[phase.index()]
    }

    /// The sums added since `before` (a reading of the same slot).
    pub fn since(&self, before: &PhaseCycles) -> PhaseCycles {
        self.combined(before, u64::wrapping_sub, u32::wrapping_sub)
    }

    /// These sums and `other`'s together (two tiles of a scene).
    pub fn plus(&self, other: &PhaseCycles) -> PhaseCycles {
        self.combined(other, u64::wrapping_add, u32::wrapping_add)
    }

    /// Cycles from the slowest warp's arrival to the mark past the
    /// barrier, over every phase (none in a phase without arrivals): what
    /// the barriers themselves took.
    pub fn barrier_cycles(&self) -> u64 {
        self.phases
            .iter()
            .map(|s| s.cycles.saturating_sub(s.slowest_cycles))
            .sum()
    }

    /// Each sum of these with `other`'s, by `cycles` and `count`.
    fn combined(
        &self,
        other: &PhaseCycles,
        cycles: fn(u64, u64) -> u64,
        count: fn(u32, u32) -> u32,
    ) -> PhaseCycles {
        let phases = Phase::ALL.map(|phase| {
            let (a, b) = (self.get(phase), other.get(phase));
            PhaseSum {
                cycles: cycles(a.cycles, b.cycles),
                own_cycles: cycles(a.own_cycles, b.own_cycles),
                slowest_cycles: cycles(a.slowest_cycles, b.slowest_cycles),
                marks: count(a.marks, b.marks),
            }
        });
        PhaseCycles {
            flushes: count(self.flushes, other.flushes),
            phases,
        }
    }

    /// Cycles of every phase together: the workgroups' dispatches from
    /// their start to their last mark.
    pub fn total_cycles(&self) -> u64 {
        self.phases.iter().map(|s| s.cycles).sum()
    }
}

/// Several slots' sums together (a scene's tiles).
impl<'a> std::iter::Sum<&'a PhaseCycles> for PhaseCycles {
    fn sum<I: Iterator<Item = &'a PhaseCycles>>(slots: I) -> PhaseCycles {
        slots.fold(PhaseCycles::default(), |sum, slot| sum.plus(slot))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scenes_words_decode_to_its_phases_with_their_high_words() {
        let mut words = vec![0u32; PHASE_CLOCK_WORDS];
        words[0] = 3;
        let updates = PHASE_FIRST_WORD + Phase::Updates.index() * PHASE_WORDS;
        words[updates] = 7;
        words[updates + 1] = 2;
        words[updates + 2] = 5;
        words[updates + 4] = 9;
        words[updates + 5] = 6;
        words[updates + 6] = 1;
        let read = PhaseCycles::from_words(&words);
        assert_eq!(read.flushes, 3);
        let sum = read.get(Phase::Updates);
        assert_eq!(sum.cycles, (2u64 << 32) + 7);
        assert_eq!(sum.own_cycles, 5);
        assert_eq!(sum.marks, 9);
        assert_eq!(sum.slowest_cycles, (1u64 << 32) + 6);
        assert_eq!(read.get(Phase::Forces), PhaseSum::default());
        assert_eq!(read.total_cycles(), (2u64 << 32) + 7);
    }

    #[test]
    fn sums_add_and_subtract_phase_by_phase() {
        let mut words = vec![0u32; PHASE_CLOCK_WORDS];
        words[0] = 2;
        let wait = PHASE_FIRST_WORD + Phase::Wait.index() * PHASE_WORDS;
        words[wait] = u32::MAX;
        words[wait + 4] = 3;
        words[wait + 5] = 1;
        let a = PhaseCycles::from_words(&words);
        let b = PhaseCycles::from_words(&words);
        let both = a.plus(&b);
        assert_eq!(both.flushes, 4);
        assert_eq!(both.get(Phase::Wait).cycles, 2 * u64::from(u32::MAX));
        assert_eq!(both.get(Phase::Wait).marks, 6);
        assert_eq!(both.get(Phase::Wait).slowest_cycles, 2);
        assert_eq!(both.get(Phase::Forces), PhaseSum::default());
        assert_eq!(both.since(&b), a);
        assert_eq!([a.clone(), b].iter().sum::<PhaseCycles>(), both);
        assert_eq!(both.barrier_cycles(), 2 * u64::from(u32::MAX) - 2);
    }

    #[test]
    fn the_constants_name_every_phase_at_its_index() {
        let wgsl = phase_constants();
        assert!(wgsl.contains("const PHASE_ENTER: u32 = 0u;"));
        assert!(wgsl.contains("const PHASE_LEAVE: u32 = 7u;"));
        assert!(wgsl.contains(&format!(
            "const PHASE_CLOCK_WORDS: u32 = {PHASE_CLOCK_WORDS}u;"
        )));
    }
}
