//! How the engine's WGSL modules are compiled: where a kernel's junction
//! lanes merge (the module's source), which run-time checks wgpu adds, and
//! how a dispatch gets its step offset.

use super::precision::GpuReal;
use super::shaders::{Kernel, LaneMerge};

/// How a kernel's module is built: where its junction lanes merge, and
/// which run-time checks wgpu adds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KernelBuild {
    pub lanes: LaneMerge,
    pub checks: ShaderChecks,
    /// The tiled kernel's rounds chained in one dispatch
    /// (`GpuOptions::chained_tiles`): its published halos are read
    /// `@coherent`, past the multiprocessor's own cache, since a
    /// neighbour writes them within the dispatch.
    pub chained_tiles: bool,
    /// The dispatch's step offset passed as an immediate
    /// (`GpuOptions::step_immediates`, where the adapter has immediates),
    /// not as a dynamic offset into a table: a dispatch then sets 4 bytes
    /// rather than rebinding group 1, which costs the host less.
    pub step_immediate: bool,
    /// The storage barriers between a step's phases with workgroup memory
    /// scope (`GpuOptions::workgroup_barriers`, `shaders/barriers.wgsl`):
    /// the engine writes the module's SPIR-V itself
    /// (`spirv::scope_workgroup_barriers`) and gives it to the driver as
    /// it is, where wgpu would write them with device scope.
    pub workgroup_barriers: bool,
    /// The kernel's phase marks read the multiprocessor's clock
    /// (`GpuOptions::phase_clocks`): the engine writes the module's SPIR-V
    /// itself, with `phase_clock`'s body an OpReadClockKHR
    /// (`spirv::read_shader_clock`).
    pub phase_clocks: bool,
    /// SPIR-V's NoContraction on every floating-point operation
    /// (`GpuOptions::arithmetic`, `spirv::forbid_contraction`): the
    /// engine writes the module's SPIR-V itself. No driver may then fuse a
    /// product into an add anywhere in the kernel, nor regroup a sum, so
    /// the kernel computes its CPU twin's operations as they are written.
    /// In mixed f32 it also compiles out the guards wgpu's modules need
    /// for the compensated sums (`FUSION_GUARDS` false,
    /// `shaders/double_single.wgsl`).
    pub strict_arithmetic: bool,
}

/// The override constant that compiles mixed f32's fusion guards in
/// (`shaders/double_single.wgsl`); strict arithmetic sets it false.
pub const FUSION_GUARDS: &str = "FUSION_GUARDS";

impl KernelBuild {
    /// The WGSL module of `kernel` built this way.
    pub fn source<T: GpuReal>(self, kernel: Kernel) -> String {
        let source = kernel.source_with::<T>(self.lanes);
        let source = match self.chained_tiles && kernel == Kernel::Tiled {
            true => coherent_halos(&source),
            false => source,
        };
        match self.step_immediate {
            true => step_as_immediate(&source),
            false => source,
        }
    }

    /// What naga needs to validate the module of this build.
    pub fn capabilities(self) -> naga::valid::Capabilities {
        let mut caps = self.lanes.capabilities();
        if self.chained_tiles {
            caps |= naga::valid::Capabilities::MEMORY_DECORATION_COHERENT;
        }
        if self.step_immediate {
            caps |= naga::valid::Capabilities::IMMEDIATES;
        }
        caps
    }
}

/// The step offset's declaration in `common.wgsl`: a storage word that a
/// dynamic offset picks from a table, one slot a dispatch.
pub const STEP_OFFSET_BINDING: &str = "@group(1) @binding(0) var<storage, read> step_offset: u32;";

/// The same variable as an immediate (Vulkan's push constant), which the
/// host sets before each dispatch (`set_immediates`).
pub const STEP_OFFSET_IMMEDIATE: &str = "var<immediate> step_offset: u32;";

/// `source` with the step offset declared an immediate. Every kernel reads
/// `step_offset` by name, so nothing else changes.
fn step_as_immediate(source: &str) -> String {
    debug_assert_eq!(source.matches(STEP_OFFSET_BINDING).count(), 1);
    source.replacen(STEP_OFFSET_BINDING, STEP_OFFSET_IMMEDIATE, 1)
}

/// The buffers a tiled kernel's tiles publish for their neighbours' halos.
pub const PUBLISHED_HALOS: [&str; 5] = [
    "pub_disp",
    "pub_vel",
    "tile_junction_state",
    "tile_junction_spring",
    "tile_junction_cache",
];

/// `source` with the published halos' bindings declared `@coherent`.
fn coherent_halos(source: &str) -> String {
    source
        .lines()
        .map(|line| {
            let published = PUBLISHED_HALOS
                .iter()
                .any(|name| line.contains(&format!("> {name}:")) && line.contains("@binding("));
            match published {
                true => format!("@coherent {line}\n"),
                false => format!("{line}\n"),
            }
        })
        .collect()
}

/// Whether wgpu adds its own run-time checks to the engine's kernels
/// (`GpuOptions::shader_checks`). Either way the storage buffers stay
/// guarded by the driver (wgpu opens the device with robust buffer
/// access), and integer divisions keep their guard against zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ShaderChecks {
    /// None added: every index into a fixed-size array (workgroup tiles,
    /// reduction slots, stencil tables) is in range by construction, and
    /// every loop is bounded by the scene's sizes and the batch's steps.
    /// The kernels are our own, validated by naga in the unit tests, and
    /// give the same bits either way (`tests/gpu_shader_checks.rs`).
    Trusted,
    /// wgpu's default: each such index clamped to its array, and each
    /// loop given an iteration counter that ends it after 2^64 rounds.
    /// Costs instructions in every inner loop; a check for a suspect kernel.
    Checked,
}

impl ShaderChecks {
    pub fn of(checked: bool) -> ShaderChecks {
        if checked {
            ShaderChecks::Checked
        } else {
            ShaderChecks::Trusted
        }
    }

    /// The module of WGSL `source`, compiled with these checks.
    pub fn module(self, device: &wgpu::Device, label: &str, source: String) -> wgpu::ShaderModule {
        let desc = wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        };
        match self {
            ShaderChecks::Checked => device.create_shader_module(desc),
            ShaderChecks::Trusted => {
                let checks = wgpu::ShaderRuntimeChecks {
                    bounds_checks: false,
                    force_loop_bounding: false,
                    ..wgpu::ShaderRuntimeChecks::checked()
                };
                // SAFETY: the engine's own kernels (shaders/), each validated
                // by naga in a unit test, index their fixed-size arrays only
                // within range and run only loops bounded by the scene's sizes
                // and the batch's step count (see `Trusted`). Storage buffer
                // accesses stay guarded by the driver's robust buffer access,
                // and integer division keeps wgpu's guard.
                unsafe { device.create_shader_module_trusted(desc, checks) }
            }
        }
    }
}

/// What one of the engine's pipelines is compiled from: its module's
/// WGSL, the entry point and the override constants, as the engine gave
/// them to wgpu. Enough to compile the same kernel again outside wgpu and
/// ask the driver what it made of it (`driver_stats`).
#[derive(Debug, Clone, PartialEq)]
pub struct KernelSource {
    pub kernel: Kernel,
    /// `GpuReal::NAME` of the kernel's precision.
    pub precision: &'static str,
    pub build: KernelBuild,
    pub entry: String,
    pub source: String,
    pub constants: Vec<(String, f64)>,
}

impl KernelSource {
    /// The source of entry point `entry` of `kernel` in precision `T`,
    /// built with `build` and compiled with `constants`.
    pub fn of<T: GpuReal>(
        kernel: Kernel,
        build: KernelBuild,
        entry: &str,
        constants: &[(&str, f64)],
    ) -> KernelSource {
        KernelSource {
            kernel,
            precision: T::NAME,
            build,
            entry: entry.to_string(),
            source: build.source::<T>(kernel),
            constants: constants.iter().map(|&(n, v)| (n.to_string(), v)).collect(),
        }
    }

    /// The kernel's module as naga parses and validates it.
    pub fn module(&self) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
        let src = &self.source;
        let module = naga::front::wgsl::parse_str(src)
            .map_err(|e| format!("{}: {}", self.entry, e.emit_to_string(src)))?;
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .map_err(|e| format!("{}: {}", self.entry, e.emit_to_string(src)))?;
        Ok((module, info))
    }

    /// `module` (this kernel's, from `module`) with the pipeline's override
    /// constants applied for its entry point, and compacted to what that
    /// entry point reaches: what a driver is given to compile
    /// (`driver_stats`), and what the workgroup memory it declares is read
    /// from (`step_kernel`'s fit test).
    pub fn with_constants(
        &self,
        module: &naga::Module,
        info: &naga::valid::ModuleInfo,
    ) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
        let mut constants: naga::back::PipelineConstants = self.constants.iter().cloned().collect();
        let guarded = module
            .overrides
            .iter()
            .any(|(_, o)| o.name.as_deref() == Some(FUSION_GUARDS));
        if self.build.strict_arithmetic && guarded {
            constants.insert(FUSION_GUARDS.to_string(), 0.0);
        }
        let (module, info) = naga::back::pipeline_constants::process_overrides(
            module,
            info,
            Some((naga::ShaderStage::Compute, &self.entry)),
            &constants,
        )
        .map_err(|e| format!("{}: override constants: {e}", self.entry))?;
        Ok((module.into_owned(), info.into_owned()))
    }

    /// The value of override constant `name`, where the pipeline sets it.
    pub fn constant(&self, name: &str) -> Option<f64> {
        self.constants
            .iter()
            .find(|(n, _)| n == name)
            .map(|&(_, v)| v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn build(lanes: LaneMerge, step_immediate: bool, chained_tiles: bool) -> KernelBuild {
        KernelBuild {
            lanes,
            checks: ShaderChecks::Trusted,
            chained_tiles,
            step_immediate,
            workgroup_barriers: false,
            phase_clocks: false,
            strict_arithmetic: false,
        }
    }

    fn validates<T: GpuReal>(src: &str, caps: naga::valid::Capabilities) -> bool {
        let module = naga::front::wgsl::parse_str(src).expect("parses");
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), T::CAPABILITIES | caps)
            .validate(&module)
            .is_ok()
    }

    /// Every kernel's module declares the step offset once, as a binding;
    /// built with the step as an immediate, it declares it as one instead,
    /// changes nothing else, and validates with the immediates capability
    /// in both precisions (and not without it).
    #[test]
    fn the_step_as_an_immediate_changes_its_declaration_alone() {
        for kernel in Kernel::ALL {
            for lanes in [LaneMerge::Storage, LaneMerge::Shuffle] {
                let chained = kernel == Kernel::Tiled;
                let plain = build(lanes, false, chained).source::<f32>(kernel);
                let immediate = build(lanes, true, chained);
                let src = immediate.source::<f32>(kernel);
                assert_eq!(plain.matches(STEP_OFFSET_BINDING).count(), 1, "{kernel:?}");
                assert!(!src.contains(STEP_OFFSET_BINDING), "{kernel:?}");
                assert_eq!(src.matches(STEP_OFFSET_IMMEDIATE).count(), 1, "{kernel:?}");
                assert_eq!(
                    src.replacen(STEP_OFFSET_IMMEDIATE, STEP_OFFSET_BINDING, 1),
                    plain
                );
                assert!(
                    validates::<f32>(&src, immediate.capabilities()),
                    "{kernel:?}"
                );
                assert!(
                    !validates::<f32>(&src, build(lanes, false, chained).capabilities()),
                    "{kernel:?}: validated without the immediates capability"
                );
                let f64_src = immediate.source::<f64>(kernel);
                assert!(
                    validates::<f64>(&f64_src, immediate.capabilities()),
                    "{kernel:?} f64"
                );
            }
        }
    }

    /// The chained tiled kernel's module declares exactly its published
    /// halos `@coherent`, validates with that capability in both
    /// precisions and both lane merges, and not without it; the other
    /// kernels' modules are the same chained or not.
    #[test]
    fn chained_tiles_read_their_published_halos_coherent() {
        for lanes in [LaneMerge::Storage, LaneMerge::Shuffle] {
            let build = build(lanes, false, true);
            let src = build.source::<f32>(Kernel::Tiled);
            let coherent: Vec<&str> = src.lines().filter(|l| l.contains("@coherent")).collect();
            assert_eq!(coherent.len(), PUBLISHED_HALOS.len(), "{coherent:?}");
            for name in PUBLISHED_HALOS {
                assert!(
                    coherent.iter().any(|l| l.contains(&format!("> {name}:"))),
                    "{name}"
                );
            }
            assert!(validates::<f32>(&src, build.capabilities()));
            assert!(!validates::<f32>(&src, lanes.capabilities()));
            let f64_src = build.source::<f64>(Kernel::Tiled);
            assert!(validates::<f64>(&f64_src, build.capabilities()));
            for kernel in Kernel::ALL.into_iter().filter(|&k| k != Kernel::Tiled) {
                assert_eq!(
                    build.source::<f32>(kernel),
                    kernel.source_with::<f32>(lanes)
                );
            }
        }
    }
}
