//! Does the GPU engine give CPU f64's outcome distribution? Each kernel's
//! perturbation ensemble against f64's, in one command for a loan of a GPU:
//!
//!     cargo bench --bench gpu_precision
//!
//! (on the lent GPU machine: the packed `gpu_precision` binary).
//!
//! The GPU's mixed f32 is not the CPU twin's to the bit: the driver's
//! divisions, square roots and contractions are its own, and the kernels
//! merge junction lanes in their own trees. Chaos makes one trajectory
//! prove nothing, so this asks what `tests/precision_ensembles.rs` asks of
//! the CPU's mixed f32, of every GPU kernel:
//!
//! - The scene: `scenarios/small_stick_slip.toml` (15×8, 0.3 s of
//!   stick-slip, about 20 events a run), the slider 1 cm along the track,
//!   drive speed × (1 + k·1e-6) for k = 0..RUNS.
//! - Ns = 32 junctions a block (the scene has 20), so a block's lanes are a
//!   multiple of a 32-wide subgroup and the lane shuffles run at every
//!   level an NVIDIA GPU allows.
//! - The reference: CPU f64 on the same members. Each GPU ensemble (one
//!   dispatch of all members, as `sweep --backend gpu` runs them) is
//!   compared on every outcome, the first event too; the verdict is the
//!   smallest p times the number of tests (Bonferroni) against 0.01.
//! - The yardstick: f64 on other members, on the outcomes chaos has mixed.
//! - The control: f64 with μd 15 % higher. Each GPU ensemble must be told
//!   from it, or the comparison could not have seen a bias.
//!
//! Environment (each refused with its name when malformed):
//! - `SLIPFRONT_GPU_PRECISION_KERNELS=auto,persistent`: those `--gpu-path`
//!   values only (default: `auto` and every kernel that fits the scene);
//! - `SLIPFRONT_GPU_PRECISION_RUNS` (default 24), `SLIPFRONT_GPU_PRECISION_END`
//!   (seconds of driving, default the scene's 0.3),
//!   `SLIPFRONT_GPU_PRECISION_JUNCTIONS` (Ns, default 32);
//! - `SLIPFRONT_GPU_PRECISION_BOND_PATCHES=1`: the GPU ensembles with their
//!   bulk forces by 2×2 patches of blocks (`--gpu-bond-patches`);
//! - `SLIPFRONT_GPU_PRECISION_F64=0`: no GPU f64 ensemble (by default one
//!   runs where the adapter has f64: on lavapipe another 20 to 50 minutes);
//! - `SLIPFRONT_GPU_PRECISION_QUICK=1`: 8 runs of 0.03 s, `auto` only, for a
//!   software adapter. Too few events for a verdict, and the table says so.
//!
//! On lavapipe a full-size GPU ensemble takes 20 to 50 minutes (2 cores);
//! on an H200 about 5 to 20 s each.

use slipfront::app::sweeps::compare::{compare_tables, Comparison};
use slipfront::app::sweeps::verdict::Members;
use slipfront::app::sweeps::{default_gpu, run_sweep, KeepMcap, Sweep, SweepOptions};
use slipfront::engines::backend::{Backend, Precision};
use slipfront::engines::gpu::kernel_choice::candidates;
use slipfront::engines::gpu::{context, GpuOptions, GpuPath};
use slipfront::model::scenario::Scenario;
use slipfront::Model;
use std::path::{Path, PathBuf};
use std::str::FromStr;

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scenarios/small_stick_slip.toml"
);
const ALPHA: f64 = 0.01;
/// μd 15 % above the scene's 0.17: about one standard deviation of the
/// event count and mean slip (tests/precision_ensembles.rs).
const BIASED: &str = "\"friction.dynamic_coefficient\" = 0.1955\n";

/// What this invocation runs.
struct Plan {
    runs: usize,
    /// Seconds of driving (None: the scene's).
    end: Option<f64>,
    junctions: usize,
    /// `--gpu-path` values.
    kernels: Vec<GpuPath>,
    /// The GPU ensembles' bulk forces by patches of blocks.
    bond_patches: bool,
    /// A GPU f64 ensemble too, where the adapter has f64.
    gpu_f64: bool,
    quick: bool,
}

/// `name`'s value, `default` where unset; a value outside `allowed` (what
/// `valid` accepts) stops the bench with a message naming both.
fn env_parsed<T: FromStr>(name: &str, default: T, allowed: &str, valid: impl Fn(&T) -> bool) -> T {
    match std::env::var(name) {
        Err(_) => default,
        Ok(text) => match text.trim().parse::<T>() {
            Ok(v) if valid(&v) => v,
            _ => {
                eprintln!("{name}={text}: expected {allowed}");
                std::process::exit(2);
            }
        },
    }
}

/// `name` set to 1 (true) or unset or 0 (false); anything else stops the
/// bench with a message naming it.
fn env_switch(name: &str) -> bool {
    match std::env::var(name).as_deref() {
        Err(_) | Ok("0") => false,
        Ok("1") => true,
        Ok(v) => {
            eprintln!("{name}={v}: expected 0 or 1");
            std::process::exit(2);
        }
    }
}

fn plan(model_of: impl Fn(usize) -> Model) -> Plan {
    let quick = env_switch("SLIPFRONT_GPU_PRECISION_QUICK");
    let runs = env_parsed(
        "SLIPFRONT_GPU_PRECISION_RUNS",
        if quick { 8 } else { 24 },
        "a whole number from 4 to 1024",
        |n| (4..=1024).contains(n),
    );
    let end = env_parsed(
        "SLIPFRONT_GPU_PRECISION_END",
        if quick { 0.03 } else { 0.0f64 },
        "seconds of driving, 0 or more (0: the scene's)",
        |t| *t >= 0.0 && t.is_finite(),
    );
    let junctions = env_parsed(
        "SLIPFRONT_GPU_PRECISION_JUNCTIONS",
        32usize,
        "a whole number from 2 to 4096",
        |n| (2..=4096).contains(n),
    );
    let kernels = match std::env::var("SLIPFRONT_GPU_PRECISION_KERNELS") {
        Ok(list) => list
            .split(',')
            .map(|name| {
                <GpuPath as clap::ValueEnum>::from_str(name.trim(), false).unwrap_or_else(|e| {
                    eprintln!("SLIPFRONT_GPU_PRECISION_KERNELS: {name}: {e}");
                    std::process::exit(2);
                })
            })
            .collect(),
        Err(_) if quick => vec![GpuPath::Auto],
        Err(_) => std::iter::once(GpuPath::Auto)
            .chain(
                candidates(&model_of(junctions))
                    .into_iter()
                    .map(GpuPath::of),
            )
            .collect(),
    };
    Plan {
        runs,
        end: (end > 0.0).then_some(end),
        junctions,
        kernels,
        bond_patches: env_switch("SLIPFRONT_GPU_PRECISION_BOND_PATCHES"),
        gpu_f64: std::env::var("SLIPFRONT_GPU_PRECISION_F64").is_err()
            || env_switch("SLIPFRONT_GPU_PRECISION_F64"),
        quick,
    }
}

/// One ensemble's sweep: RUNS members from `start`, the plan's scene with
/// `extra` keys, on `backend` in `precision` (GPU: `path`).
struct Ensemble<'a> {
    name: &'a str,
    start: usize,
    backend: Backend,
    precision: Precision,
    path: GpuPath,
    extra: &'a str,
}

/// Runs `e` into `dir`: its table, and its wall seconds.
fn run(dir: &Path, plan: &Plan, e: &Ensemble) -> Result<(PathBuf, f64), String> {
    let file = dir.join(format!("{}.toml", e.name));
    let end = plan
        .end
        .map_or(String::new(), |t| format!("\"time.end\" = {t:e}\n"));
    std::fs::write(
        &file,
        format!(
            "base = \"{SCENE}\"\n\
             perturb = {{ key = \"loading.drive.velocity\", relative = 1e-6, count = {}, \
             start = {} }}\n\
             [set]\n\"output.bulk_interval\" = 0.0\n\"start.position\" = 0.01\n\
             \"friction.junctions.count\" = {}\n{end}{}",
            plan.runs, e.start, plan.junctions, e.extra
        ),
    )
    .map_err(|err| err.to_string())?;
    let sweep = Sweep::load(&file).map_err(|errs| errs.join("; "))?;
    let out = dir.join(e.name);
    let report = run_sweep(
        &sweep,
        &SweepOptions {
            out_dir: out.clone(),
            backend: e.backend,
            precision: e.precision,
            threads: 0,
            shard: None,
            keep_mcap: KeepMcap::None,
            progress: false,
            share_loading: true,
            ensemble: slipfront::app::sweeps::DEFAULT_ENSEMBLE,
            gpu: GpuOptions {
                path: e.path,
                bond_patches: plan.bond_patches && e.backend == Backend::Gpu,
                ..default_gpu()
            },
            on_point: None,
        },
    )?;
    if report.not_ok > 0 {
        return Err(format!("{} of {} runs not ok", report.not_ok, report.ran));
    }
    Ok((out, report.wall_seconds))
}

/// (Bonferroni-corrected smallest p, the outcome and test behind it).
fn verdict(c: &Comparison, members: Members) -> (f64, String) {
    match c.verdict(members) {
        Some(v) => (v.corrected, v.describe()),
        None => (f64::NAN, "no outcome to compare".into()),
    }
}

fn compared(a: &Path, b: &Path, members: Members) -> (f64, String) {
    match compare_tables(a, b) {
        Ok(c) => verdict(&c, members),
        Err(e) => (f64::NAN, e),
    }
}

fn main() {
    let model_of = |junctions: usize| {
        let scenario = Scenario::load(
            Path::new(SCENE),
            &[format!("friction.junctions.count={junctions}")],
        )
        .expect("the scene");
        Model::from_scenario(&scenario, false).expect("the scene's model")
    };
    let plan = plan(model_of);
    let ctx = context::shared()
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe where none): {e}"));
    println!("adapter: {}", ctx.describe());
    println!(
        "scene: small_stick_slip, Ns = {}, {} members a side, {} of driving{}\n",
        plan.junctions,
        plan.runs,
        plan.end
            .map_or("the scene's 0.3 s".into(), |t| format!("{t} s")),
        if plan.quick {
            " (quick: too few events for a verdict)"
        } else {
            ""
        }
    );
    let dir = std::env::temp_dir().join(format!("slipfront-gpu-precision-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let cpu = |name, start, extra| Ensemble {
        name,
        start,
        backend: Backend::Cpu,
        precision: Precision::F64,
        path: GpuPath::Auto,
        extra,
    };
    let reference = cpu("cpu_f64", 0, "");
    let (f64_a, f64_wall) = run(&dir, &plan, &reference).expect("the f64 reference");
    let (f64_b, _) = run(&dir, &plan, &cpu("cpu_f64_other", plan.runs, "")).expect("the yardstick");
    let (biased, _) = run(&dir, &plan, &cpu("cpu_f64_biased", 0, BIASED)).expect("the control");
    let (yardstick, why) = compared(&f64_a, &f64_b, Members::Disjoint);
    println!("CPU f64 (all cores): {f64_wall:.1} s an ensemble");
    println!("yardstick, f64 against f64 on other members: corrected p {yardstick:.3} ({why})");
    let (seen, why) = compared(&f64_a, &biased, Members::Disjoint);
    println!("control, f64 against f64 with μd +15 %: corrected p {seen:.2e} ({why})\n");

    let mut gpu_runs: Vec<(String, Precision, GpuPath)> = plan
        .kernels
        .iter()
        .map(|&p| (format!("gpu_f32_{}", p.name()), Precision::F32, p))
        .collect();
    if plan.gpu_f64 && ctx.check_precision::<f64>().is_ok() {
        gpu_runs.push(("gpu_f64_auto".into(), Precision::F64, GpuPath::Auto));
    }
    println!("| GPU ensemble | wall s | against f64, same members: corrected p | verdict | against μd +15 %: corrected p | bias seen |");
    println!("| --- | ---: | --- | --- | --- | --- |");
    let mut failed = 0;
    for (name, precision, path) in &gpu_runs {
        let e = Ensemble {
            name,
            start: 0,
            backend: Backend::Gpu,
            precision: *precision,
            path: *path,
            extra: "",
        };
        let label = format!(
            "{}{} {}",
            path.name(),
            if plan.bond_patches {
                "/bond-patches"
            } else {
                ""
            },
            if *precision == Precision::F64 {
                "f64"
            } else {
                "mixed f32"
            }
        );
        match run(&dir, &plan, &e) {
            Err(err) => {
                failed += 1;
                println!("| {label} | | not run: {err} | | | |");
            }
            Ok((table, wall)) => {
                let (same, why_same) = compared(&f64_a, &table, Members::Same);
                let (bias, why_bias) = compared(&biased, &table, Members::Disjoint);
                let agrees = same >= ALPHA;
                let sees = bias < ALPHA;
                failed += usize::from(!agrees) + usize::from(!sees);
                println!(
                    "| {label} | {wall:.1} | {same:.3} ({why_same}) | {} | {bias:.2e} ({why_bias}) | {} |",
                    if agrees { "same" } else { "DIFFERS" },
                    if sees { "yes" } else { "NO" }
                );
            }
        }
    }
    println!();
    if plan.quick {
        println!("quick: {failed} lines against expectation; not a verdict at this size");
    } else if failed == 0 {
        println!(
            "every GPU ensemble gives f64's outcomes, and each is told from the biased control"
        );
    } else {
        println!("{failed} checks not met (see the table)");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
