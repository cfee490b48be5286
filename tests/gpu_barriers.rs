//! The storage barriers between a step's phases at workgroup scope
//! (`GpuOptions::workgroup_barriers`, `shaders/barriers.wgsl`): the engine
//! writes the kernel's SPIR-V itself (`spirv::kernel_spirv`, the layout's
//! bindings placed as wgpu's Vulkan backend places them) and gives it to
//! the driver as it is. The same arithmetic in the same order, so the
//! same bits as with naga's device-scope barriers (in mixed f32 both are
//! the engine's own SPIR-V, for strict arithmetic; in f64 the reference
//! is wgpu's module). On lavapipe (CI) this checks the path, not the speed: what
//! the scope saves is a hardware question (`gpu_table` section 7). These
//! tests fail, never skip, when no adapter exists.

#[path = "support/phase_kernels.rs"]
mod phase_kernels;

use phase_kernels::{driven, launches};
use slipfront::engines::gpu::ensemble::GpuEnsemble;
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuPath, GpuReal};
use slipfront::{advance_to, Engine, Model, Snapshot};

fn engine<T: GpuReal>(m: &Model, opts: GpuOptions) -> GpuEngine<T> {
    GpuEngine::<T>::with_precision(m, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

/// `opts`' run of `m` to `end`, its snapshot, and whether its step
/// kernel's barriers were scoped.
fn run<T: GpuReal>(m: &Model, opts: GpuOptions, end: u64) -> (Snapshot, bool) {
    let mut e = engine::<T>(m, opts);
    let scoped = e.kernel_sources()[0].build.workgroup_barriers;
    assert_eq!(
        e.describe().contains("phase barriers at workgroup scope"),
        scoped,
        "{}",
        e.describe()
    );
    advance_to(&mut e, end).unwrap();
    (e.snapshot().unwrap(), scoped)
}

/// Each kernel with phase barriers, in mixed f32 and (persistent) f64,
/// through the normal-load phase and into ruptures: the engine's own
/// SPIR-V with workgroup-scoped barriers ends in the bits of naga's
/// device-scoped ones. The engine took its own SPIR-V (lavapipe is a Vulkan 1.3
/// device). Negative control: a drive 1e-9 faster, scoped, is flagged.
#[test]
fn workgroup_scoped_barriers_give_the_bits_of_device_scoped_ones() {
    let m = driven(0.4);
    let end = m.prep_steps + 1500;
    for (name, opts) in launches() {
        let device = GpuOptions {
            workgroup_barriers: false,
            ..opts
        };
        let (reference, unscoped) = run::<f32>(&m, device, end);
        assert!(!unscoped, "{name}: naga's device scope");
        assert!(reference.total_ruptures() > 50, "{name}: junctions broke");
        let (got, scoped) = run::<f32>(&m, opts, end);
        assert!(scoped, "{name}: the engine's own SPIR-V on this adapter");
        assert!(
            got == reference,
            "{name}: {} ruptures against {}",
            got.total_ruptures(),
            reference.total_ruptures()
        );
    }
    let persistent = launches()[0].1;
    let (a, _) = run::<f64>(
        &m,
        GpuOptions {
            workgroup_barriers: false,
            ..persistent
        },
        end,
    );
    let (b, scoped) = run::<f64>(&m, persistent, end);
    assert!(scoped && a == b, "f64 persistent");
    let (faster, _) = run::<f32>(&driven(0.4 * (1.0 + 1e-9)), persistent, end);
    let (plain, _) = run::<f32>(&m, persistent, end);
    assert_ne!(faster.disp, plain.disp, "control");
}

/// An ensemble with two scenes side by side in a workgroup: each scene's
/// bits with scoped barriers are its bits with naga's device scope.
#[test]
fn an_ensemble_with_scoped_barriers_has_the_bits_of_device_scoped_ones() {
    let models = [driven(0.4), driven(0.45), driven(0.5)];
    let end = models[0].prep_steps + 1500;
    let opts = GpuOptions {
        path: GpuPath::Persistent,
        persistent_threads: Some(128),
        group_scenes: 2,
        ..GpuOptions::default()
    };
    let snapshots = |opts: GpuOptions| {
        let mut e = GpuEnsemble::new(&models, opts)
            .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"));
        assert_eq!(
            e.describe().contains("phase barriers at workgroup scope"),
            opts.workgroup_barriers,
            "{}",
            e.describe()
        );
        e.advance(end).unwrap();
        (0..models.len())
            .map(|k| e.snapshot(k).unwrap())
            .collect::<Vec<_>>()
    };
    let scoped = snapshots(opts);
    let device = snapshots(GpuOptions {
        workgroup_barriers: false,
        ..opts
    });
    for (k, (a, b)) in scoped.iter().zip(&device).enumerate() {
        assert!(
            a.total_ruptures() > 50,
            "scene {k}: {} ruptures",
            a.total_ruptures()
        );
        assert!(a == b, "scene {k}");
    }
}
