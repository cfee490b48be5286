//! What the host pays to write a large lattice's interface samples, per
//! message, at 1024 columns: the output target's lattice (1024×512), where
//! the fast cadence makes a sample due every 4–5 steps. The runner builds
//! and encodes each `/interface` message; the writing thread compresses
//! and writes it (`io::output::writer`). On the H200 (BENCHMARKS.md,
//! session 50) the output added about 86 µs a sample in f32 and f64
//! alike, which points at these host costs rather than the kernels.
//! The runner's part is timed with its encoder (each array copied whole,
//! `io::output::packed`) and with prost's, which it replaced; each message
//! is dropped once built, as the writing thread frees it once written.
//! The writing thread is timed with the run file's chunks
//! (`io::output::CHUNK_BYTES`, several zstd jobs each), with chunks of
//! 1 MB (one job each: the layout until session 51), and uncompressed.
//! Needs no GPU.
//!
//! `cargo bench --bench output_writer [-- MESSAGES [ROWS.mcap]]`: MESSAGES
//! messages (default 3000), built from the interface rows of ROWS.mcap
//! (cycled) or else from made-up rows of a slipping interface (smooth
//! stresses with noise, pinned fractions in steps of 1/100, noisy slip
//! speeds; they compress about as little as a driven run's). Prints a
//! Markdown table (BENCHMARKS.md).

use prost::Message;
use slipfront::engines::InterfaceRow;
use slipfront::io::output::reader::RunFile;
use slipfront::io::output::records::{Record, RecordBuilder, Topic};
use slipfront::io::output::{ChunkCompression, ChunkLayout, McapSink, CHUNK_BYTES};
use slipfront::Model;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[path = "support/bench_scene.rs"]
#[allow(dead_code)] // this bench builds its scene from the scenario
mod bench_scene;

const COLUMNS: u32 = 1024;

/// A record's protobuf bytes.
type Encoder = fn(&Record) -> Vec<u8>;

/// A small deterministic generator (xorshift), so that runs compare.
struct Noise(u64);

impl Noise {
    /// Uniform in [-1, 1).
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// `count` made-up rows of a slipping interface of `n` blocks.
fn made_up_rows(n: usize, count: usize) -> Vec<InterfaceRow> {
    let mut noise = Noise(0x9e37_79b9_7f4a_7c15);
    let mut ux: Vec<f64> = (0..n).map(|i| 1e-7 * i as f64).collect();
    (0..count)
        .map(|s| {
            let phase = s as f64 * 1e-3;
            for u in ux.iter_mut() {
                *u += 1e-9 * (1.0 + noise.next());
            }
            InterfaceRow {
                ux: ux.clone(),
                friction: (0..n)
                    .map(|i| {
                        -20.0 * (1.0 + 0.1 * ((i as f64) / 50.0 + phase).sin())
                            + 0.01 * noise.next()
                    })
                    .collect(),
                normal: (0..n)
                    .map(|i| 34.0 * (1.0 + 0.05 * ((i as f64) / 70.0).cos()) + 0.005 * noise.next())
                    .collect(),
                pinned_fraction: (0..n)
                    .map(|_| ((90.0 + 10.0 * noise.next()).round() / 100.0).min(1.0))
                    .collect(),
                slip_speed: (0..n).map(|_| 1e-3 * noise.next().abs()).collect(),
            }
        })
        .collect()
}

/// The interface rows of a run file, as the runner's rows (the stresses
/// back to forces, the slip to displacements from zero).
fn rows_of(path: &Path, model: &Model) -> Vec<InterfaceRow> {
    let file = RunFile::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let area = model.spacing * model.width;
    file.interface
        .iter()
        .map(|m| InterfaceRow {
            ux: m.slip.clone(),
            friction: m.shear_stress.iter().map(|s| -s * area).collect(),
            normal: m.normal_stress.iter().map(|p| p * area).collect(),
            pinned_fraction: m.pinned_fraction.clone(),
            slip_speed: m.slip_speed.clone(),
        })
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let messages: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(3000);
    let scenario = bench_scene::scenario(COLUMNS, 512, &[]);
    let model = Model::from_scenario(&scenario, false).expect("bench model");
    let (rows, source) = match args.get(1) {
        Some(p) => {
            let path = PathBuf::from(p);
            (
                rows_of(&path, &model),
                format!("the rows of {}", path.display()),
            )
        }
        None => (
            made_up_rows(model.nx, 256),
            "made-up rows of a slipping interface".to_string(),
        ),
    };
    assert!(!rows.is_empty(), "no interface rows");
    assert!(
        rows.iter().all(|r| r.ux.len() == model.nx),
        "rows of {} columns expected",
        model.nx
    );

    // The runner's part: a record built and encoded per sample, then
    // handed off; dropped here, as the writing thread frees each message
    // once written, so the runner's allocations reuse memory. (Keeping all
    // of them, as this bench did until session 51, timed the kernel's
    // first touch of each new page: 22 µs a message against 3.5–7.)
    let dt = model.dt;
    let build = |builder: &mut RecordBuilder, k: usize| {
        let step = 4 * k as u64;
        builder.interface(&model, step, step as f64 * dt, &rows[k % rows.len()])
    };
    // The runner's encoder (arrays copied whole), and prost's (a value at
    // a time, until session 51): the same bytes.
    let encoders: [(&str, Encoder); 2] = [
        ("build and encode", Record::encode),
        ("build and encode with prost's encoder", |r| match r {
            Record::Interface(m) => m.encode_to_vec(),
            _ => unreachable!("interface records only"),
        }),
    ];
    let mut runner = Vec::new();
    let mut bytes = 0;
    for (name, encoder) in encoders {
        let mut builder = RecordBuilder::default();
        let t0 = Instant::now();
        bytes = 0;
        for k in 0..messages {
            bytes += std::hint::black_box(encoder(&build(&mut builder, k))).len();
        }
        runner.push((name, t0.elapsed().as_secs_f64()));
    }
    // The messages the writing thread is timed on, built again untimed.
    let mut builder = RecordBuilder::default();
    let encoded: Vec<Vec<u8>> = (0..messages)
        .map(|k| build(&mut builder, k).encode())
        .collect();

    println!(
        "{messages} `/interface` messages of {} columns, {:.1} KB each, from {source}\n",
        model.nx,
        bytes as f64 / messages as f64 / 1e3
    );
    println!("| part | µs a message | MB/s of messages | file |");
    println!("| --- | ---: | ---: | ---: |");
    for (name, seconds) in runner {
        println!(
            "| runner: {name} | {:.1} | {:.0} | |",
            seconds / messages as f64 * 1e6,
            bytes as f64 / seconds / 1e6
        );
    }
    let dir = std::env::temp_dir().join(format!("slipfront-output-writer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Chunks of 1 MB were the layout until session 51: one zstd job each.
    let one_job = 1 << 20;
    let layouts = [
        ("zstd (a kept file)", ChunkCompression::Zstd, CHUNK_BYTES),
        ("zstd, chunks of 1 MB", ChunkCompression::Zstd, one_job),
        (
            "uncompressed (a sweep's scratch file)",
            ChunkCompression::None,
            CHUNK_BYTES,
        ),
    ];
    for (name, compression, chunk_bytes) in layouts {
        let layout = ChunkLayout {
            compression,
            bytes: chunk_bytes,
        };
        let path = dir.join("run.mcap");
        let _ = std::fs::remove_file(&path);
        // The runner hands the sink messages it owns: copied before the clock.
        let messages_owned = encoded.clone();
        let t0 = Instant::now();
        let mut sink =
            McapSink::create(&path, &model, &scenario, "bench", &[], layout).expect("run file");
        for (k, data) in messages_owned.into_iter().enumerate() {
            let step = 4 * k as u64;
            sink.write(Topic::Interface, step as f64 * dt, data)
                .expect("write");
        }
        sink.finish(None).expect("finish");
        let s = t0.elapsed().as_secs_f64();
        let size = std::fs::metadata(&path).map_or(0, |m| m.len());
        println!(
            "| writing thread: {name}, to the file closed | {:.1} | {:.0} | {:.1} MB ({:.2}×) |",
            s / messages as f64 * 1e6,
            bytes as f64 / s / 1e6,
            size as f64 / 1e6,
            bytes as f64 / size.max(1) as f64
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
