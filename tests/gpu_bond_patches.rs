//! Every GPU kernel with its bulk
//! forces by 2×2 patches of blocks (`GpuOptions::bond_patches`,
//! `shaders/bulk_patch.wgsl`) against the same kernels a thread per block,
//! on the same state. A bond inside a patch is computed once and added
//! negated at its far end; a thread per block computes it at both ends.
//! The arithmetic is the same, and on the CPU twin the bits are
//! (`bulk_forces.rs`, `bond_patches_give_each_block_the_bits_of_its_own_sum`),
//! but not on lavapipe in mixed f32: a few blocks one ulp apart within five
//! steps (likely a product fused into its sum where it has one use and not
//! where it has two). So the forces must agree to the rounding of a block's
//! bond terms, and a run's trajectory parts from the other's at that level,
//! like the other kernels' (docs/gpu-kernels.md). These tests fail, never
//! skip, when no adapter exists (lavapipe in CI).

use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuOutput, GpuPath, GpuReal};
use slipfront::{advance_to, Engine, Model, Snapshot};

#[path = "support/f64_adapter.rs"]
mod f64_adapter;
use f64_adapter::f64_adapter;

fn engine<T: GpuReal>(m: &Model, path: GpuPath, bond_patches: bool) -> GpuEngine<T> {
    let opts = GpuOptions {
        path,
        output: GpuOutput::Device,
        bond_patches,
        ..GpuOptions::default()
    };
    GpuEngine::<T>::with_precision(m, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

/// Steps each way runs from the shared state before its forces are
/// compared: a loaded state brings its forces, and the first step of a
/// batch uses them, so the kernels compute their own from the second on.
const STEPS_APART: u64 = 3;

/// The forces (and friction) of `reference` a thread per block and of `m`
/// by patches, on kernel `path` in `T`, `STEPS_APART` steps after the state
/// a thread-per-block run of `reference` reached at step `step`.
fn forces_both_ways<T: GpuReal>(
    reference: &Model,
    m: &Model,
    path: GpuPath,
    step: u64,
) -> (Snapshot, Snapshot) {
    let mut blocks = engine::<T>(reference, path, false);
    advance_to(&mut blocks, step).unwrap();
    let state = blocks.save_state().unwrap();
    let mut patches = engine::<T>(m, path, true);
    // A run's file names its launch (the engine's description): patches
    // step other bits, so a reader must be able to tell.
    let patched = "bulk forces by 2x2 patches";
    assert!(
        patches.describe().contains(patched),
        "{}",
        patches.describe()
    );
    assert!(
        !blocks.describe().contains(patched),
        "{}",
        blocks.describe()
    );
    let end = |e: &mut GpuEngine<T>| {
        e.load_state(&state).unwrap();
        advance_to(e, step + STEPS_APART).unwrap();
        e.snapshot().unwrap()
    };
    (end(&mut blocks), end(&mut patches))
}

/// The largest difference of any block's force or friction, in units of
/// the rounding of its bond terms (a few steps apart, the differences of
/// each step's forces have moved the states apart at that level too): T's epsilon times the sum over the
/// block's bonds of k_b |u_j − u_i| + η |v_j − v_i| (each bond's spring and
/// dashpot terms are of that size), at most the lattice's largest such
/// sum. Also that largest sum (N), so a caller can see the state moved.
fn worst_in_roundings<T: GpuReal>(m: &Model, a: &Snapshot, b: &Snapshot) -> (f64, f64) {
    let eta = m.eta;
    let mut scale: f64 = 0.0;
    for iz in 0..m.nz {
        for ix in 0..m.nx {
            let i = iz * m.nx + ix;
            let mut s = 0.0;
            for bond in slipfront::model::lattice::STENCIL {
                let (jx, jz) = (ix as i64 + bond.dx as i64, iz as i64 + bond.dz as i64);
                if jx < 0 || jz < 0 || jx >= m.nx as i64 || jz >= m.nz as i64 {
                    continue;
                }
                let j = jz as usize * m.nx + jx as usize;
                let du = (a.disp[j][0] - a.disp[i][0]).hypot(a.disp[j][1] - a.disp[i][1]);
                let dv = (a.vel_half[j][0] - a.vel_half[i][0])
                    .hypot(a.vel_half[j][1] - a.vel_half[i][1]);
                s += bond.stiffness_factor * m.k * du + eta * dv;
            }
            scale = scale.max(s);
        }
    }
    let rounding = <T as num_traits::Float>::epsilon().as_f64() * scale;
    let force = a
        .force
        .iter()
        .zip(&b.force)
        .flat_map(|(x, y)| [x[0] - y[0], x[1] - y[1]]);
    let friction = a.friction.iter().zip(&b.friction).map(|(x, y)| x - y);
    let worst = force.chain(friction).map(f64::abs).fold(0.0, f64::max);
    (worst / rounding, scale)
}

/// Roundings of a block's bond terms the two ways may differ by: a few
/// bonds' last bits, each term's fused or not (lavapipe: 0.11).
const ROUNDINGS_ALLOWED: f64 = 4.0;

/// The forces of a scene in the middle of a front, both ways, on `path` in
/// `T`: within `ROUNDINGS_ALLOWED` of each other. The state must be
/// disturbed (else they agree vacuously), and a normal load 1e-3 larger
/// (the top row's loads) is flagged by the same measure.
fn assert_forces_agree<T: GpuReal>(set: &[&str], path: GpuPath) {
    let s = slipfront::app::verify::small_triggered_scene(set).unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    let step = m.prep_steps + 1500;
    let (blocks, patches) = forces_both_ways::<T>(&m, &m, path, step);
    let (worst, scale) = worst_in_roundings::<T>(&m, &blocks, &patches);
    let ruptures = blocks.total_ruptures();
    println!(
        "{path:?}, {} on {}×{} at step {step}: {ruptures} ruptures, bond scale {scale:.3e} N, \
         worst difference {worst:.2} roundings",
        T::NAME,
        m.nx,
        m.nz
    );
    assert!(ruptures > 20, "{path:?}: no front by step {step}");
    assert!(
        worst <= ROUNDINGS_ALLOWED,
        "{path:?}: {worst} roundings apart"
    );
    // Control: the patches on a normal load 1e-3 larger.
    let heavier: Vec<&str> = set
        .iter()
        .copied()
        .chain(["loading.normal.force=1921.92"])
        .collect();
    let s = slipfront::app::verify::small_triggered_scene(&heavier).unwrap();
    let loaded = Model::from_scenario(&s, false).unwrap();
    let (blocks, other) = forces_both_ways::<T>(&m, &loaded, path, step);
    let (apart, _) = worst_in_roundings::<T>(&m, &blocks, &other);
    println!("  control: {apart:.1} roundings apart");
    assert!(
        apart > 10.0 * ROUNDINGS_ALLOWED,
        "control: {apart} roundings"
    );
}

/// The small triggered front on every kernel in mixed f32: 29 × 16 (the
/// last column's patches half full; the one-step kernels' patches start
/// at row 1, so their top row's are half full too) and 29 × 15 (the top
/// row's half full elsewhere).
#[test]
fn bond_patches_give_the_forces_of_a_thread_per_block() {
    for set in [&[][..], &["geometry.nz=15", "geometry.height=0.035"][..]] {
        for path in GpuPath::KERNELS {
            assert_forces_agree::<f32>(set, path);
        }
    }
}

/// A per-block friction law (Coulomb) takes its friction from the bulk
/// force where the patch stores it: the forces and friction of a sliding
/// lattice agree both ways.
#[test]
fn bond_patches_feed_a_per_block_law_the_same_forces() {
    let s = slipfront::app::verify::small_scene(&[
        "friction.law=\"coulomb\"",
        "loading.drive.velocity=0.4",
    ])
    .unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    let step = m.prep_steps + 1500;
    // One-step-lanes without junctions steps the interface row a thread a
    // block before its patches.
    for path in [GpuPath::OneStep, GpuPath::OneStepLanes, GpuPath::Persistent] {
        let (blocks, patches) = forces_both_ways::<f32>(&m, &m, path, step);
        let (worst, _) = worst_in_roundings::<f32>(&m, &blocks, &patches);
        let sliding = blocks.vel_half[..m.nx]
            .iter()
            .filter(|v| v[0] != 0.0)
            .count();
        let rubbing = blocks.friction.iter().filter(|f| **f != 0.0).count();
        println!(
            "coulomb, {path:?}: {sliding} interface blocks moving, {rubbing} with friction, \
             {worst:.2} roundings"
        );
        assert!(sliding > 0 && rubbing > 0, "the interface did not slide");
        assert!(worst <= ROUNDINGS_ALLOWED, "{worst} roundings apart");
    }
}

/// The same in f64 on the persistent kernel. Adapters without SHADER_F64
/// run mixed f32 only; lavapipe (CI) has it.
#[test]
fn f64_bond_patches_give_the_forces_of_a_thread_per_block() {
    if !f64_adapter() {
        return;
    }
    for path in [GpuPath::OneStep, GpuPath::Persistent] {
        assert_forces_agree::<f64>(&["geometry.nz=15", "geometry.height=0.035"], path);
    }
}
