//! The kernels' phase clocks (`GpuOptions::phase_clocks`,
//! `shaders/phase_clocks.wgsl`): thread 0 of each workgroup reads its
//! multiprocessor's cycle counter at the barriers between a step's phases
//! (the engine's own SPIR-V, `spirv::read_shader_clock`, on a device
//! opened with VK_KHR_shader_clock, which lavapipe has). The clocks only
//! watch: a clocked run ends in the bits of an unclocked one. Each phase a
//! kernel has is marked as often as it runs, and takes cycles. These tests
//! fail, never skip, when no adapter exists.

#[path = "support/one_dispatch.rs"]
mod one_dispatch;
#[path = "support/phase_kernels.rs"]
mod phase_kernels;

use one_dispatch::run_once;
use phase_kernels::{driven, launches};
use slipfront::engines::gpu::phase_clocks::{Phase, PhaseCycles};
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuPath};
use slipfront::{advance_to, Engine, Model, Snapshot};

fn engine(m: &Model, opts: GpuOptions) -> GpuEngine<f32> {
    GpuEngine::<f32>::with_precision(m, opts).unwrap_or_else(|e| {
        panic!("a GPU adapter with the shader clock is required (lavapipe in CI): {e}")
    })
}

/// `opts`' run of `m` from `start` (not timed) to `end`: its snapshot and
/// the phase sums of the steps from `start` on, the scene's and each
/// tile's (the scene's alone where the kernel has no tiles).
fn run(
    m: &Model,
    opts: GpuOptions,
    start: u64,
    end: u64,
) -> (Snapshot, PhaseCycles, Vec<PhaseCycles>) {
    let mut e = engine(m, opts);
    advance_to(&mut e, start).unwrap();
    let before = e.phase_cycles(0).unwrap();
    let tiles_before = e.phase_cycles_by_tile(0).unwrap();
    advance_to(&mut e, end).unwrap();
    let after = e.phase_cycles(0).unwrap();
    let tiles: Vec<PhaseCycles> = e
        .phase_cycles_by_tile(0)
        .unwrap()
        .iter()
        .zip(&tiles_before)
        .map(|(now, then)| now.since(then))
        .collect();
    assert_eq!(
        e.describe().contains("phase clocks"),
        opts.phase_clocks,
        "{}",
        e.describe()
    );
    (e.snapshot().unwrap(), after.since(&before), tiles)
}

/// Each kernel with phases, through ruptures: clocked, the same bits as
/// unclocked; every step marks its forces and updates once a workgroup
/// (two tiles of 16 columns for the tiled kernel, each into its own sums),
/// and each phase it has took cycles. Unclocked, every sum is zero: the counter is what moves
/// them (the control: a kernel that read a constant would pass the bits
/// and fail here).
#[test]
fn clocked_kernels_keep_their_bits_and_time_every_phase() {
    let m = driven(0.4);
    let (start, steps) = (m.prep_steps, 1500u64);
    for (name, opts) in launches() {
        let (plain, unclocked, _) = run(&m, opts, start, start + steps);
        assert!(
            unclocked.phases.iter().all(|s| *s == Default::default()),
            "{name}: unclocked sums {unclocked:?}"
        );
        let clocked_opts = GpuOptions {
            phase_clocks: true,
            ..opts
        };
        let (got, clocks, tiles) = run(&m, clocked_opts, start, start + steps);
        assert!(plain.total_ruptures() > 50, "{name}: junctions broke");
        assert!(got == plain, "{name}: the clocks changed the run");
        let workgroups = match opts.path {
            GpuPath::Tiled => 2,
            _ => 1,
        };
        for phase in [Phase::Forces, Phase::Updates] {
            let sum = clocks.get(phase);
            assert_eq!(
                u64::from(sum.marks),
                steps * workgroups,
                "{name}: {phase:?} marks"
            );
            assert!(sum.cycles > 0, "{name}: {phase:?} {sum:?}");
            // Thread 0 is among the threads that sample the latest
            // arrival, and the clock moves on from an arrival to the mark
            // past its barrier.
            assert!(
                sum.own_cycles <= sum.slowest_cycles && sum.slowest_cycles < sum.cycles,
                "{name}: {phase:?} {sum:?}"
            );
        }
        let expected: &[Phase] = match (opts.path, opts.chained_tiles) {
            (GpuPath::Tiled, false) => &[Phase::Enter, Phase::Checks, Phase::Load, Phase::Publish],
            (GpuPath::Tiled, true) => &[Phase::Checks, Phase::Load, Phase::Publish, Phase::Wait],
            _ => &[Phase::Enter, Phase::Checks, Phase::Leave],
        };
        for &phase in expected {
            let sum = clocks.get(phase);
            assert!(sum.marks > 0 && sum.cycles > 0, "{name}: {phase:?} {sum:?}");
        }
        // Each workgroup flushes once a dispatch, into its own tile's
        // sums (the tiled kernel), which add up to the scene's; each tile
        // marks each step.
        assert_eq!(tiles.len() as u64, workgroups, "{name}");
        let flushes = tiles[0].flushes;
        assert!(flushes > 0, "{name}: {tiles:?}");
        for tile in &tiles {
            assert_eq!(tile.flushes, flushes, "{name}: {tiles:?}");
            assert_eq!(u64::from(tile.get(Phase::Forces).marks), steps, "{name}");
            assert!(tile.get(Phase::Forces).cycles > 0, "{name}: {tile:?}");
        }
        let together: PhaseCycles = tiles.iter().sum();
        assert_eq!(together, clocks, "{name}");
    }
}

/// Asked of a kernel with no phases (one dispatch a step), or of `auto`
/// (which times its candidates unclocked), the clocks are refused with a
/// reason naming the option and the path.
#[test]
fn a_one_step_kernel_or_auto_is_refused_phase_clocks() {
    for (path, named) in [(GpuPath::OneStep, "one-step"), (GpuPath::Auto, "auto")] {
        let opts = GpuOptions {
            path,
            phase_clocks: true,
            ..GpuOptions::default()
        };
        let err = GpuEngine::<f32>::with_precision(&driven(0.4), opts)
            .err()
            .expect("refused");
        let text = err.to_string();
        assert!(
            text.contains("phase_clocks") && text.contains(named),
            "{text}"
        );
    }
}

/// What a test kernel's workgroup does before the flush: a clock reading
/// at the dispatch's start, then marks.
struct Script {
    scene: u32,
    clock_start: u32,
    marks: Vec<Mark>,
}

/// A phase as the test kernel runs it: thread 0 arrives at its barrier
/// `own` cycles after the last mark, thread 32 (the second sampler of the
/// arrivals) `late` cycles after thread 0, and the mark comes `rest` cycles
/// after that; where no thread `arrives`, only the mark.
struct Mark {
    phase: Phase,
    own: u32,
    late: u32,
    rest: u32,
    arrives: bool,
}

fn mark(phase: Phase, own: u32, late: u32, rest: u32) -> Mark {
    Mark {
        phase,
        own,
        late,
        rest,
        arrives: true,
    }
}

/// The source's phrases the carry controls cut (asserted present, so the
/// controls cannot pass by not changing the kernel).
const STORAGE_CARRY: &str = "select(0u, 1u, before + add < add)";
const WORKGROUP_CARRY: &str = "select(0u, 1u, low < cycles)";
const LATEST_CLEARED: &str = "atomicExchange(&phase_sums[base + PHASE_LATEST], 0u)";
const LATEST_KEPT: &str = "atomicLoad(&phase_sums[base + PHASE_LATEST])";

/// `phase_clocks.wgsl` with a clock the test sets (`fake_clock`) and
/// `source_edit` (a phrase, its replacement) applied: `workgroups`
/// workgroups of 64 threads each run `script` and flush into
/// `phase_cycles` (filled with `before` first). Returns the buffer's words
/// after.
fn flushed(
    script: &Script,
    workgroups: u32,
    before: &[u32],
    source_edit: Option<(&str, &str)>,
) -> Vec<u32> {
    use slipfront::engines::gpu::context::shared;
    use slipfront::engines::gpu::phase_clocks::{phase_constants, PHASE_CLOCK_WORDS};
    use slipfront::engines::gpu::shaders::file;
    use wgpu::util::DeviceExt;
    let ctx = shared().expect("a GPU adapter (lavapipe in CI)");
    let snippet = file("phase_clocks").expect("phase_clocks.wgsl");
    let constant_clock = "return vec2<u32>(3u, 3u);";
    assert!(snippet.contains(constant_clock));
    let mut snippet = snippet.replace(constant_clock, "return vec2<u32>(fake_clock, 0u);");
    if let Some((phrase, replacement)) = source_edit {
        assert!(snippet.contains(phrase), "{phrase}");
        snippet = snippet.replace(phrase, replacement);
    }
    let source = format!(
        "{}\nvar<private> scene: u32;\nvar<private> fake_clock: u32;\n{snippet}\n{}",
        phase_constants(),
        r#"
@group(0) @binding(0) var<storage, read> script: array<u32>;

var<workgroup> mark_count: u32;

@compute @workgroup_size(64)
fn clock_sums(@builtin(local_invocation_index) t: u32) {
    scene = script[0];
    if t == 0u {
        mark_count = script[2];
    }
    let marks = workgroupUniformLoad(&mark_count);
    var clock = script[1];
    fake_clock = clock;
    phase_start(t);
    for (var i = 0u; i < marks; i++) {
        let m = 3u + 5u * i;
        let phase = script[m];
        let own = script[m + 1u];
        let late = script[m + 2u];
        if script[m + 4u] != 0u {
            fake_clock = clock + select(own, own + late, t == 32u);
            phase_arrive(t, phase);
        }
        workgroupBarrier();
        clock += own + late + script[m + 3u];
        fake_clock = clock;
        phase_mark(t, phase);
    }
    workgroupBarrier();
    phase_flush(t, 64u, scene);
}
"#
    );
    let mut words = vec![script.scene, script.clock_start, script.marks.len() as u32];
    for m in &script.marks {
        words.extend([m.phase as u32, m.own, m.late, m.rest, m.arrives as u32]);
    }
    let init = |label, contents: &[u32], usage| {
        ctx.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(contents),
                usage,
            })
    };
    let script_buffer = init("script", &words, wgpu::BufferUsages::STORAGE);
    let sums = init(
        "phase_cycles",
        before,
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    );
    let bytes = run_once(
        &ctx,
        source,
        "clock_sums",
        &[
            ("PHASE_CLOCKS", 1.0),
            ("PHASE_SUM_WORDS", PHASE_CLOCK_WORDS as f64),
        ],
        &[(0, &script_buffer), (18, &sums)],
        workgroups,
        &sums,
    );
    bytemuck::pod_collect_to_vec(&bytes)
}

/// The sums `script` adds from one workgroup, as the host counts them in
/// 64 bits: the phase from mark to mark, thread 0's own to its arrival
/// (the whole phase where it arrived on the mark's clock, or not at all),
/// the slowest to the latest arrival (the whole phase where none arrived).
fn expected_sums(script: &Script) -> PhaseCycles {
    let mut sums = PhaseCycles {
        flushes: 1,
        ..PhaseCycles::default()
    };
    for m in &script.marks {
        let sum = &mut sums.phases[m.phase as usize];
        let whole = u64::from(m.own) + u64::from(m.late) + u64::from(m.rest);
        sum.cycles += whole;
        let arrived = m.arrives && m.own != 0;
        sum.own_cycles += if arrived { u64::from(m.own) } else { whole };
        sum.slowest_cycles += match m.arrives {
            true => u64::from(m.own) + u64::from(m.late),
            false => whole,
        };
        sum.marks += 1;
    }
    sums
}

/// The sums carried into their high words, on the device: the clock's
/// 32-bit reading wraps between two marks, a workgroup's sum passes 2^32
/// in workgroup memory, and each of three workgroups' flush carries out
/// of a storage word already near 2^32 (while the others add to it). The
/// host reads exactly the 64-bit sums, the slowest warp's included (a
/// second thread arriving later than thread 0; a phase marked twice in a
/// dispatch keeps each turn's latest apart). The controls: the same kernel
/// without either carry, or with the latest arrival never cleared, is
/// caught.
#[test]
fn phase_sums_carry_into_their_high_words() {
    use slipfront::engines::gpu::phase_clocks::{PHASE_CLOCK_WORDS, PHASE_WORDS};
    let script = Script {
        scene: 1,
        // Wraps within the first mark, after its arrivals. (Arrivals the
        // wrap falls between keep the one before it: not tested.)
        clock_start: u32::MAX - 100,
        marks: vec![
            mark(Phase::Enter, 50, 0, 200),
            mark(Phase::Forces, 0xF000_0000, 0x0100_0000, 0x0700_0000),
            mark(Phase::Updates, 7, 3, 9),
            mark(Phase::Forces, 0x2000_0000, 0x7000_0000, 0x1000_0000),
            Mark {
                phase: Phase::Wait,
                own: 0,
                late: 0,
                rest: 0xE000_0000,
                arrives: false,
            },
            mark(Phase::Checks, 0, 0x7000_0000, 5),
            mark(Phase::Wait, 0x10, 0x20, 0xE000_0000),
            mark(Phase::Leave, 1, 1, 1),
        ],
    };
    let workgroups = 3u32;
    // Scene 0 is not flushed into; scene 1's sums start near 2^32, with
    // high words of their own.
    let words = PHASE_CLOCK_WORDS;
    let mut before = vec![0u32; 2 * words];
    for (w, word) in before.iter_mut().enumerate() {
        *word = match (w / words, w % words) {
            (0, k) => 1000 + k as u32,
            (_, 0) => 5,
            (_, 1) => 0,
            (_, k) => match (k - 2) % PHASE_WORDS {
                0 | 2 | 5 => u32::MAX - 0x1000 + k as u32,
                1 | 3 | 6 => 11 + k as u32,
                _ => 13,
            },
        };
    }
    let start = PhaseCycles::from_words(&before[words..]);
    let one = expected_sums(&script);
    let mut want = start.clone();
    want.flushes += workgroups * one.flushes;
    for (sum, add) in want.phases.iter_mut().zip(one.phases) {
        sum.cycles += u64::from(workgroups) * add.cycles;
        sum.own_cycles += u64::from(workgroups) * add.own_cycles;
        sum.slowest_cycles += u64::from(workgroups) * add.slowest_cycles;
        sum.marks += workgroups * add.marks;
    }
    assert!(want.get(Phase::Wait).cycles >> 32 >= (start.get(Phase::Wait).cycles >> 32) + 5);

    let after = flushed(&script, workgroups, &before, None);
    assert_eq!(
        after[..words],
        before[..words],
        "scene 0's sums are not touched"
    );
    assert_eq!(PhaseCycles::from_words(&after[words..]), want);

    for (cut, by) in [
        (STORAGE_CARRY, "0u"),
        (WORKGROUP_CARRY, "0u"),
        (LATEST_CLEARED, LATEST_KEPT),
    ] {
        let after = flushed(&script, workgroups, &before, Some((cut, by)));
        assert_ne!(
            PhaseCycles::from_words(&after[words..]),
            want,
            "a kernel with `{by}` for `{cut}` is caught"
        );
    }
}
