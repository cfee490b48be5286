use super::printable;
use slipfront::analysis::event_table::{event_rows, EventRow};
use slipfront::analysis::events::{Event, InterfaceSeries, FRONT_WINDOW};
use slipfront::analysis::precursors::PrecursorSequence;
use slipfront::io::output::reader::RunFile;
use std::path::Path;
use std::process::ExitCode;

pub fn info(path: &Path, quiet_gap: f64) -> anyhow::Result<ExitCode> {
    let run = RunFile::read(path)?;
    println!("file        {}", path.display());
    match (&run.damage, run.truncated) {
        (Some(why), _) => println!("            (DAMAGED: {why})"),
        (None, true) => {
            println!("            (cut short: no summary; everything before the cut is read)")
        }
        (None, false) => {}
    }
    let width = run
        .metadata
        .keys()
        .map(String::len)
        .max()
        .unwrap_or(0)
        .max(11)
        + 1;
    for (k, v) in &run.metadata {
        println!("{:<width$}{}{}", printable(k), printable(v), unit(k));
    }
    if !run.history.is_empty() {
        println!("history");
        for line in &run.history {
            println!("  {}", printable(line));
        }
    }
    let checkpoint = slipfront::io::checkpoint::path_for(path);
    if let Ok(c) = slipfront::io::checkpoint::Checkpoint::read(&checkpoint) {
        println!(
            "checkpoint  {} at step {} (t = {:.6e} s), by {}; continue with slipfront run \
             --resume {}",
            checkpoint.display(),
            c.header.step,
            c.header.time,
            c.header.backend,
            path.display()
        );
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
    let events = series.events_separated_by(quiet_gap);
    println!(
        "events      {} found (a block counts as slipping below half its junctions pinned; \
         ruptures less than {quiet_gap:e} s apart are one event)",
        events.len()
    );
    let ratio_at = |t: f64| run.drive_ratio_at(t);
    println!("  #    start (s)     end (s)       kind     length (m)  from (m)    slip (m)    F/F_N   front           v_front (m/s) min..max");
    for (n, e) in events.iter().enumerate() {
        let row = EventRow::new(&series, e, ratio_at(e.start));
        println!(
            "  {n:<4} {:<13.6e} {:<13.6e} {:<8} {:<11.4e} {:<11.4e} {:<11.4e} {:<7.4} {:<15} {}",
            e.start,
            e.end,
            row.kind,
            e.rupture_length,
            row.origin,
            e.slip,
            row.drive_ratio,
            row.front,
            row.speed_range()
        );
    }
    print_precursors(
        &PrecursorSequence::from_events(&events, series.spacing, |e| ratio_at(e.start)),
        series.spacing,
    );
    print_sequence(&series, &events);
    let pairs = series.slip_front_pairs(&events, FRONT_WINDOW);
    if let Some(fit) = slipfront::analysis::events::slip_front_relation(&pairs) {
        println!(
            "slip speed vs front speed: v_slip = {:.3e} v_front; fitted v_slip ∝ v_front^{:.2} (1: proportional), log-log correlation {:.3}, {} crossings",
            fit.alpha, fit.exponent, fit.correlation, fit.points
        );
        println!("  front speed decade   count   median v_front   median v_slip   ratio");
        for (decade, n, f, s) in slipfront::analysis::events::slip_front_by_decade(&pairs) {
            println!(
                "  {decade:<9.0e} m/s      {n:<7} {f:<16.3e} {s:<15.3e} {:.2e}",
                s / f
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// The event sequence as PNAS 2014 reads it: front kinds, whether partial
/// and full events alternate, and whether each slow-to-fast transition
/// starts where the event before it arrested.
fn print_sequence(series: &InterfaceSeries, events: &[Event]) {
    if events.is_empty() {
        return;
    }
    let mut kinds = std::collections::BTreeMap::new();
    for e in events {
        *kinds
            .entry(format!("{:?}", series.front_kind(e, FRONT_WINDOW)))
            .or_insert(0usize) += 1;
    }
    let kinds: Vec<String> = kinds.iter().map(|(k, n)| format!("{n} {k}")).collect();
    let pattern: String = events
        .iter()
        .map(|e| if e.full { 'F' } else { 'p' })
        .collect();
    let changes = pattern
        .as_bytes()
        .windows(2)
        .filter(|w| w[0] != w[1])
        .count();
    println!(
        "sequence    fronts: {}; partial (p) and full (F): {pattern} ({changes} changes in {} \
         neighbours)",
        kinds.join(", "),
        events.len().saturating_sub(1)
    );
    for (n, x, before) in series.transitions_at_previous_arrest(events, FRONT_WINDOW) {
        match before {
            Some(a) => println!(
                "  event {n}: slow to fast at x = {x:.4e} m; the last trailing-edge \
                 precursor arrested at {a:.4e} m ({:+.1} mm)",
                1e3 * (x - a)
            ),
            None => println!(
                "  event {n}: slow to fast at x = {x:.4e} m (no trailing-edge precursor since \
                 the last full event)"
            ),
        }
    }
}

/// The event table as CSV (one row per event).
pub fn events_csv(path: &Path, quiet_gap: f64) -> anyhow::Result<ExitCode> {
    let run = RunFile::read(path)?;
    let series = run.interface_series();
    println!(
        "event,start_s,end_s,kind,rupture_length_m,origin_m,mean_slip_m,drive_ratio,front,\
         v_front_min_m_per_s,v_front_max_m_per_s,v_front_unresolved_at_least_m_per_s"
    );
    let rows = event_rows(&series, quiet_gap, |t| run.drive_ratio_at(t));
    for (n, (e, row)) in rows.iter().enumerate() {
        let (lo, hi) = row.speeds.map_or((String::new(), String::new()), |(a, b)| {
            (format!("{a:e}"), format!("{b:e}"))
        });
        println!(
            "{n},{:e},{:e},{},{:e},{:e},{:e},{},{},{lo},{hi},{}",
            e.start,
            e.end,
            row.kind,
            e.rupture_length,
            row.origin,
            e.slip,
            row.drive_ratio,
            row.front,
            row.bound.map_or(String::new(), |b| format!("{b:e}"))
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The unit of a metadata value.
fn unit(key: &str) -> &'static str {
    match key {
        "dt" => " s",
        "spacing" => " m",
        "normal_force" => " N",
        _ => "",
    }
}

/// The precursors before the first full event and whether they grow.
fn print_precursors(seq: &PrecursorSequence, spacing: f64) {
    let list = |p: &[slipfront::analysis::precursors::Precursor]| {
        p.iter()
            .map(|p| {
                format!(
                    "{:.1} mm at {:.3}{}",
                    p.length * 1e3,
                    p.drive_ratio,
                    if !p.at_trailing_edge(spacing) {
                        format!(" (from x = {:.1} mm)", p.origin * 1e3)
                    } else {
                        String::new()
                    }
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let extended = seq.extended(spacing);
    let trailing = seq.from_trailing_edge(spacing);
    match seq.first_full_ratio {
        Some(r) => println!(
            "precursors  {} before the first full event (at F/F_N {r:.4}), {} longer than one block, {} of them from the trailing edge",
            seq.precursors.len(),
            extended.len(),
            trailing.len()
        ),
        None => println!(
            "precursors  {} partial events and no full event, {} longer than one block, {} of them from the trailing edge",
            seq.precursors.len(),
            extended.len(),
            trailing.len()
        ),
    }
    if !extended.is_empty() {
        println!("  lengths against F/F_N: {}", list(&extended));
    }
    if let Some(r) = PrecursorSequence::growth(&trailing) {
        println!(
            "  growth: rank correlation of length with F/F_N {r:.2} over those from the trailing edge (+1: each longer than the last)"
        );
    }
}
