//! Bad scenario input is refused with the key, the value, the allowed range
//! and the line; never a panic.

use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::model::Model;

fn parse_err(text: &str, set: &[&str]) -> String {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    Scenario::parse(text, "test.toml", &set)
        .expect_err("must be refused")
        .to_string()
}

#[test]
fn default_scenario_is_valid_and_round_trips() {
    let s = Scenario::default_scene();
    let again = Scenario::parse(&s.to_toml(), "round trip", &[]).unwrap();
    assert_eq!(s, again);
}

#[test]
fn unknown_key_names_key_and_line() {
    let text = DEFAULT_SCENARIO.replace("width = 0.006", "width = 0.006\nwidht = 1.0");
    let e = parse_err(&text, &[]);
    assert!(e.contains("widht"), "{e}");
    assert!(e.contains("line"), "{e}");
}

#[test]
fn missing_key_is_named() {
    let text = DEFAULT_SCENARIO.replace("nz = 31", "");
    let e = parse_err(&text, &[]);
    assert!(e.contains("missing field `nz`"), "{e}");
}

#[test]
fn out_of_range_value_names_key_value_range_and_line() {
    let text = DEFAULT_SCENARIO.replace("density = 1200.0", "density = -1200.0");
    let e = parse_err(&text, &[]);
    assert!(e.contains("material.density = -1200"), "{e}");
    assert!(e.contains("allowed: a finite value > 0"), "{e}");
    let line = DEFAULT_SCENARIO
        .lines()
        .position(|l| l.starts_with("density"))
        .unwrap()
        + 1;
    assert!(e.contains(&format!("(line {line})")), "{e}");
}

#[test]
fn set_overrides_apply_and_are_checked() {
    let s = Scenario::parse(
        DEFAULT_SCENARIO,
        "t",
        &["loading.drive.velocity=1e-3".into()],
    )
    .unwrap();
    assert_eq!(s.loading.drive.velocity, Some(1e-3));
    let e = parse_err(DEFAULT_SCENARIO, &["friction.static_coefficient=-1"]);
    assert!(e.contains("friction.static_coefficient = -1"), "{e}");
    assert!(e.contains("command line"), "{e}");
    let e = parse_err(DEFAULT_SCENARIO, &["friction.typo=1"]);
    assert!(e.contains("typo"), "{e}");
    let e = parse_err(DEFAULT_SCENARIO, &["friction.law=sticky"]);
    assert!(e.contains("sticky"), "{e}");
    let e = parse_err(DEFAULT_SCENARIO, &["start.position=2.5"]);
    assert!(e.contains("start.position = 2.5"), "{e}");
    let e = parse_err(DEFAULT_SCENARIO, &["start.speed=1"]);
    assert!(e.contains("speed"), "{e}");
    Scenario::parse(DEFAULT_SCENARIO, "t", &["start.position=0.01".into()]).unwrap();
}

/// A material out of scale makes dt tiny: the refusal names the material,
/// not only the run length it breaks.
#[test]
fn a_tiny_time_step_names_what_set_it() {
    let s = Scenario::parse(
        DEFAULT_SCENARIO,
        "t",
        &["material.youngs_modulus=1e308".into()],
    )
    .unwrap();
    let e = slipfront::Model::from_scenario(&s, false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("time.end"), "{e}");
    assert!(e.contains("material.youngs_modulus = 1e308"), "{e}");
}

#[test]
fn keys_a_mode_does_not_use_are_refused_and_needed_ones_required() {
    let e = parse_err(DEFAULT_SCENARIO, &["loading.drive.mode=none"]);
    assert!(
        e.contains("loading.drive.stiffness = 4000000 is not used"),
        "{e}"
    );
    let text = DEFAULT_SCENARIO.replace("velocity = 4.0e-4   # V (m/s) [paper]", "");
    let e = parse_err(&text, &[]);
    assert!(e.contains("missing key loading.drive.velocity"), "{e}");
}

#[test]
fn missing_file_is_named() {
    let e = Scenario::load(std::path::Path::new("no/such/file.toml"), &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("no/such/file.toml"), "{e}");
}

#[test]
fn lattice_must_be_square() {
    let e = parse_err(DEFAULT_SCENARIO, &["geometry.height=0.08"]);
    assert!(e.contains("geometry.height = 0.08"), "{e}");
    assert!(e.contains("square"), "{e}");
}

#[test]
fn time_step_above_stability_limit_is_refused_with_the_limit() {
    let s = Scenario::parse(DEFAULT_SCENARIO, "t", &["time.dt=1e-6".into()]).unwrap();
    let e = Model::from_scenario(&s, false).unwrap_err().to_string();
    assert!(
        e.contains("dt = 1.0000e-6 s is above the stability limit 6.6681e-7 s"),
        "{e}"
    );
    assert!(e.contains("6.6681e-7"), "{e}");
    assert!(Model::from_scenario(&s, true).is_ok());
}

#[test]
fn every_shipped_scenario_is_valid() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios");
    let (mut scenes, mut single_blocks) = (0, 0);
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        if slipfront::model::scenario::looks_like_single_block(&text) {
            slipfront::engines::single_block::SingleBlockScene::load(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            single_blocks += 1;
            continue;
        }
        let s = Scenario::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
        Model::from_scenario(&s, false).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        scenes += 1;
    }
    assert!(scenes >= 3);
    assert_eq!(single_blocks, 1);
    // Sweep files: every point of each valid.
    for entry in std::fs::read_dir(format!("{dir}/sweeps")).unwrap() {
        let path = entry.unwrap().path();
        let sweep = slipfront::app::sweeps::Sweep::load(&path)
            .unwrap_or_else(|p| panic!("{}: {}", path.display(), p.join("; ")));
        assert!(!sweep.points.is_empty());
    }
}

#[test]
fn output_cadences_are_checked() {
    let e = parse_err(DEFAULT_SCENARIO, &["output.fast_slip_speed=-1"]);
    assert!(
        e.contains("output.fast_slip_speed = -1 is out of range"),
        "{e}"
    );
    let e = parse_err(DEFAULT_SCENARIO, &["output.fast_interval=nan"]);
    assert!(e.contains("output.fast_interval = NaN"), "{e}");
}

#[test]
fn drive_speed_is_bounded_by_the_p_wave_speed_not_a_round_number() {
    let model = |v: &str| {
        let set = vec![format!("loading.drive.velocity={v}")];
        Model::from_scenario(
            &Scenario::parse(DEFAULT_SCENARIO, "t", &set).unwrap(),
            false,
        )
    };
    // 1500 m/s was refused by a ±1000 cap; it is below c_p ≈ 1720 m/s.
    assert!(model("1500").is_ok());
    let e = model("2000")
        .expect_err("faster than the P wave")
        .to_string();
    assert!(e.contains("loading.drive.velocity = 2000"), "{e}");
    assert!(e.contains("P-wave speed"), "{e}");
    assert!(e.contains("1719.9"), "{e}");
    let e = parse_err(DEFAULT_SCENARIO, &["loading.drive.velocity=inf"]);
    assert!(e.contains("any finite value"), "{e}");
}

#[test]
fn ranges_come_from_what_the_run_can_represent() {
    let model = |set: &[&str]| {
        let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        Model::from_scenario(
            &Scenario::parse(DEFAULT_SCENARIO, "t", &set).unwrap(),
            false,
        )
    };
    // Former round-number caps, now accepted: damping.ratio 20 (stable at
    // a small enough dt), Ns = 8192, time.end 2e6 s; a 500 s slip time fits
    // the 32-bit countdown at the Table S1 dt (2^32 steps = 985 s).
    assert!(model(&["damping.ratio=20", "time.dt_fraction=0.001"]).is_ok());
    assert!(model(&["friction.junctions.count=8192"]).is_ok());
    assert!(model(&["friction.junctions.slip_time_mean=500"]).is_ok());
    assert!(model(&["time.end=2e6"]).is_ok());
    // The limits that remain name the reason.
    let e = model(&["friction.junctions.slip_time_mean=1e4"])
        .expect_err("longer than the 32-bit countdown")
        .to_string();
    assert!(e.contains("2^32 - 2 steps"), "{e}");
    let e = model(&["time.end=1e10"])
        .expect_err("past 2^53 steps")
        .to_string();
    assert!(e.contains("2^53 steps"), "{e}");
    let e = parse_err(DEFAULT_SCENARIO, &["friction.junctions.count=20000000"]);
    assert!(e.contains("1 to 16777216"), "{e}");
    let e = parse_err(DEFAULT_SCENARIO, &["damping.ratio=-1"]);
    assert!(e.contains("a finite value >= 0"), "{e}");
}

#[test]
fn fast_forward_keys_are_checked_and_need_junctions() {
    let e = parse_err(
        DEFAULT_SCENARIO,
        &["time.fast_forward=true", "fast_forward.lead_time=-1e-3"],
    );
    assert!(e.contains("fast_forward.lead_time = -0.001"), "{e}");
    let e = parse_err(DEFAULT_SCENARIO, &["fast_forward.cascade_overshoot=-2"]);
    assert!(e.contains("fast_forward.cascade_overshoot = -2"), "{e}");
    let e = parse_err(DEFAULT_SCENARIO, &["fast_forward.quiet_enrgy=1e-3"]);
    assert!(e.contains("quiet_enrgy"), "{e}");
    let e = parse_err(
        DEFAULT_SCENARIO,
        &["time.fast_forward=true", "friction.law=\"coulomb\""],
    );
    assert!(
        e.contains("time.fast_forward = true needs friction.law"),
        "{e}"
    );
    // Defaults apply to missing keys; the switch round-trips.
    let s = Scenario::parse(
        DEFAULT_SCENARIO,
        "ff",
        &[
            "time.fast_forward=true".into(),
            "fast_forward.quiet_time=5e-4".into(),
        ],
    )
    .unwrap();
    let f = s.fast_forward.clone().unwrap();
    assert_eq!((f.quiet_time, f.lead_time), (5e-4, 1e-4));
    assert_eq!(Scenario::parse(&s.to_toml(), "again", &[]).unwrap(), s);
}

#[test]
fn each_scene_kind_refused_by_the_other_loader_names_the_right_command() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios");
    let single = std::path::PathBuf::from(format!("{dir}/thogersen2014_single_block.toml"));
    let e = Scenario::load(&single, &[]).unwrap_err().to_string();
    assert!(e.contains("slipfront single-block"), "{e}");
    let lattice = std::path::PathBuf::from(format!("{dir}/tromborg2014_stick_slip.toml"));
    let e = slipfront::engines::single_block::SingleBlockScene::load(&lattice)
        .unwrap_err()
        .to_string();
    assert!(e.contains("slipfront run"), "{e}");
    // Negative control: the lattice scene still loads as a lattice.
    assert!(Scenario::load(&lattice, &[]).is_ok());
}

/// No foundation under a normal load: refused (no time step can help), as
/// `check` and `run` both read the scenario; held in z, it is allowed.
#[test]
fn a_normal_load_needs_a_foundation_or_a_held_interface() {
    let e = parse_err(DEFAULT_SCENARIO, &["foundation.stiffness_ratio=0"]);
    assert!(e.contains("foundation.stiffness_ratio = 0"), "{e}");
    assert!(e.contains("nothing carries the normal load"), "{e}");
    Scenario::parse(
        DEFAULT_SCENARIO,
        "t",
        &[
            "foundation.stiffness_ratio=0".into(),
            "boundary.bottom=fix_z".into(),
        ],
    )
    .unwrap();
    Scenario::parse(
        DEFAULT_SCENARIO,
        "t",
        &[
            "foundation.stiffness_ratio=0".into(),
            "loading.normal.force=0".into(),
        ],
    )
    .unwrap();
}

/// The single-block scene checks its time step as the lattice scenes do: a
/// light block on stiff junctions is refused, not left to rattle.
#[test]
fn a_single_block_pulled_through_a_spring_checks_its_stability_limit() {
    use slipfront::engines::single_block::{SingleBlockScene, SCENARIO};
    let start = SCENARIO.find("[motion]").unwrap();
    let end = start
        + SCENARIO[start..]
            .find("\n\n")
            .unwrap_or(SCENARIO.len() - start);
    let spring = |mass: f64| {
        format!(
            "{}[motion]\nkind = \"spring\"\nmass_per_normal_force = {mass:e}\n\
             stiffness_per_normal_force = 1.0e3\nspeed = 1.0e-3\nduration = 1.0e-3\n{}",
            &SCENARIO[..start],
            &SCENARIO[end..]
        )
    };
    let e = SingleBlockScene::parse(&spring(1e-7), "light.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("above the stability limit"), "{e}");
    SingleBlockScene::parse(&spring(1e-3), "heavy.toml").unwrap();
    // A dashpot and an at-rest rule: read, and a negative damping refused.
    let damped = |ratio: &str| {
        spring(1e-3).replace(
            "duration = 1.0e-3\n",
            &format!("duration = 1.0e-3\ndamping_ratio = {ratio}\nat_rest = \"sign\"\n"),
        )
    };
    SingleBlockScene::parse(&damped("1.0"), "damped.toml").unwrap();
    let e = SingleBlockScene::parse(&damped("-1.0"), "negative.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("motion.damping_ratio = -1 is out of range"),
        "{e}"
    );
}

/// Rate-and-state friction needs its own table, and its table is refused
/// under another law; its keys are range-checked with their line.
#[test]
fn the_rate_state_table_is_required_by_its_law_only_and_checked() {
    let text = std::fs::read_to_string("scenarios/rate_state.toml").unwrap();
    let start = text.find("\n[friction.rate_state]\n").unwrap() + 1;
    let end = start + text[start..].find("\n[").unwrap() + 1;
    let without = format!("{}{}", &text[..start], &text[end..]);
    let e = parse_err(&without, &[]);
    assert!(
        e.contains(
            "missing table [friction.rate_state], required by friction.law = \"rate_state\""
        ),
        "{e}"
    );
    let e = parse_err(&text, &["friction.law=coulomb"]);
    assert!(
        e.contains("[friction.rate_state] is read only by friction.law = \"rate_state\""),
        "{e}"
    );
    let bad = text.replace(
        "characteristic_slip = 1.0e-6",
        "characteristic_slip = -1.0e-6",
    );
    let e = parse_err(&bad, &[]);
    assert!(
        e.contains("friction.rate_state.characteristic_slip = -0.000001"),
        "{e}"
    );
    assert!(e.contains("allowed: 0 < characteristic_slip <= 1"), "{e}");
    assert!(e.contains("(line "), "{e}");
    let e = parse_err(&text, &["friction.rate_state.state_evolution=\"ageing\""]);
    assert!(e.contains("ageing"), "{e}");
    let slip = Scenario::parse(
        &text,
        "slip law",
        &["friction.rate_state.state_evolution=\"slip\"".into()],
    );
    assert!(slip.is_ok());
}

/// The at-rest rule of slipping junctions: `hold` by default, `sign` when
/// asked; anything else is refused with its line and the allowed values.
#[test]
fn the_junctions_at_rest_rule_defaults_to_hold_and_refuses_other_values() {
    let s = Scenario::parse(DEFAULT_SCENARIO, "default", &[]).unwrap();
    let j = s.friction.junctions.as_ref().unwrap();
    assert_eq!(
        j.at_rest,
        slipfront::model::friction::junctions::SlipAtRest::Hold
    );
    let set = ["friction.junctions.at_rest=\"sign\"".to_string()];
    let sign = Scenario::parse(DEFAULT_SCENARIO, "sign", &set).unwrap();
    assert_eq!(
        sign.friction.junctions.unwrap().at_rest,
        slipfront::model::friction::junctions::SlipAtRest::Sign
    );
    let text =
        DEFAULT_SCENARIO.replace("slip_time_std = ", "at_rest = \"stick\"\nslip_time_std = ");
    let e = parse_err(&text, &[]);
    assert!(e.contains("line") && e.contains("at_rest"), "{e}");
    assert!(e.contains("expected `hold` or `sign`"), "{e}");
}
