//! A kernel's SPIR-V as wgpu's Vulkan backend writes it: the module parsed
//! and validated by naga, its override constants applied for its entry
//! point, then written with the options wgpu 30 uses (its checks as the
//! engine asked, workgroup memory zeroed, integer divisions guarded).
//! Where the kernel's build asks for it (`KernelBuild::workgroup_barriers`),
//! the barriers of `workgroup_storage_barrier` (`shaders/barriers.wgsl`)
//! then get workgroup memory scope (`scope_workgroup_barriers`), and where
//! it asks for strict arithmetic (`KernelBuild::strict_arithmetic`) every
//! floating-point operation is decorated NoContraction
//! (`forbid_contraction`): the SPIR-V
//! the engine gives the driver itself (`GpuContext::pipeline_of`) and
//! the driver's statistics (`driver_stats`) compile.

#[cfg(test)]
use crate::engines::gpu::compile::FUSION_GUARDS;
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
///
/// `layout`: where each (group, binding) of the module goes in the
/// pipeline layout (`vulkan_binding_map`), as wgpu's layouts place them;
/// empty: at the same numbers (a layout made from the module's own
/// bindings, as `driver_stats` makes it).
pub fn kernel_spirv(
    kernel: &KernelSource,
    language: (u8, u8),
    zero: ZeroWorkgroupMemory,
    layout: &spv::BindingMap,
) -> Result<(Vec<u32>, Vec<BufferBinding>), String> {
    let (module, info) = kernel.module()?;
    let bindings = buffer_bindings(&module);
    let (module, info) = kernel.with_constants(&module, &info)?;
    // An entry point that reaches no phase barrier (the tiled kernel's
    // gather) is written as wgpu writes it.
    let has_function = |name: &str| {
        module
            .functions
            .iter()
            .any(|(_, f)| f.name.as_deref() == Some(name))
    };
    let scoped = kernel.build.workgroup_barriers && has_function(WORKGROUP_BARRIER_FUNCTION);
    // An entry point that marks no phase (the gather) reads no clock.
    let clocked = kernel.build.phase_clocks && has_function(CLOCK_FUNCTION);
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
        // No debug names: what the driver compiles for wgpu in a release
        // build. The barriers' function is found by its name, which is
        // then taken out with every other (`scope_workgroup_barriers`).
        flags: match scoped || clocked {
            true => spv::WriterFlags::DEBUG,
            false => spv::WriterFlags::empty(),
        },
        // A binding the layout does not place is an error where there is
        // a layout; at its own number where there is none.
        fake_missing_bindings: layout.is_empty(),
        binding_map: layout.clone(),
        ..spv::Options::default()
    };
    let pipeline = spv::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: kernel.entry.clone(),
    };
    let words = spv::write_vec(&module, &info, &options, Some(&pipeline))
        .map_err(|e| format!("{}: SPIR-V: {e}", kernel.entry))?;
    // Each pass finds its function by name; the names go after the last.
    let named = |e: String| format!("{}: {e}", kernel.entry);
    let mut words = words;
    if clocked {
        words = read_shader_clock(&words, CLOCK_FUNCTION).map_err(named)?;
    }
    if scoped {
        words = scope_named_barriers(&words, WORKGROUP_BARRIER_FUNCTION).map_err(named)?;
    }
    if scoped || clocked {
        words = without_names(&words).map_err(named)?;
    }
    if kernel.build.strict_arithmetic {
        words = forbid_contraction(&words).map_err(named)?;
    }
    Ok((words, bindings))
}

/// Where wgpu's Vulkan backend puts the bindings of a pipeline layout
/// whose group g has the entries `groups[g]`: set g, and in it the
/// entries numbered in order of their WGSL binding, from 0 (wgpu sorts a
/// group's entries by binding and numbers them densely). So WGSL's
/// `@binding(12)` is Vulkan's binding 12 only where the group has every
/// binding below it.
pub fn vulkan_binding_map(groups: &[&[wgpu::BindGroupLayoutEntry]]) -> spv::BindingMap {
    let mut map = spv::BindingMap::new();
    for (group, entries) in groups.iter().enumerate() {
        let mut numbers: Vec<u32> = entries.iter().map(|e| e.binding).collect();
        numbers.sort_unstable();
        for (dense, &binding) in numbers.iter().enumerate() {
            map.insert(
                naga::ResourceBinding {
                    group: group as u32,
                    binding,
                },
                spv::BindingInfo {
                    descriptor_set: group as u32,
                    binding: dense as u32,
                    binding_array_size: None,
                },
            );
        }
    }
    map
}

/// The WGSL function whose storage barrier orders storage within the
/// workgroup alone (`shaders/barriers.wgsl`).
pub const WORKGROUP_BARRIER_FUNCTION: &str = "workgroup_storage_barrier";

/// The WGSL function whose value is the multiprocessor's clock where the
/// engine writes the SPIR-V (`shaders/phase_clocks.wgsl`).
pub const CLOCK_FUNCTION: &str = "phase_clock";

const OP_EXTENSION: u32 = 10;
const OP_CAPABILITY: u32 = 17;
const OP_CONSTANT_COMPOSITE: u32 = 44;
const OP_COMPOSITE_CONSTRUCT: u32 = 80;
const OP_RETURN_VALUE: u32 = 254;
const OP_READ_CLOCK_KHR: u32 = 5056;
const CAPABILITY_SHADER_CLOCK_KHR: u32 = 5055;
const SHADER_CLOCK_EXTENSION: &str = "SPV_KHR_shader_clock";
const OP_NAME: u32 = 5;
const OP_MEMBER_NAME: u32 = 6;
const OP_FUNCTION: u32 = 54;
const OP_FUNCTION_END: u32 = 56;
const OP_CONTROL_BARRIER: u32 = 224;
/// A SPIR-V module's first word.
pub const MAGIC: u32 = 0x0723_0203;
/// Words of a SPIR-V module's header, before its first instruction.
const HEADER_WORDS: usize = 5;

/// `words` (a module naga wrote with debug names) with the memory scope of
/// each control barrier in function `function` set to the barrier's
/// execution scope, and without debug names: the release module but for
/// those operands.
///
/// naga writes WGSL's `storageBarrier` as `OpControlBarrier` with
/// execution scope Workgroup, memory scope Device and semantics
/// AcquireRelease | UniformMemory. Its execution scope's operand is
/// naga's constant for Workgroup, so the memory scope takes that operand:
/// no constant is added. Fails where the function is not in the module or
/// holds no barrier, so a renamed function cannot pass unscoped.
pub fn scope_workgroup_barriers(words: &[u32], function: &str) -> Result<Vec<u32>, String> {
    without_names(&scope_named_barriers(words, function)?)
}

/// `scope_workgroup_barriers` with the debug names kept, for a later pass.
fn scope_named_barriers(words: &[u32], function: &str) -> Result<Vec<u32>, String> {
    let instructions = instructions(words)?;
    let target = named_id(&instructions, function)?;
    let mut out = words[..HEADER_WORDS].to_vec();
    let mut inside = false;
    let mut scoped = 0usize;
    for i in &instructions {
        match i.opcode {
            OP_FUNCTION => inside = i.operands.get(1) == Some(&target),
            OP_FUNCTION_END => inside = false,
            _ => {}
        }
        let start = out.len();
        out.extend_from_slice(i.words);
        if inside && i.opcode == OP_CONTROL_BARRIER {
            // Operands: execution scope, memory scope, semantics (ids).
            out[start + 2] = out[start + 1];
            scoped += 1;
        }
    }
    if scoped == 0 {
        return Err(format!(
            "SPIR-V: function {function} holds no control barrier"
        ));
    }
    Ok(out)
}

/// `words` (a module naga wrote with debug names) with the body of
/// function `function`, which returns the constant vector (s, s), made to
/// return OpReadClockKHR at scope s instead: the clock as a (low, high)
/// pair of words. The capability and extension it needs are declared; the
/// names are kept. Fails where the function is not in the module, returns
/// anything but such a vector, or returns more than once.
pub fn read_shader_clock(words: &[u32], function: &str) -> Result<Vec<u32>, String> {
    let instructions = instructions(words)?;
    let target = named_id(&instructions, function)?;
    // The function's result type, and the id of the value it returns.
    let mut inside = false;
    let mut result_type = None;
    let mut returned = Vec::new();
    for i in &instructions {
        match i.opcode {
            OP_FUNCTION if i.operands.get(1) == Some(&target) => {
                inside = true;
                result_type = i.operands.first().copied();
            }
            OP_FUNCTION_END => inside = false,
            OP_RETURN_VALUE if inside => returned.push(i.operands[0]),
            _ => {}
        }
    }
    let (Some(result_type), [value]) = (result_type, returned.as_slice()) else {
        return Err(format!(
            "SPIR-V: function {function} does not return one value ({} returns)",
            returned.len()
        ));
    };
    // (s, s): its first constituent is the scope's constant.
    let scope = instructions
        .iter()
        .find(|i| {
            matches!(i.opcode, OP_CONSTANT_COMPOSITE | OP_COMPOSITE_CONSTRUCT)
                && i.operands.get(1) == Some(value)
        })
        .and_then(|i| i.operands.get(2).copied())
        .ok_or_else(|| format!("SPIR-V: {function} returns no constant vector"))?;
    let clock = words[3];
    let mut out = words[..HEADER_WORDS].to_vec();
    out[3] = clock + 1;
    let mut inside = false;
    let last_capability = instructions
        .iter()
        .rposition(|i| i.opcode == OP_CAPABILITY)
        .ok_or("SPIR-V: no capability declared")?;
    for (at, i) in instructions.iter().enumerate() {
        match i.opcode {
            OP_FUNCTION => inside = i.operands.get(1) == Some(&target),
            OP_FUNCTION_END => inside = false,
            _ => {}
        }
        if inside && i.opcode == OP_RETURN_VALUE {
            out.extend_from_slice(&[(4 << 16) | OP_READ_CLOCK_KHR, result_type, clock, scope]);
            out.extend_from_slice(&[(2 << 16) | OP_RETURN_VALUE, clock]);
            continue;
        }
        out.extend_from_slice(i.words);
        if at == last_capability {
            out.extend_from_slice(&[(2 << 16) | OP_CAPABILITY, CAPABILITY_SHADER_CLOCK_KHR]);
            let name = literal_words(SHADER_CLOCK_EXTENSION);
            out.push(((1 + name.len() as u32) << 16) | OP_EXTENSION);
            out.extend_from_slice(&name);
        }
    }
    Ok(out)
}

/// SPIR-V's floating-point arithmetic opcodes, which NoContraction may
/// decorate: OpFNegate, OpFAdd, OpFSub, OpFMul, OpFDiv, OpFRem, OpFMod,
/// OpVectorTimesScalar, OpMatrixTimesScalar, OpVectorTimesMatrix,
/// OpMatrixTimesVector, OpMatrixTimesMatrix, OpOuterProduct, OpDot.
const FLOAT_ARITHMETIC: [u32; 14] = [
    127, 129, 131, 133, 136, 140, 141, 142, 143, 144, 145, 146, 147, 148,
];
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const DECORATION_NO_CONTRACTION: u32 = 42;

/// `words` with every floating-point arithmetic result decorated
/// NoContraction, the decorations placed after the module's last: no
/// driver may fuse a product into the add that takes it, nor regroup a
/// sum (SPIR-V 2.16: "such operations are not allowed to reassociate"),
/// as GLSL's `precise`. The CPU twins' arithmetic, which Rust never
/// fuses, operation for operation.
pub fn forbid_contraction(words: &[u32]) -> Result<Vec<u32>, String> {
    let instructions = instructions(words)?;
    let last_annotation = instructions
        .iter()
        .rposition(|i| matches!(i.opcode, OP_DECORATE | OP_MEMBER_DECORATE))
        .ok_or("SPIR-V: no decoration to place NoContraction after")?;
    let arithmetic: Vec<u32> = instructions
        .iter()
        .filter(|i| FLOAT_ARITHMETIC.contains(&i.opcode))
        .map(|i| i.operands[1])
        .collect();
    let mut out = words[..HEADER_WORDS].to_vec();
    for (at, i) in instructions.iter().enumerate() {
        out.extend_from_slice(i.words);
        if at == last_annotation {
            for &id in &arithmetic {
                out.extend_from_slice(&[(3 << 16) | OP_DECORATE, id, DECORATION_NO_CONTRACTION]);
            }
        }
    }
    Ok(out)
}

/// `words` without their debug names (OpName, OpMemberName).
pub fn without_names(words: &[u32]) -> Result<Vec<u32>, String> {
    let instructions = instructions(words)?;
    let mut out = words[..HEADER_WORDS].to_vec();
    for i in instructions {
        if !matches!(i.opcode, OP_NAME | OP_MEMBER_NAME) {
            out.extend_from_slice(i.words);
        }
    }
    Ok(out)
}

/// The id named `name` (OpName), as naga writes a function's.
fn named_id(instructions: &[Instruction], name: &str) -> Result<u32, String> {
    instructions
        .iter()
        .find(|i| {
            i.opcode == OP_NAME && i.operands.len() >= 2 && literal_string(&i.operands[1..]) == name
        })
        .map(|i| i.operands[0])
        .ok_or_else(|| format!("SPIR-V: no function named {name} (written with debug names?)"))
}

/// `text` as a SPIR-V literal string: its bytes and a zero, in words.
fn literal_words(text: &str) -> Vec<u32> {
    let mut bytes = text.as_bytes().to_vec();
    bytes.push(0);
    bytes.resize(bytes.len().next_multiple_of(4), 0);
    bytes
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// One instruction of a module: its opcode, its words (the first holds
/// the word count and opcode) and its operands.
struct Instruction<'a> {
    opcode: u32,
    words: &'a [u32],
    operands: &'a [u32],
}

/// The instructions of module `words`, after its header (which every
/// pass copies from `words`, so it must be there).
fn instructions(words: &[u32]) -> Result<Vec<Instruction<'_>>, String> {
    if words.len() < HEADER_WORDS {
        return Err("SPIR-V: shorter than its header".into());
    }
    let mut out = Vec::new();
    let mut at = HEADER_WORDS;
    while at < words.len() {
        let count = (words[at] >> 16) as usize;
        if count == 0 || at + count > words.len() {
            return Err(format!(
                "SPIR-V: an instruction of {count} words at word {at}"
            ));
        }
        let instruction = &words[at..at + count];
        out.push(Instruction {
            opcode: words[at] & 0xffff,
            words: instruction,
            operands: &instruction[1..],
        });
        at += count;
    }
    Ok(out)
}

/// A SPIR-V literal string: UTF-8 bytes, little-endian in words, ended by
/// a zero byte.
fn literal_string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .take_while(|&b| b != 0)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::gpu::kernel_choice::Launch;
    use crate::engines::gpu::{AdapterTraits, Arithmetic, GpuEngine, GpuOptions, GpuPath, GpuReal};
    use crate::model::scenario::{built_in, Scenario};
    use crate::Model;

    /// Device scope's and Workgroup's values (SPIR-V's Scope).
    const DEVICE: u32 = 1;
    const WORKGROUP: u32 = 2;

    fn table_s1() -> Model {
        let s = Scenario::parse(built_in("tromborg2014_precursors").unwrap(), "S1", &[]).unwrap();
        Model::from_scenario(&s, false).unwrap()
    }

    /// The step kernel's source of `launch` on Table S1, its options then
    /// changed by `with`.
    fn launch_source<T: GpuReal>(
        launch: &str,
        with: impl FnOnce(GpuOptions) -> GpuOptions,
    ) -> KernelSource {
        let opts = with(
            Launch::named(launch)
                .unwrap()
                .options(GpuOptions::default()),
        );
        GpuEngine::<T>::kernel_sources_on(&table_s1(), opts, &AdapterTraits::test_hardware())
            .unwrap()
            .remove(0)
    }

    /// The step kernel's source of `launch` on Table S1, its phase
    /// barriers scoped or not.
    fn step_source<T: GpuReal>(launch: &str, scoped: bool) -> KernelSource {
        launch_source::<T>(launch, |o| GpuOptions {
            workgroup_barriers: scoped,
            ..o
        })
    }

    fn words(k: &KernelSource) -> Vec<u32> {
        kernel_spirv(
            k,
            (1, 6),
            ZeroWorkgroupMemory::Native,
            &spv::BindingMap::new(),
        )
        .unwrap()
        .0
    }

    /// `k`'s module as naga writes it with debug names, before any pass.
    fn named_words(k: &KernelSource) -> Vec<u32> {
        let (module, info) = k.module().unwrap();
        let (module, info) = k.with_constants(&module, &info).unwrap();
        let options = spv::Options {
            flags: spv::WriterFlags::DEBUG,
            ..spv::Options::default()
        };
        let pipeline = spv::PipelineOptions {
            shader_stage: naga::ShaderStage::Compute,
            entry_point: k.entry.clone(),
        };
        spv::write_vec(&module, &info, &options, Some(&pipeline)).unwrap()
    }

    /// The constant ids of each value of a module's OpConstant u32s.
    fn constant_values(words: &[u32]) -> std::collections::HashMap<u32, u32> {
        instructions(words)
            .unwrap()
            .iter()
            .filter(|i| i.opcode == 43 && i.operands.len() == 3)
            .map(|i| (i.operands[1], i.operands[2]))
            .collect()
    }

    /// The memory scopes of a module's control barriers, in order.
    fn barrier_memory_scopes(words: &[u32]) -> Vec<u32> {
        let values = constant_values(words);
        instructions(words)
            .unwrap()
            .iter()
            .filter(|i| i.opcode == OP_CONTROL_BARRIER)
            .map(|i| values[&i.operands[1]])
            .collect()
    }

    /// The phase barriers of the persistent, resident and tiled kernels
    /// get workgroup scope, in both precisions, and nothing else changes:
    /// the module is naga's release module word for word but for the one
    /// barrier in `workgroup_storage_barrier`. The tiled kernel's barriers
    /// between rounds, which order a tile's writes for its neighbours,
    /// keep device scope.
    #[test]
    fn the_phase_barriers_get_workgroup_scope_and_nothing_else_changes() {
        for (launch, rounds) in [
            ("persistent/256", 0),
            ("persistent/1024/2-scenes", 0),
            ("resident/1024", 0),
            // A round's end orders its publication for the tiles
            // that read it (chained, within the dispatch).
            ("tiled/256/8x4", 2),
            ("tiled/256/8x4/chained", 2),
        ] {
            for f64 in [false, true] {
                let (plain, scoped) = match f64 {
                    false => (
                        step_source::<f32>(launch, false),
                        step_source::<f32>(launch, true),
                    ),
                    true => (
                        step_source::<f64>(launch, false),
                        step_source::<f64>(launch, true),
                    ),
                };
                assert!(!plain.build.workgroup_barriers && scoped.build.workgroup_barriers);
                let (a, b) = (words(&plain), words(&scoped));
                assert_eq!(a.len(), b.len(), "{launch} f64 {f64}");
                let changed: Vec<usize> = (0..a.len()).filter(|&k| a[k] != b[k]).collect();
                assert_eq!(
                    changed.len(),
                    1,
                    "{launch} f64 {f64}: words {changed:?} changed"
                );
                let plain_scopes = barrier_memory_scopes(&a);
                let scoped_scopes = barrier_memory_scopes(&b);
                let count = |scopes: &[u32], scope| scopes.iter().filter(|&&s| s == scope).count();
                assert_eq!(
                    count(&scoped_scopes, DEVICE) + 1,
                    count(&plain_scopes, DEVICE),
                    "{launch}"
                );
                assert_eq!(
                    count(&scoped_scopes, DEVICE),
                    rounds,
                    "{launch}: device-scope barriers left"
                );
            }
        }
    }

    /// A group's bindings are numbered densely in order of their WGSL
    /// numbers, as wgpu's Vulkan layouts number them: bindings 0, 2 and 5
    /// of group 0 are Vulkan's 0, 1 and 2, however the entries are listed.
    #[test]
    fn bindings_are_placed_as_wgpus_vulkan_layouts_place_them() {
        let entry = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let group0 = [entry(5), entry(0), entry(2)];
        let group1 = [entry(0), entry(1)];
        let map = vulkan_binding_map(&[&group0, &group1]);
        let at = |group, binding| {
            let b = &map[&naga::ResourceBinding { group, binding }];
            (b.descriptor_set, b.binding)
        };
        assert_eq!([at(0, 0), at(0, 2), at(0, 5)], [(0, 0), (0, 1), (0, 2)]);
        assert_eq!([at(1, 0), at(1, 1)], [(1, 0), (1, 1)]);
        assert_eq!(map.len(), 5);
    }

    /// The one-step kernels have no phase barriers: their builds never ask
    /// for scoping (the engine writes them for strict arithmetic alone).
    #[test]
    fn only_kernels_with_phase_barriers_are_scoped() {
        for launch in ["one-step", "one-step-lanes"] {
            assert!(
                !step_source::<f32>(launch, true).build.workgroup_barriers,
                "{launch}"
            );
        }
        let traits = AdapterTraits {
            own_spirv: false,
            ..AdapterTraits::test_hardware()
        };
        let opts = Launch::named("persistent/256")
            .unwrap()
            .options(GpuOptions::default());
        let k = GpuEngine::<f32>::kernel_sources_on(&table_s1(), opts, &traits).unwrap();
        assert!(
            !k[0].build.workgroup_barriers,
            "an adapter that writes its own SPIR-V only"
        );
    }

    /// The ids decorated NoContraction in module `words`.
    fn uncontracted(words: &[u32]) -> std::collections::BTreeSet<u32> {
        instructions(words)
            .unwrap()
            .iter()
            .filter(|i| is_no_contraction(i))
            .map(|i| i.operands[0])
            .collect()
    }

    fn is_no_contraction(i: &Instruction) -> bool {
        i.opcode == OP_DECORATE && i.operands[1] == DECORATION_NO_CONTRACTION
    }

    /// The results of module `words`' floating-point arithmetic.
    fn float_results(words: &[u32]) -> std::collections::BTreeSet<u32> {
        instructions(words)
            .unwrap()
            .iter()
            .filter(|i| FLOAT_ARITHMETIC.contains(&i.opcode))
            .map(|i| i.operands[1])
            .collect()
    }

    /// The value the module of `k` (its constants applied) gives the
    /// fusion guards' override, where it declares it.
    fn fusion_guards(k: &KernelSource) -> Option<bool> {
        let (module, info) = k.module().unwrap();
        let declared = module
            .overrides
            .iter()
            .find(|(_, o)| o.name.as_deref() == Some(FUSION_GUARDS))?;
        let (module, _) = k.with_constants(&module, &info).unwrap();
        let constant = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(FUSION_GUARDS))
            .unwrap_or_else(|| panic!("{}: {declared:?} not made a constant", k.entry));
        match module.global_expressions[constant.1.init] {
            naga::Expression::Literal(naga::Literal::Bool(b)) => Some(b),
            ref other => panic!("{}: FUSION_GUARDS = {other:?}", k.entry),
        }
    }

    /// Strict (mixed f32's default where the engine writes the SPIR-V),
    /// every mixed f32 kernel's floating-point results are decorated
    /// NoContraction, each once and nothing else, and its fusion guards
    /// are compiled out (FUSION_GUARDS false). Guarded, as wgpu writes it:
    /// the guards in and no decoration. f64 has no guards: by default
    /// (`Arithmetic::Leaner`) nothing is decorated; strict, every result
    /// is. Nothing is decorated on an adapter that takes wgpu's modules.
    #[test]
    fn strict_arithmetic_forbids_contraction_and_compiles_the_guards_out() {
        for launch in [
            "one-step",
            "one-step-lanes",
            "persistent/256",
            "resident/1024",
            "tiled/256/8x4/chained",
        ] {
            let strict = launch_source::<f32>(launch, |o| o);
            assert!(strict.build.strict_arithmetic, "{launch}: the default");
            assert_eq!(fusion_guards(&strict), Some(false), "{launch}");
            let w = words(&strict);
            let results = float_results(&w);
            assert!(results.len() > 100, "{launch}: {} results", results.len());
            assert_eq!(uncontracted(&w), results, "{launch}");
            let decorations = instructions(&w)
                .unwrap()
                .iter()
                .filter(|i| is_no_contraction(i))
                .count();
            assert_eq!(decorations, results.len(), "{launch}: each once");
            let strict = |o| GpuOptions {
                arithmetic: Arithmetic::Strict,
                ..o
            };
            let wgpu = |o| GpuOptions {
                arithmetic: Arithmetic::Wgpu,
                ..o
            };
            assert_eq!(
                launch_source::<f32>(launch, strict),
                launch_source::<f32>(launch, |o| o)
            );
            let guarded = launch_source::<f32>(launch, wgpu);
            assert!(!guarded.build.strict_arithmetic);
            assert_eq!(fusion_guards(&guarded), Some(true), "{launch}");
            assert!(uncontracted(&words(&guarded)).is_empty(), "{launch}");
            // f64 has no guards: strict is the decorations alone.
            let f64 = launch_source::<f64>(launch, strict);
            assert!(f64.build.strict_arithmetic, "{launch} f64");
            assert_eq!(fusion_guards(&f64), None, "{launch} f64");
            let w = words(&f64);
            assert_eq!(uncontracted(&w), float_results(&w), "{launch} f64");
            let plain = launch_source::<f64>(launch, |o| o);
            assert!(!plain.build.strict_arithmetic, "{launch} f64: the default");
            assert_eq!(plain, launch_source::<f64>(launch, wgpu));
            assert!(uncontracted(&words(&plain)).is_empty(), "{launch} f64");
        }
        let traits = AdapterTraits {
            own_spirv: false,
            ..AdapterTraits::test_hardware()
        };
        let opts = Launch::named("one-step")
            .unwrap()
            .options(GpuOptions::default());
        let k = GpuEngine::<f32>::kernel_sources_on(&table_s1(), opts, &traits).unwrap();
        assert!(!k[0].build.strict_arithmetic, "wgpu's modules");
    }

    /// The pass decorates after the module's last decoration, and refuses a
    /// module with none to place them after rather than misplace them.
    #[test]
    fn forbid_contraction_places_its_decorations_among_the_others() {
        let w = words(&launch_source::<f32>("one-step", |o| o));
        let all = instructions(&w).unwrap();
        let first = all.iter().position(is_no_contraction).unwrap();
        let last_other = all
            .iter()
            .rposition(|i| {
                matches!(i.opcode, OP_DECORATE | OP_MEMBER_DECORATE) && !is_no_contraction(i)
            })
            .unwrap();
        assert_eq!(first, last_other + 1);
        let type_or_constant = |i: &Instruction| (19..=52).contains(&i.opcode);
        let types = all.iter().position(type_or_constant).unwrap();
        let last = all.iter().rposition(is_no_contraction).unwrap();
        assert!(last < types, "annotations before the types");
        let header = &w[..HEADER_WORDS];
        let bare = [header, &[(2 << 16) | OP_CAPABILITY, 1]].concat();
        let err = forbid_contraction(&bare).unwrap_err();
        assert!(err.contains("no decoration"), "{err}");
    }

    /// The pass fails, never passes a module unscoped, where the function is
    /// not named in it (a module written without debug names) or holds no
    /// barrier.
    #[test]
    fn the_pass_refuses_a_module_it_cannot_scope() {
        let plain = words(&step_source::<f32>("persistent/256", false));
        let err = scope_workgroup_barriers(&plain, WORKGROUP_BARRIER_FUNCTION).unwrap_err();
        assert!(err.contains("no function named"), "{err}");
        let k = step_source::<f32>("persistent/256", true);
        let named = named_words(&k);
        // The entry point's own function holds barriers; one without any.
        let err = scope_workgroup_barriers(&named, "state_enter").unwrap_err();
        assert!(err.contains("holds no control barrier"), "{err}");
        let scoped = scope_workgroup_barriers(&named, WORKGROUP_BARRIER_FUNCTION).unwrap();
        assert!(barrier_memory_scopes(&scoped).contains(&WORKGROUP));
        assert!(!instructions(&scoped)
            .unwrap()
            .iter()
            .any(|i| i.opcode == OP_NAME));
    }

    /// The clocked source of `launch` on Table S1 (phase barriers scoped).
    fn clocked_source(launch: &str, clocks: bool) -> KernelSource {
        launch_source::<f32>(launch, |o| GpuOptions {
            phase_clocks: clocks,
            ..o
        })
    }

    fn count(words: &[u32], opcode: u32) -> usize {
        instructions(words)
            .unwrap()
            .iter()
            .filter(|i| i.opcode == opcode)
            .count()
    }

    /// Clocked, each kernel with phases reads the clock in one place
    /// (`phase_clock`'s body, at Subgroup scope: naga's constant 3), and
    /// declares the capability and extension it needs; its barriers are
    /// still scoped and its names gone. Unclocked, none of it. Word for
    /// word, the clocked module is the unclocked one with those words
    /// added where the constant PHASE_CLOCKS differs, so only the counts
    /// are compared.
    #[test]
    fn clocked_kernels_read_the_subgroup_clock_once() {
        for launch in ["persistent/256", "resident/1024", "tiled/512/8x4/chained"] {
            let plain = words(&clocked_source(launch, false));
            assert_eq!(count(&plain, OP_READ_CLOCK_KHR), 0, "{launch}");
            let clocked = words(&clocked_source(launch, true));
            assert_eq!(count(&clocked, OP_READ_CLOCK_KHR), 1, "{launch}");
            assert_eq!(count(&clocked, OP_NAME), 0, "{launch}");
            let all = instructions(&clocked).unwrap();
            let read = all.iter().find(|i| i.opcode == OP_READ_CLOCK_KHR).unwrap();
            let scope = constant_values(&clocked)[&read.operands[2]];
            assert_eq!(scope, 3, "{launch}: Subgroup scope");
            assert!(all
                .iter()
                .any(|i| i.opcode == OP_CAPABILITY && i.operands == [CAPABILITY_SHADER_CLOCK_KHR]));
            assert!(all.iter().any(|i| i.opcode == OP_EXTENSION
                && literal_string(i.operands) == SHADER_CLOCK_EXTENSION));
            // The id bound covers the new id.
            assert!(read.operands[1] < clocked[3], "{launch}");
            assert!(barrier_memory_scopes(&clocked).contains(&WORKGROUP));
        }
    }

    /// The clock pass refuses a module without names, or a function that
    /// does not return one constant vector, rather than read nothing.
    #[test]
    fn the_clock_pass_refuses_what_it_cannot_rewrite() {
        let plain = words(&clocked_source("persistent/256", false));
        let err = read_shader_clock(&plain, CLOCK_FUNCTION).unwrap_err();
        assert!(err.contains("no function named"), "{err}");
        let k = clocked_source("persistent/256", true);
        let named = named_words(&k);
        // A function that returns nothing (a phase mark).
        let err = read_shader_clock(&named, "phase_arrive").unwrap_err();
        assert!(err.contains("does not return one value"), "{err}");
        let read = read_shader_clock(&named, CLOCK_FUNCTION).unwrap();
        assert_eq!(count(&read, OP_READ_CLOCK_KHR), 1);
        assert!(count(&read, OP_NAME) > 0, "the names are kept");
        assert_eq!(without_names(&read).map(|w| count(&w, OP_NAME)), Ok(0));
    }

    /// SPIRV-Tools' `spirv-val` (Debian's spirv-tools), or None outside CI
    /// where it is not installed; in CI (`CI=true`) its absence fails.
    fn spirv_val() -> Option<&'static str> {
        let found = std::process::Command::new("spirv-val")
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success());
        if !found {
            assert!(
                std::env::var("CI").map_or(true, |v| v != "true"),
                "spirv-val is required in CI (apt-get install spirv-tools)"
            );
            eprintln!("skipped: spirv-val not found (apt-get install spirv-tools)");
        }
        found.then_some("spirv-val")
    }

    /// `spirv-val`'s verdict on `words` as Vulkan 1.3 SPIR-V: None where
    /// valid, else its message.
    fn invalid(val: &str, words: &[u32]) -> Option<String> {
        use std::io::Write;
        let mut child = std::process::Command::new(val)
            .args(["--target-env", "vulkan1.3", "-"])
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        child.stdin.take().unwrap().write_all(&bytes).unwrap();
        let out = child.wait_with_output().unwrap();
        (!out.status.success()).then(|| {
            let text = String::from_utf8_lossy(&out.stderr) + String::from_utf8_lossy(&out.stdout);
            text.lines().take(3).collect::<Vec<_>>().join(" / ")
        })
    }

    /// The words of every entry point of `k`'s module, as `pipeline_of`
    /// writes them for Vulkan 1.3.
    fn every_entry_point(k: &KernelSource) -> Vec<(String, Vec<u32>)> {
        let (module, _) = k.module().unwrap();
        module
            .entry_points
            .iter()
            .map(|e| {
                let one = KernelSource {
                    entry: e.name.clone(),
                    ..k.clone()
                };
                let words = kernel_spirv(
                    &one,
                    language_version(1, 3),
                    ZeroWorkgroupMemory::Native,
                    &spv::BindingMap::new(),
                )
                .unwrap_or_else(|e| panic!("{}: {e}", one.entry))
                .0;
                (one.entry, words)
            })
            .collect()
    }

    /// Every module the engine can hand a driver is valid SPIR-V as
    /// SPIRV-Tools judges it: each kernel's every entry point (steps,
    /// gathers, records), in both precisions, for each friction law,
    /// strict and guarded, barriers scoped or not, clocked, checked, lanes
    /// in subgroups or storage, scenes grouped. naga's validator passes
    /// modules spirv-val refuses, and a driver may refuse or miscompile
    /// them: until session 68 every mixed f32 module passed a struct's
    /// `array<f32, 2>` field where a function took the alias
    /// `packed_coord`, two SPIR-V types (`WgslType::FIELD`). The control:
    /// the same module with that field spelled out again is refused.
    #[test]
    fn every_module_the_engine_writes_is_valid_spirv() {
        let Some(val) = spirv_val() else { return };
        fn check<T: GpuReal>(
            val: &str,
            model: &Model,
            launch: &str,
            failures: &mut Vec<String>,
        ) -> usize {
            type Variant = (&'static str, fn(GpuOptions) -> GpuOptions);
            let variants: [Variant; 3] = [
                ("default", |o| o),
                ("wgpu's arithmetic, unscoped, lanes in storage", |o| {
                    GpuOptions {
                        arithmetic: Arithmetic::Wgpu,
                        workgroup_barriers: false,
                        lane_shuffle: false,
                        ..o
                    }
                }),
                ("strict, clocked, checked", |o| GpuOptions {
                    arithmetic: Arithmetic::Strict,
                    phase_clocks: !matches!(o.path, GpuPath::OneStep | GpuPath::OneStepLanes),
                    shader_checks: true,
                    ..o
                }),
            ];
            let mut checked = 0;
            for (variant, with) in variants {
                let opts = with(
                    Launch::named(launch)
                        .unwrap()
                        .options(GpuOptions::default()),
                );
                let traits = AdapterTraits::test_hardware();
                let Ok(sources) = GpuEngine::<T>::kernel_sources_on(model, opts, &traits) else {
                    continue;
                };
                for k in &sources {
                    for (entry, words) in every_entry_point(k) {
                        checked += 1;
                        if let Some(why) = invalid(val, &words) {
                            failures.push(format!("{launch} {} {variant} {entry}: {why}", T::NAME));
                        }
                    }
                }
            }
            checked
        }
        let scene = |name: &str| {
            let s = Scenario::parse(built_in(name).unwrap(), name, &[]).unwrap();
            Model::from_scenario(&s, false).unwrap()
        };
        let mut failures = Vec::new();
        let mut checked = 0;
        for name in [
            "tromborg2014_precursors",
            "tromborg2011_coulomb_precursors",
            "rate_state",
        ] {
            let model = scene(name);
            for launch in [
                "one-step",
                "one-step-lanes",
                "persistent/256",
                "persistent/1024/2-scenes",
                "resident/1024/lane-run-4",
                "persistent/512/bond-patches",
                "tiled/512",
                "tiled/256/8x4/chained",
            ] {
                checked += check::<f32>(val, &model, launch, &mut failures);
                checked += check::<f64>(val, &model, launch, &mut failures);
            }
        }
        assert!(
            failures.is_empty(),
            "{} of {checked} invalid:\n{}",
            failures.len(),
            failures.join("\n")
        );
        assert!(checked >= 150, "{checked} modules checked");

        // The control: the junction spring's anchor spelled as the array again.
        let k = launch_source::<f32>("one-step", |o| o);
        let spelled = KernelSource {
            source: k
                .source
                .replacen("anchor: packed_coord,", "anchor: array<f32, 2>,", 1),
            ..k.clone()
        };
        assert_ne!(spelled.source, k.source);
        let why = invalid(val, &words(&spelled)).expect("the two array types refused");
        assert!(why.contains("OpFunctionCall"), "{why}");
    }
}
