//! The friction-law seam: every law the interface can have, and what each
//! declares so that the engines carry it without knowing it.
//!
//! A law declares (`Law`):
//! - its scenario name and its kernel code (the WGSL `LAW_*` constants and
//!   the `FRICTION_LAW` override are generated from this list);
//! - its constants (`constants`: up to `LAW_CONSTANTS` numbers, carried in
//!   the engines' run constants as `law` / `c.law0..7`);
//! - its state: `block_state_words` reals per interface block, kept by
//!   every engine, snapshot, checkpoint and GPU buffer as one generic
//!   array (`law_state`, block-major), with the law's initial values;
//! - for a per-block law (one friction force per interface block from the
//!   block's own state), its CPU twin (`block_friction` dispatches to it)
//!   and its WGSL file in `shaders/laws/`, whose entry the generated
//!   `friction_law` shader calls (`wgsl_dispatch`).
//!
//! The junction laws keep many junctions per block in their own arrays,
//! computed lane by lane: the kernels call them directly.
//!
//! Adding a per-block law: a folder here with its table, constants and
//! twin, its WGSL file, and one entry in each list of this file
//! (docs/adding-a-law.md).

pub mod coulomb;
pub mod junctions;
pub mod rate_state;

use crate::model::real::{Coordinate, Real};
use serde::{Deserialize, Serialize};

/// Room for a law's constants in the engines' run constants.
pub const LAW_CONSTANTS: usize = 8;

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FrictionLaw {
    /// Ns micro-junctions per interface block.
    Junctions,
    /// Amontons–Coulomb per interface block.
    Coulomb,
    /// One junction per block with slow post-rupture slip.
    SingleJunction,
    /// Dieterich–Ruina rate-and-state friction per interface block.
    RateState,
    /// Frictionless (wave tests).
    None,
}

/// What the engines know of a law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Law {
    /// Its name in a scenario file (`friction.law`).
    pub name: &'static str,
    /// The kernel code compiled into the shaders (`FRICTION_LAW`), and the
    /// WGSL constant naming it. The single-junction law is the junction
    /// code with one junction per block.
    pub kernel: u32,
    pub kernel_constant: &'static str,
    /// Reals of state per interface block.
    pub block_state_words: usize,
    /// A per-block law's shader: (file name in `shaders/laws/`, text, the
    /// entry `fn NAME(ix: u32, other: real, ld: Loads) -> vec2<real>`).
    pub block_shader: Option<(&'static str, &'static str, &'static str)>,
    /// Loop iterations the shader may take for one block in one step, at
    /// most (software adapters end a dispatch's loops after a fixed count:
    /// the persistent kernel sizes its dispatches with this).
    pub block_loop_iterations: usize,
}

/// Every law, in kernel-code order where it has its own code.
pub const LAWS: [(FrictionLaw, Law); 5] = [
    (
        FrictionLaw::None,
        Law {
            name: "none",
            kernel: 0,
            kernel_constant: "LAW_NONE",
            block_state_words: 0,
            block_shader: None,
            block_loop_iterations: 0,
        },
    ),
    (FrictionLaw::Junctions, junctions::LAW),
    (FrictionLaw::SingleJunction, junctions::SINGLE_JUNCTION_LAW),
    (FrictionLaw::Coulomb, coulomb::LAW),
    (FrictionLaw::RateState, rate_state::LAW),
];

impl FrictionLaw {
    pub fn declaration(self) -> Law {
        LAWS.iter()
            .find(|(l, _)| *l == self)
            .map(|(_, d)| *d)
            .expect("every law is declared in LAWS")
    }

    pub fn name(self) -> &'static str {
        self.declaration().name
    }

    /// A law whose friction is one force per interface block from the
    /// block's own state (Coulomb, rate-and-state).
    pub fn is_per_block(self) -> bool {
        self.declaration().block_shader.is_some()
    }
}

/// The laws' own scenario tables (`[friction.<law>]`), each optional: the
/// law in use needs its own (`validate`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LawTables {
    pub junctions: Option<junctions::Junctions>,
    pub rate_state: Option<rate_state::RateStateTable>,
}

/// The checks a law's table needs, each problem naming the key, the value,
/// the allowed range and the key's place in the file (`line`): the
/// scenario's validator implements them.
pub trait TableChecks {
    /// Where `key` is set, as " (line N)" or how else it was set.
    fn line(&self, key: &str) -> String;
    fn problem(&mut self, text: String);
    fn positive(&mut self, key: &str, v: f64);
    fn at_least(&mut self, key: &str, v: f64, lo: f64);
    fn range_u(&mut self, key: &str, v: u32, lo: u32, hi: u32);
}

/// A law's constants (unused slots 0), from the static and dynamic
/// friction coefficients μs, μd and the laws' tables.
pub fn constants(law: FrictionLaw, mu_s: f64, mu_d: f64, t: &LawTables) -> [f64; LAW_CONSTANTS] {
    let mut k = [0.0; LAW_CONSTANTS];
    match law {
        FrictionLaw::Coulomb => k[..2].copy_from_slice(&coulomb::constants(mu_s, mu_d)),
        FrictionLaw::RateState => {
            if let Some(r) = &t.rate_state {
                k[..rate_state::CONSTANTS].copy_from_slice(&r.constants());
            }
        }
        FrictionLaw::Junctions | FrictionLaw::SingleJunction => {
            if let Some(j) = &t.junctions {
                k[..1].copy_from_slice(&junctions::constants(j));
            }
        }
        FrictionLaw::None => {}
    }
    k
}

/// A law's state of one interface block at t = 0.
pub fn initial_block_state(law: FrictionLaw, t: &LawTables) -> Vec<f64> {
    match (law, &t.rate_state) {
        (FrictionLaw::RateState, Some(r)) => r.initial_state(),
        _ => vec![0.0; law.declaration().block_state_words],
    }
}

/// The problems of the laws' tables for `law`: its own table present and
/// in range, no table of another law.
pub fn validate(law: FrictionLaw, t: &LawTables, c: &mut dyn TableChecks) {
    junctions::validate(law, t.junctions.as_ref(), c);
    match (law, &t.rate_state) {
        (FrictionLaw::RateState, Some(r)) => r.validate(c),
        (FrictionLaw::RateState, None) => c.problem(
            "missing table [friction.rate_state], required by friction.law = \"rate_state\"".into(),
        ),
        (_, Some(_)) => {
            let line = c.line("friction.law");
            c.problem(format!(
                "table [friction.rate_state] is read only by friction.law = \"rate_state\", but \
                 friction.law = \"{}\"{line}",
                law.name()
            ))
        }
        _ => {}
    }
}

/// What a per-block law sees of its interface block over one step: the
/// leapfrog's velocity update is v(n+½) = v(n−½) + dt·(other + friction)/m,
/// and the law returns the friction of that update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockContact<T> {
    pub mass: T,
    pub dt: T,
    /// The foundation's normal force p under the block.
    pub normal: T,
    /// v_x(n−½).
    pub velocity: T,
    /// Every force along x on the block but friction.
    pub other_force: T,
    /// In the normal-load phase: the interface holds.
    pub preparing: bool,
}

/// CPU twin of the generated `block_law_friction` (`wgsl_dispatch`): the
/// friction along x of a per-block law on one interface block, updating
/// its `slide` pair (sliding direction 0/±1, stick → slip count) and its
/// law state (coordinates: increments are added without losing their low
/// bits). 0 for the other laws.
#[inline]
pub fn block_law_friction<T: Real, C: Coordinate<T>>(
    law: FrictionLaw,
    constants: &[T; LAW_CONSTANTS],
    b: &BlockContact<T>,
    slide: &mut [i32; 2],
    state: &mut [C],
) -> T {
    match law {
        FrictionLaw::Coulomb => coulomb::coulomb(constants, b, slide),
        FrictionLaw::RateState => rate_state::rate_state(constants, b, slide, state),
        FrictionLaw::Junctions | FrictionLaw::SingleJunction | FrictionLaw::None => T::zero(),
    }
}

/// The generated shader `friction_law`: the kernel-code constants' users
/// call `block_law_friction(ix, other, ld)` and `is_block_law()`, which
/// dispatch on `FRICTION_LAW` to the per-block laws' WGSL entries.
pub fn wgsl_dispatch() -> String {
    let block_laws: Vec<Law> = LAWS
        .iter()
        .map(|(_, d)| *d)
        .filter(|d| d.block_shader.is_some())
        .collect();
    let mut imports = vec!["common", "coordinates", "scene", "state"];
    imports.extend(
        block_laws
            .iter()
            .filter_map(|d| d.block_shader.map(|s| s.0)),
    );
    let mut s = String::from(
        "// Generated from src/model/friction/mod.rs: the per-block friction laws' dispatch.\n\
         // CPU twin: src/model/friction/mod.rs block_law_friction.\n",
    );
    s += &format!("// import: {}\n\n", imports.join(", "));
    let tests: Vec<String> = block_laws
        .iter()
        .map(|d| format!("FRICTION_LAW == {}", d.kernel_constant))
        .collect();
    s += &format!(
        "fn is_block_law() -> bool {{\n    return {};\n}}\n\n",
        if tests.is_empty() {
            "false".to_string()
        } else {
            tests.join(" || ")
        }
    );
    s += "// (friction along x, normal force) of interface block ix, given the\n\
          // other forces along x on it.\n\
          fn block_law_friction(ix: u32, other: real, ld: Loads) -> vec2<real> {\n";
    for d in &block_laws {
        let (_, _, entry) = d.block_shader.expect("filtered");
        s += &format!(
            "    if FRICTION_LAW == {} {{\n        return {entry}(ix, other, ld);\n    }}\n",
            d.kernel_constant
        );
    }
    s += "    return vec2<real>(0.0, 0.0);\n}\n";
    s
}

/// The per-block laws' shader files: (name, text).
pub fn wgsl_files() -> impl Iterator<Item = (&'static str, &'static str)> {
    LAWS.iter()
        .filter_map(|(_, d)| d.block_shader.map(|(name, text, _)| (name, text)))
}

/// Each kernel code once, with its WGSL constant's name.
pub fn kernel_codes() -> Vec<(u32, &'static str)> {
    let mut codes: Vec<(u32, &'static str)> = Vec::new();
    for (_, d) in LAWS {
        if !codes.iter().any(|(k, _)| *k == d.kernel) {
            codes.push((d.kernel, d.kernel_constant));
        }
    }
    codes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_law_is_declared_once_and_codes_name_one_constant() {
        for law in [
            FrictionLaw::None,
            FrictionLaw::Junctions,
            FrictionLaw::SingleJunction,
            FrictionLaw::Coulomb,
            FrictionLaw::RateState,
        ] {
            assert_eq!(LAWS.iter().filter(|(l, _)| *l == law).count(), 1);
            let name = format!("\"{}\"", law.name());
            assert_eq!(serde_json::to_string(&law).unwrap(), name);
        }
        let codes = kernel_codes();
        for (code, name) in &codes {
            assert_eq!(codes.iter().filter(|(c, _)| c == code).count(), 1);
            assert_eq!(codes.iter().filter(|(_, n)| n == name).count(), 1);
        }
    }

    #[test]
    fn the_dispatch_calls_every_per_block_law() {
        let text = wgsl_dispatch();
        assert!(text.contains("return coulomb(ix, other, ld);"), "{text}");
        assert!(text.contains("return rate_state(ix, other, ld);"), "{text}");
        assert!(text.contains("// import: common, coordinates, scene, state, coulomb, rate_state"));
    }
}
