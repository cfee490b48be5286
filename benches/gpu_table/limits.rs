//! Section 8: what limits an ensemble of Table S1 scenes.

use crate::common::counts_from_env;
use crate::gpu_timing::ensemble_step_seconds_in;
use slipfront::engines::gpu::kernel_choice::{Launch, ENSEMBLE_GROUP_SCENES};
use slipfront::engines::gpu::options::LANE_RUN_TIMED;
use slipfront::engines::gpu::shaders::Kernel;
use slipfront::engines::gpu::{GpuOptions, GpuReal};
use slipfront::model::scenario::built_in;
use slipfront::{Model, Scenario};

/// Section 8: the single-workgroup kernels on one Table S1 scene and on a
/// staircase of scene counts (1, 128, 192, 256 by default), for scenes with
/// less and less junction work (Ns = 100 as shipped, Ns = 16, Coulomb) in
/// mixed f32, and as shipped in f64. More scenes than fit the GPU at once
/// run in waves, so the step grows in stairs: from 128 to 192 scenes it
/// doubles where one workgroup fills an SM (an H200 has 132), and stays
/// where two fit. Where they fit, how much longer the step is than one
/// scene's says whether scenes that share an SM overlap or contend, and the
/// scene variants say in which phase (docs/gpu-kernels.md, "What limits an
/// ensemble").
pub fn ensemble_limits(quick: bool, min_seconds: f64) {
    // 8. What limits an ensemble.
    println!("\n## 8. What limits an ensemble of Table S1 scenes\n");
    let counts = counts_from_env(
        "SLIPFRONT_GPU_TABLE_LIMIT_SCENES",
        if quick { &[1, 4] } else { &[1, 132, 264, 528] },
    );
    let most = counts.iter().copied().max().unwrap_or(1);
    // Half a second a figure: a step of tens of µs is then thousands of
    // steps, and the section fits one step of gpu_call.sh.
    let min_seconds = min_seconds.min(0.5);
    let text = built_in("tromborg2014_precursors").expect("shipped scene");
    print_header(&counts);
    // Why a launch did not run ("–" in the table), each reason once.
    let mut not_run: Vec<String> = Vec::new();
    // (scene, its settings, precision, threads): 1024 threads (a scene a
    // workgroup that fills its SM) as the control on the shipped scene,
    // 256 threads (room for several scenes an SM) on every variant.
    let both: &[u32] = &[256, 1024];
    let few: &[u32] = &[256];
    let variants: [(&str, Option<&str>, bool, &[u32]); 4] = [
        ("Ns = 100 (as shipped)", None, false, both),
        ("Ns = 100 (as shipped)", None, true, both),
        ("Ns = 16", Some("friction.junctions.count=16"), false, few),
        (
            "Coulomb (no junctions)",
            Some("friction.law=coulomb"),
            false,
            few,
        ),
    ];
    for (name, set, f64_run, threads) in variants {
        let models = seeded_models(text, set, most);
        let rows = LimitRows {
            name,
            models: &models,
            counts: &counts,
            threads,
            min_seconds,
            // In f64 one lane a round needs fewer registers (AMD: 72–80
            // VGPRs against 88), so it may fit more scenes an SM.
            one_lane_too: f64_run,
            // Lane runs: fewer instructions a block's lanes, more
            // registers a thread (BENCHMARKS.md, session 57); on the
            // shipped scene in mixed f32.
            lane_run_too: name.contains("shipped") && !f64_run,
        };
        if f64_run {
            rows.print::<f64>("f64", &mut not_run);
        } else {
            rows.print::<f32>("mixed f32", &mut not_run);
        }
    }
    println!();
    for line in &not_run {
        println!("{line}");
    }
}

/// What a row says, and the table's header: a column for each of
/// `counts`, then each count's step over one scene's.
fn print_header(counts: &[usize]) {
    println!(
        "Each row: µs per ensemble step at each scene count, then each count's step over \
         one scene's (1.0: the scenes ran at once without slowing each other; 2.0: in two \
         waves, or side by side at half speed).\n"
    );
    let header: String = counts
        .iter()
        .map(|&n| format!(" {n} scene{} |", if n == 1 { "" } else { "s" }))
        .collect();
    let ratios: String = counts[1..].iter().map(|n| format!(" {n} / 1 |")).collect();
    let last = counts[counts.len() - 1];
    println!("| scene | precision | launch |{header}{ratios} block-steps/s at {last} |");
    let rule = " ---: |".repeat(2 * counts.len());
    println!("| --- | --- | --- |{rule}");
}

/// Seeds 1 to `most` of the precursors scene in `text`, with `set`'s key
/// changed where given.
fn seeded_models(text: &str, set: Option<&str>, most: usize) -> Vec<Model> {
    (1..=most)
        .map(|seed| {
            let mut sets = vec![format!("time.seed={seed}")];
            sets.extend(set.map(String::from));
            let scenario = Scenario::parse(text, "table S1", &sets).expect("a Table S1 variant");
            Model::from_scenario(&scenario, false).expect("a Table S1 variant")
        })
        .collect()
}

/// Section 8's rows of one scene variant.
struct LimitRows<'a> {
    name: &'a str,
    models: &'a [Model],
    counts: &'a [usize],
    threads: &'a [u32],
    min_seconds: f64,
    /// Each launch again with one junction lane a round.
    one_lane_too: bool,
    /// Each launch again with `LANE_RUN_TIMED` junction lanes a thread.
    lane_run_too: bool,
}

impl LimitRows<'_> {
    /// The rows in precision `T`: the resident and persistent kernels at
    /// each of the threads (and each with one junction lane a round, and
    /// with lane runs, where asked), each on the first `n` scenes for each
    /// count. A
    /// launch that does not run (resident in f64 at Table S1 does not fit)
    /// adds its reason to `not_run`.
    fn print<T: GpuReal>(&self, precision: &str, not_run: &mut Vec<String>) {
        let launches = [Kernel::Resident, Kernel::Persistent]
            .into_iter()
            .flat_map(|kernel| {
                self.threads
                    .iter()
                    .map(move |&t| Launch::with_threads(kernel, t))
            })
            .flat_map(|launch| {
                let one = self.one_lane_too.then(|| launch.with_one_lane_a_round());
                let run = self
                    .lane_run_too
                    .then(|| launch.with_lane_run(LANE_RUN_TIMED));
                std::iter::once(launch).chain(one).chain(run)
            });
        // Where the rows have 1024 threads, also the persistent kernel with
        // two and four scenes side by side in them: 1024-thread
        // workgroups fill an SM's registers, so this is how scenes share
        // one (264 scenes in pairs: one wave of 132 workgroups).
        let grouped = self
            .threads
            .contains(&1024)
            .then_some(ENSEMBLE_GROUP_SCENES)
            .into_iter()
            .flatten()
            .map(|g| Launch::with_threads(Kernel::Persistent, 1024).with_group_scenes(g));
        for launch in launches.chain(grouped) {
            self.print_launch::<T>(launch, precision, not_run);
        }
    }

    /// The row of `launch` in precision `T`.
    fn print_launch<T: GpuReal>(&self, launch: Launch, precision: &str, not_run: &mut Vec<String>) {
        let blocks = self.models[0].n_blocks() as f64;
        let steps: Vec<Result<f64, String>> = self
            .counts
            .iter()
            .map(|&n| {
                ensemble_step_seconds_in::<T>(
                    &self.models[..n],
                    launch.options(GpuOptions::default()),
                    self.min_seconds,
                )
                .map(|(s, _)| s)
            })
            .collect();
        let cells: String = steps
            .iter()
            .map(|r| match r {
                Ok(s) => format!(" {:.2} |", s * 1e6),
                Err(_) => " – |".to_string(),
            })
            .collect();
        for e in steps.iter().filter_map(|r| r.as_ref().err()) {
            let line = format!("- {}, {precision}: not run: {e}", launch.name());
            if !not_run.contains(&line) {
                not_run.push(line);
            }
        }
        let ratios: String = steps[1..]
            .iter()
            .map(|r| match (r, &steps[0]) {
                (Ok(s), Ok(one)) => format!(" {:.2} |", s / one),
                _ => " |".to_string(),
            })
            .collect();
        let last = self.counts[self.counts.len() - 1] as f64;
        let rate = match steps.last() {
            Some(Ok(s)) => format!("{:.3e}", last * blocks / s),
            _ => String::new(),
        };
        println!(
            "| {} | {precision} | {} |{cells}{ratios} {rate} |",
            self.name,
            launch.name()
        );
    }
}
