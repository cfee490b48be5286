//! The thesis's other models: published trends on small versions, the GPU
//! against the CPU on them, and the energy ledger of their new loads.

use slipfront::analysis::energy::{step_power, stored_energy};
use slipfront::app::studies::front_1d::{run_chain, run_point, FrontCase, Grid, Viscosity};
use slipfront::engines::backend::{cpu_engine, Backend, Precision};
use slipfront::{advance_to, Model};

fn chain(case: FrontCase, dt_scale: f64) -> Model {
    Model::from_scenario(&case.scenario(dt_scale).unwrap(), false).unwrap()
}

fn case(ratio: Option<f64>, viscosity: Viscosity, alpha: f64, tau_bar: f64) -> FrontCase {
    FrontCase {
        stiffness_ratio: ratio,
        viscosity,
        alpha,
        tau_bar,
        n_blocks: 0,
        trigger_blocks: 1,
    }
}

/// Two short lengths and the dt/2 check: seconds per point.
fn small_grid() -> Grid {
    Grid {
        lengths: vec![40, 80],
        dt_check_length: 40,
        ..Grid::quick()
    }
}

fn v_inf(c: FrontCase) -> f64 {
    let r = run_point(c, &small_grid(), Backend::Cpu, Precision::F64).unwrap();
    let d = r.dt_change.unwrap();
    assert!(d < 0.01, "{c:?}: dt → dt/2 moves the speed by {d}");
    r.extrapolated.unwrap()
}

#[test]
fn one_d_front_speed_grows_with_prestress_viscosity_and_interface_stiffness() {
    let rel = Viscosity::Relative;
    let rigid: Vec<f64> = [0.2, 0.5, 0.8]
        .iter()
        .map(|&t| v_inf(case(None, rel, 0.0, t)))
        .collect();
    println!("rigid, no viscosity: {rigid:?}");
    assert!(rigid.windows(2).all(|w| w[1] > w[0]), "increasing in τ̄");
    assert!(rigid[2] > 1.0, "supersonic at τ̄ = 0.8");
    let viscous = v_inf(case(None, rel, 0.5, 0.5));
    assert!(viscous > rigid[1], "relative viscosity speeds it up");
    let soft = v_inf(case(Some(1.0), rel, 0.0, 0.5));
    let softer = v_inf(case(Some(0.1), rel, 0.0, 0.5));
    println!("k_I/k = 1: {soft}, 0.1: {softer}");
    assert!(
        softer < soft && soft < rigid[1],
        "stiffer interfaces are faster"
    );
}

#[test]
fn a_one_d_front_runs_at_a_speed_set_by_the_prestress_not_a_perturbation_of_it() {
    // The yardstick: τ̄ moved by 1e-6 moves the speed by far less than the
    // trends above resolve; τ̄ moved by 0.05 moves it by far more.
    let c = |t: f64| FrontCase {
        n_blocks: 80,
        ..case(None, Viscosity::Relative, 0.0, t)
    };
    let speed = |t: f64| {
        run_chain(&chain(c(t), 0.125), Backend::Cpu, Precision::F64)
            .unwrap()
            .front_speed
            .unwrap()
    };
    let (a, b, far) = (speed(0.5), speed(0.5 + 1e-6), speed(0.55));
    assert!((a - b).abs() < 1e-3 * a, "{a} vs {b}");
    assert!((far - a).abs() > 1e-2 * a, "{a} vs {far}");
}

/// First rupture steps of every block of a chain on `backend`.
fn rupture_steps(m: &Model, backend: Backend) -> (Vec<i64>, f64) {
    let r = run_chain(m, backend, Precision::F32)
        .unwrap_or_else(|e| panic!("{backend:?}: {e} (a GPU adapter is required: lavapipe in CI)"));
    let steps = r
        .rupture_time
        .iter()
        .map(|t| (t.expect("every block breaks") / m.dt).round() as i64)
        .collect();
    (steps, r.front_speed.unwrap())
}

#[test]
fn gpu_one_d_fronts_match_the_cpu_block_by_block() {
    // Rigid with relative viscosity; compliant with absolute viscosity:
    // the prestress, the trigger block and the absolute dashpot on the GPU.
    let scenes = [
        case(None, Viscosity::Relative, 0.2, 0.6),
        case(Some(1.0), Viscosity::Absolute, 0.2, 0.6),
    ];
    for c in scenes {
        let m = chain(FrontCase { n_blocks: 48, ..c }, 1.0);
        let (cpu, v_cpu) = rupture_steps(&m, Backend::Cpu);
        let (gpu, v_gpu) = rupture_steps(&m, Backend::Gpu);
        let worst = cpu.iter().zip(&gpu).map(|(a, b)| (a - b).abs()).max();
        println!("{c:?}: CPU {v_cpu:.5}, GPU {v_gpu:.5}, worst block {worst:?} steps");
        assert!(worst <= Some(1), "{cpu:?}\n{gpu:?}");
        assert!((v_cpu - v_gpu).abs() < 5e-3 * v_cpu);
        // Negative control: a prestress 0.05 higher is flagged.
        let other = chain(
            FrontCase {
                n_blocks: 48,
                tau_bar: c.tau_bar + 0.05,
                ..c
            },
            1.0,
        );
        let (moved, _) = rupture_steps(&other, Backend::Cpu);
        let diff = cpu.iter().zip(&moved).map(|(a, b)| (a - b).abs()).max();
        assert!(diff > Some(1), "the comparison must see τ̄ + 0.05: {diff:?}");
    }
}

#[test]
fn energy_balance_of_a_prestressed_chain_with_absolute_viscosity() {
    let c = FrontCase {
        n_blocks: 40,
        ..case(Some(1.0), Viscosity::Absolute, 0.5, 0.6)
    };
    let m = chain(c, 1.0);
    let mut e = cpu_engine(&m, Precision::F64, 1).unwrap();
    advance_to(e.as_mut(), m.prep_steps).unwrap();
    let start = e.snapshot().unwrap();
    let e0 = stored_energy(&m, &start, 0.0);
    let (mut w_load, mut w_friction, mut dissipated) = (0.0, 0.0, 0.0);
    let mut before = start;
    for _ in 0..1500 {
        advance_to(e.as_mut(), before.step + 1).unwrap();
        let after = e.snapshot().unwrap();
        let p = step_power(&m, &before, &after, 0.0);
        w_load += p.top_loads * m.dt;
        w_friction += p.friction * m.dt;
        dissipated += p.damping * m.dt;
        before = after;
    }
    assert!(before.total_ruptures() >= 20, "the front must run");
    let change = stored_energy(&m, &before, 0.0).total() - e0.total();
    let net_in = w_load + w_friction - dissipated;
    let rel = (change - net_in).abs() / w_load;
    println!("prestress work {w_load:.4e} J, friction {w_friction:.4e} J, absolute damping {dissipated:.4e} J, change {change:.4e} J: mismatch {rel:.2e}");
    assert!(rel < 0.01, "{rel}");
    // Negative control: without the absolute damping the books do not close.
    let without = (change - (net_in + dissipated)).abs() / w_load;
    assert!(without > 0.05, "{without}");
}

mod single_block {
    use slipfront::app::studies::junction_laws::{laws, shape};
    use slipfront::engines::single_block::law::{JunctionLaw, SlipForce, SlipTime};
    use slipfront::engines::single_block::{next_static_threshold, simulated_steady_friction};

    fn base() -> JunctionLaw {
        JunctionLaw {
            threshold: 0.4,
            break_stretch: 1e-7,
            slip_force: SlipForce::Constant { level: 0.17 },
            slip_time: SlipTime::Gaussian {
                mean: 2e-3,
                std: 2e-4,
            },
            drag: 0.0,
        }
    }

    #[test]
    fn simulated_steady_friction_is_within_2_percent_of_the_renewal_formula() {
        let mut all = laws(&base());
        all.push(slipfront::app::studies::junction_laws::NamedLaw {
            name: "exponential slip times",
            law: JunctionLaw {
                slip_time: SlipTime::Exponential { mean: 1e-3 },
                ..base()
            },
        });
        for l in &all {
            for v in [1e-5, 1e-4, 1e-3, 1e-2] {
                let analytic = l.law.steady_friction(v);
                let sim = simulated_steady_friction(&l.law, v, 400, 15.0, 3);
                let err = (sim - analytic).abs() / analytic;
                assert!(err < 0.02, "{} at {v}: {sim} vs {analytic}", l.name);
                // Negative control: a 10 % higher threshold in the formula
                // is flagged wherever the pinned phase counts.
                let wrong = JunctionLaw {
                    threshold: 0.44,
                    ..l.law
                }
                .steady_friction(v);
                if v <= 1e-4 {
                    assert!((sim - wrong).abs() / wrong > 0.02, "{} at {v}", l.name);
                }
            }
        }
    }

    #[test]
    fn the_three_laws_give_the_three_shapes() {
        let speeds: Vec<f64> = (0..=20)
            .map(|i| 10f64.powf(-6.0 + 0.25 * i as f64))
            .collect();
        let shapes: Vec<&str> = laws(&base())
            .iter()
            .map(|l| {
                shape(
                    &speeds
                        .iter()
                        .map(|&v| l.law.steady_friction(v))
                        .collect::<Vec<_>>(),
                )
            })
            .collect();
        assert!(shapes[0].starts_with("decreasing"), "{shapes:?}");
        assert!(shapes[1].starts_with("increasing"), "{shapes:?}");
        assert!(shapes[2].starts_with("non-monotonic"), "{shapes:?}");
    }

    #[test]
    fn a_more_abrupt_stop_gives_a_higher_next_static_threshold() {
        let t = |a: f64| next_static_threshold(&base(), 400, 1, 1e-3, a, 1e-5);
        let (gentle, abrupt) = (t(1e-2), t(1e2));
        println!("gentle {gentle:.4}, abrupt {abrupt:.4}");
        assert!(abrupt > gentle + 0.05, "{gentle} → {abrupt}");
        // The yardstick: a deceleration moved by 1e-6 does not move it.
        let nudged = t(1e2 * (1.0 + 1e-6));
        assert!((nudged - abrupt).abs() < 0.01, "{abrupt} vs {nudged}");
    }
}

#[test]
fn gpu_asymmetric_normal_load_matches_the_cpu_field_by_field() {
    use slipfront::io::compare::{compare_snapshots, fields_over};
    let load = |ratio: f64| {
        let s = slipfront::Scenario::load(
            std::path::Path::new("scenarios/tromborg2011_coulomb_precursors.toml"),
            &[
                format!("loading.normal.trailing_to_leading={ratio}"),
                "geometry.nx=21".into(),
                "geometry.length=0.05".into(),
                "geometry.nz=11".into(),
                "geometry.height=0.025".into(),
            ],
        )
        .unwrap();
        Model::from_scenario(&s, false).unwrap()
    };
    let m = load(3.0);
    let steps = m.prep_steps + 2000;
    let run = |m: &Model, backend: Backend| {
        let mut e = slipfront::engines::backend::make_engine(m, backend, Precision::F32, 1)
            .unwrap_or_else(|e| panic!("{backend:?}: {e} (lavapipe in CI)"));
        advance_to(e.as_mut(), steps).unwrap();
        e.snapshot().unwrap()
    };
    let (c, g) = (run(&m, Backend::Cpu), run(&m, Backend::Gpu));
    let errors = compare_snapshots(&c, &g);
    assert_eq!(
        fields_over(&errors, 1e-4, 1e-5),
        Vec::<String>::new(),
        "{errors:?}"
    );
    // The profile is there: the trailing edge pressed harder than the
    // leading one (3× at the top, spread by the bulk at the interface;
    // uniformly loaded, the side spring's moment makes it the other way).
    let (p0, p1) = (c.normal[0], c.normal[m.nx - 1]);
    assert!(p0 / p1 > 2.0, "{p0} / {p1}");
    // Negative control: the uniform load is flagged by the same comparison.
    let u = run(&load(1.0), Backend::Cpu);
    assert!(!fields_over(&compare_snapshots(&c, &u), 1e-4, 1e-5).is_empty());
}
