//! Work-precision study: run time against error for time steps T/10 … T/400,
//! CPU f64/f32 (and the GPU with SLIPFRONT_BENCH_GPU=1), for
//!   a. the P-wave speed against the lattice value (57 × 31),
//!   b. the single-block Amontons–Coulomb trajectory against the exact solution,
//!   c. the first full sliding event of a side-driven 29 × 16 lattice (time
//!      and loading-curve peak) against an f64 run at T/800.
//! Prints a Markdown table and writes log-log plots (error against run time;
//! SVG or PNG by extension) to the path given by SLIPFRONT_PLOT (default
//! work_precision.svg). SLIPFRONT_REPLOT=CSV redraws them from saved data.

use slipfront::app::observables::{first_full_sliding, FirstEvent};
use slipfront::app::verify::{coulomb_ensemble_error, measure_wave_speed};
use slipfront::engines::backend::{make_engine, Backend, Precision};
use slipfront::model::scenario::Component;
use slipfront::{Engine, EngineError, Model};
use std::time::Instant;

const FRACTIONS: [f64; 6] = [0.1, 0.05, 0.02, 0.01, 0.005, 0.0025];

fn stick_slip_model(fraction: f64) -> Result<Model, String> {
    let dt = format!("time.dt_fraction={fraction}");
    let s = slipfront::app::verify::small_scene(&["loading.drive.velocity=0.04", &dt])
        .map_err(|e| e.to_string())?;
    Model::from_scenario(&s, false).map_err(|e| e.to_string())
}

fn first_event(engine: &mut dyn Engine) -> Result<FirstEvent, String> {
    first_full_sliding(engine, 0.05, 2e-6, 1e-3)
        .map_err(|e| e.to_string())?
        .ok_or_else(|| "no full sliding event".to_string())
}

use slipfront::analysis::plot::scatter::{WorkPoint as Point, WorkPrecision};

/// Points from a CSV written by an earlier run (observable,engine,fraction,seconds,error).
fn read_csv(path: &str) -> Vec<Point> {
    let observables = [
        "a. P-wave speed (relative)",
        "b. Coulomb block (mean |x − x_exact|)",
        "c. first full slip (time, peak; relative)",
    ];
    std::fs::read_to_string(path)
        .expect("csv")
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            Point {
                observable: observables
                    .iter()
                    .find(|o| o.starts_with(f[0]))
                    .expect("observable")
                    .to_string(),
                engine: f[1].to_string(),
                fraction: f[2].parse().unwrap(),
                seconds: f[3].parse().unwrap(),
                error: f[4].parse().unwrap(),
            }
        })
        .collect()
}

fn write_outputs(points: &[Point]) {
    let path = std::env::var("SLIPFRONT_PLOT").unwrap_or("work_precision.svg".into());
    let options = slipfront::analysis::plot::FigureOptions {
        format: slipfront::analysis::plot::Format::from_path(std::path::Path::new(&path))
            .expect("format"),
        width: 1350,
        height: 480,
        dpi: 100,
    };
    slipfront::analysis::plot::write(
        &WorkPrecision { points },
        std::path::Path::new(&path),
        &options,
        "cargo bench --bench work_precision",
    )
    .expect("write plot");
    let csv_path = std::path::Path::new(&path)
        .with_extension("csv")
        .display()
        .to_string();
    let mut csv = String::from("observable,engine,fraction,seconds,error\n");
    for p in points {
        csv += &format!(
            "{},{},{},{},{}\n",
            &p.observable[..2],
            p.engine,
            p.fraction,
            p.seconds,
            p.error
        );
    }
    std::fs::write(&csv_path, csv).expect("write csv");
    println!("plot: {path}, data: {csv_path}");
}

fn main() {
    if let Ok(csv) = std::env::var("SLIPFRONT_REPLOT") {
        write_outputs(&read_csv(&csv));
        return;
    }
    let mut engines = vec![
        (Backend::Cpu, Precision::F64),
        (Backend::Cpu, Precision::F32),
    ];
    if std::env::var("SLIPFRONT_BENCH_GPU").is_ok() {
        engines.push((Backend::Gpu, Precision::F32));
    }
    let reference = {
        let m = stick_slip_model(0.00125).expect("reference scene");
        let mut e = make_engine(&m, Backend::Cpu, Precision::F64, 1).unwrap();
        first_event(e.as_mut()).expect("reference event")
    };
    println!(
        "reference (cpu f64, T/800): first full sliding at {:.5e} s, peak F/F_N {:.5}, drop {:.5}",
        reference.time, reference.peak_ratio, reference.drop
    );
    println!("| observable | engine | dt | run time (s) | error |");
    println!("| --- | --- | ---: | ---: | ---: |");
    let mut points = Vec::new();
    for &(backend, precision) in &engines {
        let label = format!("{backend:?} {precision:?}").to_lowercase();
        let factory = |m: &Model| -> Result<Box<dyn Engine>, EngineError> {
            make_engine(m, backend, precision, 1)
        };
        for f in FRACTIONS {
            let mut record = |observable: &'static str,
                              result: Result<f64, String>,
                              seconds: f64,
                              unit: &str| {
                match result {
                    Ok(error) => {
                        println!("| {observable} | {label} | T/{:.0} | {seconds:.3} | {error:.3e} {unit} |", 1.0 / f);
                        points.push(Point {
                            observable: observable.to_string(),
                            engine: label.clone(),
                            fraction: f,
                            seconds,
                            error,
                        });
                    }
                    Err(why) => println!(
                        "| {observable} | {label} | T/{:.0} | | {} |",
                        1.0 / f,
                        why.lines()
                            .next()
                            .unwrap_or("")
                            .chars()
                            .take(90)
                            .collect::<String>()
                    ),
                }
            };
            let t = Instant::now();
            let r = measure_wave_speed(&factory, Component::X, 57, f)
                .map(|(c, c0)| ((c - c0) / c0).abs())
                .map_err(|e| e.to_string());
            record(
                "a. P-wave speed (relative)",
                r,
                t.elapsed().as_secs_f64(),
                "",
            );
            let t = Instant::now();
            let r = coulomb_ensemble_error(&factory, f).map_err(|e| e.to_string());
            record(
                "b. Coulomb block (mean |x − x_exact|)",
                r,
                t.elapsed().as_secs_f64(),
                "m",
            );
            let t = Instant::now();
            let r = stick_slip_model(f).and_then(|m| {
                let mut e = make_engine(&m, backend, precision, 1).map_err(|e| e.to_string())?;
                let ev = first_event(e.as_mut())?;
                Ok(((ev.time - reference.time) / reference.time)
                    .abs()
                    .max(((ev.peak_ratio - reference.peak_ratio) / reference.peak_ratio).abs()))
            });
            record(
                "c. first full slip (time, peak; relative)",
                r,
                t.elapsed().as_secs_f64(),
                "",
            );
        }
    }
    write_outputs(&points);
}
