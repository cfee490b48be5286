//! A device that refuses the engine's own SPIR-V (`GpuContext::
//! pipeline_from_spirv`, `refuse_own_spirv`): the refusal is caught as an
//! error, not left for the run's device check, and every engine built
//! after it runs wgpu's modules, with the phase barriers at device scope
//! and mixed f32's fusion guards in place of strict arithmetic, and says
//! so. One test in a binary of its own: the refusal holds for the
//! process's shared context. It fails, never skips, when no adapter
//! exists (lavapipe in CI).

use slipfront::engines::gpu::spirv::{kernel_spirv, ZeroWorkgroupMemory};
use slipfront::engines::gpu::{context, GpuEngine, GpuOptions, GpuPath};
use slipfront::model::scenario::{Scenario, DEFAULT_SCENARIO};
use slipfront::{advance_to, Engine, Model};

fn small() -> Model {
    let set: Vec<String> = slipfront::app::verify::SMALL_SCENE
        .iter()
        .map(|s| s.to_string())
        .collect();
    Model::from_scenario(
        &Scenario::parse(DEFAULT_SCENARIO, "test", &set).unwrap(),
        false,
    )
    .unwrap()
}

#[test]
fn a_refused_own_spirv_falls_back_to_wgpus_modules() {
    let ctx = context::shared()
        .unwrap_or_else(|e| panic!("a GPU adapter is required (lavapipe in CI): {e}"));
    assert!(
        ctx.has_own_spirv(),
        "lavapipe (Vulkan 1.3) takes the engine's SPIR-V"
    );
    let m = small();
    let opts = GpuOptions {
        path: GpuPath::Persistent,
        ..GpuOptions::default()
    };
    let scoped = GpuEngine::<f32>::with_precision(&m, opts).unwrap();
    assert!(scoped
        .describe()
        .contains("phase barriers at workgroup scope"));
    assert!(scoped.describe().contains("strict arithmetic"));
    let k = &scoped.kernel_sources()[0];
    assert!(k.build.workgroup_barriers && k.build.strict_arithmetic);
    // The engine's own words with their first word lost: refused with an
    // error, never given to the driver (the layout's bindings do not matter
    // here: `kernel_spirv` places them at their WGSL numbers). (A module the driver itself
    // refuses comes back the same way, through error scopes; lavapipe
    // cannot be made to refuse a module without undefined behaviour.)
    let (mut words, _) =
        kernel_spirv(k, (1, 3), ZeroWorkgroupMemory::Native, &Default::default()).unwrap();
    words[0] = 0;
    let why = ctx
        .pipeline_from_spirv(k.kernel, &k.entry, words)
        .expect_err("words that are not SPIR-V are refused");
    assert!(why.contains("not a SPIR-V module"), "{why}");
    ctx.check()
        .expect("the refusal is not left as a device error");
    assert!(ctx.has_own_spirv(), "a refusal is the caller's to record");
    ctx.refuse_own_spirv(format!("as the driver would: {why}"));
    assert!(!ctx.has_own_spirv());
    let mut plain = GpuEngine::<f32>::with_precision(&m, opts).unwrap();
    assert!(
        !plain.describe().contains("workgroup scope"),
        "{}",
        plain.describe()
    );
    assert!(!plain.describe().contains("strict arithmetic"));
    let k = &plain.kernel_sources()[0];
    assert!(!k.build.workgroup_barriers && !k.build.strict_arithmetic);
    advance_to(&mut plain, m.prep_steps + 200).unwrap();
    assert!(ctx
        .own_spirv_refused()
        .unwrap()
        .contains("as the driver would"));
}
