//! The driver's own figures for the kernels (`driver_stats`), from a real
//! production compiler on a machine without a GPU: Mesa's RADV on its null
//! device (`RADV_FORCE_FAMILY`), AMD's ACO compiler, which reports its
//! registers through VK_KHR_pipeline_executable_properties. The same
//! Debian package as lavapipe (mesa-vulkan-drivers) ships it. In CI
//! (`CI=true`) these tests fail, never skip, without it.
//!
//! This binary never opens wgpu: with RADV_FORCE_FAMILY set, wgpu would
//! list the null device as a discrete GPU and pick it. The engine's own
//! kernels are taken device-free (`GpuEngine::kernel_sources_on`);
//! `tests/gpu_engine.rs` checks they are the ones an engine compiles.

use slipfront::engines::gpu::compile::{KernelBuild, KernelSource, ShaderChecks};
use slipfront::engines::gpu::driver_stats::{DeviceChoice, StatsDevice};
use slipfront::engines::gpu::kernel_choice::Launch;
use slipfront::engines::gpu::shaders::{Kernel, LaneMerge};
use slipfront::engines::gpu::{Arithmetic, GpuEngine, GpuOptions};
use slipfront::model::scenario::built_in;
use slipfront::{Model, Scenario};

/// RADV's null device for one RDNA2 family, or None (outside CI) where
/// Mesa's radv is not installed.
fn radv() -> Option<StatsDevice> {
    // SAFETY (of set_var): every test of this binary sets the same value
    // before any Vulkan call, so a concurrent read sees it either way.
    if std::env::var_os("RADV_FORCE_FAMILY").is_none() {
        std::env::set_var("RADV_FORCE_FAMILY", "navi21");
    }
    match StatsDevice::open(DeviceChoice::NameContains("RADV")) {
        Ok(d) => Some(d),
        Err(why) => {
            assert!(
                std::env::var("CI").map_or(true, |v| v != "true"),
                "Mesa's RADV null device is required in CI (apt-get install \
                 mesa-vulkan-drivers): {why}"
            );
            eprintln!("skipped: {why}");
            None
        }
    }
}

fn table_s1(set: &[&str]) -> Model {
    let text = built_in("tromborg2014_precursors").unwrap();
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    Model::from_scenario(&Scenario::parse(text, "table S1", &set).unwrap(), false).unwrap()
}

fn step_source<T: slipfront::engines::gpu::GpuReal>(
    dev: &StatsDevice,
    model: &Model,
    launch: &str,
) -> KernelSource {
    let opts = Launch::named(launch)
        .unwrap()
        .options(GpuOptions::default());
    let mut sources = GpuEngine::<T>::kernel_sources_on(model, opts, dev.traits()).unwrap();
    sources.remove(0)
}

fn registers(dev: &StatsDevice, k: &KernelSource) -> u64 {
    let executables = dev.compile(k).unwrap();
    assert_eq!(executables.len(), 1, "a compute pipeline is one executable");
    executables[0]
        .registers()
        .unwrap_or_else(|| panic!("{}: no register count in {:?}", k.entry, executables[0]))
}

/// The registers of `launch` on Table S1 in mixed f32: as shipped
/// (junctions), and with Coulomb friction.
fn with_and_without_junctions(dev: &StatsDevice, launch: &str) -> (u64, u64) {
    let shipped = table_s1(&[]);
    let coulomb = table_s1(&["friction.law=coulomb"]);
    (
        registers(dev, &step_source::<f32>(dev, &shipped, launch)),
        registers(dev, &step_source::<f32>(dev, &coulomb, launch)),
    )
}

/// Every kernel of Table S1 compiles on the driver as the engine builds it
/// there, and reports the registers a thread holds. The figures are the
/// compiler's, not constants: a one-step kernel with the junction phase
/// needs more registers than the same kernel with Coulomb friction, and a
/// kernel that stores one number fewer than any of them.
#[test]
fn the_driver_reports_each_kernels_registers() {
    let Some(dev) = radv() else { return };
    let shipped = table_s1(&[]);
    for launch in [
        "one-step",
        "one-step-lanes",
        "persistent/256",
        "resident/256",
        "tiled/256/8x4",
    ] {
        let k = step_source::<f32>(&dev, &shipped, launch);
        let r = registers(&dev, &k);
        assert!(r > 0 && r <= 256, "{launch}: {r} registers");
    }
    for launch in ["one-step", "one-step-lanes"] {
        let (junctions, plain) = with_and_without_junctions(&dev, launch);
        assert!(
            plain < junctions,
            "{launch}: Coulomb {plain} registers, junctions {junctions}"
        );
    }
    // f64 compiles too (RADV has f64 shaders).
    let r64 = registers(&dev, &step_source::<f64>(&dev, &shipped, "persistent/256"));
    assert!(r64 > 0);
    let trivial = KernelSource {
        kernel: Kernel::OneStep,
        precision: "f32",
        build: KernelBuild {
            lanes: LaneMerge::Storage,
            checks: ShaderChecks::Trusted,
            chained_tiles: false,
            step_immediate: false,
            workgroup_barriers: false,
            phase_clocks: false,
            strict_arithmetic: false,
        },
        entry: "store_one".into(),
        source: "@group(0) @binding(0) var<storage, read_write> out: array<u32>;\n\
                 @compute @workgroup_size(64) fn store_one(@builtin(global_invocation_id) id: \
                 vec3<u32>) { out[id.x] = 1u; }"
            .into(),
        constants: vec![],
    };
    let least = registers(&dev, &trivial);
    let one_step = registers(&dev, &step_source::<f32>(&dev, &shipped, "one-step"));
    assert!(
        least < one_step,
        "a single store: {least}, one-step: {one_step}"
    );
}

/// `kernel` with the override constant `name` set to `value`.
fn with_constant(kernel: &KernelSource, name: &str, value: f64) -> KernelSource {
    let mut k = kernel.clone();
    k.constants.retain(|(n, _)| n != name);
    k.constants.push((name.into(), value));
    k
}

/// Kept junction sums cost the single-workgroup kernels no registers: the
/// lane sums' two maxima, which only the kept bound reads, go beside the
/// lane tree as one running max (`lane_maxima`), not in each of its six
/// levels. Carried in the levels they took 16 VGPRs a thread on this
/// compiler (88 against 72 with `KEEP_JUNCTION_SUMS` off, session 34).
#[test]
fn kept_sums_cost_the_single_workgroup_kernels_no_registers() {
    let Some(dev) = radv() else { return };
    let shipped = table_s1(&[]);
    for launch in ["persistent/256", "resident/1024", "tiled/256/8x4"] {
        let kept = step_source::<f32>(&dev, &shipped, launch);
        assert_ne!(
            kept.constant("KEEP_JUNCTION_SUMS"),
            Some(0.0),
            "{launch}: the engine keeps sums"
        );
        let with = registers(&dev, &kept);
        let without = registers(&dev, &with_constant(&kept, "KEEP_JUNCTION_SUMS", 0.0));
        assert!(
            with <= without,
            "{launch}: {with} registers with kept sums, {without} without"
        );
    }
}

/// The single-workgroup kernels hold a thread's junction phase in the
/// registers their bulk phase needs anyway: no more than the same kernel
/// with Coulomb friction (64 VGPRs on this compiler). The lane partials
/// are merged as a tree of at most eight pending subtrees
/// (`merged_lane_partials`, runs of eight first where no subgroup merged
/// them), with the maxima beside it; before session 35 the tree of 64
/// took them to 72, and to 88 with the maxima in its levels.
#[test]
fn the_junction_phase_costs_the_single_workgroup_kernels_no_registers() {
    let Some(dev) = radv() else { return };
    for launch in ["persistent/256", "resident/256", "resident/1024"] {
        let (junctions, plain) = with_and_without_junctions(&dev, launch);
        assert!(
            junctions <= plain,
            "{launch}: junctions {junctions} registers, Coulomb {plain}"
        );
    }
}

/// `auto`'s one-lane-a-round launches reach the compiled kernel: on
/// hardware the persistent kernels step two junction lanes a round unless
/// the launch says one (`TWO_LANES_A_ROUND`), and in f64 one lane a round
/// needs fewer registers a thread on this compiler (72–80 VGPRs against
/// 88), which is why `auto` times it.
#[test]
fn one_lane_a_round_is_compiled_in_and_needs_fewer_f64_registers() {
    let Some(dev) = radv() else { return };
    let shipped = table_s1(&[]);
    for launch in ["persistent/256", "resident/256", "resident/1024"] {
        let two = step_source::<f64>(&dev, &shipped, launch);
        let one = step_source::<f64>(&dev, &shipped, &format!("{launch}/one-lane-a-round"));
        assert_eq!(two.constant("TWO_LANES_A_ROUND"), Some(1.0), "{launch}");
        assert_eq!(one.constant("TWO_LANES_A_ROUND"), Some(0.0), "{launch}");
        let (two, one) = (registers(&dev, &two), registers(&dev, &one));
        assert!(
            one < two,
            "{launch}, f64: {one} registers with one lane a round, {two} with two"
        );
    }
}

/// The instructions the driver reports for a kernel (ACO's "Instructions").
fn instructions(dev: &StatsDevice, k: &KernelSource) -> u64 {
    let executables = dev.compile(k).unwrap();
    executables[0]
        .count("Instructions")
        .unwrap_or_else(|| panic!("{}: no instruction count in {:?}", k.entry, executables[0]))
}

/// Strict arithmetic (the default where the engine writes the SPIR-V)
/// compiles mixed f32's fusion guards out and decorates every operation
/// NoContraction instead. On AMD's compiler each kernel then issues fewer
/// instructions than wgpu's guarded module (2.5-5 % at session 67), and
/// not the quarter fewer of a module with neither guards nor decorations,
/// whose compensated sums the compiler folds away (1,163 against 1,567
/// for one-step, measured at session 67): the decorations hold the sums.
/// f64, which has no guards, costs more decorated (its fused multiply-adds
/// come apart: 4-7 % at session 68), and no more than a tenth.
#[test]
fn strict_arithmetic_costs_fewer_instructions_than_the_guards() {
    let Some(dev) = radv() else { return };
    let shipped = table_s1(&[]);
    let source = |launch: &str, strict: bool, f64: bool| {
        let opts = GpuOptions {
            arithmetic: match strict {
                true => Arithmetic::Strict,
                false => Arithmetic::Wgpu,
            },
            ..Launch::named(launch)
                .unwrap()
                .options(GpuOptions::default())
        };
        let mut sources = match f64 {
            false => GpuEngine::<f32>::kernel_sources_on(&shipped, opts, dev.traits()),
            true => GpuEngine::<f64>::kernel_sources_on(&shipped, opts, dev.traits()),
        }
        .unwrap();
        sources.remove(0)
    };
    for launch in ["one-step", "one-step-lanes", "resident/1024", "tiled/512"] {
        let strict = source(launch, true, false);
        let guarded = source(launch, false, false);
        assert!(strict.build.strict_arithmetic && !guarded.build.strict_arithmetic);
        let (s, g) = (instructions(&dev, &strict), instructions(&dev, &guarded));
        assert!(
            s < g && s * 10 > g * 9,
            "{launch}: {s} instructions strict, {g} guarded"
        );
        let (s64, g64) = (
            instructions(&dev, &source(launch, true, true)),
            instructions(&dev, &source(launch, false, true)),
        );
        assert!(
            s64 > g64 && s64 * 10 < g64 * 11,
            "{launch} f64: {s64} instructions strict, {g64} plain"
        );
    }
}

/// A kernel the driver cannot be given is an error naming it, not a
/// panic: WGSL that does not parse, and an override constant the module
/// does not declare.
#[test]
fn a_kernel_that_cannot_compile_is_an_error_naming_it() {
    let Some(dev) = radv() else { return };
    let shipped = table_s1(&[]);
    let mut k = step_source::<f32>(&dev, &shipped, "persistent/256");
    k.constants.push(("NO_SUCH_CONSTANT".into(), 1.0));
    let e = dev.compile(&k).unwrap_err();
    assert!(
        e.contains("persistent_steps") && e.contains("override"),
        "{e}"
    );
    let mut k = step_source::<f32>(&dev, &shipped, "one-step");
    k.source.push_str("\nfn broken( {");
    let e = dev.compile(&k).unwrap_err();
    assert!(e.contains("one_step"), "{e}");
}

/// A device that is not there is an error listing the devices seen.
#[test]
fn a_missing_device_is_named_with_those_seen() {
    if radv().is_none() {
        return;
    }
    let e = StatsDevice::open(DeviceChoice::NameContains("no such GPU"))
        .err()
        .expect("no device has that name");
    assert!(e.contains("no such GPU") && e.contains("RADV"), "{e}");
}

/// Asked to, the device captures the driver's internal representations of
/// a kernel: on RADV its disassembly, a whole program (it ends the shader
/// with `s_endpgm`). Not asked, it captures none: the statistics alone.
#[test]
fn the_driver_gives_a_kernels_disassembly_when_asked() {
    let Some(mut dev) = radv() else { return };
    let k = step_source::<f32>(&dev, &table_s1(&[]), "resident/1024");
    let plain = dev.compile(&k).unwrap();
    assert!(plain[0].representations.is_empty(), "none unless asked");
    dev.capture_representations(true);
    let captured = dev.compile(&k).unwrap();
    let names: Vec<&str> = captured[0]
        .representations
        .iter()
        .map(|r| r.name.as_str())
        .collect();
    let assembly = captured[0]
        .representations
        .iter()
        .find(|r| r.is_text && r.name.contains("Assembly"))
        .unwrap_or_else(|| panic!("no disassembly among {names:?}"));
    let text = String::from_utf8_lossy(&assembly.data);
    assert!(text.contains("s_endpgm"), "{} bytes", assembly.data.len());
    assert_eq!(
        captured[0].registers(),
        plain[0].registers(),
        "the same compile"
    );
}
