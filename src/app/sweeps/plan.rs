//! Sweep files and their points: a base scenario, axes (any scenario key →
//! a list or a linear/log range) combined as a grid or zipped, fixed
//! overrides, and seeds.

use crate::model::scenario::{Scenario, DEFAULT_SCENARIO, DEFAULT_SCENARIO_NAME};
use crate::model::Model;
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
    #[serde(default)]
    pub axes: BTreeMap<String, Axis>,
    /// A perturbation ensemble of every point (after the axes and seeds).
    pub perturb: Option<Perturb>,
}

/// `perturb = { key, relative, count, start }`: `count` runs of every point
/// with `key` multiplied by 1 + k·relative, k taking the members `start`,
/// `start + 1`, … of the sequence 0, +1, −1, +2, −2, … The scenes are
/// chaotic (a 1e-6 change of the drive speed moves an event by ~2 %), so
/// two engines or precisions are compared on such ensembles, never on one
/// trajectory; `start` gives a second, disjoint ensemble of the same key.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Perturb {
    pub key: String,
    pub relative: f64,
    pub count: usize,
    #[serde(default)]
    pub start: usize,
}

impl Perturb {
    /// The column of the perturbation in the sweep table.
    pub fn column(&self) -> String {
        format!("perturb({})", self.key)
    }

    /// The relative offsets k·relative of the ensemble's members.
    pub fn offsets(&self) -> Vec<f64> {
        (self.start..self.start + self.count)
            .map(|m| {
                let k = m.div_ceil(2) as f64;
                let k = if m % 2 == 0 { -k } else { k } + 0.0; // no −0
                                                               // 13 significant digits: 5e-6, not 4.9999999999999996e-6.
                format!("{:.12e}", k * self.relative)
                    .parse::<f64>()
                    .expect("a number")
            })
            .collect()
    }

    fn check(&self) -> Result<(), String> {
        let limit = 1.0e-2;
        if !(self.relative.is_finite() && self.relative > 0.0 && self.relative <= limit) {
            return Err(format!(
                "perturb.relative = {} is out of range (allowed: 0 < relative <= {limit})",
                self.relative
            ));
        }
        if self.count == 0 || self.count > 100_000 {
            return Err(format!(
                "perturb.count = {} is out of range (allowed: 1 to 100000)",
                self.count
            ));
        }
        if self.start > 1_000_000 {
            return Err(format!(
                "perturb.start = {} is out of range (allowed: 0 to 1000000)",
                self.start
            ));
        }
        if self.key.trim().is_empty() || self.key.split('.').any(str::is_empty) {
            return Err(format!(
                "perturb.key = \"{}\": not a scenario key",
                self.key
            ));
        }
        Ok(())
    }
}

/// The number at `key` (a dotted path) of a scenario's TOML.
fn scenario_number(scenario: &Scenario, key: &str) -> Result<f64, String> {
    let table: toml::Table = scenario
        .to_toml()
        .parse()
        .map_err(|e| format!("perturb: cannot read the scenario back: {e}"))?;
    let mut node = &toml::Value::Table(table);
    for part in key.split('.') {
        node = node
            .get(part)
            .ok_or_else(|| format!("perturb.key = \"{key}\": the scenario has no such key"))?;
    }
    match node {
        toml::Value::Float(v) => Ok(*v),
        toml::Value::Integer(_) => Err(format!(
            "perturb.key = \"{key}\": an integer key cannot be perturbed by a relative amount"
        )),
        other => Err(format!(
            "perturb.key = \"{key}\" is {other}: only a real-valued key can be perturbed"
        )),
    }
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
            crate::io::output::fnv1a(self.scenario.to_toml().as_bytes())
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

/// The most points one sweep file may hold. A point is a run; a study of
/// more runs than this is several sweep files (or several shards of each).
/// Every point is built and validated up front (about 1 KB each).
pub const MAX_SWEEP_POINTS: u128 = 100_000;

/// How many points `file` makes, from its axes, seeds and perturbation,
/// before any is built; an error names the counts when they are out of
/// bounds (no seeds, or more than [`MAX_SWEEP_POINTS`]).
fn point_count(file: &SweepFile) -> Result<u128, String> {
    let lengths: Vec<(&String, u128)> = file
        .axes
        .iter()
        .map(|(k, a)| {
            let n = match a {
                Axis::List(v) => v.len(),
                Axis::Range(r) => r.count,
            };
            (k, n as u128)
        })
        .collect();
    let combos = match file.combine {
        // Saturating: a product past u128 is refused below like any count
        // over the cap.
        Combine::Grid => lengths
            .iter()
            .fold(1u128, |acc, (_, n)| acc.saturating_mul(*n)),
        Combine::Zip => lengths.first().map_or(1, |(_, n)| *n),
    };
    let seeds = match &file.seeds {
        None => 1,
        Some(Seeds::Count(0)) => return Err("seeds = 0: give at least one seed".into()),
        Some(Seeds::List(l)) if l.is_empty() => {
            return Err("seeds = []: give at least one seed".into())
        }
        Some(Seeds::Count(n)) => *n as u128,
        Some(Seeds::List(l)) => l.len() as u128,
    };
    let runs = file.perturb.as_ref().map_or(1, |p| p.count as u128);
    let total = combos.saturating_mul(seeds).saturating_mul(runs);
    if total > MAX_SWEEP_POINTS {
        let axes: Vec<String> = lengths
            .iter()
            .map(|(k, n)| format!("axes.\"{k}\" {n}"))
            .collect();
        return Err(format!(
            "the sweep has {} points ({}{}, {seeds} seed(s), {runs} perturbed run(s) each): \
             more than the {MAX_SWEEP_POINTS} one sweep file may hold; split it into several \
             sweep files",
            if total == u128::MAX {
                "more than 2¹²⁸".to_string()
            } else {
                total.to_string()
            },
            if axes.is_empty() {
                "no axes".to_string()
            } else {
                axes.join(" × ")
            },
            if file.combine == Combine::Zip {
                " zipped"
            } else {
                ""
            },
        ));
    }
    Ok(total)
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
        point_count(&file).map_err(|e| vec![e])?;
        let mut problems = Vec::new();
        let mut axis_keys: Vec<String> = file.axes.keys().cloned().collect();
        let offsets = match &file.perturb {
            None => vec![None],
            Some(p) => {
                p.check().map_err(|e| vec![e])?;
                if file.axes.contains_key(&p.key) {
                    return Err(vec![format!(
                        "perturb.key = \"{}\" is also an axis: perturb another key",
                        p.key
                    )]);
                }
                p.offsets().into_iter().map(Some).collect()
            }
        };
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
                for offset in &offsets {
                    let index = points.len() + problems.len();
                    let mut values: Vec<(String, toml::Value)> =
                        axis_keys.iter().cloned().zip(combo.clone()).collect();
                    let scenario = match (offset, &file.perturb) {
                        (Some(offset), Some(perturb)) => {
                            let perturbed =
                                scenario_number(&scenario, &perturb.key).and_then(|base| {
                                    let mut set = set.clone();
                                    set.push(format!(
                                        "{}={:e}",
                                        perturb.key,
                                        base * (1.0 + offset)
                                    ));
                                    Scenario::parse(&base_text, &base_name, &set)
                                        .map_err(|e| e.to_string().replace('\n', "\n    "))
                                });
                            values.push((perturb.column(), toml::Value::Float(*offset)));
                            match perturbed {
                                Ok(s) => s,
                                Err(e) => {
                                    problems.push(format!(
                                        "point {index} ({}, perturbation {offset:e}): {e}",
                                        label()
                                    ));
                                    continue;
                                }
                            }
                        }
                        _ => scenario.clone(),
                    };
                    if let Err(e) = Model::from_scenario(&scenario, false) {
                        problems.push(format!("point {index} ({}): {e}", label()));
                        continue;
                    }
                    points.push(Point {
                        index,
                        values,
                        seed: scenario.time.seed,
                        scenario,
                    });
                }
            }
        }
        if let Some(p) = &file.perturb {
            axis_keys.push(p.column());
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

#[cfg(test)]
mod tests {
    use super::*;

    fn build(text: &str) -> Result<Sweep, Vec<String>> {
        let file: SweepFile = toml::from_str(text).map_err(|e| vec![e.to_string()])?;
        Sweep::build(file, Path::new(env!("CARGO_MANIFEST_DIR")))
    }

    #[test]
    fn perturbation_members_are_symmetric_and_disjoint_by_start() {
        let p = |start, count| Perturb {
            key: "loading.drive.velocity".into(),
            relative: 1.0e-6,
            count,
            start,
        };
        let first: Vec<f64> = p(0, 5).offsets().iter().map(|o| o / 1.0e-6).collect();
        assert_eq!(first, [0.0, 1.0, -1.0, 2.0, -2.0]);
        let next: Vec<f64> = p(5, 3).offsets().iter().map(|o| o / 1.0e-6).collect();
        assert_eq!(next, [3.0, -3.0, 4.0]);
    }

    #[test]
    fn a_perturbed_sweep_multiplies_the_key_of_every_point() {
        let sweep = build(
            "base = \"scenarios/triggered_front.toml\"\nseeds = [4, 5]\n\
             perturb = { key = \"friction.static_coefficient\", relative = 1e-6, count = 3 }\n\
             [axes]\n\"loading.trigger.shear_prestress\" = [0.2, 0.3]\n",
        )
        .expect("sweep");
        assert_eq!(sweep.points.len(), 2 * 2 * 3);
        assert_eq!(
            sweep.axis_keys.last().map(String::as_str),
            Some("perturb(friction.static_coefficient)")
        );
        let base =
            scenario_number(&sweep.points[0].scenario, "friction.static_coefficient").unwrap();
        for (k, p) in sweep.points.iter().enumerate() {
            let offset = [0.0, 1.0e-6, -1.0e-6][k % 3];
            let v = scenario_number(&p.scenario, "friction.static_coefficient").unwrap();
            assert_eq!(v, base * (1.0 + offset), "point {k}");
            assert_eq!(p.values.last().unwrap().1, toml::Value::Float(offset));
            assert_eq!(p.seed, [4, 4, 4, 5, 5, 5][k % 6]);
        }
        // Every point is its own scenario: no two share a fingerprint.
        let mut ids: Vec<String> = sweep.points.iter().map(Point::id).collect();
        ids.sort();
        ids.dedup();
        assert_eq!(ids.len(), sweep.points.len());
    }

    #[test]
    fn bad_perturbations_are_refused_naming_the_field() {
        let text = |p: &str| format!("base = \"scenarios/triggered_front.toml\"\nperturb = {p}\n");
        let cases = [
            (
                "{ key = \"friction.static_coefficient\", relative = 0.0, count = 3 }",
                "perturb.relative = 0 is out of range",
            ),
            (
                "{ key = \"friction.static_coefficient\", relative = 1e-6, count = 0 }",
                "perturb.count = 0 is out of range",
            ),
            (
                "{ key = \"loading.drive.speed\", relative = 1e-6, count = 2 }",
                "no such key",
            ),
            (
                "{ key = \"geometry.nx\", relative = 1e-6, count = 2 }",
                "an integer key",
            ),
            (
                "{ key = \"friction.law\", relative = 1e-6, count = 2 }",
                "only a real-valued key",
            ),
        ];
        for (p, expected) in cases {
            let err = build(&text(p)).err().expect(p).join("\n");
            assert!(err.contains(expected), "{p}: {err}");
        }
    }

    /// Counts are checked before any point is built: no panic, no
    /// allocation of a huge sweep, and no sweep without seeds.
    #[test]
    fn point_counts_are_bounded_before_any_point_is_built() {
        let build = |text: &str| {
            let file: SweepFile = toml::from_str(text).unwrap();
            Sweep::build(file, Path::new(".")).map(|s| s.points.len())
        };
        let huge = build(
            "[axes]\n\"friction.static_coefficient\" = \
             { from = 0.3, to = 0.5, count = 18446744073709551615 }\n",
        )
        .unwrap_err();
        assert!(huge[0].contains("18446744073709551615 points"), "{huge:?}");
        assert!(huge[0].contains("more than the 100000"), "{huge:?}");
        let grid = build(
            "[axes]\n\"friction.static_coefficient\" = { from = 0.3, to = 0.5, count = 100000 }\n\
             \"friction.dynamic_coefficient\" = { from = 0.1, to = 0.2, count = 100000 }\n\
             \"loading.drive.velocity\" = { from = 1e-4, to = 1e-3, count = 100000 }\n",
        )
        .unwrap_err();
        assert!(grid[0].contains("1000000000000000 points"), "{grid:?}");
        for (seeds, message) in [("0", "seeds = 0"), ("[]", "seeds = []")] {
            let e = build(&format!("seeds = {seeds}\n")).unwrap_err();
            assert!(e[0].contains(message), "{e:?}");
        }
        // At the cap it builds (and a count just over is refused).
        let at_cap = "perturb = { key = \"loading.drive.velocity\", relative = 1e-6, \
                      count = 50000 }\nseeds = 2\n";
        assert_eq!(point_count(&toml::from_str(at_cap).unwrap()), Ok(100_000));
        let over = at_cap.replace("seeds = 2", "seeds = 3");
        assert!(point_count(&toml::from_str(&over).unwrap()).is_err());
        assert_eq!(build("seeds = 2\n"), Ok(2));
    }
}
