use slipfront::app::verify::run_all_reporting;
use slipfront::engines::backend::{make_engine, Backend, Precision};
use std::process::ExitCode;

pub fn verify(
    backend: Backend,
    precision: Option<Precision>,
    json: bool,
) -> anyhow::Result<ExitCode> {
    // The GPU defaults to mixed f32 (f64 where asked and the adapter has
    // it), the CPU to f64.
    let precision = precision.unwrap_or(backend.default_precision());
    let probe =
        slipfront::Model::from_scenario(&slipfront::app::verify::bare_scene("probe"), true)?;
    let engine = make_engine(&probe, backend, precision, 0)?.describe();
    eprintln!("verify: on {engine}");
    let factory = |m: &slipfront::Model| make_engine(m, backend, precision, 0);
    let results = run_all_reporting(&factory, &mut |group, seconds| {
        eprintln!("verify: {group} done in {seconds:.1} s")
    })?;
    if json {
        println!("{}", serde_json::to_string_pretty(&results)?);
    } else {
        let name = results
            .iter()
            .map(|r| r.name.chars().count())
            .max()
            .unwrap_or(4);
        let unit = results
            .iter()
            .map(|r| r.unit.chars().count())
            .max()
            .unwrap_or(4);
        let need = results
            .iter()
            .map(|r| r.requirement().chars().count())
            .max()
            .unwrap_or(8);
        println!(
            "{:<name$}  {:>14}  {:<need$}  {:<unit$}  result",
            "case", "measured", "required", "unit"
        );
        for r in &results {
            println!(
                "{:<name$}  {:>14.6e}  {:<need$}  {:<unit$}  {}",
                r.name,
                r.measured,
                r.requirement(),
                r.unit,
                if r.pass { "pass" } else { "FAIL" }
            );
        }
    }
    let failed = results.iter().filter(|r| !r.pass).count();
    if failed > 0 {
        eprintln!("{failed} of {} cases failed", results.len());
        return Ok(ExitCode::FAILURE);
    }
    Ok(ExitCode::SUCCESS)
}
