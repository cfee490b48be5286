//! Every case of `slipfront verify` on the GPU engine (lavapipe in CI).
//! Fails, never skips, when no adapter exists.

use slipfront::gpu::GpuEngine;
use slipfront::verify::{failures, run_all};
use slipfront::{Engine, EngineError, Model};

// On 2-core lavapipe the whole list takes longer than 10 minutes (about
// 400 000 steps at ~0.3 ms of dispatch overhead each): run it with
// `cargo test --release --test gpu_verify -- --ignored` or
// `slipfront verify --backend gpu --precision f32`.
#[test]
#[ignore = "over 10 minutes on lavapipe; run explicitly"]
fn every_verify_case_passes_on_the_gpu() {
    let factory =
        |m: &Model| -> Result<Box<dyn Engine>, EngineError> { Ok(Box::new(GpuEngine::new(m)?)) };
    let results = run_all(&factory).expect("a GPU adapter is required (lavapipe in CI)");
    assert_eq!(failures(&results), Vec::<String>::new());
}
