use slipfront::output::reader::RunFile;
use std::path::Path;
use std::process::ExitCode;

pub fn info(path: &Path) -> anyhow::Result<ExitCode> {
    let run = RunFile::read(path)?;
    println!("file        {}", path.display());
    if run.truncated {
        println!("            (cut short: no summary; everything before the cut is read)");
    }
    for (k, v) in &run.metadata {
        println!("{k:<12}{v}");
    }
    let span = |t: &[f64]| match (t.first(), t.last()) {
        (Some(a), Some(b)) => format!("{a:.6e} .. {b:.6e} s"),
        _ => "empty".into(),
    };
    let g: Vec<f64> = run.global.iter().map(|m| m.time).collect();
    let i: Vec<f64> = run.interface.iter().map(|m| m.time).collect();
    let b: Vec<f64> = run.bulk.iter().map(|m| m.time).collect();
    println!("channels");
    println!("  /global     {:>8} messages, {}", g.len(), span(&g));
    println!("  /interface  {:>8} messages, {}", i.len(), span(&i));
    println!("  /bulk       {:>8} messages, {}", b.len(), span(&b));
    let series = run.interface_series();
    let events = series.events();
    println!(
        "events      {} found (a block counts as slipping below half its junctions pinned)",
        events.len()
    );
    for (n, e) in events.iter().enumerate() {
        println!(
            "  {n:>3}  {:.6e} .. {:.6e} s  {:<7}  length {:.4e} m  slip {:.4e} m",
            e.start,
            e.end,
            if e.full { "full" } else { "partial" },
            e.rupture_length,
            e.slip
        );
    }
    Ok(ExitCode::SUCCESS)
}
