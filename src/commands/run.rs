use slipfront::backend::{make_engine_with, Backend, Precision};
use slipfront::gpu::{GpuOptions, GpuPath};
use slipfront::model::Model;
use slipfront::runner::{run_scene, RunOptions};
use std::path::PathBuf;
use std::process::ExitCode;

pub struct RunArgs {
    pub scenario: Option<PathBuf>,
    pub backend: Backend,
    pub gpu_path: GpuPath,
    pub precision: Option<Precision>,
    pub set: Vec<String>,
    pub t_end: Option<f64>,
    pub fast_forward: Option<bool>,
    pub output: Option<PathBuf>,
    pub threads: usize,
    pub allow_unstable: bool,
    pub quiet: bool,
}

pub fn run(a: RunArgs) -> anyhow::Result<ExitCode> {
    let mut set = a.set.clone();
    if let Some(t) = a.t_end {
        set.push(format!("time.end={t:e}"));
    }
    if let Some(on) = a.fast_forward {
        set.push(format!("time.fast_forward={on}"));
    }
    let (scenario, name) = super::load_scenario(a.scenario.as_deref(), &set)?;
    let model = Model::from_scenario(&scenario, a.allow_unstable)?;
    let precision = a.precision.unwrap_or(match a.backend {
        Backend::Cpu | Backend::CpuReference => Precision::F64,
        _ => Precision::F32,
    });
    let gpu = GpuOptions {
        path: a.gpu_path,
        ..GpuOptions::default()
    };
    let mut engine = make_engine_with(&model, a.backend, precision, a.threads, gpu)?;
    eprintln!("slipfront: {name} on {}", engine.describe());
    let summary = run_scene(
        engine.as_mut(),
        &scenario,
        &RunOptions {
            fast_forward: None,
            output: a.output.clone(),
            progress: !a.quiet,
        },
    )?;
    println!("{summary}");
    Ok(ExitCode::SUCCESS)
}
