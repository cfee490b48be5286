//! Device output samples against their CPU twin (`engine::record_sample`)
//! on host snapshots, shared by the GPU record tests of both precisions.

use slipfront::engines::{record_sample, Sample, SamplePlan};
use slipfront::{advance_to, Engine, Model, Scenario};

/// The CPU twin of each device sample, applied to host snapshots of a
/// second run (`host`) at the sample's step and, as the negative control,
/// one step later.
pub fn twins(m: &Model, host: &mut dyn Engine, samples: &[Sample]) -> (Vec<Sample>, Vec<Sample>) {
    let (mut twin, mut later) = (Vec::new(), Vec::new());
    for smp in samples {
        advance_to(host, smp.step).unwrap();
        let (i, b) = (smp.interface.is_some(), smp.bulk.is_some());
        twin.push(record_sample(m, &host.snapshot().unwrap(), i, b));
        advance_to(host, smp.step + 1).unwrap();
        later.push(record_sample(m, &host.snapshot().unwrap(), i, b));
    }
    (twin, later)
}

/// The largest error of `b` against `a` relative to the scale of each
/// quantity over all samples (sums, interface rows, bulk fields), with the
/// name of the worst quantity.
pub fn worst_error(a: &[Sample], b: &[Sample]) -> (f64, String) {
    type Get = fn(&Sample) -> Vec<f64>;
    let fields: [(&str, Get); 15] = [
        ("kinetic_energy", |s| vec![s.sums.kinetic_energy]),
        ("driven_ux", |s| vec![s.sums.driven_ux]),
        ("top_reaction", |s| vec![s.sums.top_reaction]),
        ("friction", |s| vec![s.sums.friction]),
        ("pinned_fraction", |s| vec![s.sums.pinned_fraction]),
        ("max_slip_speed", |s| vec![s.sums.max_slip_speed]),
        ("ruptures", |s| vec![s.sums.ruptures as f64]),
        ("interface.ux", |s| {
            s.interface.as_ref().map_or(vec![], |r| r.ux.clone())
        }),
        ("interface.friction", |s| {
            s.interface.as_ref().map_or(vec![], |r| r.friction.clone())
        }),
        ("interface.normal", |s| {
            s.interface.as_ref().map_or(vec![], |r| r.normal.clone())
        }),
        ("interface.pinned", |s| {
            s.interface
                .as_ref()
                .map_or(vec![], |r| r.pinned_fraction.clone())
        }),
        ("interface.slip_speed", |s| {
            s.interface
                .as_ref()
                .map_or(vec![], |r| r.slip_speed.clone())
        }),
        ("bulk.ux", |s| {
            s.bulk
                .as_ref()
                .map_or(vec![], |f| f.ux.iter().map(|&x| x as f64).collect())
        }),
        ("bulk.vx", |s| {
            s.bulk
                .as_ref()
                .map_or(vec![], |f| f.vx.iter().map(|&x| x as f64).collect())
        }),
        ("bulk.vz", |s| {
            s.bulk
                .as_ref()
                .map_or(vec![], |f| f.vz.iter().map(|&x| x as f64).collect())
        }),
    ];
    let mut worst = (0.0, String::new());
    for (name, get) in fields {
        let x: Vec<f64> = a.iter().flat_map(get).collect();
        let y: Vec<f64> = b.iter().flat_map(get).collect();
        assert_eq!(x.len(), y.len(), "{name}: sample shapes differ");
        // A field zero but for round-off (the friction total on a lattice
        // driven at the top for 20 µs: 1e-21 N) carries no signal: errors
        // are taken against 1e-12 (SI units) at least.
        let scale = x.iter().map(|v| v.abs()).fold(0.0, f64::max).max(1e-12);
        let err = x
            .iter()
            .zip(&y)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max)
            / scale;
        if err > worst.0 {
            worst = (err, name.to_string());
        }
    }
    worst
}

/// The sample plan of scenario `s`'s output cadences.
pub fn plan(m: &Model, s: &Scenario) -> SamplePlan {
    let every = |t: f64| {
        if t > 0.0 {
            ((t / m.dt).round() as u64).max(1)
        } else {
            0
        }
    };
    SamplePlan {
        prep_steps: m.prep_steps,
        every_global: every(s.output.global_interval),
        every_interface: every(s.output.interface_interval),
        every_bulk: every(s.output.bulk_interval),
        every_fast: every(s.output.fast_interval),
        fast_slip_speed: s.output.fast_slip_speed,
        fast: false,
    }
}

/// A 257 × 65 lattice (more blocks than one workgroup records), with a
/// bulk field among its samples.
pub fn large_lattice() -> Scenario {
    Scenario::parse(
        slipfront::model::scenario::DEFAULT_SCENARIO,
        "large",
        &large_lattice_keys(),
    )
    .unwrap()
}

pub fn large_lattice_keys() -> Vec<String> {
    [
        "geometry.nx=257",
        "geometry.nz=65",
        "geometry.length=0.64",
        "geometry.height=0.16",
        "loading.normal.ramp_time=2e-5",
        "loading.normal.relax_time=2e-5",
        "time.end=2e-5",
        "output.global_interval=2e-6",
        "output.interface_interval=4e-6",
        "output.bulk_interval=1e-5",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}
