//! What a run shows while it runs: on a terminal a bar with the phase, the
//! simulated time against its end, steps and block-steps per second, the
//! slip events so far and the ETA; without one (nohup, CI, a batch job) a
//! plain log line every `PLAIN_EVERY`.

use crate::model::Model;
use indicatif::{ProgressBar, ProgressStyle};
use std::time::{Duration, Instant};

/// Interval of the plain log lines.
const PLAIN_EVERY: Duration = Duration::from_secs(10);

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ProgressMode {
    /// A bar on a terminal, plain lines otherwise.
    Auto,
    Bar,
    /// A log line every 10 s on stderr.
    Plain,
    /// Nothing until the summary (the library's default).
    #[default]
    None,
}

impl ProgressMode {
    /// `Auto` resolved against stderr.
    fn resolve(self) -> ProgressMode {
        use std::io::IsTerminal;
        match self {
            ProgressMode::Auto if std::io::stderr().is_terminal() => ProgressMode::Bar,
            ProgressMode::Auto => ProgressMode::Plain,
            m => m,
        }
    }
}

pub(super) struct Reporter {
    mode: ProgressMode,
    bar: ProgressBar,
    prep: u64,
    total: u64,
    start_step: u64,
    dt: f64,
    end_time: f64,
    blocks: f64,
    started: Instant,
    last_line: Instant,
}

/// Decimals that resolve about 1e-4 of `end` (s).
fn decimals(end: f64) -> usize {
    if end > 0.0 {
        (4.0 - end.log10().floor()).clamp(0.0, 12.0) as usize
    } else {
        6
    }
}

/// 1.2e4-style rate.
fn rate(v: f64) -> String {
    format!("{v:.2e}")
}

/// h:mm:ss.
fn clock(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

impl Reporter {
    pub fn new(mode: ProgressMode, model: &Model, start_step: u64) -> Self {
        let mode = mode.resolve();
        let total = model.total_steps();
        let bar = if mode == ProgressMode::Bar {
            let b = ProgressBar::new(total.saturating_sub(start_step));
            b.set_style(
                ProgressStyle::with_template("{bar:30} {msg} | ETA {eta}").expect("valid template"),
            );
            b
        } else {
            ProgressBar::hidden()
        };
        Reporter {
            mode,
            bar,
            prep: model.prep_steps,
            total,
            start_step,
            dt: model.dt,
            end_time: model.time_of_step(total),
            blocks: model.n_blocks() as f64,
            started: Instant::now(),
            last_line: Instant::now(),
        }
    }

    /// "driving t = 0.1234 of 1 s | 5.1e4 steps/s (9.0e7 block-steps/s) |
    /// 3 slip events".
    fn status(&self, step: u64, events: Option<u64>) -> String {
        let elapsed = self.started.elapsed().as_secs_f64().max(1e-9);
        let steps_per_second = (step - self.start_step) as f64 / elapsed;
        let phase = if step < self.prep {
            format!(
                "normal load {:.0}% (then driving to t = {:.d$} s)",
                100.0 * step as f64 / self.prep.max(1) as f64,
                self.end_time,
                d = decimals(self.end_time)
            )
        } else {
            let t = (step - self.prep) as f64 * self.dt;
            format!(
                "driving t = {t:.d$} of {:.d$} s",
                self.end_time,
                d = decimals(self.end_time)
            )
        };
        let events = events.map_or(String::new(), |n| format!(" | {n} slip events"));
        format!(
            "{phase} | {} steps/s ({} block-steps/s){events}",
            rate(steps_per_second),
            rate(steps_per_second * self.blocks)
        )
    }

    pub fn update(&mut self, step: u64, events: Option<u64>) {
        match self.mode {
            ProgressMode::Bar => {
                self.bar.set_position(step - self.start_step);
                self.bar.set_message(self.status(step, events));
            }
            ProgressMode::Plain if self.last_line.elapsed() >= PLAIN_EVERY => {
                self.last_line = Instant::now();
                let done = (step - self.start_step) as f64;
                let left = (self.total - step) as f64;
                let eta = self.started.elapsed().as_secs_f64() * left / done.max(1.0);
                eprintln!(
                    "slipfront: {} | {:.1}% | ETA {}",
                    self.status(step, events),
                    100.0 * step as f64 / self.total.max(1) as f64,
                    clock(eta)
                );
            }
            _ => {}
        }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }

    pub fn abandon(&self) {
        self.bar.abandon();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_digits_follow_the_end_time() {
        assert_eq!(decimals(1.0), 4);
        assert_eq!(decimals(2.5), 4);
        assert_eq!(decimals(2e-4), 8);
        assert_eq!(decimals(30.0), 3);
        assert_eq!(clock(3725.0), "1:02:05");
    }
}
