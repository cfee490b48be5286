//! A kernel's SPIR-V as wgpu's Vulkan backend writes it: the module parsed
//! and validated by naga, its override constants applied for its entry
//! point, then written with the options wgpu 30 uses (its checks as the
//! engine asked, workgroup memory zeroed, integer divisions guarded).

use crate::engines::gpu::compile::{KernelSource, ShaderChecks};
use naga::back::spv;

/// The SPIR-V version wgpu writes for a device of Vulkan `api` (1.0 →
/// 1.0, 1.1 → 1.3, 1.2 → 1.5, 1.3 and later → 1.6).
pub fn language_version(api_major: u32, api_minor: u32) -> (u8, u8) {
    match (api_major, api_minor) {
        (1, 0) => (1, 0),
        (1, 1) => (1, 3),
        (1, 2) => (1, 5),
        _ => (1, 6),
    }
}

/// How the device zeroes workgroup memory: natively (Vulkan 1.3's
/// shaderZeroInitializeWorkgroupMemory) or by code naga adds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ZeroWorkgroupMemory {
    Native,
    Polyfill,
}

/// A buffer binding a module declares: (group, binding, is uniform).
pub type BufferBinding = (u32, u32, bool);

/// The SPIR-V words of `kernel`'s entry point, and the buffer bindings its
/// module declares: the pipeline layout a driver compiles it against. One
/// parse for both.
pub fn kernel_spirv(
    kernel: &KernelSource,
    language: (u8, u8),
    zero: ZeroWorkgroupMemory,
) -> Result<(Vec<u32>, Vec<BufferBinding>), String> {
    let (module, info) = kernel.module()?;
    let bindings = buffer_bindings(&module);
    let (module, info) = kernel.with_constants(&module, &info)?;
    let checked = kernel.build.checks == ShaderChecks::Checked;
    let policy = if checked {
        naga::proc::BoundsCheckPolicy::Restrict
    } else {
        naga::proc::BoundsCheckPolicy::Unchecked
    };
    let options = spv::Options {
        lang_version: language,
        // wgpu opens devices with robust buffer access, so it leaves
        // storage buffers to the driver and clamps only array indices.
        bounds_check_policies: naga::proc::BoundsCheckPolicies {
            index: policy,
            buffer: naga::proc::BoundsCheckPolicy::Unchecked,
            image_load: naga::proc::BoundsCheckPolicy::Unchecked,
            binding_array: naga::proc::BoundsCheckPolicy::Unchecked,
        },
        zero_initialize_workgroup_memory: match zero {
            ZeroWorkgroupMemory::Native => spv::ZeroInitializeWorkgroupMemoryMode::Native,
            ZeroWorkgroupMemory::Polyfill => spv::ZeroInitializeWorkgroupMemoryMode::Polyfill,
        },
        force_loop_bounding: checked,
        emit_int_div_checks: true,
        // No debug names: what the driver compiles for wgpu in a release build.
        flags: spv::WriterFlags::empty(),
        // wgpu maps each (group, binding) to the same (set, binding)
        // through its layout's binding map: the identity, as here.
        fake_missing_bindings: true,
        ..spv::Options::default()
    };
    let pipeline = spv::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: kernel.entry.clone(),
    };
    let words = spv::write_vec(&module, &info, &options, Some(&pipeline))
        .map_err(|e| format!("{}: SPIR-V: {e}", kernel.entry))?;
    Ok((words, bindings))
}

/// The buffer bindings `module` declares.
fn buffer_bindings(module: &naga::Module) -> Vec<BufferBinding> {
    let mut out: Vec<BufferBinding> = module
        .global_variables
        .iter()
        .filter_map(|(_, var)| {
            let at = var.binding.as_ref()?;
            match var.space {
                naga::AddressSpace::Uniform => Some((at.group, at.binding, true)),
                naga::AddressSpace::Storage { .. } => Some((at.group, at.binding, false)),
                _ => None,
            }
        })
        .collect();
    out.sort();
    out.dedup();
    out
}
