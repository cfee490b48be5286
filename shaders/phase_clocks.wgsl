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
// One thread in PHASE_ARRIVAL_STRIDE (a warp's first on NVIDIA: its threads
// arrive together) also keeps the latest arrival: the slowest warp's, so
// that mark less it is what the barrier itself took.
// The sums live in workgroup memory (no register of any thread holds them)
// and go to storage once a dispatch (`phase_flush`). Off (the default),
// every mark compiles out.

override PHASE_CLOCKS: bool = false;
// Words of phase_sums: PHASE_CLOCK_WORDS (phase_clocks.rs) where the clocks are
// on, 1 where they are off (no workgroup memory to speak of).
override PHASE_SUM_WORDS: u32 = 1u;

// Each slot's sums over its workgroups and dispatches, PHASE_CLOCK_WORDS a
// slot: a scene's (a persistent workgroup adds to its first scene's), or a
// tile's (the tiled kernel, `tile_index()`: imbalance between a scene's
// tiles shows). A slot holds the workgroup-dispatches flushed, a spare
// word, then for each
// phase (PHASE_WORDS) its cycles (low, high word), thread 0's own cycles
// (low, high), its marks, the slowest warp's cycles (low, high) and a
// spare.
@group(0) @binding(18) var<storage, read_write> phase_cycles: array<atomic<u32>>;

// The same layout for this workgroup's dispatch, but for its first two
// words, the clock at the last mark and at thread 0's last arrival, and
// each phase's last word, the latest arrival's clock since its last mark
// (0: none). Atomic for the arrivals' maximum; the rest thread 0's alone.
var<workgroup> phase_sums: array<atomic<u32>, PHASE_SUM_WORDS>;

const PHASE_LAST: u32 = 0u;
const PHASE_ARRIVED: u32 = 1u;
const PHASE_FLUSHES: u32 = 0u;
// A phase's words (after its first): thread 0's own cycles, its marks, the
// slowest warp's cycles, the latest arrival.
const PHASE_OWN: u32 = 2u;
const PHASE_MARKS: u32 = 4u;
const PHASE_SLOWEST: u32 = 5u;
const PHASE_LATEST: u32 = 7u;
// Threads a clock sample of the arrivals: NVIDIA's warp, whose threads
// arrive together. AMD's 64-wide waves take two samples each; llvmpipe's
// 8-wide subgroups one in four, where the slowest is a lower bound.
const PHASE_ARRIVAL_STRIDE: u32 = 32u;

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
    let low = atomicLoad(&phase_sums[word]) + cycles;
    atomicStore(&phase_sums[word], low);
    atomicAdd(&phase_sums[word + 1u], select(0u, 1u, low < cycles));
}

// Thread t (of the workgroup) starts its clock: the dispatch's start.
fn phase_start(t: u32) {
    if PHASE_CLOCKS && t == 0u {
        let now = phase_clock().x;
        atomicStore(&phase_sums[PHASE_LAST], now);
        atomicStore(&phase_sums[PHASE_ARRIVED], now);
    }
}

// Thread t arrives at the barrier that ends `phase`. The latest arrival is
// a maximum of clock readings: a phase that the 32-bit clock wraps within
// (one in about 2^32 / its cycles) keeps the latest before the wrap.
fn phase_arrive(t: u32, phase: u32) {
    if PHASE_CLOCKS && t % PHASE_ARRIVAL_STRIDE == 0u {
        let now = phase_clock().x;
        atomicMax(&phase_sums[PHASE_FIRST_WORD + phase * PHASE_WORDS + PHASE_LATEST], now);
        if t == 0u {
            atomicStore(&phase_sums[PHASE_ARRIVED], now);
        }
    }
}

// Thread t, past the barrier that ends `phase`: the phase's cycles since
// the last mark, thread 0's own up to its arrival and the slowest warp's
// up to its (each the whole phase where none arrived). Its latest arrival
// is cleared for its next turn: no thread arrives at this phase again
// before this mark, since consecutive marks are of different phases and
// thread 0 reaches the next one's barrier only after this.
fn phase_mark(t: u32, phase: u32) {
    if PHASE_CLOCKS && t == 0u {
        let now = phase_clock().x;
        let last = atomicLoad(&phase_sums[PHASE_LAST]);
        var arrived = atomicLoad(&phase_sums[PHASE_ARRIVED]);
        if arrived == last {
            arrived = now;
        }
        let base = PHASE_FIRST_WORD + phase * PHASE_WORDS;
        var latest = atomicExchange(&phase_sums[base + PHASE_LATEST], 0u);
        if latest == 0u {
            latest = now;
        }
        phase_add(base, now - last);
        phase_add(base + PHASE_OWN, arrived - last);
        atomicAdd(&phase_sums[base + PHASE_MARKS], 1u);
        phase_add(base + PHASE_SLOWEST, min(latest - last, now - last));
        atomicStore(&phase_sums[PHASE_LAST], now);
        atomicStore(&phase_sums[PHASE_ARRIVED], now);
    }
}

// Every thread t of the workgroup's `threads`, past thread 0's last mark:
// this dispatch's sums added to thread 0's `slot` (its scene's, or its
// tile's). A thread a sum, each a 64-bit sum carried by hand (storage
// atomics are 32 bits), so the flush waits on one atomic, not on one per
// sum in a row (a dispatch of the tiled kernel is as short as 2 steps).
fn phase_flush(t: u32, threads: u32, slot: u32) {
    if PHASE_CLOCKS {
        if t == 0u {
            // The last mark's clock is no longer needed: the slot's base.
            atomicStore(&phase_sums[PHASE_LAST], slot * PHASE_CLOCK_WORDS);
        }
        workgroupBarrier();
        let base = atomicLoad(&phase_sums[PHASE_LAST]);
        // Items: three pairs a phase (its cycles, thread 0's own, the
        // slowest warp's), then each phase's marks, then the flush itself.
        let pairs = 3u * PHASE_COUNT;
        for (var k = t; k < pairs + PHASE_COUNT + 1u; k += threads) {
            if k < pairs {
                let offsets = vec3<u32>(0u, PHASE_OWN, PHASE_SLOWEST);
                let w = PHASE_FIRST_WORD + (k / 3u) * PHASE_WORDS + offsets[k % 3u];
                let add = atomicLoad(&phase_sums[w]);
                let high = atomicLoad(&phase_sums[w + 1u]);
                if add != 0u || high != 0u {
                    let before = atomicAdd(&phase_cycles[base + w], add);
                    let carry = select(0u, 1u, before + add < add);
                    if high + carry != 0u {
                        atomicAdd(&phase_cycles[base + w + 1u], high + carry);
                    }
                }
            } else if k < pairs + PHASE_COUNT {
                let w = PHASE_FIRST_WORD + (k - pairs) * PHASE_WORDS + PHASE_MARKS;
                let marks = atomicLoad(&phase_sums[w]);
                if marks != 0u {
                    atomicAdd(&phase_cycles[base + w], marks);
                }
            } else {
                atomicAdd(&phase_cycles[base + PHASE_FLUSHES], 1u);
            }
        }
    }
}
