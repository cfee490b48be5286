//! The GPU engine against the CPU reference, on whatever adapter is present
//! (lavapipe in CI). These tests fail, never skip, when no adapter exists.

use slipfront::app::verify::STICK_SLIP_WINDOW;
use slipfront::engines::backend::{cpu_engine, Precision};
use slipfront::engines::gpu::shaders::Variant;
use slipfront::engines::gpu::{Arithmetic, GpuEngine, GpuOptions, GpuPath};
use slipfront::io::compare::{compare_snapshots, fields_over};
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Engine, EngineError, Model, Snapshot};

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

fn model(set: &[&str]) -> Model {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let s = Scenario::parse(DEFAULT_SCENARIO, "test", &set).unwrap();
    Model::from_scenario(&s, false).unwrap()
}

fn gpu(m: &Model) -> GpuEngine {
    GpuEngine::new(m).unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

/// The engine on one kernel: every cross-check runs on each.
fn gpu_on(m: &Model, path: GpuPath) -> GpuEngine {
    let opts = GpuOptions {
        path,
        ..GpuOptions::default()
    };
    GpuEngine::with_options(m, opts)
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

const KERNELS: [GpuPath; 5] = GpuPath::KERNELS;

fn run_both(m: &Model, steps: u64, path: GpuPath) -> (Snapshot, Snapshot) {
    let mut c = cpu_engine(m, Precision::F32, 1).unwrap();
    let mut g = gpu_on(m, path);
    advance_to(c.as_mut(), steps).unwrap();
    advance_to(&mut g, steps).unwrap();
    (c.snapshot().unwrap(), g.snapshot().unwrap())
}

/// The small side-driven scene of the cross-checks (29 × 16 blocks).
const SMALL: &[&str] = &slipfront::app::verify::SMALL_SCENE;

/// Every kernel against the CPU twin through the normal load and 3000
/// steps of driving, before any junction breaks: within the rounding of
/// division and square roots on any adapter, and bit for bit on one that
/// rounds them as IEEE does (llvmpipe): strict arithmetic (the default
/// where the engine writes the SPIR-V) forbids the driver any fusing or
/// regrouping, so a kernel computes the twin's operations in the twin's
/// order. Wgpu's guarded modules, which llvmpipe may fuse outside the
/// guarded sums, part from the twin within ten steps there (session 67).
/// Negative control: a drive 1e-9 faster is told apart, bit for bit.
#[test]
fn gpu_f32_matches_cpu_f32_field_by_field() {
    let m = model(SMALL);
    let ieee_division = slipfront::engines::gpu::context::shared()
        .expect("an adapter")
        .is_software();
    for path in KERNELS {
        let (c, g) = run_both(&m, m.prep_steps + 3000, path);
        assert_eq!(c.total_ruptures(), 0);
        if ieee_division {
            assert!(c == g, "{path:?}: not the CPU twin's bits");
        }
        let errors = compare_snapshots(&c, &g);
        // f32 kernels differ from the CPU twins only by the rounding of
        // division and square roots: 1e-4 of each field's scale;
        // velocities near rest are f32 force noise (k·l·2⁻²⁴·dt/m ≈ 3e-7
        // m/s a step), so they get a floor of 1e-5 m/s, 1% of the slowest
        // slip speeds of interest.
        assert_eq!(
            fields_over(&errors, 1e-4, 1e-5),
            Vec::<String>::new(),
            "{path:?}: {errors:?}"
        );
    }
    let mut faster = m.clone();
    if let slipfront::model::Driver::SideSpring { velocity, .. } = &mut faster.driver {
        *velocity *= 1.0 + 1e-9;
    }
    let (plain, _) = run_both(&m, m.prep_steps + 3000, GpuPath::OneStep);
    let mut g = gpu_on(&faster, GpuPath::OneStep);
    advance_to(&mut g, m.prep_steps + 3000).unwrap();
    assert!(
        g.snapshot().unwrap() != plain,
        "control: the drive 1e-9 faster"
    );
}

/// Per-block rupture counts and the first rupture step of each block.
fn rupture_record(m: &Model, e: &mut dyn Engine, end: u64) -> (Vec<u32>, Vec<u64>) {
    let ns = m.junctions.unwrap().count;
    let mut first = vec![u64::MAX; m.nx];
    let mut step = m.prep_steps;
    advance_to(e, step).unwrap();
    while step < end {
        step += 20;
        advance_to(e, step).unwrap();
        let s = e.snapshot().unwrap();
        for (ix, first) in first.iter_mut().enumerate() {
            if *first == u64::MAX && s.ruptures[ix * ns..(ix + 1) * ns].iter().any(|&r| r > 0) {
                *first = step;
            }
        }
    }
    let s = e.snapshot().unwrap();
    let counts = (0..m.nx)
        .map(|ix| s.ruptures[ix * ns..(ix + 1) * ns].iter().sum())
        .collect();
    (counts, first)
}

/// The stick-slip comparator: total ruptures within 0.1%, and each block's
/// first rupture within one sampling interval (20 steps, 4.5 µs). Measured on
/// lavapipe with wgpu's guarded modules: the GPU was 0.02% off (13746 against
/// 13749); a 1% higher μs is 0.34% off. With strict arithmetic (session 67)
/// lavapipe gives the twin's ruptures exactly (the next test).
fn stick_slip_mismatch(a: &(Vec<u32>, Vec<u64>), b: &(Vec<u32>, Vec<u64>)) -> Vec<String> {
    let mut out = Vec::new();
    let (ta, tb): (u64, u64) = (
        a.0.iter().map(|&x| x as u64).sum(),
        b.0.iter().map(|&x| x as u64).sum(),
    );
    if (ta as f64 - tb as f64).abs() > 0.001 * ta as f64 {
        out.push(format!("total ruptures {ta} vs {tb}"));
    }
    for (ix, (x, y)) in a.1.iter().zip(&b.1).enumerate() {
        if (*x == u64::MAX) != (*y == u64::MAX) || x.abs_diff(*y) > 20 {
            out.push(format!("block {ix}: first rupture at step {x} vs {y}"));
        }
    }
    out
}

fn stick_slip_scene(extra: &[&str]) -> Model {
    let mut set = SMALL.to_vec();
    set.extend_from_slice(&STICK_SLIP_WINDOW);
    set.extend_from_slice(extra);
    model(&set)
}

/// Every kernel against the CPU twin through the stick-slip window: its
/// ruptures' counts and first times within the comparator's bounds on any
/// adapter, and on one that rounds division and square roots as IEEE does
/// (llvmpipe) the twin's snapshot at the window's end, bit for bit: strict
/// arithmetic computes the twin's operations in its order, and each slip
/// draw, though its `log` and `cos` are the driver's on one side and
/// libm's on the other, gave the same whole number of slip steps (13,633
/// ruptures, session 67). Negative control: μs 1% higher is flagged.
#[test]
fn gpu_reproduces_rupture_counts_and_times_and_flags_a_1_percent_change() {
    let m = stick_slip_scene(&[]);
    let end = m.prep_steps + 6000;
    let ieee_division = slipfront::engines::gpu::context::shared()
        .expect("an adapter")
        .is_software();
    let mut twin = cpu_engine(&m, Precision::F32, 1).unwrap();
    let reference = rupture_record(&m, twin.as_mut(), end);
    let twin = twin.snapshot().unwrap();
    assert!(
        reference.0.iter().sum::<u32>() > 100,
        "the window must contain ruptures"
    );
    let diff = |a: &(Vec<u32>, Vec<u64>), b: &(Vec<u32>, Vec<u64>)| {
        let t: (u32, u32) = (a.0.iter().sum(), b.0.iter().sum());
        let d = a.1.iter().zip(&b.1).map(|(x, y)| x.abs_diff(*y)).max();
        format!("totals {t:?}, max first-rupture shift {d:?}")
    };
    for path in KERNELS {
        let mut g = gpu_on(&m, path);
        let on_gpu = rupture_record(&m, &mut g, end);
        println!("gpu {path:?}: {}", diff(&reference, &on_gpu));
        assert_eq!(
            stick_slip_mismatch(&reference, &on_gpu),
            Vec::<String>::new(),
            "{path:?}"
        );
        if ieee_division {
            assert!(
                g.snapshot().unwrap() == twin,
                "{path:?}: not the CPU twin's bits at the window's end"
            );
        }
    }
    // Negative control: μs 1% higher must be flagged by the same comparator.
    let perturbed = stick_slip_scene(&["friction.static_coefficient=0.404"]);
    let mut g = gpu(&perturbed);
    let changed = rupture_record(&perturbed, &mut g, end);
    println!("perturbed: {}", diff(&reference, &changed));
    assert!(!stick_slip_mismatch(&reference, &changed).is_empty());
    assert!(g.snapshot().unwrap() != twin);
}

#[test]
fn field_comparator_flags_a_1_percent_change() {
    let m = model(SMALL);
    let p = model(&[SMALL, &["material.youngs_modulus=3.03e9"]].concat());
    let steps = m.prep_steps + 1000;
    let mut c = cpu_engine(&m, Precision::F32, 1).unwrap();
    advance_to(c.as_mut(), steps).unwrap();
    let mut g = gpu(&p);
    advance_to(&mut g, steps).unwrap();
    let errors = compare_snapshots(&c.snapshot().unwrap(), &g.snapshot().unwrap());
    assert!(!fields_over(&errors, 1e-4, 1e-5).is_empty(), "{errors:?}");
}

#[test]
fn each_example_scenario_builds_only_the_terms_it_uses() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios");
    let mut listed = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        // Scenario files; the sweep files live in scenarios/sweeps/.
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        // The single-block scene has no lattice and no kernels.
        let text = std::fs::read_to_string(&path).unwrap();
        if slipfront::model::scenario::looks_like_single_block(&text) {
            continue;
        }
        let s = Scenario::load(&path, &[]).unwrap();
        let m = Model::from_scenario(&s, false).unwrap();
        let v = Variant::for_model(&m);
        println!("{}: {}", path.display(), v.describe());
        listed.push((s.name.clone(), v.describe()));
    }
    let s1 = &listed
        .iter()
        .find(|(n, _)| n == "tromborg2014_stick_slip")
        .unwrap()
        .1;
    assert_eq!(
        s1,
        "FRICTION_LAW=1,DAMPING_FORM=1,USE_FOUNDATION=1,USE_TOP_LOADS=1,USE_SIDE_SPRING=1,USE_RELAXATION=1,USE_PRESTRESS=0"
    );
    // A frictionless, undamped wave test builds no friction kernel.
    let wave = slipfront::app::verify::bare_scene("wave");
    let v = Variant::for_model(&Model::from_scenario(&wave, false).unwrap()).describe();
    assert_eq!(
        v,
        "FRICTION_LAW=0,DAMPING_FORM=0,USE_FOUNDATION=0,USE_TOP_LOADS=0,USE_SIDE_SPRING=0,USE_RELAXATION=0,USE_PRESTRESS=0"
    );
}

#[test]
fn large_lattice_with_junctions_runs() {
    // 2048 × 512 with Ns = 100: 1.0e6 blocks, 2.0e5 junctions.
    let l = 0.14 / 56.0;
    let m = model(&[
        "geometry.nx=2048",
        "geometry.nz=512",
        &format!("geometry.length={}", l * 2047.0),
        &format!("geometry.height={}", l * 511.0),
        "loading.normal.ramp_time=1e-6",
        "loading.normal.relax_time=1e-6",
    ]);
    let mut g = gpu(&m);
    advance_to(&mut g, m.prep_steps + 4).unwrap();
    let s = g.snapshot().unwrap();
    assert_eq!(s.disp.len(), 2048 * 512);
    assert_eq!(s.ruptures.len(), 2048 * 100);
    // The top row has been pushed down, the rest is still finite.
    assert!(s.disp[(511 * 2048) + 1000][1] < 0.0);
}

#[test]
fn a_lattice_beyond_the_adapter_limits_is_refused_clearly() {
    // 16385 × 16384 blocks: 2^32 + 2^18 bytes of double-single
    // displacements, more than any adapter binds in one storage buffer.
    let l = 0.14 / 56.0;
    let m = model(&[
        "geometry.nx=16385",
        "geometry.nz=16384",
        &format!("geometry.length={}", l * 16384.0),
        &format!("geometry.height={}", l * 16383.0),
    ]);
    let err = match GpuEngine::new(&m) {
        Ok(_) => panic!("a 2.1 GB buffer must be refused"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("block displacement buffer needs"), "{err}");
    assert!(err.contains("smaller lattice"), "{err}");
}

/// The resident kernel runs the persistent kernel's loop with u and v in
/// workgroup memory: the same arithmetic in the same order, so with the
/// same threads it matches the persistent kernel bit for bit, through
/// junction ruptures and across dispatches (llvmpipe cuts them short, so
/// the state goes to storage and back every few hundred steps). The
/// resident run steps one junction lane a round: on hardware the
/// persistent one steps two, which must not change a bit either
/// (software adapters always step one). Negative control: V × (1 + 1e-9)
/// differs.
#[test]
fn the_resident_kernel_is_the_persistent_kernel_bit_for_bit() {
    let m = model(&[SMALL, &["loading.drive.velocity=0.4"]].concat());
    let end = m.prep_steps + 4096 + 700;
    let on = |m: &Model, path| {
        let opts = GpuOptions {
            path,
            persistent_threads: Some(64),
            two_lanes_a_round: path != GpuPath::Resident,
            ..GpuOptions::default()
        };
        let mut g = GpuEngine::with_options(m, opts).expect("a GPU adapter (lavapipe in CI)");
        advance_to(&mut g, end).unwrap();
        (g.describe(), g.snapshot().unwrap())
    };
    let (persistent_how, persistent) = on(&m, GpuPath::Persistent);
    let (resident_how, resident) = on(&m, GpuPath::Resident);
    assert!(resident_how.contains("resident kernel"), "{resident_how}");
    assert!(persistent_how.contains("64 threads") && resident_how.contains("64 threads"));
    assert!(persistent.total_ruptures() > 0, "junctions broke");
    assert!(persistent == resident, "resident and persistent differ");
    let mut faster = m.clone();
    if let slipfront::model::Driver::SideSpring { velocity, .. } = &mut faster.driver {
        *velocity *= 1.0 + 1e-9;
    }
    let (_, other) = on(&faster, GpuPath::Resident);
    assert_ne!(other.disp, resident.disp, "control");
}

/// The resident kernel needs the lattice to fit the adapter's workgroup
/// memory: a lattice that does not is refused with both sizes and the
/// kernels that take it.
#[test]
fn a_lattice_beyond_workgroup_memory_is_refused_by_the_resident_kernel() {
    let l = 0.14 / 56.0;
    let m = model(&[
        "geometry.nx=400",
        "geometry.nz=100",
        &format!("geometry.length={}", l * 399.0),
        &format!("geometry.height={}", l * 99.0),
    ]);
    let opts = GpuOptions {
        path: GpuPath::Resident,
        ..GpuOptions::default()
    };
    let err = match GpuEngine::with_options(&m, opts) {
        Ok(_) => panic!("40000 blocks in workgroup memory must be refused"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("40000 blocks in f32 need"), "{err}");
    assert!(err.contains("the adapter allows"), "{err}");
    assert!(
        err.contains("--gpu-path one-step-lanes or persistent"),
        "{err}"
    );
}

/// Amontons–Coulomb stick → slip transitions count as ruptures (they were
/// not counted at all): in the run summary and `/global.ruptures`, and the
/// same per block on the GPU as on the CPU.
#[test]
fn coulomb_stick_slip_transitions_are_counted_as_ruptures_on_both_engines() {
    use slipfront::app::runner::{run_scene, RunOptions};
    let mut set: Vec<String> = SMALL.iter().map(|s| s.to_string()).collect();
    set.extend(
        [
            "friction.law=coulomb",
            "loading.drive.velocity=0.4",
            "time.end=0.0015",
        ]
        .map(String::from),
    );
    let s = Scenario::parse(DEFAULT_SCENARIO, "coulomb", &set).unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    let opts = RunOptions {
        fast_forward: None,
        output: None,
        ..RunOptions::default()
    };
    let mut c = cpu_engine(&m, Precision::F32, 1).unwrap();
    let summary = run_scene(c.as_mut(), &s, &opts).unwrap();
    assert!(summary.ruptures > 0, "{summary}");
    let mut g = gpu(&m);
    let on_gpu = run_scene(&mut g, &s, &opts).unwrap();
    let (cs, gs) = (c.snapshot().unwrap(), g.snapshot().unwrap());
    println!("cpu {} gpu {} slips", summary.ruptures, on_gpu.ruptures);
    assert_eq!(cs.total_ruptures(), summary.ruptures);
    let off = cs
        .slips
        .iter()
        .zip(&gs.slips)
        .map(|(a, b)| a.abs_diff(*b))
        .sum::<u32>();
    assert!(
        off as u64 * 100 <= summary.ruptures,
        "{:?} vs {:?}",
        cs.slips,
        gs.slips
    );
}

/// Opening: driven at 40 m/s, interface blocks of the small scene lift off
/// the track and land again. On both engines no junction re-pins while its
/// block is lifted (none is ever pinned with zero stiffness, as happened
/// before), and the GPU keeps the CPU's rupture counts and times.
#[test]
fn lifted_blocks_re_pin_only_when_pressed_back_on_both_engines() {
    let m = stick_slip_scene(&["loading.drive.velocity=40"]);
    let mut c = cpu_engine(&m, Precision::F32, 1).unwrap();
    let mut g = gpu(&m);
    let ns = m.junctions.unwrap().count;
    let mut lifted = 0;
    let end = m.prep_steps + 3000;
    for step in (m.prep_steps..=end).step_by(100) {
        for e in [c.as_mut(), &mut g as &mut dyn Engine] {
            advance_to(e, step).unwrap();
            let s = e.snapshot().unwrap();
            for ix in 0..m.nx {
                let block = ix * ns..(ix + 1) * ns;
                let zero_pinned = block
                    .filter(|&j| s.slip_steps_left[j] == slipfront::engines::cpu::PINNED)
                    .any(|j| s.junction_stiffness[j] <= 0.0);
                assert!(
                    !zero_pinned,
                    "block {ix} at step {step}: pinned with k_j = 0"
                );
                lifted += (s.disp[ix][1] > 0.0) as u32;
            }
        }
    }
    assert!(lifted > 20, "the scene must lift blocks off: {lifted}");
    let m2 = stick_slip_scene(&["loading.drive.velocity=40"]);
    let reference = rupture_record(
        &m2,
        cpu_engine(&m2, Precision::F32, 1).unwrap().as_mut(),
        end,
    );
    let on_gpu = rupture_record(&m2, &mut gpu(&m2), end);
    assert_eq!(
        stick_slip_mismatch(&reference, &on_gpu),
        Vec::<String>::new()
    );
}

/// The kernel reports its dispatches: one per step on the one-step path,
/// one per many steps on the persistent path (`describe` says how many).
#[test]
fn dispatches_per_step_are_one_or_one_per_batch() {
    let m = model(SMALL);
    let steps = 2000;
    let mut one = gpu_on(&m, GpuPath::OneStep);
    advance_to(&mut one, steps).unwrap();
    assert_eq!(one.dispatches(), Some(steps));
    let mut persistent = gpu_on(&m, GpuPath::Persistent);
    advance_to(&mut persistent, steps).unwrap();
    let d = persistent.dispatches().unwrap();
    // Batches split at the end of the ramp and of the normal-load phase.
    assert!(d * 100 <= steps, "{d} dispatches for {steps} steps");
    println!("{}", persistent.describe());
}

/// The device time of the batches' passes (timestamp queries, which
/// lavapipe has): it grows with the steps and never exceeds the wall time
/// they took. On a software adapter the passes are the whole of the work,
/// so it is most of the wall time too: a timestamp period misread (ticks
/// for nanoseconds, microseconds for nanoseconds) fails one bound or the other.
#[test]
fn the_device_time_of_the_steps_is_measured_and_bounded_by_the_wall_time() {
    let m = model(SMALL);
    let mut e = gpu_on(&m, GpuPath::OneStep);
    let Some(start) = e.device_seconds() else {
        panic!("{}: no timestamp queries", e.describe());
    };
    assert_eq!(start, 0.0);
    let t0 = std::time::Instant::now();
    advance_to(&mut e, 1500).unwrap();
    let wall = t0.elapsed().as_secs_f64();
    let device = e.device_seconds().unwrap();
    assert!(
        device > 0.0 && device <= wall * 1.02 + 1e-3,
        "device {device} s, wall {wall} s"
    );
    if e.describe().contains("Cpu") {
        assert!(
            device >= 0.3 * wall,
            "device {device} s of {wall} s on a software adapter"
        );
    }
    advance_to(&mut e, 3000).unwrap();
    assert!(e.device_seconds().unwrap() > device);
}

/// A driver that cuts a persistent dispatch short (llvmpipe stops a
/// shader's loops after 65535 iterations) is caught, not taken as done:
/// on a software adapter, one dispatch of 4096 steps must fail with the
/// reason; elsewhere it must run.
#[test]
fn a_persistent_dispatch_cut_short_is_an_error() {
    let m = model(SMALL);
    let opts = GpuOptions {
        path: GpuPath::Persistent,
        steps_per_dispatch: Some(4096),
        ..GpuOptions::default()
    };
    let mut g = GpuEngine::with_options(&m, opts).expect("an adapter");
    let result = advance_to(&mut g, 4000);
    if g.adapter().contains("llvmpipe") {
        let err = result
            .expect_err("llvmpipe cuts 4000 steps short")
            .to_string();
        assert!(err.contains("cut a persistent dispatch short"), "{err}");
    } else {
        result.unwrap();
    }
}

/// A loop cut inside a dispatch's last step leaves every step counted, so
/// the count of steps run alone would pass it; the kernel's loop probe
/// (`persistent.wgsl` `loop_budget_left`) must catch it. On a software
/// adapter, bisect the length of a persistent dispatch (8 threads, so
/// llvmpipe's budget runs out within tens of steps): the longest that runs
/// must give the one-step kernel's bits, and must be shorter than one that
/// is caught. Elsewhere (no budget) a long dispatch runs and gives them.
/// Control: a perturbed one-step run differs.
#[test]
fn the_longest_persistent_dispatch_a_loop_budget_allows_is_exact() {
    let m = model(SMALL);
    let persistent = |steps: u64| -> Result<Snapshot, String> {
        let opts = GpuOptions {
            path: GpuPath::Persistent,
            persistent_threads: Some(8),
            steps_per_dispatch: Some(steps),
            ..GpuOptions::default()
        };
        let mut g = GpuEngine::with_options(&m, opts).expect("an adapter");
        advance_to(&mut g, steps).map_err(|e| e.to_string())?;
        Ok(g.snapshot().unwrap())
    };
    let one_step = |m: &Model, steps: u64| {
        let opts = GpuOptions {
            path: GpuPath::OneStep,
            ..GpuOptions::default()
        };
        let mut g = GpuEngine::with_options(m, opts).expect("an adapter");
        advance_to(&mut g, steps).unwrap();
        g.snapshot().unwrap()
    };
    let software = slipfront::engines::gpu::context::shared()
        .expect("an adapter")
        .is_software();
    let (longest, edge) = if software {
        // runs(ok) < cut: the budget runs out past `ok` steps and by `cut`.
        let (mut ok, mut cut) = (1u64, 2u64);
        while persistent(cut).is_ok() {
            ok = cut;
            cut *= 2;
            assert!(
                cut <= 4096,
                "llvmpipe ran a dispatch of {ok} steps of 8 threads"
            );
        }
        while cut - ok > 1 {
            let mid = (ok + cut) / 2;
            match persistent(mid) {
                Ok(_) => ok = mid,
                Err(e) => {
                    assert!(e.contains("cut a persistent dispatch short"), "{e}");
                    cut = mid;
                }
            }
        }
        eprintln!("llvmpipe: {ok} steps a dispatch run, {cut} are caught");
        (ok, Some(cut))
    } else {
        (1000, None)
    };
    let reference = one_step(&m, longest);
    let snapshot = persistent(longest).unwrap();
    assert!(
        snapshot == reference,
        "a dispatch of {longest} steps ran (the next, {edge:?}, was caught) but differs \
         from the one-step kernel"
    );
    let mut heavier = m.clone();
    heavier.mass *= 1.0 + 1e-6;
    assert!(one_step(&heavier, longest) != reference, "control");
}

/// A run that blows up stops with the step and block where it happened, on
/// every kernel, as the CPU does: junctions 10⁴× too stiff for the time
/// step (forced past the stability check) blow up within a few hundred
/// steps; the GPU must name the CPU f32 engine's step (within 5 steps) and
/// an interface block, and stop there.
#[test]
fn a_blow_up_stops_the_run_at_its_step_and_block_on_every_kernel() {
    let s = slipfront::app::verify::small_scene(&slipfront::app::verify::STIFF_JUNCTIONS_BLOW_UP)
        .unwrap();
    let m = Model::from_scenario(&s, true).unwrap();
    let mut c = cpu_engine(&m, Precision::F32, 1).unwrap();
    let Err(EngineError::BlowUp { step: at, .. }) = advance_to(c.as_mut(), m.total_steps()) else {
        panic!("the CPU run must blow up");
    };
    for path in KERNELS {
        let mut g = gpu_on(&m, path);
        let err = advance_to(&mut g, m.total_steps()).unwrap_err();
        let text = err.to_string();
        let EngineError::BlowUp { step, iz, .. } = err else {
            panic!("{path:?}: {text}");
        };
        println!("{path:?}: {text} (cpu step {at})");
        assert!(step.abs_diff(at) <= 5, "{path:?}: step {step} vs {at}");
        assert!(iz <= 1, "{path:?}: {text}");
        assert!(text.contains("blew up at step"), "{text}");
        assert_eq!(g.steps_done(), step);
    }
}

/// Fast-forward on the GPU engine (its state read back, advanced on the
/// host, written back): the first junction rupture of the small scene,
/// driven 10× faster, where full dynamics on the CPU f32 twin puts it, to
/// 0.5% in time and F/F_N, with most of the loading skipped.
#[test]
fn gpu_fast_forward_finds_the_first_rupture_of_full_dynamics() {
    use slipfront::app::runner::{run_scene, RunOptions};
    use slipfront::engines::quasistatic::FastForwardSettings;
    let scenario = slipfront::app::verify::small_scene(&[
        "loading.drive.velocity=4e-3",
        "time.end=0.032",
        "output.global_interval=1e-5",
        "output.interface_interval=0",
        "output.bulk_interval=0",
        "output.fast_interval=0",
    ])
    .unwrap();
    let m = Model::from_scenario(&scenario, false).unwrap();
    let dir = Scratch::new("gpu", "ff");
    let first_rupture = |engine: &mut dyn Engine, ff: Option<FastForwardSettings>, name: &str| {
        let path = dir.join(name);
        let opts = RunOptions {
            fast_forward: ff,
            output: Some(path.clone()),
            ..RunOptions::default()
        };
        let summary = run_scene(engine, &scenario, &opts).unwrap();
        let run = slipfront::io::output::reader::RunFile::read(&path).unwrap();
        let g = run
            .global
            .iter()
            .find(|g| g.ruptures > 0)
            .expect("a rupture");
        (g.time, g.drive_ratio, summary.fast_forward)
    };
    let mut cpu = cpu_engine(&m, Precision::F32, 1).unwrap();
    let (t_full, r_full, _) = first_rupture(cpu.as_mut(), None, "full.mcap");
    let mut g = gpu_on(&m, GpuPath::Auto);
    let settings = FastForwardSettings::from_scenario(&scenario);
    let (t_ff, r_ff, stats) = first_rupture(&mut g, Some(settings), "gpu-ff.mcap");
    let stats = stats.unwrap();
    eprintln!("first rupture: CPU full {t_full:.7} s {r_full:.6}; GPU fast-forward {t_ff:.7} s {r_ff:.6}; {stats:?}");
    assert!(stats.jumps >= 1 && stats.skipped_time > 0.02, "{stats:?}");
    assert!((t_ff - t_full).abs() < 0.005 * t_full, "{t_ff} vs {t_full}");
    assert!((r_ff - r_full).abs() < 0.005 * r_full, "{r_ff} vs {r_full}");
}

/// A state saved by one engine continues on another (checkpoints across
/// engines): CPU f64 → GPU (rounded to mixed f32 once) agrees with the CPU
/// mixed-f32 engine continuing from the same state, and GPU → CPU agrees
/// with the GPU continuing, within the cross-check tolerance; a state the
/// GPU loads comes back out bit for bit.
#[test]
fn states_cross_between_cpu_and_gpu() {
    let m = model(SMALL);
    let mut f64_engine = cpu_engine(&m, Precision::F64, 1).unwrap();
    advance_to(f64_engine.as_mut(), m.prep_steps + 1500).unwrap();
    let saved = f64_engine.save_state().unwrap();
    for path in KERNELS {
        let mut g = gpu_on(&m, path);
        g.load_state(&saved).unwrap();
        let on_gpu = g.save_state().unwrap();
        assert_eq!(on_gpu.precision, "f32 mixed (f32+f32 coordinates)");
        let mut again = gpu_on(&m, path);
        again.load_state(&on_gpu).unwrap();
        assert_eq!(again.save_state().unwrap(), on_gpu, "{path:?}");
        let mut c = cpu_engine(&m, Precision::F32, 1).unwrap();
        c.load_state(&saved).unwrap();
        g.advance(1500).unwrap();
        c.advance(1500).unwrap();
        let (gs, cs) = (g.snapshot().unwrap(), c.snapshot().unwrap());
        assert_eq!(gs.step, m.prep_steps + 3000);
        let errors = compare_snapshots(&cs, &gs);
        assert_eq!(
            fields_over(&errors, 1e-4, 1e-5),
            Vec::<String>::new(),
            "CPU f64 → GPU, {path:?}: {errors:?}"
        );
        // GPU → CPU.
        let from_gpu = g.save_state().unwrap();
        let mut c = cpu_engine(&m, Precision::F32, 1).unwrap();
        c.load_state(&from_gpu).unwrap();
        g.advance(1000).unwrap();
        c.advance(1000).unwrap();
        let errors = compare_snapshots(&c.snapshot().unwrap(), &g.snapshot().unwrap());
        assert_eq!(
            fields_over(&errors, 1e-4, 1e-5),
            Vec::<String>::new(),
            "GPU → CPU, {path:?}: {errors:?}"
        );
    }
}

/// Where a run is cut into batches changes no bit: batches are anchored
/// every 4096 steps of driving (the drive's time and target at a step are
/// the anchor's plus the steps since), so a side-driven run advanced in one
/// call equals one advanced in chunks of 37 steps with a snapshot (a
/// forces-only pass) after each, past an anchor, on the one-step and the
/// persistent kernels. Negative control: V × (1 + 1e-9) differs.
#[test]
fn gpu_bits_do_not_depend_on_where_batches_begin() {
    let m = model(&[SMALL, &["loading.drive.velocity=0.4"]].concat());
    let end = m.prep_steps + 4096 + 700;
    let mut faster = m.clone();
    if let slipfront::model::Driver::SideSpring { velocity, .. } = &mut faster.driver {
        *velocity *= 1.0 + 1e-9;
    }
    for path in [GpuPath::OneStep, GpuPath::Persistent, GpuPath::Resident] {
        let mut whole = gpu_on(&m, path);
        advance_to(&mut whole, end).unwrap();
        let a = whole.snapshot().unwrap();
        let mut cut = gpu_on(&m, path);
        while cut.steps_done() < end {
            let next = (cut.steps_done() + 37).min(end);
            advance_to(&mut cut, next).unwrap();
            cut.snapshot().unwrap();
        }
        let b = cut.snapshot().unwrap();
        assert!(a.total_ruptures() > 0, "{path:?}: junctions broke");
        assert!(a == b, "{path:?}: chunks changed the bits");
        let mut other = gpu_on(&faster, path);
        advance_to(&mut other, end).unwrap();
        assert_ne!(a.disp, other.snapshot().unwrap().disp, "{path:?}: control");
    }
}

/// A slider started 1 cm along the track (`start.position`) slips as on the
/// CPU on every kernel: its blocks, junction anchors and drive start there
/// (were the anchors left at 0, every junction would break at once).
#[test]
fn a_slider_started_along_the_track_slips_as_on_the_cpu_on_every_kernel() {
    let m = stick_slip_scene(&["start.position=0.01"]);
    let end = m.prep_steps + 6000;
    let reference = rupture_record(&m, cpu_engine(&m, Precision::F32, 1).unwrap().as_mut(), end);
    let at_zero = stick_slip_scene(&[]);
    let unmoved = rupture_record(
        &at_zero,
        cpu_engine(&at_zero, Precision::F32, 1).unwrap().as_mut(),
        end,
    );
    // Mixed f32 keeps displacements to 48 bits: where the slider starts
    // does not change what it does.
    assert_eq!(
        stick_slip_mismatch(&unmoved, &reference),
        Vec::<String>::new()
    );
    for path in KERNELS {
        let on_gpu = rupture_record(&m, &mut gpu_on(&m, path), end);
        assert_eq!(
            stick_slip_mismatch(&reference, &on_gpu),
            Vec::<String>::new(),
            "{path:?}"
        );
        let s = gpu_on(&m, path).snapshot().unwrap();
        assert!(
            s.disp.iter().all(|u| (u[0] - 0.01).abs() < 1e-12),
            "{path:?}"
        );
    }
}

/// Rate-and-state friction on every kernel (mixed f32) against the CPU in
/// f32: every field, θ included, through the first slips of the small
/// scene, and the same blocks slipping.
#[test]
fn rate_state_friction_matches_the_cpu_on_every_kernel() {
    let text = std::fs::read_to_string("scenarios/rate_state.toml").unwrap();
    let mut set: Vec<String> = SMALL.iter().map(|s| s.to_string()).collect();
    set.push("loading.drive.velocity=0.4".into());
    let s = Scenario::parse(&text, "rate_state", &set).unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    // The tiled kernel refuses per-block laws (gpu_tiled.rs).
    for path in KERNELS.into_iter().filter(|p| *p != GpuPath::Tiled) {
        let (c, g) = run_both(&m, m.prep_steps + 3000, path);
        let slips: u32 = c.slips.iter().sum();
        assert!(slips > 0, "the window must contain slips");
        let errors = compare_snapshots(&c, &g);
        println!("{path:?}: {errors:?}");
        assert_eq!(
            fields_over(&errors, 1e-4, 1e-5),
            Vec::<String>::new(),
            "{path:?}: {errors:?}"
        );
        assert_eq!(c.slips, g.slips, "{path:?}");
    }
}

/// A block whose junctions are all pinned and whose u_x stays well inside
/// every junction's threshold keeps its junction sums and skips its
/// junctions (`GpuOptions::keep_junction_sums`). That must give the bits
/// of summing every junction every step, on every kernel, through the
/// stick-slip window's ruptures and re-pinnings; and the sums must be kept
/// for most blocks between events, or the test would pass without them.
#[test]
fn kept_junction_sums_give_the_bits_of_summing_every_step() {
    let m = stick_slip_scene(&[]);
    let run = |m: &Model, path, keep| {
        let opts = GpuOptions {
            path,
            keep_junction_sums: keep,
            ..GpuOptions::default()
        };
        let mut g = GpuEngine::with_options(m, opts).expect("a GPU adapter (lavapipe in CI)");
        let mut kept = Vec::new();
        for step in (m.prep_steps..=m.prep_steps + 6000).step_by(500) {
            advance_to(&mut g, step).unwrap();
            kept.push(g.kept_junction_blocks(0).unwrap());
        }
        (g.snapshot().unwrap(), kept)
    };
    for path in KERNELS {
        let (kept, counts) = run(&m, path, true);
        let (summed, none) = run(&m, path, false);
        println!("{path:?}: blocks with kept sums every 500 steps {counts:?}");
        assert!(
            kept.total_ruptures() > 100,
            "{path:?}: the window must hold ruptures"
        );
        assert!(none.iter().all(|&n| n == 0), "{path:?}: {none:?}");
        assert!(
            counts.iter().any(|&n| 2 * n >= m.nx),
            "{path:?}: sums kept for at most {:?} of {} blocks",
            counts.iter().max(),
            m.nx
        );
        assert!(kept == summed, "{path:?}: kept sums changed the bits");
    }
    // Control: the same comparison sees a drive 1e-9 faster.
    let mut faster = m.clone();
    if let slipfront::model::Driver::SideSpring { velocity, .. } = &mut faster.driver {
        *velocity *= 1.0 + 1e-9;
    }
    let (kept, _) = run(&m, GpuPath::OneStep, true);
    let (other, _) = run(&faster, GpuPath::OneStep, true);
    assert!(kept != other, "control");
}

/// The engine on `path` with every block's junctions summed every step
/// (no kept sums), its lanes merged in subgroups where `lane_shuffle`.
fn summing_every_step(m: &Model, path: GpuPath, lane_shuffle: bool) -> GpuEngine {
    summing_every_step_with(m, path, lane_shuffle, Arithmetic::Leaner)
}

/// `summing_every_step`, with strict arithmetic or wgpu's guarded modules.
fn summing_every_step_with(
    m: &Model,
    path: GpuPath,
    lane_shuffle: bool,
    arithmetic: Arithmetic,
) -> GpuEngine {
    let opts = GpuOptions {
        path,
        keep_junction_sums: false,
        lane_shuffle,
        arithmetic,
        ..GpuOptions::default()
    };
    GpuEngine::with_options(m, opts).expect("a GPU adapter (lavapipe in CI)")
}

/// The persistent, resident and tiled kernels merge runs of a block's
/// junction lanes in subgroups before storage where the adapter has
/// subgroup operations (`GpuOptions::lane_shuffle`): the same tree of the
/// same lane sums, so the bits of every lane's sum through storage,
/// through the normal-load phase and the stick-slip window's first 2,000
/// steps of driving (2,400 ruptures), with every block summed every
/// step (the whole window: the next test, for persistent). The kernels
/// must report that they merged in subgroups (lavapipe: runs of 8 lanes),
/// or the test would pass without them; in CI the adapter must have
/// subgroups.
#[test]
fn lane_shuffles_give_the_bits_of_lane_sums_through_storage() {
    let m = stick_slip_scene(&[]);
    let run = |m: &Model, path, shuffle| {
        let mut g = summing_every_step(m, path, shuffle);
        advance_to(&mut g, m.prep_steps + 2000).unwrap();
        (g.snapshot().unwrap(), g.lane_shuffle_levels())
    };
    let ctx = slipfront::engines::gpu::context::shared().expect("a GPU adapter");
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        assert!(ctx.has_subgroups(), "{}: no subgroups", ctx.info.name);
    }
    for path in [GpuPath::Persistent, GpuPath::Resident, GpuPath::Tiled] {
        let (shuffled, levels) = run(&m, path, true);
        let (stored, none) = run(&m, path, false);
        println!("{path:?}: lane tree levels merged in subgroups: {levels}");
        assert!(
            shuffled.total_ruptures() > 100,
            "{path:?}: the window must hold ruptures"
        );
        assert_eq!(none, 0, "{path:?}");
        if ctx.has_subgroups() {
            assert!(levels >= 3, "{path:?}: merged {levels} levels in subgroups");
        }
        assert!(
            shuffled == stored,
            "{path:?}: lane shuffles changed the bits"
        );
    }
    // Control: the same comparison sees a drive 1e-9 faster.
    let mut faster = m.clone();
    if let slipfront::model::Driver::SideSpring { velocity, .. } = &mut faster.driver {
        *velocity *= 1.0 + 1e-9;
    }
    let (base, _) = run(&m, GpuPath::Persistent, true);
    let (other, _) = run(&faster, GpuPath::Persistent, true);
    assert!(base != other, "control");
}

/// Every kernel keeps the one-step kernel's bits through the whole
/// stick-slip window (6,000 driving steps, over 13,000 ruptures, every
/// block summed every step), its lanes merged in subgroups or through
/// storage, compared every 250 steps. Until session 66 every other kernel
/// parted from one-step 3,650 steps in on lavapipe, where a block's
/// junction sum landed on a rounding tie: a product reaching a two-sum's
/// first add was fused into it (an FMA) in some kernels' compiles and
/// not in others, and the two-sum's error term, made from the product
/// rounded, then missed the difference. The terms now pass through
/// `opaque` first in wgpu's modules (`shaders/double_single.wgsl`); in
/// strict arithmetic (the default where the engine writes the SPIR-V,
/// session 67) no operation may be fused at all. Both ways are checked:
/// each kernel against one-step built the same way. Negative control: a
/// drive 1e-9 faster is flagged.
#[test]
fn every_kernel_keeps_the_one_step_kernels_bits_through_the_stick_slip_window() {
    let m = stick_slip_scene(&[]);
    let end = m.prep_steps + 6000;
    let mut strict_reference = None;
    for strict in [true, false] {
        let arithmetic = match strict {
            true => Arithmetic::Strict,
            false => Arithmetic::Wgpu,
        };
        let engine =
            |m: &Model, path, shuffle| summing_every_step_with(m, path, shuffle, arithmetic);
        let mut reference = engine(&m, GpuPath::OneStep, false);
        let mut others: Vec<(String, GpuEngine)> = KERNELS
            .into_iter()
            .filter(|&p| p != GpuPath::OneStep)
            .map(|p| (format!("{p:?}"), engine(&m, p, true)))
            .collect();
        others.push((
            "Persistent, lanes through storage".into(),
            engine(&m, GpuPath::Persistent, false),
        ));
        for (name, e) in &others {
            assert!(
                e.describe().contains("strict arithmetic") == strict,
                "{name}: {}",
                e.describe()
            );
        }
        for step in (m.prep_steps + 250..=end).step_by(250) {
            advance_to(&mut reference, step).unwrap();
            let expected = reference.snapshot().unwrap();
            for (name, e) in others.iter_mut() {
                advance_to(e, step).unwrap();
                assert!(
                    e.snapshot().unwrap() == expected,
                    "{name} (strict {strict}): parted from one-step by driving step {}",
                    step - m.prep_steps
                );
            }
        }
        assert!(reference.snapshot().unwrap().total_ruptures() > 10_000);
        strict_reference.get_or_insert(reference.snapshot().unwrap());
    }
    let mut faster = m.clone();
    if let slipfront::model::Driver::SideSpring { velocity, .. } = &mut faster.driver {
        *velocity *= 1.0 + 1e-9;
    }
    let mut other = summing_every_step(&faster, GpuPath::Resident, true);
    advance_to(&mut other, end).unwrap();
    assert!(
        Some(other.snapshot().unwrap()) != strict_reference,
        "control"
    );
}

/// The process's pipelines are compiled once a key, whichever threads ask
/// at once: four threads asking for two builds of the one-step kernel (with
/// and without wgpu's run-time checks) get one pipeline a build, and the
/// two builds' pipelines differ (each key has its own slot, and the
/// cache's map is locked only to find it).
#[test]
fn pipelines_asked_for_at_once_are_compiled_once_a_key() {
    use slipfront::engines::gpu::compile::{KernelBuild, ShaderChecks};
    use slipfront::engines::gpu::shaders::{Kernel, LaneMerge};
    let ctx = slipfront::engines::gpu::context::shared().expect("a GPU adapter");
    let build = |checks| KernelBuild {
        lanes: LaneMerge::Storage,
        checks,
        chained_tiles: false,
        step_immediate: false,
        workgroup_barriers: false,
        phase_clocks: false,
        strict_arithmetic: false,
    };
    // A constant no other test compiles with: a key of this test's own.
    let constants = [("DAMPING_FORM", 2.0)];
    let asked = [
        ShaderChecks::Trusted,
        ShaderChecks::Checked,
        ShaderChecks::Trusted,
        ShaderChecks::Checked,
    ];
    let pipelines: Vec<wgpu::ComputePipeline> = std::thread::scope(|s| {
        let threads: Vec<_> = asked
            .iter()
            .map(|&checks| {
                let ctx = &ctx;
                s.spawn(move || ctx.pipeline::<f32>(Kernel::OneStep, build(checks), &constants))
            })
            .collect();
        threads.into_iter().map(|t| t.join().unwrap()).collect()
    });
    ctx.check().unwrap();
    assert!(pipelines[0] == pipelines[2] && pipelines[1] == pipelines[3]);
    assert!(pipelines[0] != pipelines[1], "two builds, two pipelines");
}
