//! Sweep files and their points: a base scenario, axes (any scenario key →
//! a list or a linear/log range) combined as a grid or zipped, fixed
//! overrides, and seeds.

use crate::model::Model;
use crate::scenario::{Scenario, DEFAULT_SCENARIO, DEFAULT_SCENARIO_NAME};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Combine {
    /// Every combination of the axes' values.
    #[default]
    Grid,
    /// The i-th value of every axis together (equal lengths).
    Zip,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum Seeds {
    /// Seeds 1..=n.
    Count(u32),
    List(Vec<u32>),
}

#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Scale {
    #[default]
    Linear,
    Log,
}

/// `{ from, to, count, scale }`: `count` values from `from` to `to`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    pub from: f64,
    pub to: f64,
    pub count: usize,
    #[serde(default)]
    pub scale: Scale,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum Axis {
    List(Vec<toml::Value>),
    Range(Range),
}

/// A sweep file, as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// The base scenario, relative to the sweep file (absent: the built-in
    /// default scene).
    pub base: Option<PathBuf>,
    #[serde(default)]
    pub combine: Combine,
    /// Seeds of every point (absent: the base scenario's seed only).
    pub seeds: Option<Seeds>,
    /// Overrides applied to every point.
    #[serde(default)]
    pub set: BTreeMap<String, toml::Value>,
    /// The swept keys (in key order).
    pub axes: BTreeMap<String, Axis>,
}

/// One run of a sweep.
#[derive(Debug, Clone)]
pub struct Point {
    /// Index in the sweep (stable: grid order, then seed).
    pub index: usize,
    /// (key, value) of each axis, in axis order.
    pub values: Vec<(String, toml::Value)>,
    pub seed: u32,
    pub scenario: Scenario,
}

impl Point {
    /// "key=value, key=value, seed 3".
    pub fn label(&self) -> String {
        let mut parts: Vec<String> = self
            .values
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        parts.push(format!("seed {}", self.seed));
        parts.join(", ")
    }

    /// A fingerprint of what the point runs (its scenario), so a resumed
    /// sweep never takes a row of another sweep for one of its own.
    pub fn id(&self) -> String {
        format!(
            "{:016x}",
            crate::output::fnv1a(self.scenario.to_toml().as_bytes())
        )
    }
}

/// A sweep, every point validated.
pub struct Sweep {
    pub file: SweepFile,
    pub axis_keys: Vec<String>,
    pub points: Vec<Point>,
}

fn axis_values(key: &str, axis: &Axis) -> Result<Vec<toml::Value>, String> {
    match axis {
        Axis::List(v) if v.is_empty() => Err(format!("axes.\"{key}\": an empty list")),
        Axis::List(v) => Ok(v.clone()),
        Axis::Range(r) => {
            if r.count == 0 || !r.from.is_finite() || !r.to.is_finite() {
                return Err(format!(
                    "axes.\"{key}\": a range needs finite from and to and count ≥ 1"
                ));
            }
            if r.scale == Scale::Log && (r.from <= 0.0 || r.to <= 0.0) {
                return Err(format!(
                    "axes.\"{key}\": a log range needs from > 0 and to > 0 (got {} and {})",
                    r.from, r.to
                ));
            }
            Ok((0..r.count)
                .map(|i| {
                    let f = if r.count == 1 {
                        0.0
                    } else {
                        i as f64 / (r.count - 1) as f64
                    };
                    toml::Value::Float(match (r.scale, i) {
                        // The ends exactly as written.
                        (_, 0) => r.from,
                        (_, i) if i + 1 == r.count => r.to,
                        // 13 significant digits: 0.3, not 0.30000000000000004.
                        (Scale::Linear, _) => format!("{:.12e}", r.from + f * (r.to - r.from))
                            .parse()
                            .expect("a number"),
                        (Scale::Log, _) => (r.from.ln() + f * (r.to.ln() - r.from.ln())).exp(),
                    })
                })
                .collect())
        }
    }
}

/// "key=value" as `--set` takes it.
fn override_item(key: &str, value: &toml::Value) -> String {
    format!("{key}={value}")
}

impl Sweep {
    /// Reads a sweep file and builds and validates every point; every
    /// problem is reported, each naming its point.
    pub fn load(path: &Path) -> Result<Sweep, Vec<String>> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| vec![format!("cannot read sweep file `{}`: {e}", path.display())])?;
        let file: SweepFile = toml::from_str(&text)
            .map_err(|e| vec![format!("sweep file `{}`: {e}", path.display())])?;
        let dir = path.parent().unwrap_or(Path::new("."));
        Sweep::build(file, dir)
    }

    pub fn build(file: SweepFile, dir: &Path) -> Result<Sweep, Vec<String>> {
        let (base_text, base_name) = match &file.base {
            Some(p) => {
                let p = dir.join(p);
                let text = std::fs::read_to_string(&p)
                    .map_err(|e| vec![format!("base = `{}`: cannot read it: {e}", p.display())])?;
                (text, p.display().to_string())
            }
            None => (
                DEFAULT_SCENARIO.to_string(),
                DEFAULT_SCENARIO_NAME.to_string(),
            ),
        };
        let mut problems = Vec::new();
        let axis_keys: Vec<String> = file.axes.keys().cloned().collect();
        let mut columns = Vec::new();
        for (key, axis) in &file.axes {
            match axis_values(key, axis) {
                Ok(v) => columns.push(v),
                Err(e) => problems.push(e),
            }
        }
        if !problems.is_empty() {
            return Err(problems);
        }
        let combos: Vec<Vec<toml::Value>> = match file.combine {
            Combine::Grid => columns.iter().fold(vec![Vec::new()], |acc, col| {
                acc.iter()
                    .flat_map(|prefix| {
                        col.iter().map(move |v| {
                            let mut p = prefix.clone();
                            p.push(v.clone());
                            p
                        })
                    })
                    .collect()
            }),
            Combine::Zip => {
                let n = columns.first().map_or(1, Vec::len);
                if let Some((k, c)) = axis_keys.iter().zip(&columns).find(|(_, c)| c.len() != n) {
                    return Err(vec![format!(
                        "combine = \"zip\" needs axes of one length: axes.\"{}\" has {} values, \
                         axes.\"{k}\" has {}",
                        axis_keys[0],
                        n,
                        c.len()
                    )]);
                }
                (0..n)
                    .map(|i| columns.iter().map(|c| c[i].clone()).collect())
                    .collect()
            }
        };
        let fixed: Vec<String> = file.set.iter().map(|(k, v)| override_item(k, v)).collect();
        let mut points = Vec::new();
        for combo in combos {
            let mut set = fixed.clone();
            set.extend(
                axis_keys
                    .iter()
                    .zip(&combo)
                    .map(|(k, v)| override_item(k, v)),
            );
            let seeds: Vec<Option<u32>> = match &file.seeds {
                None => vec![None],
                Some(Seeds::Count(n)) => (1..=*n).map(Some).collect(),
                Some(Seeds::List(l)) => l.iter().copied().map(Some).collect(),
            };
            for seed in seeds {
                let mut set = set.clone();
                if let Some(s) = seed {
                    set.push(format!("time.seed={s}"));
                }
                let index = points.len() + problems.len();
                let label = || {
                    let mut parts: Vec<String> = axis_keys
                        .iter()
                        .zip(&combo)
                        .map(|(k, v)| format!("{k}={v}"))
                        .collect();
                    if let Some(s) = seed {
                        parts.push(format!("seed {s}"));
                    }
                    parts.join(", ")
                };
                let scenario = match Scenario::parse(&base_text, &base_name, &set) {
                    Ok(s) => s,
                    Err(e) => {
                        let e = e.to_string().replace('\n', "\n    ");
                        problems.push(format!("point {index} ({}): {e}", label()));
                        continue;
                    }
                };
                if let Err(e) = Model::from_scenario(&scenario, false) {
                    problems.push(format!("point {index} ({}): {e}", label()));
                    continue;
                }
                points.push(Point {
                    index,
                    values: axis_keys.iter().cloned().zip(combo.clone()).collect(),
                    seed: scenario.time.seed,
                    scenario,
                });
            }
        }
        if problems.is_empty() {
            Ok(Sweep {
                file,
                axis_keys,
                points,
            })
        } else {
            Err(problems)
        }
    }
}
