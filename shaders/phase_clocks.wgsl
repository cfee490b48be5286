// Where a workgroup's steps spend their time, phase by phase, on the
// multiprocessor's own cycle counter (GpuOptions::phase_clocks): what
// decides between the designs for Table S1 and for ensembles, and what no
// host-side timer can split.
// CPU twin: src/engines/gpu/phase_clocks.rs PhaseCycles (the host's reading
// of these sums; the CPU engines have no phases to time).
// import: scene
//
// Thread 0 of the workgroup reads the clock as it arrives at the barrier
// that ends a phase (`phase_arrive`) and again past it (`phase_mark`): past
// a barrier every thread has finished the phase, so mark to mark is the
// phase's length for the whole workgroup, its slowest thread and the
// barrier included, and arrival less the last mark is thread 0's own work.
// The sums live in workgroup memory (no register of any thread holds them)
// and go to storage once a dispatch (`phase_flush`). Off (the default),
// every mark compiles out.

override PHASE_CLOCKS: bool = false;
// Words of phase_sums: PHASE_CLOCK_WORDS (phase_clocks.rs) where the clocks are
// on, 1 where they are off (no workgroup memory to speak of).
override PHASE_SUM_WORDS: u32 = 1u;

// Each scene's sums over its workgroups and dispatches, PHASE_CLOCK_WORDS a
// scene: the workgroup-dispatches flushed, a spare word, then for each
// phase its cycles (low, high word), thread 0's own cycles (low, high) and
// its marks.
@group(0) @binding(18) var<storage, read_write> phase_cycles: array<atomic<u32>>;

// The same layout for this workgroup's dispatch, but for its first two
// words: the clock at the last mark and at thread 0's last arrival.
var<workgroup> phase_sums: array<u32, PHASE_SUM_WORDS>;

const PHASE_LAST: u32 = 0u;
const PHASE_ARRIVED: u32 = 1u;
const PHASE_FLUSHES: u32 = 0u;

// The multiprocessor's cycle counter, low word first. naga writes this
// function as the constant (3, 3); the engine's own SPIR-V
// (spirv::read_shader_clock) gives it the body OpReadClockKHR at the scope
// of its first component, 3: Subgroup, a counter of the multiprocessor
// that runs the workgroup (VK_KHR_shader_clock's shaderSubgroupClock).
fn phase_clock() -> vec2<u32> {
    return vec2<u32>(3u, 3u);
}

// phase_sums' 64-bit sum at `word` (low, high) plus `cycles`.
fn phase_add(word: u32, cycles: u32) {
    let low = phase_sums[word] + cycles;
    phase_sums[word] = low;
    phase_sums[word + 1u] += select(0u, 1u, low < cycles);
}

// Thread t (of the workgroup) starts its clock: the dispatch's start.
fn phase_start(t: u32) {
    if PHASE_CLOCKS && t == 0u {
        let now = phase_clock().x;
        phase_sums[PHASE_LAST] = now;
        phase_sums[PHASE_ARRIVED] = now;
    }
}

// Thread t arrives at the barrier that ends a phase.
fn phase_arrive(t: u32) {
    if PHASE_CLOCKS && t == 0u {
        phase_sums[PHASE_ARRIVED] = phase_clock().x;
    }
}

// Thread t, past the barrier that ends `phase`: the phase's cycles since
// the last mark, and thread 0's own up to its arrival (the whole phase
// where it did not mark one).
fn phase_mark(t: u32, phase: u32) {
    if PHASE_CLOCKS && t == 0u {
        let now = phase_clock().x;
        let last = phase_sums[PHASE_LAST];
        var arrived = phase_sums[PHASE_ARRIVED];
        if arrived == last {
            arrived = now;
        }
        let base = PHASE_FIRST_WORD + phase * PHASE_WORDS;
        phase_add(base, now - last);
        phase_add(base + 2u, arrived - last);
        phase_sums[base + 4u] += 1u;
        phase_sums[PHASE_LAST] = now;
        phase_sums[PHASE_ARRIVED] = now;
    }
}

// Every thread t of the workgroup's `threads`, past thread 0's last mark:
// this dispatch's sums added to the scene's of thread 0 (the workgroup's
// first). A thread a sum, each a 64-bit sum carried by hand (storage
// atomics are 32 bits), so the flush waits on one atomic, not on one per
// sum in a row (a dispatch of the tiled kernel is as short as 2 steps).
fn phase_flush(t: u32, threads: u32) {
    if PHASE_CLOCKS {
        if t == 0u {
            // The last mark's clock is no longer needed: the scene's base.
            phase_sums[PHASE_LAST] = scene * PHASE_CLOCK_WORDS;
        }
        workgroupBarrier();
        let base = phase_sums[PHASE_LAST];
        // Items: a pair a phase for its cycles and thread 0's own, then
        // each phase's marks, then the flush itself.
        let pairs = 2u * PHASE_COUNT;
        for (var k = t; k < pairs + PHASE_COUNT + 1u; k += threads) {
            if k < pairs {
                let w = PHASE_FIRST_WORD + (k / 2u) * PHASE_WORDS + 2u * (k % 2u);
                let add = phase_sums[w];
                let high = phase_sums[w + 1u];
                if add != 0u || high != 0u {
                    let before = atomicAdd(&phase_cycles[base + w], add);
                    let carry = select(0u, 1u, before + add < add);
                    if high + carry != 0u {
                        atomicAdd(&phase_cycles[base + w + 1u], high + carry);
                    }
                }
            } else if k < pairs + PHASE_COUNT {
                let w = PHASE_FIRST_WORD + (k - pairs) * PHASE_WORDS + 4u;
                if phase_sums[w] != 0u {
                    atomicAdd(&phase_cycles[base + w], phase_sums[w]);
                }
            } else {
                atomicAdd(&phase_cycles[base + PHASE_FLUSHES], 1u);
            }
        }
    }
}
