//! Every case of `slipfront verify` on the GPU engine (lavapipe in CI).
//! Fails, never skips, when no adapter exists.

use slipfront::app::verify::{failures, run_all};
use slipfront::engines::gpu::GpuEngine;
use slipfront::{Engine, EngineError, Model};

// About 70 s on 2-core lavapipe.
#[test]
fn every_verify_case_passes_on_the_gpu() {
    let factory =
        |m: &Model| -> Result<Box<dyn Engine>, EngineError> { Ok(Box::new(GpuEngine::new(m)?)) };
    let results = run_all(&factory).expect("a GPU adapter is required (lavapipe in CI)");
    assert_eq!(failures(&results), Vec::<String>::new());
}
