//! Timing shared by the GPU benches: wall time per step after a warm-up
//! over at least a given span, with the host's CPU time of the same span;
//! one scene alone past its normal-load phase; a run with and without an
//! output file; the Table S1 scene.
// Each bench uses a part.
#![allow(dead_code)]

use super::thread_cpu;
use slipfront::app::runner::{run_scene, ProgressMode, RunOptions};
use slipfront::engines::gpu::ensemble::GpuEnsemble;
use slipfront::engines::gpu::{GpuEngine, GpuOptions, GpuOutput, GpuReal};
use slipfront::model::scenario::built_in;
use slipfront::{advance_to, Engine, EngineError, Model, Scenario};
use std::time::Instant;

/// CPU seconds used so far by every thread of this process (the driver's
/// included).
pub fn process_cpu_seconds() -> f64 {
    cpu_seconds(libc::CLOCK_PROCESS_CPUTIME_ID)
}

/// CPU seconds used so far by the calling thread alone.
pub fn thread_cpu_seconds() -> f64 {
    cpu_seconds(libc::CLOCK_THREAD_CPUTIME_ID)
}

fn cpu_seconds(clock: libc::clockid_t) -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes the timespec it is given.
    unsafe { libc::clock_gettime(clock, &mut t) };
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

/// Wall seconds of `advance(steps)` calls, doubling `steps` until one takes
/// at least `min_seconds`: (seconds, steps) of that last one.
pub fn timed_advance(
    advance: impl FnMut(u64) -> Result<(), EngineError>,
    min_seconds: f64,
) -> Result<(f64, u64), EngineError> {
    timed_with_cpu(advance, min_seconds).map(|t| (t.0, t.1))
}

/// As `timed_advance`, with the host CPU seconds of the same span: a
/// share of the wall time near 1 (or above, with threads) says the host
/// is the limit; near 0, the device (on a hardware adapter).
pub fn timed_with_cpu(
    mut advance: impl FnMut(u64) -> Result<(), EngineError>,
    min_seconds: f64,
) -> Result<(f64, u64, f64), EngineError> {
    let mut steps = 16u64;
    loop {
        let (t0, cpu0) = (Instant::now(), process_cpu_seconds());
        advance(steps)?;
        let dt = t0.elapsed().as_secs_f64();
        let cpu = process_cpu_seconds() - cpu0;
        if dt >= min_seconds || steps >= 1 << 24 {
            return Ok((dt, steps, cpu));
        }
        steps *= if dt < min_seconds / 8.0 { 8 } else { 2 };
    }
}

/// One timed run (`output_run`): its wall time, engine, CPU seconds per wall
/// second, per thread, device busy time and, when timed, its dispatches.
#[derive(Debug)]
pub struct Timed {
    pub wall: f64,
    pub how: String,
    pub cpu: f64,
    pub threads: String,
    pub device: Option<f64>,
    pub dispatches: Option<slipfront::engines::gpu::DispatchTimes>,
    /// The output samples planned on the device and those it computed.
    pub samples: Option<slipfront::engines::PlannedAndComputed>,
}

impl Timed {
    /// "N planned, M computed" (the device's samples), or "none".
    pub fn samples_text(&self) -> String {
        self.samples.map_or("none".into(), |s| s.to_string())
    }
}

/// One run of a scenario (`gpu_table`'s section 4) in precision `T` with device records,
/// timed from the end of its normal-load phase: with an output file at
/// `output` or none, running ahead by `run_ahead` batches, and with
/// `time_dispatches` its dispatches timed one by one (timestamps inside
/// the pass, which add a little device time) for the split of its device
/// time.
pub fn output_run<T: GpuReal>(
    scenario: &Scenario,
    output: Option<&std::path::Path>,
    run_ahead: usize,
    time_dispatches: bool,
) -> Result<Timed, String> {
    let model = Model::from_scenario(scenario, false).map_err(|e| e.to_string())?;
    let opts = GpuOptions {
        output: GpuOutput::Device,
        run_ahead,
        ..GpuOptions::default()
    };
    let mut e = GpuEngine::<T>::with_precision(&model, opts).map_err(|e| e.to_string())?;
    advance_to(&mut e, model.prep_steps).map_err(|e| e.to_string())?;
    if time_dispatches && !e.time_each_dispatch().map_err(|e| e.to_string())? {
        return Err("no timestamps inside passes".into());
    }
    if let Some(p) = output {
        let _ = std::fs::remove_file(p);
        let _ = std::fs::remove_file(slipfront::io::checkpoint::path_for(p));
    }
    let run = RunOptions {
        output: output.map(|p| p.to_path_buf()),
        progress: ProgressMode::None,
        ..RunOptions::default()
    };
    let threads = thread_cpu::ThreadCpu::start();
    let device0 = e.device_seconds();
    let (t0, cpu0) = (Instant::now(), process_cpu_seconds());
    run_scene(&mut e, scenario, &run).map_err(|e| e.to_string())?;
    let device = e.device_seconds().zip(device0).map(|(b, a)| b - a);
    let wall = t0.elapsed().as_secs_f64();
    let cpu = (process_cpu_seconds() - cpu0) / wall;
    let threads = thread_cpu::per_wall(&threads.finish(), wall);
    let megabytes = output
        .and_then(|p| std::fs::metadata(p).ok())
        .map_or(String::new(), |m| {
            format!("; file {:.1} MB", m.len() as f64 / 1e6)
        });
    Ok(Timed {
        wall,
        how: e.describe(),
        cpu,
        threads: format!("{threads}{megabytes}"),
        device,
        dispatches: e.dispatch_times(),
        samples: e.device_samples(),
    })
}

/// Seconds per step of `kernel` on `model` alone, past its normal-load
/// phase, and the host CPU seconds per wall second of the same span.
pub fn solo_step_seconds(
    model: &Model,
    opts: GpuOptions,
    min_seconds: f64,
) -> Result<(f64, f64), String> {
    solo_step_seconds_in::<f32>(model, opts, min_seconds)
}

/// `solo_step_seconds` in precision `T` (f64 fails on an adapter without
/// f64 shaders, with that reason). With `opts.samples` the engine records
/// its samples on the device at those cadences, as a run with an output
/// file does, and drops them (an error where it cannot).
pub fn solo_step_seconds_in<T: GpuReal>(
    model: &Model,
    opts: GpuOptions,
    min_seconds: f64,
) -> Result<(f64, f64), String> {
    solo_step_figures_in::<T>(model, opts, min_seconds).map(|f| (f.seconds, f.host))
}

/// A launch's step timed: its wall seconds, the host's CPU seconds a wall
/// second, and the device's busy seconds a step (its passes' timestamps;
/// None where the adapter has none). Busy near the wall time says the
/// device sets the pace; well under it, the host does (a host CPU share
/// near 1 can also be a driver spinning in its wait).
#[derive(Debug, Clone, Copy)]
pub struct StepFigures {
    pub seconds: f64,
    pub host: f64,
    pub device: Option<f64>,
}

/// `solo_step_seconds_in`, with the device's busy time of the same span.
pub fn solo_step_figures_in<T: GpuReal>(
    model: &Model,
    opts: GpuOptions,
    min_seconds: f64,
) -> Result<StepFigures, String> {
    let mut e = GpuEngine::<T>::with_precision(model, opts).map_err(|e| e.to_string())?;
    if let Some(plan) = opts.samples.as_ref() {
        if !e.record_samples(plan).map_err(|e| e.to_string())? {
            return Err("cannot record samples on the device".into());
        }
    }
    advance_to(&mut e, model.prep_steps + 16).map_err(|e| e.to_string())?;
    // The device's busy seconds of the last advance, the one timed (an
    // advance without running ahead returns with its batches retired).
    let mut busy = None;
    let (dt, steps, cpu) = timed_with_cpu(
        |n| {
            let before = e.device_seconds();
            let stepped = e.advance(n);
            e.take_samples();
            busy = e
                .device_seconds()
                .zip(before)
                .map(|(after, before)| after - before);
            stepped
        },
        min_seconds,
    )
    .map_err(|e| e.to_string())?;
    Ok(StepFigures {
        seconds: dt / steps as f64,
        host: cpu / dt,
        device: busy.map(|b| b / steps as f64),
    })
}

/// The precursors scene (Table S1, Ns = 100) with seed `seed`.
pub fn table_s1(seed: usize) -> Model {
    Model::from_scenario(&table_s1_scenario(seed), false).expect("model")
}

/// The scenario of `table_s1(seed)`.
pub fn table_s1_scenario(seed: usize) -> Scenario {
    let text = built_in("tromborg2014_precursors").expect("shipped scene");
    Scenario::parse(text, "table S1", &[format!("time.seed={seed}")]).expect("scene")
}

/// Seconds per step of the ensemble of `models` (one dispatch steps them
/// all) with `opts`, past their normal-load phase, and the host CPU
/// seconds per wall second of the same span.
pub fn ensemble_step_seconds(
    models: &[Model],
    opts: GpuOptions,
    min_seconds: f64,
) -> Result<(f64, f64), String> {
    ensemble_step_seconds_in::<f32>(models, opts, min_seconds)
}

/// `ensemble_step_seconds` in precision `T` (f64 fails on an adapter
/// without f64 shaders, with that reason).
pub fn ensemble_step_seconds_in<T: GpuReal>(
    models: &[Model],
    opts: GpuOptions,
    min_seconds: f64,
) -> Result<(f64, f64), String> {
    let mut e = GpuEnsemble::<T>::with_precision(models, opts).map_err(|e| e.to_string())?;
    e.advance(models[0].prep_steps + 16)
        .map_err(|e| e.to_string())?;
    let (dt, steps, cpu) =
        timed_with_cpu(|k| e.advance(k), min_seconds).map_err(|e| e.to_string())?;
    Ok((dt / steps as f64, cpu / dt))
}
