//! The sweep's results table: one CSV row per run, appended and synced as
//! each run finishes (so a killed sweep keeps every finished row), read
//! back to skip finished points, and merged across shards.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Columns before the axes.
pub const LEAD: [&str; 3] = ["point", "id", "seed"];

/// Outcome columns after the axes.
pub const OUTCOMES: [&str; 25] = [
    "status",
    "message",
    "first_full_time_s",
    "first_full_drive_ratio",
    "events",
    "full_events",
    "precursors",
    "precursor_lengths_m",
    "precursor_max_length_m",
    "rupture_length_max_m",
    "front_speed_mean_m_per_s",
    "front_speed_max_m_per_s",
    "fronts_fast",
    "fronts_slow",
    "fronts_fast_slow",
    "fronts_fast_slow_fast",
    "mean_slip_m",
    "first_event_time_s",
    "first_event_length_m",
    "slow_front_speed_m_per_s",
    "slow_slip_speed_m_per_s",
    "first_front_class",
    "peak_drive_ratio",
    "steps",
    "wall_s",
];

/// The header of a sweep with these axes.
pub fn header(axes: &[String]) -> Vec<String> {
    LEAD.iter()
        .map(|s| s.to_string())
        .chain(axes.iter().cloned())
        .chain(OUTCOMES.iter().map(|s| s.to_string()))
        .collect()
}

/// A CSV field, quoted when it must be.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

pub fn line(fields: &[String]) -> String {
    let mut l = fields
        .iter()
        .map(|f| field(f))
        .collect::<Vec<_>>()
        .join(",");
    l.push('\n');
    l
}

/// Splits one CSV line (no trailing newline) into fields.
pub fn split(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            (c, _) => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// The complete rows of a table file by point index: lines that end with a
/// newline and have the header's field count (a line cut by a kill is
/// dropped). None when the file does not exist; an error when its header
/// is another sweep's.
pub fn read_rows(
    path: &Path,
    header: &[String],
) -> Result<Option<BTreeMap<usize, Vec<String>>>, String> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("cannot read `{}`: {e}", path.display())),
    };
    let mut lines = text.split_inclusive('\n');
    match lines.next() {
        Some(h) if h.ends_with('\n') && split(h.trim_end_matches('\n')) == header => {}
        Some(h) => {
            return Err(format!(
                "`{}` holds another sweep's table (header `{}`); use another output folder",
                path.display(),
                h.trim_end()
            ))
        }
        None => return Ok(Some(BTreeMap::new())),
    }
    let mut rows = BTreeMap::new();
    for l in lines.filter(|l| l.ends_with('\n')) {
        let f = split(l.trim_end_matches('\n'));
        if f.len() == header.len() {
            if let Ok(point) = f[0].parse::<usize>() {
                rows.insert(point, f);
            }
        }
    }
    Ok(Some(rows))
}

/// A table file rows are appended to, each synced to disk.
pub struct Appender {
    file: std::fs::File,
    pub path: PathBuf,
}

impl Appender {
    /// Opens `path` for appending, writing the header if it is new; a last
    /// line cut by a kill is cut off first so that rows stay whole.
    pub fn open(path: &Path, header: &[String]) -> Result<Appender, String> {
        let io = |e: std::io::Error| format!("`{}`: {e}", path.display());
        if path.exists() {
            let text = std::fs::read(path).map_err(io)?;
            let whole = text.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
            if whole < text.len() {
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(io)?;
                f.set_len(whole as u64).map_err(io)?;
            }
        }
        let fresh = !path.exists() || std::fs::metadata(path).map_err(io)?.len() == 0;
        let mut file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(io)?;
        if fresh {
            file.write_all(line(header).as_bytes()).map_err(io)?;
            file.sync_data().map_err(io)?;
        }
        Ok(Appender {
            file,
            path: path.to_path_buf(),
        })
    }

    pub fn append(&mut self, row: &[String]) -> Result<(), String> {
        let io = |e: std::io::Error| format!("`{}`: {e}", self.path.display());
        self.file.write_all(line(row).as_bytes()).map_err(io)?;
        self.file.sync_data().map_err(io)
    }
}

/// Writes `rows` sorted by point under `header` to `path` atomically.
pub fn write_sorted(
    path: &Path,
    header: &[String],
    rows: &BTreeMap<usize, Vec<String>>,
) -> Result<(), String> {
    let tmp = path.with_extension("csv.tmp");
    let mut text = line(header);
    for r in rows.values() {
        text.push_str(&line(r));
    }
    std::fs::write(&tmp, text).map_err(|e| format!("`{}`: {e}", tmp.display()))?;
    std::fs::rename(&tmp, path).map_err(|e| format!("`{}`: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_round_trip_through_quoting() {
        let row: Vec<String> = ["1", "a,b", "say \"hi\"", ""]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let l = line(&row);
        assert_eq!(split(l.trim_end_matches('\n')), row);
    }
}
