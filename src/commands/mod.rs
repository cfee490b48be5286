pub mod check;
pub mod compare;
pub mod gpu_launch;
pub mod info;
pub mod plot;
pub mod recover;
pub mod replay;
pub mod run;
pub mod study;
pub mod sweep;
pub mod verify;

use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO, DEFAULT_SCENARIO_NAME};
use std::path::Path;

/// The scenario at `path`, or the built-in default, with overrides applied.
pub fn load_scenario(path: Option<&Path>, set: &[String]) -> anyhow::Result<(Scenario, String)> {
    Ok(match path {
        Some(p) => (Scenario::load(p, set)?, p.display().to_string()),
        None => (
            Scenario::parse(DEFAULT_SCENARIO, DEFAULT_SCENARIO_NAME, set)?,
            DEFAULT_SCENARIO_NAME.to_string(),
        ),
    })
}

/// `text` with control characters (terminal escape sequences among them)
/// shown as escapes instead of sent to the terminal.
pub fn printable(text: &str) -> String {
    text.chars()
        .flat_map(|c| {
            if c.is_control() {
                c.escape_default().collect::<Vec<_>>()
            } else {
                vec![c]
            }
        })
        .collect()
}
