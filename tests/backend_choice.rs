//! `--backend auto` on a hardware GPU times the GPU engine against the CPU
//! engine on the scene, from the same state, and runs the faster
//! (`engines::backend_choice`). The comparison itself runs on any adapter:
//! here on lavapipe (in CI), which steps this scene many times slower than
//! the CPU, so the CPU must win; a cached line saying the GPU is faster
//! must make the GPU win (the choice follows the figures). The GPU tests
//! fail, never skip, when no adapter exists.

use slipfront::engines::backend::{faster_of_gpu_and_cpu, Precision};
use slipfront::engines::backend_choice::{cpu_step_seconds, CACHE_FILE};
use slipfront::engines::cpu::SweepEngine;
use slipfront::engines::gpu::context::{self, GpuContext};
use slipfront::engines::gpu::kernel_choice::{ChoiceCache, ChoiceSource, TimedPhase};
use slipfront::engines::gpu::GpuOptions;
use slipfront::{Engine, Model};

#[path = "support/scratch.rs"]
mod scratch;
use scratch::Scratch;

fn ctx() -> GpuContext {
    context::shared().unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"))
}

/// The small scene (29 × 16) with a short normal-load phase, so that
/// lavapipe reaches driving within the kernel choice's budget.
fn small() -> Model {
    let s = slipfront::app::verify::small_scene(&[
        "loading.normal.ramp_time=5e-5",
        "loading.normal.relax_time=5e-5",
    ])
    .unwrap();
    Model::from_scenario(&s, false).unwrap()
}

#[test]
fn auto_times_the_gpu_against_the_cpu_from_the_same_state_and_runs_the_faster() {
    let m = small();
    let dir = Scratch::new("backend", "choice");
    let cache = ChoiceCache::at(&dir);
    let auto = |cache: &ChoiceCache| {
        let (engine, choice) = faster_of_gpu_and_cpu::<f32>(
            &m,
            ctx(),
            GpuOptions::default(),
            Precision::F32,
            1,
            cache,
        )
        .unwrap();
        let timed = choice
            .timed()
            .expect("a small scene's CPU engine fits")
            .clone();
        assert_eq!(choice.describe(), timed.describe());
        (engine, timed)
    };
    let (engine, measured) = auto(&cache);
    println!("{}", measured.describe());
    assert_eq!(measured.source, ChoiceSource::Measured);
    assert_eq!(
        measured.phase,
        TimedPhase::Driving {
            from_step: m.prep_steps - 1
        },
        "both timed from the last step of the normal load"
    );
    assert_eq!(measured.cpu_threads, 1, "the threads asked");
    // lavapipe steps this scene tens of times slower than one CPU thread
    // (BENCHMARKS.md); a factor of 3 leaves room for a busy machine.
    assert!(
        measured.gpu_seconds > 3.0 * measured.cpu_seconds,
        "{}",
        measured.describe()
    );
    assert!(measured.cpu_is_faster());
    assert!(
        engine.describe().starts_with("cpu f32 mixed"),
        "{}",
        engine.describe()
    );
    assert!(measured.describe().ends_with("the CPU steps the run"));

    // Cached: the same figures, no timing.
    let (again, cached) = auto(&cache);
    assert_eq!(cached.source, ChoiceSource::Cached);
    assert_eq!(
        (cached.gpu_seconds, cached.cpu_seconds, &cached.gpu_launch),
        (
            measured.gpu_seconds,
            measured.cpu_seconds,
            &measured.gpu_launch
        )
    );
    assert!(again.describe().starts_with("cpu"));

    // Control: the same line with the GPU's figure under the CPU's; the
    // GPU steps the run.
    let file = dir.join(CACHE_FILE);
    let text = std::fs::read_to_string(&file).unwrap();
    let gpu = format!("{:e}", measured.gpu_seconds);
    let faster = format!("{:e}", measured.cpu_seconds / 2.0);
    assert_eq!(text.matches(&gpu).count(), 1, "{text}");
    std::fs::write(&file, text.replace(&gpu, &faster)).unwrap();
    let (gpu_engine, doctored) = auto(&cache);
    assert!(!doctored.cpu_is_faster());
    assert!(
        gpu_engine.describe().starts_with("gpu f32 mixed"),
        "{}",
        gpu_engine.describe()
    );
    assert!(doctored.describe().ends_with("the GPU steps the run"));
}

/// `--threads 0` on a small lattice: the CPU engine is timed after its own
/// trial of thread counts, on the count it keeps.
#[test]
fn the_cpu_is_timed_on_the_thread_count_its_trial_keeps() {
    let m = small();
    let mut engine = SweepEngine::<f64>::new(&m, 0).unwrap();
    let seconds = cpu_step_seconds(&mut engine, None, 0.0).unwrap();
    assert!(seconds > 0.0 && seconds < 0.01, "{seconds}");
    assert!(
        !engine.timing_threads(),
        "the trial ended before the timing"
    );
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if cores > 1 {
        let timed = engine
            .threads_timed()
            .expect("a trial on a machine with cores");
        assert!(timed.describe().contains("µs"), "{}", timed.describe());
    }
}

/// A large lattice whose first CPU step is slower than `SLOW_STEP_SECONDS`
/// (5 ms) and than the GPU's figure is timed over that step alone: `auto`
/// does not spend seconds timing a CPU that has lost. Control: against a
/// slower GPU the same CPU is timed in full.
#[test]
fn a_cpu_slower_than_the_gpu_on_its_first_large_step_is_not_timed_further() {
    // Square blocks: the small scene's length over 2047 spacings.
    let height = format!("geometry.height={}", 0.07 * 255.0 / 2047.0);
    let s = slipfront::app::verify::small_scene(&["geometry.nx=2048", "geometry.nz=256", &height])
        .unwrap();
    let m = Model::from_scenario(&s, false).unwrap();
    let mut lost = SweepEngine::<f64>::new(&m, 1).unwrap();
    let first = cpu_step_seconds(&mut lost, None, 1e-6).unwrap();
    assert!(first > 5e-3, "{first}");
    assert_eq!(lost.steps_done(), 1);
    let mut timed = SweepEngine::<f64>::new(&m, 1).unwrap();
    cpu_step_seconds(&mut timed, None, 10.0).unwrap();
    assert!(timed.steps_done() > 32, "{}", timed.steps_done());
}
