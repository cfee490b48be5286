//! A sweep table read back as the outcomes of its runs, for comparing
//! ensembles: the rows with status ok, parsed, and how many rows of each
//! other status were left out.

use super::table::split;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What `compare` reads of one run's row.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunOutcomes {
    /// None: no full event in the run.
    pub first_full_time_s: Option<f64>,
    pub first_full_drive_ratio: Option<f64>,
    pub events: u64,
    pub full_events: u64,
    pub precursors: u64,
    pub precursor_lengths_m: Vec<f64>,
    /// None: no precursor.
    pub precursor_max_length_m: Option<f64>,
    /// None: no event.
    pub mean_slip_m: Option<f64>,
    /// Columns later tables have (None where a table lacks them): the
    /// first event's start and length (None: no event), the median slow
    /// front speed and slip speed behind the tip (None: no slow front).
    pub first_event_time_s: Option<f64>,
    pub first_event_length_m: Option<f64>,
    pub slow_front_speed_m_per_s: Option<f64>,
    pub slow_slip_speed_m_per_s: Option<f64>,
    /// The run's relative perturbation (a `perturb(KEY)` column), if the
    /// sweep had one.
    pub perturbation: Option<f64>,
}

/// The ok runs of one sweep table.
#[derive(Debug, Clone)]
pub struct Ensemble {
    /// The table read.
    pub path: PathBuf,
    pub runs: Vec<RunOutcomes>,
    /// Rows left out, by status (`blew_up`, `failed`, ...; `incomplete`
    /// for a line with the wrong number of fields).
    pub dropped: BTreeMap<String, usize>,
}

/// The columns read besides the status.
const NEEDED: [&str; 8] = [
    "first_full_time_s",
    "first_full_drive_ratio",
    "events",
    "full_events",
    "precursors",
    "precursor_lengths_m",
    "precursor_max_length_m",
    "mean_slip_m",
];

/// Columns read where a table has them (older tables do not).
const OPTIONAL: [&str; 4] = [
    "first_event_time_s",
    "first_event_length_m",
    "slow_front_speed_m_per_s",
    "slow_slip_speed_m_per_s",
];

/// `path`'s table: `path/summary.csv` for a folder, else the file itself.
pub fn table_file(path: &Path) -> PathBuf {
    if path.is_dir() {
        path.join("summary.csv")
    } else {
        path.to_path_buf()
    }
}

/// Reads the ok rows of the sweep table at `path` (a sweep folder or a
/// CSV file). Errors name the file: missing or unreadable, a header
/// without the outcome columns, a field that is not a number, no ok row.
pub fn read_ensemble(path: &Path) -> Result<Ensemble, String> {
    let file = table_file(path);
    let text = std::fs::read_to_string(&file).map_err(|e| {
        format!(
            "cannot read the sweep table `{}`: {e} (give a sweep folder holding summary.csv, \
             or a .csv file)",
            file.display()
        )
    })?;
    let mut lines = text.lines();
    let header = split(lines.next().unwrap_or_default());
    let column = |name: &str| {
        header.iter().position(|h| h == name).ok_or_else(|| {
            format!(
                "`{}` is not a sweep table: it has no column `{name}` (columns: {})",
                file.display(),
                header.join(", ")
            )
        })
    };
    let status = column("status")?;
    let columns: Vec<usize> = NEEDED.iter().map(|n| column(n)).collect::<Result<_, _>>()?;
    let perturbation = header.iter().position(|h| h.starts_with("perturb("));
    let optional: Vec<Option<usize>> = OPTIONAL
        .iter()
        .map(|n| header.iter().position(|h| h == n))
        .collect();
    let mut runs = Vec::new();
    let mut dropped = BTreeMap::new();
    for (k, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let fields = split(line);
        let kind = if fields.len() != header.len() {
            "incomplete".to_string()
        } else if fields[status] != "ok" {
            fields[status].clone()
        } else {
            let needed: Vec<&str> = columns.iter().map(|&c| fields[c].as_str()).collect();
            let mut row = parse_row(&needed)
                .map_err(|e| format!("`{}` line {}: {e}", file.display(), k + 2))?;
            row.perturbation = perturbation.and_then(|c| fields[c].trim().parse::<f64>().ok());
            let value = |o: usize| -> Result<Option<f64>, String> {
                let Some(c) = optional[o] else {
                    return Ok(None);
                };
                let s = fields[c].trim();
                match s.parse::<f64>() {
                    _ if s.is_empty() => Ok(None),
                    Ok(v) if v.is_finite() => Ok(Some(v)),
                    _ => Err(format!(
                        "`{}` line {}: {} = `{s}` is not a finite number",
                        file.display(),
                        k + 2,
                        OPTIONAL[o]
                    )),
                }
            };
            row.first_event_time_s = value(0)?;
            row.first_event_length_m = value(1)?;
            row.slow_front_speed_m_per_s = value(2)?;
            row.slow_slip_speed_m_per_s = value(3)?;
            runs.push(row);
            continue;
        };
        *dropped.entry(kind).or_insert(0) += 1;
    }
    if runs.is_empty() {
        let left_out: Vec<String> = dropped.iter().map(|(s, n)| format!("{n} {s}")).collect();
        return Err(format!(
            "`{}` has no row with status ok ({})",
            file.display(),
            if left_out.is_empty() {
                "no rows at all".to_string()
            } else {
                left_out.join(", ")
            }
        ));
    }
    Ok(Ensemble {
        path: file,
        runs,
        dropped,
    })
}

/// One ok row from its fields in `NEEDED` order.
fn parse_row(fields: &[&str]) -> Result<RunOutcomes, String> {
    let at = |c: usize| fields[c];
    let number = |c: usize| -> Result<Option<f64>, String> {
        let s = at(c).trim();
        if s.is_empty() {
            return Ok(None);
        }
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(format!("{} = `{s}` is not a finite number", NEEDED[c])),
        }
    };
    let count = |c: usize| -> Result<u64, String> {
        at(c)
            .trim()
            .parse::<u64>()
            .map_err(|_| format!("{} = `{}` is not a count", NEEDED[c], at(c)))
    };
    let lengths = at(5)
        .split(';')
        .filter(|s| !s.trim().is_empty())
        .map(|s| match s.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(format!(
                "precursor_lengths_m holds `{s}`, not a finite number"
            )),
        })
        .collect::<Result<Vec<f64>, String>>()?;
    Ok(RunOutcomes {
        first_full_time_s: number(0)?,
        first_full_drive_ratio: number(1)?,
        events: count(2)?,
        full_events: count(3)?,
        precursors: count(4)?,
        precursor_lengths_m: lengths,
        precursor_max_length_m: number(6)?,
        mean_slip_m: number(7)?,
        ..RunOutcomes::default()
    })
}
