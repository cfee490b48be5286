//! `slipfront compare A B`: two sweep tables' outcome distributions side
//! by side with their tests, as text or JSON, and optionally a figure of
//! the empirical CDFs. Exits 1 when some outcome differs at p < alpha, or,
//! with `--members`, when the Bonferroni verdict over the tests those
//! members make fair is below alpha.

use slipfront::analysis::stats::Quartiles;
use slipfront::app::sweeps::compare::{
    compare_ensembles, Comparison, ContinuousOutcome, FOLLOWS_PERTURBATION,
};
use slipfront::app::sweeps::outcome_rows::read_ensemble;
use slipfront::app::sweeps::verdict::{shared_perturbations, Members, Verdict};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

pub struct CompareArgs {
    pub a: PathBuf,
    pub b: PathBuf,
    pub alpha: f64,
    pub label_a: Option<String>,
    pub label_b: Option<String>,
    pub json: bool,
    pub figure: Option<PathBuf>,
    /// Judge by one corrected verdict for ensembles of these members.
    pub members: Option<Members>,
}

pub fn compare(args: CompareArgs) -> anyhow::Result<ExitCode> {
    anyhow::ensure!(
        args.alpha > 0.0 && args.alpha < 1.0,
        "--alpha {}: expected a level between 0 and 1",
        args.alpha
    );
    if let Some(f) = &args.figure {
        slipfront::analysis::plot::Format::from_path(f)?;
    }
    let ea = read_ensemble(&args.a).map_err(|e| anyhow::anyhow!(e))?;
    let eb = read_ensemble(&args.b).map_err(|e| anyhow::anyhow!(e))?;
    if args.members == Some(Members::Same) {
        let shared = shared_perturbations(&ea.runs, &eb.runs);
        let fewer = ea.runs.len().min(eb.runs.len());
        anyhow::ensure!(
            2 * shared > fewer,
            "--members same: {shared} of A's {} ok runs have a perturbation that B has (the \
             tables' perturb(KEY) column), expected most of the {fewer} runs of the smaller side; \
             ensembles of other perturbations are compared with --members disjoint",
            ea.runs.len()
        );
    }
    let label = |given: Option<String>, path: &Path| given.unwrap_or(path.display().to_string());
    let c = compare_ensembles(
        &ea,
        &eb,
        &label(args.label_a, &args.a),
        &label(args.label_b, &args.b),
    );
    let verdict = args.members.and_then(|m| c.verdict(m));
    let differs = match args.members {
        Some(_) => verdict.as_ref().is_some_and(|v| v.differs(args.alpha)),
        None => c.differs(args.alpha),
    };
    if args.json {
        let mut v = serde_json::to_value(&c)?;
        v["alpha"] = serde_json::json!(args.alpha);
        v["min_p"] = serde_json::to_value(c.min_p())?;
        v["bonferroni_min_p"] = serde_json::json!(c.bonferroni_min_p());
        v["tests"] = serde_json::json!(c.p_values().len());
        v["differing"] = serde_json::to_value(c.differing(args.alpha))?;
        v["verdict"] = serde_json::to_value(&verdict)?;
        v["differs"] = serde_json::json!(differs);
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        print_report(&c, args.alpha, args.members.is_some());
        if let Some(members) = args.members {
            print_verdict(verdict.as_ref(), members, args.alpha);
        }
    }
    if let Some(path) = &args.figure {
        write_figure(&c, path)?;
        eprintln!("compare: figure {}", path.display());
    }
    Ok(if differs {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

/// "0.0123" or "3.2e-5"; "-" for no test; " differs" appended below alpha.
fn p_text(p: Option<f64>, alpha: f64) -> String {
    match p {
        None => "-".into(),
        Some(p) => {
            let text = if p >= 1e-3 {
                format!("{p:.4}")
            } else {
                format!("{p:.2e}")
            };
            if p < alpha {
                format!("{text} differs")
            } else {
                text
            }
        }
    }
}

fn summary_line(name: &str, q: Option<Quartiles>, extra: &str) -> String {
    match q {
        None => format!("  {name:<12} {:>5}  (no values){extra}", 0),
        Some(q) => format!(
            "  {name:<12} {:>5}  {:>11.4e} {:>11.4e} {:>11.4e} {:>11.4e} {:>11.4e}{extra}",
            q.n, q.min, q.q1, q.median, q.q3, q.max
        ),
    }
}

/// The side labels shortened for the table's first column.
fn short(label: &str) -> String {
    let chars: Vec<char> = label.chars().collect();
    if chars.len() <= 12 {
        label.to_string()
    } else {
        format!("…{}", chars[chars.len() - 11..].iter().collect::<String>())
    }
}

fn print_continuous(c: &ContinuousOutcome, la: &str, lb: &str, alpha: f64) {
    println!("{}", c.name);
    println!(
        "  {:<12} {:>5}  {:>11} {:>11} {:>11} {:>11} {:>11}",
        "", "n", "min", "q1", "median", "q3", "max"
    );
    let missing = |n: usize| match c.missing_label {
        Some(l) if n > 0 => format!("  (+{n} {l})"),
        _ => String::new(),
    };
    println!("{}", summary_line(la, c.a.summary, &missing(c.a.missing)));
    println!("{}", summary_line(lb, c.b.summary, &missing(c.b.missing)));
    println!(
        "  KS D = {}  p = {}   AD A² = {}  p = {}",
        c.ks.map_or("-".into(), |t| format!("{:.3}", t.statistic)),
        p_text(c.ks.map(|t| t.p), alpha),
        c.ad.map_or("-".into(), |t| format!("{:.3}", t.statistic)),
        p_text(c.ad.map(|t| t.p), alpha),
    );
    let modes: Vec<String> = c
        .modes
        .iter()
        .map(|m| format!("[{}] {}:{}", m.label, m.a, m.b))
        .collect();
    println!(
        "  modes ({la}:{lb}) {}   p = {}{}",
        modes.join("  "),
        p_text(c.modes_test.map(|t| t.p), alpha),
        simulated(c.modes_test.map_or(0, |t| t.simulated)),
    );
    let follows: Vec<String> = [
        (la, c.a.follows_perturbation),
        (lb, c.b.follows_perturbation),
    ]
    .iter()
    .filter_map(|(l, r)| {
        r.filter(|r| r.abs() >= FOLLOWS_PERTURBATION)
            .map(|r| format!("{l} ρ = {r:.2}"))
    })
    .collect();
    if !follows.is_empty() {
        println!(
            "  note: follows the perturbation smoothly ({}): chaos has not scrambled it, so this \
             compares responses to the perturbation, not draws from one spread",
            follows.join(", ")
        );
    }
}

fn simulated(tables: usize) -> String {
    if tables > 0 {
        format!(" (Monte Carlo, {tables} tables)")
    } else {
        String::new()
    }
}

/// `judged_after`: a `--members` verdict follows, so the closing line is
/// marked as each test's own.
fn print_report(c: &Comparison, alpha: f64, judged_after: bool) {
    let (la, lb) = (short(&c.label_a), short(&c.label_b));
    for (label, runs, dropped) in [
        (&c.label_a, c.runs_a, &c.dropped_a),
        (&c.label_b, c.runs_b, &c.dropped_b),
    ] {
        let left_out: Vec<String> = dropped.iter().map(|(s, n)| format!("{n} {s}")).collect();
        println!(
            "{label}: {runs} ok runs{}",
            if left_out.is_empty() {
                String::new()
            } else {
                format!(" ({} left out)", left_out.join(", "))
            }
        );
    }
    println!();
    for o in &c.continuous {
        print_continuous(o, &la, &lb, alpha);
        println!();
    }
    for o in &c.counts {
        println!("{}", o.name);
        let hist = |side: fn(&(u64, u64, u64)) -> u64| {
            o.histogram
                .iter()
                .filter(|h| side(h) > 0)
                .map(|h| format!("{}×{}", h.0, side(h)))
                .collect::<Vec<_>>()
                .join(" ")
        };
        println!("  {la:<12} {}", hist(|h| h.1));
        println!("  {lb:<12} {}", hist(|h| h.2));
        println!(
            "  exact p = {}{}",
            p_text(o.test.map(|t| t.p), alpha),
            simulated(o.test.map_or(0, |t| t.simulated))
        );
        println!();
    }
    let tests = c.p_values().len();
    match c.min_p() {
        None => println!("no test could run (no outcome has values on both sides)"),
        Some(m) => {
            let differing = c.differing(alpha);
            println!(
                "{}smallest p = {} ({} {}) of {tests} tests (Bonferroni {}): {}",
                if judged_after {
                    "each test alone: "
                } else {
                    ""
                },
                p_text(Some(m.p), 0.0),
                m.outcome,
                m.test,
                p_text(c.bonferroni_min_p(), 0.0),
                if differing.is_empty() {
                    format!("no outcome differs at p < {alpha}")
                } else {
                    let names: Vec<String> = differing
                        .iter()
                        .map(|d| format!("{} {}", d.outcome, d.test))
                        .collect();
                    format!("DIFFERS at p < {alpha}: {}", names.join(", "))
                }
            )
        }
    }
}

/// The closing line of `--members`: the one verdict the exit status follows.
fn print_verdict(verdict: Option<&Verdict>, members: Members, alpha: f64) {
    let which = match members {
        Members::Same => "same members: every outcome",
        Members::Disjoint => "disjoint members: the whole-run outcomes chaos has mixed",
    };
    match verdict {
        None => println!("verdict ({which}): no such test could run"),
        Some(v) => println!(
            "verdict ({which}): corrected p = {} ({}): {}",
            p_text(Some(v.corrected), 0.0),
            v.describe(),
            if v.differs(alpha) {
                format!("the ensembles DIFFER at corrected p < {alpha}")
            } else {
                format!("the ensembles do not differ at corrected p < {alpha}")
            }
        ),
    }
}

/// One panel per continuous outcome with values: both empirical CDFs,
/// captioned with the KS and AD p-values.
fn write_figure(c: &Comparison, path: &Path) -> anyhow::Result<()> {
    use slipfront::analysis::plot::ecdf::{EcdfComparison, EcdfPanel};
    let p = |p: Option<f64>| p_text(p, 0.0);
    let figure = EcdfComparison {
        panels: c
            .continuous
            .iter()
            .map(|o| EcdfPanel {
                caption: format!(
                    "{}: KS p = {}, AD p = {}",
                    o.name,
                    p(o.ks.map(|t| t.p)),
                    p(o.ad.map(|t| t.p))
                ),
                a: &o.a.values,
                b: &o.b.values,
            })
            .collect(),
        label_a: &c.label_a,
        label_b: &c.label_b,
    };
    let options = slipfront::analysis::plot::FigureOptions {
        format: slipfront::analysis::plot::Format::from_path(path)?,
        width: 1200,
        height: 700,
        dpi: 100,
    };
    slipfront::analysis::plot::write(&figure, path, &options, "")?;
    Ok(())
}
