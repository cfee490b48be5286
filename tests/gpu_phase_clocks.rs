//! The kernels' phase clocks (`GpuOptions::phase_clocks`,
//! `shaders/phase_clocks.wgsl`): thread 0 of each workgroup reads its
//! multiprocessor's cycle counter at the barriers between a step's phases
//! (the engine's own SPIR-V, `spirv::read_shader_clock`, on a device
//! opened with VK_KHR_shader_clock, which lavapipe has). The clocks only
//! watch: a clocked run ends in the bits of an unclocked one. Each phase a
//! kernel has is marked as often as it runs, and takes cycles. These tests
//! fail, never skip, when no adapter exists.

#[path = "support/phase_kernels.rs"]
mod phase_kernels;

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
/// the phase sums of the steps from `start` on.
fn run(m: &Model, opts: GpuOptions, start: u64, end: u64) -> (Snapshot, PhaseCycles) {
    let mut e = engine(m, opts);
    advance_to(&mut e, start).unwrap();
    let before = e.phase_cycles(0).unwrap();
    advance_to(&mut e, end).unwrap();
    let after = e.phase_cycles(0).unwrap();
    assert_eq!(
        e.describe().contains("phase clocks"),
        opts.phase_clocks,
        "{}",
        e.describe()
    );
    (e.snapshot().unwrap(), after.since(&before))
}

/// Each kernel with phases, through ruptures: clocked, the same bits as
/// unclocked; every step marks its forces and updates once a workgroup
/// (two tiles of 16 columns for the tiled kernel), and each phase it has
/// took cycles. Unclocked, every sum is zero: the counter is what moves
/// them (the control: a kernel that read a constant would pass the bits
/// and fail here).
#[test]
fn clocked_kernels_keep_their_bits_and_time_every_phase() {
    let m = driven(0.4);
    let (start, steps) = (m.prep_steps, 1500u64);
    for (name, opts) in launches() {
        let (plain, unclocked) = run(&m, opts, start, start + steps);
        assert!(
            unclocked.phases.iter().all(|s| *s == Default::default()),
            "{name}: unclocked sums {unclocked:?}"
        );
        let clocked_opts = GpuOptions {
            phase_clocks: true,
            ..opts
        };
        let (got, clocks) = run(&m, clocked_opts, start, start + steps);
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
            assert!(sum.own_cycles <= sum.cycles, "{name}: {phase:?} {sum:?}");
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
        // Each workgroup flushes once a dispatch.
        assert!(
            clocks.flushes > 0 && u64::from(clocks.flushes) % workgroups == 0,
            "{name}: {clocks:?}"
        );
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
