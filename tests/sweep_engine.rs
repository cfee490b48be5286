//! The sweep engine (the fast CPU path) against the reference engine
//! (`CpuEngine`, the WGSL kernels' twin): the same bits, snapshot for
//! snapshot, in every precision, for any thread count, through the
//! normal-load phase, the start of driving and ruptures; for every friction
//! law, damping form, driver and the trigger. A perturbed reference run is
//! the negative control: the comparison must see a one-ulp change.

use slipfront::app::verify::STICK_SLIP_WINDOW;
use slipfront::engines::cpu::{CpuEngine, SweepEngine};
use slipfront::model::real::{Coordinate, DoubleSingle, Real};
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Engine, Model, Snapshot};

/// The Table S1 scene shortened: brief normal-load phase, hard driving so
/// that junctions rupture within a few hundred steps.
const QUICK: &[&str] = &[
    "geometry.nx=33",
    "geometry.nz=9",
    "geometry.length=0.08",
    "geometry.height=0.02",
    "loading.normal.ramp_time=1e-5",
    "loading.normal.relax_time=1e-5",
];

fn model_from(text: &str, extra: &[&str]) -> Model {
    let set: Vec<String> = QUICK.iter().chain(extra).map(|s| s.to_string()).collect();
    let s = Scenario::parse(text, "sweep test", &set).unwrap();
    Model::from_scenario(&s, false).unwrap()
}

/// The default scene (side spring) driven hard.
fn model(extra: &[&str]) -> Model {
    let mut set = vec!["loading.drive.velocity=2.0"];
    set.extend(extra);
    model_from(DEFAULT_SCENARIO, &set)
}

/// Steps both engines to the same checkpoints and asserts equal snapshots;
/// returns the last one.
fn same_bits<T: Real, C: Coordinate<T>>(m: &Model, threads: usize, steps: u64) -> Snapshot {
    let mut reference = CpuEngine::<T, C>::new(m, 1).unwrap();
    // The detected instruction set (AVX2 here) and the baseline.
    let mut sweeps = [
        SweepEngine::<T, C>::new(m, threads).unwrap(),
        SweepEngine::<T, C>::new(m, threads).unwrap(),
    ];
    sweeps[1].use_baseline_isa();
    let at_start = reference.snapshot().unwrap();
    for sweep in &mut sweeps {
        assert_eq!(sweep.threads(), threads.clamp(1, m.nz));
        assert_eq!(at_start, sweep.snapshot().unwrap(), "at step 0");
    }
    let end = m.prep_steps + steps;
    let checkpoints = [
        m.prep_steps - 1,
        m.prep_steps,
        m.prep_steps + 1,
        end / 2 + 1,
        end,
    ];
    let mut last = None;
    for at in checkpoints {
        advance_to(&mut reference, at).unwrap();
        let a = reference.snapshot().unwrap();
        for sweep in &mut sweeps {
            advance_to(sweep, at).unwrap();
            let b = sweep.snapshot().unwrap();
            if a != b {
                panic!(
                    "{:?}, {threads} threads: {}",
                    sweep.isa(),
                    first_difference(&a, &b)
                );
            }
        }
        last = Some(a);
    }
    last.unwrap()
}

fn first_difference(a: &Snapshot, b: &Snapshot) -> String {
    let pairs: [(&str, Vec<f64>, Vec<f64>); 5] = [
        ("disp", a.disp.concat(), b.disp.concat()),
        ("vel_half", a.vel_half.concat(), b.vel_half.concat()),
        ("force", a.force.concat(), b.force.concat()),
        ("friction", a.friction.clone(), b.friction.clone()),
        ("anchor", a.anchor.clone(), b.anchor.clone()),
    ];
    for (name, x, y) in pairs {
        if let Some(i) = (0..x.len()).find(|&i| x[i].to_bits() != y[i].to_bits()) {
            return format!("step {}: {name}[{i}] {} != {}", a.step, x[i], y[i]);
        }
    }
    format!("step {}: junction or slide states differ", a.step)
}

#[test]
fn f64_sweep_is_bitwise_the_reference_on_one_two_and_three_threads() {
    let m = model(&[]);
    for threads in [1, 2, 3] {
        let last = same_bits::<f64, f64>(&m, threads, 600);
        assert!(
            last.total_ruptures() > 0,
            "the comparison must cover ruptures"
        );
    }
}

#[test]
fn mixed_and_plain_f32_sweeps_are_bitwise_the_reference() {
    let m = model(&[]);
    for threads in [1, 2] {
        let last = same_bits::<f32, DoubleSingle>(&m, threads, 600);
        assert!(last.total_ruptures() > 0);
        same_bits::<f32, f32>(&m, threads, 300);
    }
}

#[test]
fn coulomb_law_and_bond_damping_sweeps_are_bitwise_the_reference() {
    let m = model(&["friction.law=coulomb", "loading.drive.velocity=0.4"]);
    let last = same_bits::<f64, f64>(&m, 2, 800);
    assert!(last.slips.iter().any(|&s| s > 0), "blocks must slide");
    let m = model(&["damping.form=bond"]);
    same_bits::<f64, f64>(&m, 2, 400);
    same_bits::<f32, DoubleSingle>(&m, 1, 400);
}

/// Rate-and-state friction (a per-block law with its own state θ): the
/// same bits, θ included, through slip.
#[test]
fn rate_state_law_sweeps_are_bitwise_the_reference() {
    let text = std::fs::read_to_string("scenarios/rate_state.toml").unwrap();
    let m = model_from(&text, &["loading.drive.velocity=2.0"]);
    let last = same_bits::<f64, f64>(&m, 2, 800);
    assert!(last.slips.iter().any(|&s| s > 0), "blocks must slide");
    assert_eq!(last.law_state.len(), m.nx);
    let start = m.law_initial_state()[0];
    assert!(
        last.law_state.iter().any(|&theta| theta < start),
        "θ must renew"
    );
    same_bits::<f32, DoubleSingle>(&m, 2, 400);
}

#[test]
fn top_drives_and_the_trigger_sweeps_are_bitwise_the_reference() {
    let drive_start = DEFAULT_SCENARIO.find("[loading.drive]").unwrap();
    let drive_end = drive_start + DEFAULT_SCENARIO[drive_start..].find("\n[").unwrap() + 1;
    for block in [
        "[loading.drive]\nmode = \"top_force\"\nforce_rate = 1.6e6\n",
        "[loading.drive]\nmode = \"top_velocity\"\nvelocity = 0.4\n",
    ] {
        let text = format!(
            "{}{block}{}",
            &DEFAULT_SCENARIO[..drive_start],
            &DEFAULT_SCENARIO[drive_end..]
        );
        same_bits::<f64, f64>(&model_from(&text, &[]), 2, 400);
    }
    let triggered = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenarios/triggered_front.toml"
    ))
    .unwrap();
    let m = model_from(&triggered, &[]);
    assert!(m.trigger.is_some());
    same_bits::<f64, f64>(&m, 2, 300);
}

/// Negative control: the comparison flags a reference run whose driving
/// speed differs by one part in 1e12.
#[test]
fn the_comparison_sees_a_perturbed_run() {
    let m = model(&[]);
    let mut p = model(&[]);
    if let slipfront::model::Driver::SideSpring { velocity, .. } = &mut p.driver {
        *velocity *= 1.0 + 1e-12;
    }
    let mut reference = CpuEngine::<f64>::new(&p, 1).unwrap();
    let mut sweep = SweepEngine::<f64>::new(&m, 1).unwrap();
    let end = m.prep_steps + 200;
    advance_to(&mut reference, end).unwrap();
    advance_to(&mut sweep, end).unwrap();
    assert_ne!(reference.snapshot().unwrap(), sweep.snapshot().unwrap());
}

/// A blow-up stops the sweep engine at the reference's step and block.
#[test]
fn blow_up_is_reported_at_the_reference_step_and_block() {
    let set = ["time.dt_fraction=0.2"];
    let sets: Vec<String> = QUICK.iter().chain(&set).map(|s| s.to_string()).collect();
    let s = Scenario::parse(DEFAULT_SCENARIO, "unstable", &sets).unwrap();
    let m = Model::from_scenario(&s, true).unwrap();
    let err = |e: &mut dyn Engine| advance_to(e, m.total_steps()).unwrap_err().to_string();
    let a = err(&mut CpuEngine::<f64>::new(&m, 1).unwrap());
    let b = err(&mut SweepEngine::<f64>::new(&m, 2).unwrap());
    assert!(a.contains("blew up at step"), "{a}");
    assert_eq!(a, b);
}

/// Lattices at the edges of the band logic: bands of one row (each its
/// neighbours' halo; three threads asked for two rows get two), one
/// column, one row.
#[test]
fn tiny_lattices_sweep_bitwise_the_reference() {
    for (nx, nz, threads) in [(5, 2, 3), (5, 3, 3), (1, 4, 2), (6, 1, 1)] {
        let set = [
            format!("geometry.nx={nx}"),
            format!("geometry.nz={nz}"),
            format!("geometry.length={}", 0.0025 * (nx.max(2) - 1) as f64),
            format!("geometry.height={}", 0.0025 * (nz.max(2) - 1) as f64),
            "loading.drive.height=0".to_string(),
        ];
        let set: Vec<&str> = set.iter().map(String::as_str).collect();
        let m = model(&set);
        same_bits::<f64, f64>(&m, threads, 300);
    }
}

/// The evaluators of the quasi-static path's output samples: the sweep
/// engine's `with_junctions` gives the reference's bits for a state it is
/// handed (junction arrays of one snapshot, kinematics of another instant),
/// and a one-ulp change of that state is seen.
#[test]
fn path_evaluators_are_bitwise_the_reference() {
    let m = model(&[]);
    let mut run = CpuEngine::<f64>::new(&m, 1).unwrap();
    // A base with junctions slipping, and a later instant.
    let mut at = m.prep_steps;
    let base = loop {
        at += 50;
        advance_to(&mut run, at).unwrap();
        let snap = run.snapshot().unwrap();
        if snap.ruptures.iter().any(|&r| r > 0) {
            break snap;
        }
        assert!(at < m.prep_steps + 20_000, "no rupture");
    };
    advance_to(&mut run, at + 100).unwrap();
    let later = run.snapshot().unwrap();
    let origin = 1.5e-7;
    let mut reference = CpuEngine::<f64>::with_junctions(&m, &base, origin).unwrap();
    let mut sweep = SweepEngine::<f64>::with_junctions(&m, &base, origin).unwrap();
    assert_eq!(reference.snapshot().unwrap(), sweep.snapshot().unwrap());
    let step = later.step;
    reference
        .set_kinematics(step, &later.disp, &later.vel_half)
        .unwrap();
    sweep
        .set_kinematics(step, &later.disp, &later.vel_half)
        .unwrap();
    let (a, b) = (reference.snapshot().unwrap(), sweep.snapshot().unwrap());
    assert!(a == b, "{}", first_difference(&a, &b));
    // Negative control: one block moved by one ulp changes its forces.
    let mut moved = later.disp.clone();
    moved[m.nx + 3][0] = f64::from_bits(moved[m.nx + 3][0].to_bits() + 1);
    sweep.set_kinematics(step, &moved, &later.vel_half).unwrap();
    assert_ne!(a, sweep.snapshot().unwrap());
}

/// The sweep engine keeps a quiet interface block's junction sums and
/// skips its junctions (`junctions::KeptSums`); the reference engine sums
/// every junction every step. Through ruptures and re-pinnings they must
/// agree bit for bit, in mixed f32 and f64, and the sums must be kept for
/// most blocks at some point, or the comparison would not cover them.
fn kept_sums_match<T: Real, C: Coordinate<T>>() {
    let m = model(&STICK_SLIP_WINDOW);
    let mut reference = CpuEngine::<T, C>::new(&m, 1).unwrap();
    let mut sweep = SweepEngine::<T, C>::new(&m, 2).unwrap();
    let mut most = 0;
    for at in (m.prep_steps..=m.prep_steps + 6000).step_by(250) {
        advance_to(&mut reference, at).unwrap();
        advance_to(&mut sweep, at).unwrap();
        most = most.max(sweep.kept_junction_blocks());
        let (a, b) = (reference.snapshot().unwrap(), sweep.snapshot().unwrap());
        assert!(a == b, "{}", first_difference(&a, &b));
    }
    let ruptures = reference.snapshot().unwrap().total_ruptures();
    assert!(ruptures > 100, "the window must hold ruptures: {ruptures}");
    assert!(
        2 * most >= m.nx,
        "sums kept for at most {most} of {} blocks",
        m.nx
    );
}

#[test]
fn kept_junction_sums_are_bitwise_the_reference() {
    kept_sums_match::<f32, DoubleSingle>();
    kept_sums_match::<f64, f64>();
}

/// A thread-count trial (`SweepEngine::with_thread_trials`, what `--threads
/// 0` does on a small lattice) steps the run itself on each count in turn,
/// at the start of the normal load and again at the start of driving, and
/// then keeps one: every switch of count (bands, pool, the interface
/// band's kept sums carried over) must leave the reference's bits, through
/// ruptures. Spans of the trial's fewest steps, so that both trials end
/// within the window; calls of 37 steps, so that switches fall within
/// calls and after odd step counts.
#[test]
fn thread_trials_switch_counts_on_the_reference_bits() {
    use slipfront::engines::cpu::fast::threads::Plan;
    // A normal load long enough for its trial (about 750 steps here).
    let mut set = STICK_SLIP_WINDOW.to_vec();
    set.extend([
        "loading.normal.ramp_time=2e-4",
        "loading.normal.relax_time=1e-4",
    ]);
    let m = model(&set);
    assert!(m.prep_steps > 1000, "{} steps of normal load", m.prep_steps);
    let plan = Plan {
        candidates: vec![1, 3, 2],
        span_seconds: 0.0,
        retrial_seconds: f64::INFINITY,
    };
    let mut reference = CpuEngine::<f64>::new(&m, 1).unwrap();
    let mut sweep = SweepEngine::<f64>::with_thread_trials(&m, plan).unwrap();
    assert!(sweep.timing_threads());
    let mut seen = std::collections::BTreeSet::new();
    let mut timed_in_loading = None;
    let end = m.prep_steps + 4000;
    while sweep.steps_done() < end {
        let at = (sweep.steps_done() + 37).min(end);
        advance_to(&mut sweep, at).unwrap();
        seen.insert(sweep.threads());
        if at < m.prep_steps && !sweep.timing_threads() {
            timed_in_loading = sweep.threads_timed().cloned();
        }
        if at % 250 < 37 || at == end {
            advance_to(&mut reference, at).unwrap();
            let (a, b) = (reference.snapshot().unwrap(), sweep.snapshot().unwrap());
            assert!(a == b, "{}", first_difference(&a, &b));
        }
    }
    assert_eq!(seen.into_iter().collect::<Vec<_>>(), vec![1, 2, 3]);
    let loading = timed_in_loading.expect("the normal load's trial ends within it");
    let driving = sweep.threads_timed().expect("the driving's trial ends");
    assert!(!sweep.timing_threads());
    for timed in [&loading, driving] {
        let counts: Vec<usize> = timed.figures.iter().map(|f| f.0).collect();
        assert_eq!(counts, vec![1, 3, 2]);
        assert!(timed.figures.iter().all(|f| f.1 > 0.0 && f.1.is_finite()));
        assert!([1, 2, 3].contains(&timed.threads));
    }
    assert_eq!(sweep.threads(), driving.threads);
    assert!(
        sweep.describe().contains("threads timed: 1: "),
        "{}",
        sweep.describe()
    );
    let ruptures = reference.snapshot().unwrap().total_ruptures();
    assert!(ruptures > 100, "the window must hold ruptures: {ruptures}");
}

/// `--threads 0` times the thread counts on a small lattice where the
/// machine has several cores, and on a large one takes every core.
#[test]
fn the_engine_times_threads_on_a_small_lattice_of_a_machine_with_cores() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let small = SweepEngine::<f64>::new(&model(&[]), 0).unwrap();
    assert_eq!(small.timing_threads(), cores > 1);
    assert_eq!(small.threads(), 1, "a trial starts on one thread");
    let large = SweepEngine::<f64>::new(
        &model(&[
            "geometry.nx=160",
            "geometry.nz=32",
            "geometry.length=0.3975",
            "geometry.height=0.0775",
        ]),
        0,
    )
    .unwrap();
    assert!(!large.timing_threads());
    assert_eq!(large.threads(), cores.min(32));
}

/// Trials back to back (a new one as soon as one ends, as after every
/// `RETRIAL_SECONDS` of a run): the counts change all through the window,
/// on the reference's bits.
#[test]
fn back_to_back_thread_trials_keep_the_reference_bits() {
    use slipfront::engines::cpu::fast::threads::Plan;
    let m = model(&STICK_SLIP_WINDOW);
    let plan = Plan {
        candidates: vec![2, 1],
        span_seconds: 0.0,
        retrial_seconds: 0.0,
    };
    let mut reference = CpuEngine::<f64>::new(&m, 1).unwrap();
    let mut sweep = SweepEngine::<f64>::with_thread_trials(&m, plan).unwrap();
    let mut trials = 0;
    let mut last = None;
    let end = m.prep_steps + 3000;
    for at in (m.prep_steps..=end).step_by(50) {
        advance_to(&mut sweep, at).unwrap();
        // Each trial's figures are its own timings.
        let timed = sweep.threads_timed().cloned();
        if timed.is_some() && timed != last {
            trials += 1;
            last = timed;
        }
        if at % 500 == 0 {
            advance_to(&mut reference, at).unwrap();
            let (a, b) = (reference.snapshot().unwrap(), sweep.snapshot().unwrap());
            assert!(a == b, "{}", first_difference(&a, &b));
        }
    }
    advance_to(&mut reference, end).unwrap();
    let (a, b) = (reference.snapshot().unwrap(), sweep.snapshot().unwrap());
    assert!(a == b, "{}", first_difference(&a, &b));
    assert!(trials >= 3, "{trials} trials ended in the window");
}
