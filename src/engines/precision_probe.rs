//! A measuring instrument for the precision study (issue 31,
//! results/precision_ensembles.md): an f64 engine with one class of
//! quantities at a time held in f32, to find which rounding biases mixed
//! f32's outcome distribution against f64's.
//!
//! Set by the environment variable `SLIPFRONT_F32_PROBE`, a comma list of
//! `forces` (every bond's spring and dashpot force and each block's total
//! force rounded to f32), `velocities` (each block's velocity after its
//! update), `coordinates` (each displacement kept to a double-single
//! pair's ≈ 48 bits), `junctions` (junction forces, thresholds, sliding
//! forces and stiffnesses), `draws` (slip times drawn in f32) and
//! `constants` (every run constant rounded to f32, as an f32 engine holds
//! them: dt, stiffnesses, 1/m, μs, μd, loads), or `all`.
//! It is read once per engine into `Consts::f32_probe`; empty or unset, the
//! engines are untouched (every test runs that way). In an f32 engine the
//! rounding changes nothing: its values are f32 already.

use crate::model::real::{Coordinate, DoubleSingle, Real};

pub const FORCES: u32 = 1;
pub const VELOCITIES: u32 = 2;
pub const COORDINATES: u32 = 4;
pub const JUNCTIONS: u32 = 8;
pub const DRAWS: u32 = 16;
pub const CONSTANTS: u32 = 32;

const NAMES: [(&str, u32); 6] = [
    ("forces", FORCES),
    ("velocities", VELOCITIES),
    ("coordinates", COORDINATES),
    ("junctions", JUNCTIONS),
    ("draws", DRAWS),
    ("constants", CONSTANTS),
];

/// The environment variable naming the quantities held in f32.
pub const VARIABLE: &str = "SLIPFRONT_F32_PROBE";

/// The mask of a comma list of quantity names.
pub fn parse(list: &str) -> Result<u32, String> {
    let mut mask = 0;
    for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        mask |= match name {
            "all" => NAMES.iter().fold(0, |m, (_, bit)| m | bit),
            _ => NAMES
                .iter()
                .find(|(n, _)| *n == name)
                .map(|(_, bit)| *bit)
                .ok_or_else(|| {
                    format!(
                        "{VARIABLE}: unknown quantity `{name}` (allowed: forces, velocities, \
                         coordinates, junctions, draws, constants, all)"
                    )
                })?,
        };
    }
    Ok(mask)
}

/// The mask the environment asks for (0 when unset). An unknown name is an
/// error the engine reports before running.
pub fn from_environment() -> Result<u32, String> {
    std::env::var(VARIABLE).map_or(Ok(0), |v| parse(&v))
}

/// The names in `mask`, for logs and run metadata ("" when none).
pub fn describe(mask: u32) -> String {
    NAMES
        .iter()
        .filter(|(_, bit)| mask & bit != 0)
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(",")
}

/// What an engine's description adds when the probe is on: the run
/// header and the run file's metadata then name the quantities held.
pub fn label(mask: u32) -> String {
    if mask == 0 {
        String::new()
    } else {
        format!(" [{VARIABLE}={}]", describe(mask))
    }
}

/// Whether the probe can change an engine computing in `T`: only f64. A
/// compile-time constant, so an f32 engine's loops carry no probe branch
/// (with it they lost their vectorisation: 1.77× slower).
#[inline(always)]
const fn probed<T>() -> bool {
    std::mem::size_of::<T>() == 8
}

/// `x` rounded to f32 when `mask` holds `quantity`.
#[inline(always)]
pub fn hold<T: Real>(mask: u32, quantity: u32, x: T) -> T {
    if probed::<T>() && mask & quantity != 0 {
        T::from_f64(x.as_f64() as f32 as f64)
    } else {
        x
    }
}

/// Every value of `xs` rounded to f32 when `mask` holds `quantity`.
pub fn hold_all<T: Real>(mask: u32, quantity: u32, xs: &mut [T]) {
    if probed::<T>() && mask & quantity != 0 {
        for x in xs {
            *x = T::from_f64(x.as_f64() as f32 as f64);
        }
    }
}

/// A coordinate kept to a double-single pair's precision when `mask` holds
/// `COORDINATES`.
#[inline(always)]
pub fn hold_coordinate<T: Real, C: Coordinate<T>>(mask: u32, u: C) -> C {
    if probed::<T>() && mask & COORDINATES != 0 {
        C::from_f64(DoubleSingle::from_f64(u.as_f64()).as_f64())
    } else {
        u
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_to_bits_and_unknown_names_are_refused() {
        assert_eq!(parse("").unwrap(), 0);
        assert_eq!(parse("forces, draws").unwrap(), FORCES | DRAWS);
        assert_eq!(
            describe(parse("all").unwrap()),
            "forces,velocities,coordinates,junctions,draws,constants"
        );
        let err = parse("forces,speed").unwrap_err();
        assert!(err.contains("unknown quantity `speed`"), "{err}");
    }

    #[test]
    fn held_values_are_f32_values_and_others_untouched() {
        let x = 0.1f64;
        assert_eq!(hold(FORCES, FORCES, x), 0.1f32 as f64);
        assert_ne!(hold(FORCES, FORCES, x), x);
        assert_eq!(hold(VELOCITIES, FORCES, x), x);
        // An f32 engine's values are f32 already.
        assert_eq!(hold(FORCES, FORCES, 0.1f32), 0.1f32);
        let u = 1.0e-4 + 1.0e-17;
        let held: f64 = hold_coordinate(COORDINATES, u);
        assert_eq!(held, DoubleSingle::from_f64(u).as_f64());
        assert!((held - u).abs() < 1e-4 * 1e-13 && held != u);
    }
}
