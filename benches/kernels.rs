//! criterion benches of the CPU twins of the WGSL kernels, one step of each
//! phase on the 1024×256 lattice with Ns = 100 (single thread).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use slipfront::engines::kernels::bulk_forces::{bond_consts, bulk_forces, Blocks};
use slipfront::engines::kernels::junctions::{junctions, JunctionSlots, JunctionSpring, PINNED};
use slipfront::engines::kernels::verlet::verlet;
use slipfront::engines::step_params::{step_params, Consts};
use slipfront::model::lattice::block_flags;
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::Model;
use std::hint::black_box;

fn model() -> Model {
    let l = 0.14 / 56.0;
    let set = vec![
        "geometry.nx=1024".to_string(),
        "geometry.nz=256".to_string(),
        format!("geometry.length={}", l * 1023.0),
        format!("geometry.height={}", l * 255.0),
    ];
    Model::from_scenario(
        &Scenario::parse(DEFAULT_SCENARIO, "bench", &set).unwrap(),
        false,
    )
    .unwrap()
}

fn kernels(c: &mut Criterion) {
    let m = model();
    let consts = Consts::<f64>::new(&m);
    let bonds = bond_consts(&consts);
    let p = step_params(&consts, m.prep_steps + 10);
    let n = m.n_blocks();
    let flags = block_flags(&m);
    // A small smooth strain field, so that every bond is stretched.
    let disp: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            let (x, z) = ((i % m.nx) as f64, (i / m.nx) as f64);
            [1e-7 * x.sin(), -1e-7 * z]
        })
        .collect();
    let vel = vec![[1e-4, 0.0]; n];
    let mut force = vec![[0.0; 2]; n];
    let blocks = Blocks {
        disp: &disp,
        vel: &vel,
        flags: &flags,
    };

    let mut g = c.benchmark_group("cpu_twins_1024x256_f64");
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("bulk_forces", |b| {
        b.iter(|| bulk_forces(&consts, &bonds, &p, 0.0, blocks, black_box(&mut force), 0))
    });
    let ns = consts.junction_count;
    let mut spring = vec![
        JunctionSpring {
            anchor: 0.0,
            stiffness: 1e5
        };
        m.nx * ns
    ];
    let mut state = vec![[PINNED, 0u32]; m.nx * ns];
    g.throughput(Throughput::Elements((m.nx * ns) as u64));
    g.bench_function("junctions", |b| {
        b.iter(|| {
            for ix in 0..m.nx {
                let s = ix * ns..(ix + 1) * ns;
                let slots = JunctionSlots {
                    spring: &mut spring[s.clone()],
                    state: &mut state[s],
                };
                black_box(junctions(&consts, &p, ix, disp[ix], vel[ix], 0.0, slots));
            }
        })
    });
    let mut u = disp.clone();
    let mut v = vel.clone();
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("verlet", |b| {
        b.iter(|| {
            for i in 0..n {
                black_box(verlet(
                    &consts, &p, flags[i], force[i], 0.0, &mut u[i], &mut v[i], 1e3,
                ));
            }
        })
    });
    g.finish();
}

criterion_group!(benches, kernels);
criterion_main!(benches);
