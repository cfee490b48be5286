use slipfront::backend::{make_engine, Backend, Precision};
use slipfront::verify::run_all_reporting;
use std::process::ExitCode;

pub fn verify(backend: Backend, precision: Precision, json: bool) -> anyhow::Result<ExitCode> {
    let factory = |m: &slipfront::Model| make_engine(m, backend, precision, 0);
    let results = run_all_reporting(&factory, &mut |group, seconds| {
        eprintln!("verify: {group} done in {seconds:.1} s")
    })?;
    if json {
        println!("{}", serde_json::to_string_pretty(&results)?);
    } else {
        println!(
            "{:<44} {:>14} {:>14} {:>11} {:>6}  result",
            "case", "measured", "expected", "tolerance", "unit"
        );
        for r in &results {
            println!(
                "{:<44} {:>14.6e} {:>14.6e} {:>11.3e} {:>6}  {}",
                r.name,
                r.measured,
                r.expected,
                r.tolerance,
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
