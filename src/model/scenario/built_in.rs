//! The scenarios shipped in `scenarios/`, compiled in, so that a program
//! without the repository (the Python package) loads them by name.

macro_rules! shipped {
    ($($name:literal),* $(,)?) => {
        &[$(($name, include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"), "/scenarios/", $name, ".toml"
        )))),*]
    };
}

/// (name, TOML text) of every shipped lattice scenario (the single-block
/// scene is `slipfront single-block`'s, not a lattice).
pub const BUILT_IN: &[(&str, &str)] = shipped!(
    "tromborg2014_stick_slip",
    "tromborg2014_precursors",
    "triggered_front",
    "small_stick_slip",
    "tromborg2011_coulomb_precursors",
    "amundsen2015_1d_front",
    "rate_state",
);

/// The TOML text of the shipped scenario `name` (with or without `.toml`).
pub fn built_in(name: &str) -> Option<&'static str> {
    let name = name.strip_suffix(".toml").unwrap_or(name);
    BUILT_IN.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scenario::Scenario;

    #[test]
    fn every_built_in_scenario_is_valid_and_every_lattice_file_is_built_in() {
        for (name, text) in BUILT_IN {
            Scenario::parse(text, name, &[]).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios");
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                let text = std::fs::read_to_string(&path).unwrap();
                let stem = path.file_stem().unwrap().to_str().unwrap();
                let lattice = !crate::model::scenario::looks_like_single_block(&text);
                assert_eq!(built_in(stem).is_some(), lattice, "{}", path.display());
            }
        }
        assert_eq!(
            built_in("triggered_front.toml"),
            built_in("triggered_front")
        );
        assert!(built_in("no_such_scene").is_none());
    }
}
