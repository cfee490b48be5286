//! Whether the shared adapter runs the f64 kernels (SHADER_F64). Adapters
//! without it run mixed f32 only, and an f64 comparison has nothing to
//! compare there; in CI (`CI=true`, lavapipe, which has it) its absence
//! fails the test instead.

pub fn f64_adapter() -> bool {
    let ctx = slipfront::engines::gpu::context::shared().expect("a GPU adapter");
    if ctx.check_precision::<f64>().is_ok() {
        return true;
    }
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "{}: no f64 in CI",
        ctx.info.name
    );
    println!("{}: no f64, nothing to compare", ctx.info.name);
    false
}
