//! A Vulkan device of its own (ash), opened with
//! VK_KHR_pipeline_executable_properties, which wgpu neither enables nor
//! exposes: it compiles a kernel's SPIR-V into a pipeline that captures
//! the driver's statistics, reads them and destroys the pipeline. It never
//! runs anything.

use super::{Executable, Representation, StatValue, Statistic};
use crate::engines::gpu::compile::KernelSource;
use crate::engines::gpu::context::STEP_IMMEDIATE_BYTES;
use crate::engines::gpu::spirv::{kernel_spirv, language_version, ZeroWorkgroupMemory};
use crate::engines::gpu::AdapterTraits;
use ash::vk;
use std::ffi::CStr;

/// Which of the machine's Vulkan devices to ask.
#[derive(Debug, Clone, Copy)]
pub enum DeviceChoice<'a> {
    /// The one with this PCI vendor and device id (wgpu's
    /// `AdapterInfo::vendor` and `device`): the adapter the engine runs on.
    Ids { vendor: u32, device: u32 },
    /// The first whose name contains this text (`RADV` for Mesa's AMD
    /// compiler on its null device, `RADV_FORCE_FAMILY`).
    NameContains(&'a str),
}

/// An open device that reports shader statistics.
pub struct StatsDevice {
    // Dropped last: the instance's and device's functions live in its library.
    _entry: ash::Entry,
    instance: ash::Instance,
    open: OpenDevice,
    /// Whether compiles capture the driver's internal representations.
    representations: bool,
}

fn c_text(s: Result<&CStr, std::ffi::FromBytesUntilNulError>) -> String {
    s.map(|c| c.to_string_lossy().into_owned())
        .unwrap_or_default()
}

impl StatsDevice {
    /// Opens the device `choice` names; an error says why none could be
    /// (no Vulkan loader, no such device, or one whose driver does not
    /// report statistics: lavapipe).
    pub fn open(choice: DeviceChoice) -> Result<StatsDevice, String> {
        // SAFETY: loads the system's Vulkan loader; the entry outlives every
        // object made from it (it is dropped last).
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| format!("no Vulkan loader (libvulkan): {e}"))?;
        let app = vk::ApplicationInfo::default()
            .application_name(c"slipfront driver statistics")
            .api_version(vk::API_VERSION_1_3);
        // SAFETY: a valid create info with no layers or extensions.
        let instance = unsafe {
            entry.create_instance(
                &vk::InstanceCreateInfo::default().application_info(&app),
                None,
            )
        }
        .map_err(|e| format!("cannot create a Vulkan instance: {e}"))?;
        match Self::open_on(&instance, choice) {
            Ok(open) => Ok(StatsDevice {
                representations: false,
                _entry: entry,
                instance,
                open,
            }),
            Err(e) => {
                // SAFETY: nothing made from the instance is alive.
                unsafe { instance.destroy_instance(None) };
                Err(e)
            }
        }
    }

    /// The device's name, as the driver gives it.
    pub fn name(&self) -> &str {
        &self.open.name
    }

    /// Its PCI vendor id (`NVIDIA`).
    pub fn vendor_id(&self) -> u32 {
        self.open.vendor_id
    }

    /// Its driver's name and version.
    pub fn driver(&self) -> &str {
        &self.open.driver
    }

    /// What the engine would decide its kernels by on this device.
    pub fn traits(&self) -> &AdapterTraits {
        &self.open.traits
    }

    fn open_on(instance: &ash::Instance, choice: DeviceChoice) -> Result<OpenDevice, String> {
        // SAFETY: the instance is valid for these queries.
        let physical = unsafe { instance.enumerate_physical_devices() }
            .map_err(|e| format!("cannot list Vulkan devices: {e}"))?;
        let mut seen = Vec::new();
        let mut found = None;
        for pd in physical {
            // SAFETY: pd comes from this instance.
            let props = unsafe { instance.get_physical_device_properties(pd) };
            let name = c_text(props.device_name_as_c_str());
            let wanted = match choice {
                DeviceChoice::Ids { vendor, device } => {
                    props.vendor_id == vendor && props.device_id == device
                }
                DeviceChoice::NameContains(text) => name.contains(text),
            };
            seen.push(name.clone());
            if wanted {
                found = Some((pd, props, name));
                break;
            }
        }
        let Some((pd, props, name)) = found else {
            return Err(format!(
                "no Vulkan device matches {choice:?} (devices: {})",
                if seen.is_empty() {
                    "none".to_string()
                } else {
                    seen.join(", ")
                }
            ));
        };
        // SAFETY: pd comes from this instance.
        let extensions = unsafe { instance.enumerate_device_extension_properties(pd) }
            .map_err(|e| format!("{name}: cannot list its extensions: {e}"))?;
        let has = |ext: &CStr| {
            extensions
                .iter()
                .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == ext))
        };
        let stats_ext = ash::khr::pipeline_executable_properties::NAME;
        if !has(stats_ext) {
            return Err(format!(
                "{name} does not report shader statistics (no {})",
                stats_ext.to_string_lossy()
            ));
        }
        let api = (
            vk::api_version_major(props.api_version),
            vk::api_version_minor(props.api_version),
        );
        let vulkan13 = api >= (1, 3);
        // What the device has, to enable what wgpu would: f64, robust
        // buffer access (wgpu's bounds policy relies on it), workgroup
        // memory zeroed natively, subgroups of the size the driver picks.
        let mut exec_features =
            vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default();
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut robust2 = vk::PhysicalDeviceRobustness2FeaturesEXT::default();
        let has_robust2 = has(ash::ext::robustness2::NAME);
        // The subgroup clock, as GpuContext::open enables it: the phase
        // clocks' kernels compile here too (their registers).
        let mut clock = vk::PhysicalDeviceShaderClockFeaturesKHR::default();
        let has_clock_ext = has(vk::KHR_SHADER_CLOCK_NAME);
        {
            let mut query = vk::PhysicalDeviceFeatures2::default().push_next(&mut exec_features);
            if has_clock_ext {
                query = query.push_next(&mut clock);
            }
            if vulkan13 {
                query = query.push_next(&mut f13);
            }
            if has_robust2 {
                query = query.push_next(&mut robust2);
            }
            // SAFETY: a valid chain of feature structs for pd.
            unsafe { instance.get_physical_device_features2(pd, &mut query) };
        }
        if exec_features.pipeline_executable_info != vk::TRUE {
            return Err(format!("{name}: pipelineExecutableInfo is not supported"));
        }
        // SAFETY: pd comes from this instance.
        let core = unsafe { instance.get_physical_device_features(pd) };
        let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let family = families
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .ok_or_else(|| format!("{name} has no compute queue"))? as u32;
        let priorities = [1.0f32];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&priorities)];
        let enabled_core = vk::PhysicalDeviceFeatures::default()
            .shader_float64(core.shader_float64 == vk::TRUE)
            .robust_buffer_access(core.robust_buffer_access == vk::TRUE);
        let mut enable_exec = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
            .pipeline_executable_info(true);
        let zero_native = vulkan13 && f13.shader_zero_initialize_workgroup_memory == vk::TRUE;
        let varying_subgroups = vulkan13 && f13.subgroup_size_control == vk::TRUE;
        let mut enable13 = vk::PhysicalDeviceVulkan13Features::default()
            .shader_zero_initialize_workgroup_memory(zero_native)
            .subgroup_size_control(varying_subgroups);
        let mut enable_robust2 = vk::PhysicalDeviceRobustness2FeaturesEXT::default()
            .robust_buffer_access2(robust2.robust_buffer_access2 == vk::TRUE);
        let shader_clock = has_clock_ext && clock.shader_subgroup_clock == vk::TRUE;
        let mut enable_clock =
            vk::PhysicalDeviceShaderClockFeaturesKHR::default().shader_subgroup_clock(true);
        let mut names = vec![stats_ext.as_ptr()];
        if has_robust2 {
            names.push(ash::ext::robustness2::NAME.as_ptr());
        }
        if shader_clock {
            names.push(vk::KHR_SHADER_CLOCK_NAME.as_ptr());
        }
        let mut info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&names)
            .enabled_features(&enabled_core)
            .push_next(&mut enable_exec);
        if vulkan13 {
            info = info.push_next(&mut enable13);
        }
        if has_robust2 {
            info = info.push_next(&mut enable_robust2);
        }
        if shader_clock {
            info = info.push_next(&mut enable_clock);
        }
        // SAFETY: every feature enabled was reported supported above.
        let device = unsafe { instance.create_device(pd, &info, None) }
            .map_err(|e| format!("cannot open {name}: {e}"))?;
        let executables = ash::khr::pipeline_executable_properties::Device::new(instance, &device);
        // The driver's name, as wgpu's AdapterInfo::driver_info gives it,
        // and the subgroup operations wgpu's SUBGROUP feature needs.
        let mut driver_props = vk::PhysicalDeviceDriverProperties::default();
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default()
            .push_next(&mut driver_props)
            .push_next(&mut subgroup);
        // SAFETY: a valid chain for pd.
        unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
        let needed = vk::SubgroupFeatureFlags::BASIC
            | vk::SubgroupFeatureFlags::VOTE
            | vk::SubgroupFeatureFlags::ARITHMETIC
            | vk::SubgroupFeatureFlags::BALLOT
            | vk::SubgroupFeatureFlags::SHUFFLE
            | vk::SubgroupFeatureFlags::SHUFFLE_RELATIVE;
        let l = &props.limits;
        let traits = AdapterTraits {
            limits: wgpu::Limits {
                max_compute_workgroup_storage_size: l.max_compute_shared_memory_size,
                max_compute_invocations_per_workgroup: l.max_compute_work_group_invocations,
                max_compute_workgroup_size_x: l.max_compute_work_group_size[0],
                ..wgpu::Limits::default()
            },
            software: props.device_type == vk::PhysicalDeviceType::CPU,
            subgroups: subgroup
                .supported_stages
                .contains(vk::ShaderStageFlags::COMPUTE)
                && subgroup.supported_operations.contains(needed),
            // wgpu offers @coherent on every Vulkan device.
            coherent_storage: true,
            // And immediates (push constants) where there is room for
            // the step offset, as GpuContext::open asks for them.
            immediates: l.max_push_constants_size >= STEP_IMMEDIATE_BYTES,
            // And writes the SPIR-V itself on a Vulkan 1.3 device
            // (`context::SpirvTarget`).
            own_spirv: api >= (1, 3),
            // And reads the clock where the engine writes the SPIR-V
            // and the device has it (`GpuContext::has_shader_clock`).
            shader_clock: api >= (1, 3) && shader_clock,
        };
        let driver = format!(
            "{} {}",
            c_text(driver_props.driver_name_as_c_str()),
            c_text(driver_props.driver_info_as_c_str())
        );
        Ok(OpenDevice {
            device,
            executables,
            name,
            vendor_id: props.vendor_id,
            driver,
            traits,
            language: language_version(api.0, api.1),
            zero: if zero_native {
                ZeroWorkgroupMemory::Native
            } else {
                ZeroWorkgroupMemory::Polyfill
            },
            varying_subgroups,
        })
    }

    /// Whether later compiles also capture the driver's internal
    /// representations (`Executable::representations`): RADV gives its
    /// NIR, ACO IR and disassembly; what NVIDIA's driver gives is read
    /// on a lent GPU (`gpu_registers`, SLIPFRONT_GPU_REGISTERS_DUMP).
    pub fn capture_representations(&mut self, on: bool) {
        self.representations = on;
    }

    /// Compiles `kernel` as wgpu would and returns what the driver reports
    /// of each executable it made (a compute pipeline has one).
    pub fn compile(&self, kernel: &KernelSource) -> Result<Vec<Executable>, String> {
        let open = &self.open;
        // A layout of the module's own bindings, at their own numbers.
        let (words, bindings) = kernel_spirv(
            kernel,
            open.language,
            open.zero,
            &naga::back::spv::BindingMap::new(),
        )?;
        let d = &open.device;
        let mut made = Made::new(d);
        // SAFETY: every object is made on this device from valid create
        // infos, and `made` destroys each once, after the pipeline.
        unsafe {
            made.module = d
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None)
                .map_err(|e| format!("{}: the driver refused the module: {e}", kernel.entry))?;
            let groups = bindings.iter().map(|b| b.0 + 1).max().unwrap_or(0);
            for g in 0..groups {
                let entries: Vec<vk::DescriptorSetLayoutBinding> = bindings
                    .iter()
                    .filter(|b| b.0 == g)
                    .map(|&(_, binding, uniform)| {
                        vk::DescriptorSetLayoutBinding::default()
                            .binding(binding)
                            .descriptor_type(if uniform {
                                vk::DescriptorType::UNIFORM_BUFFER
                            } else {
                                vk::DescriptorType::STORAGE_BUFFER
                            })
                            .descriptor_count(1)
                            .stage_flags(vk::ShaderStageFlags::COMPUTE)
                    })
                    .collect();
                let layout = d
                    .create_descriptor_set_layout(
                        &vk::DescriptorSetLayoutCreateInfo::default().bindings(&entries),
                        None,
                    )
                    .map_err(|e| format!("descriptor set layout: {e}"))?;
                made.set_layouts.push(layout);
            }
            // As wgpu's layouts: room for the step offset as an immediate
            // (a push constant) where the module declares it one.
            let immediates = [vk::PushConstantRange::default()
                .stage_flags(vk::ShaderStageFlags::COMPUTE)
                .offset(0)
                .size(STEP_IMMEDIATE_BYTES)];
            let ranges: &[vk::PushConstantRange] = match kernel.build.step_immediate {
                true => &immediates,
                false => &[],
            };
            made.layout = d
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default()
                        .set_layouts(&made.set_layouts)
                        .push_constant_ranges(ranges),
                    None,
                )
                .map_err(|e| format!("pipeline layout: {e}"))?;
            let entry = std::ffi::CString::new(kernel.entry.as_str())
                .map_err(|_| format!("{}: not an entry point name", kernel.entry))?;
            // As wgpu: the driver picks the subgroup size where it may.
            let stage_flags = if open.varying_subgroups {
                vk::PipelineShaderStageCreateFlags::ALLOW_VARYING_SUBGROUP_SIZE
            } else {
                vk::PipelineShaderStageCreateFlags::empty()
            };
            let stage = vk::PipelineShaderStageCreateInfo::default()
                .flags(stage_flags)
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(made.module)
                .name(&entry);
            let mut flags = vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR;
            if self.representations {
                flags |= vk::PipelineCreateFlags::CAPTURE_INTERNAL_REPRESENTATIONS_KHR;
            }
            let info = vk::ComputePipelineCreateInfo::default()
                .flags(flags)
                .stage(stage)
                .layout(made.layout);
            let pipelines = d
                .create_compute_pipelines(vk::PipelineCache::null(), &[info], None)
                .map_err(|(_, e)| {
                    format!("{}: the driver could not compile it: {e}", kernel.entry)
                })?;
            made.pipeline = pipelines[0];
            let properties = open
                .executables
                .get_pipeline_executable_properties(
                    &vk::PipelineInfoKHR::default().pipeline(made.pipeline),
                )
                .map_err(|e| format!("executable properties: {e}"))?;
            let mut out = Vec::new();
            for (index, p) in properties.iter().enumerate() {
                let stats = open
                    .executables
                    .get_pipeline_executable_statistics(
                        &vk::PipelineExecutableInfoKHR::default()
                            .pipeline(made.pipeline)
                            .executable_index(index as u32),
                    )
                    .map_err(|e| format!("executable statistics: {e}"))?;
                let info = vk::PipelineExecutableInfoKHR::default()
                    .pipeline(made.pipeline)
                    .executable_index(index as u32);
                let representations = if self.representations {
                    representations(&open.executables, &info)?
                } else {
                    Vec::new()
                };
                out.push(Executable {
                    name: c_text(p.name_as_c_str()),
                    description: c_text(p.description_as_c_str()),
                    subgroup_size: p.subgroup_size,
                    statistics: stats.iter().map(statistic).collect(),
                    representations,
                });
            }
            Ok(out)
        }
    }
}

/// The internal representations of one executable, by the spec's
/// three calls: their count, their names and sizes, then their bytes
/// into buffers of those sizes.
///
/// # Safety
/// `info` names an executable of a live pipeline made with
/// CAPTURE_INTERNAL_REPRESENTATIONS_KHR on the device of `executables`.
unsafe fn representations(
    executables: &ash::khr::pipeline_executable_properties::Device,
    info: &vk::PipelineExecutableInfoKHR,
) -> Result<Vec<Representation>, String> {
    let get = executables
        .fp()
        .get_pipeline_executable_internal_representations_khr;
    let device = executables.device();
    let failed = |e: vk::Result| format!("internal representations: {e}");
    let mut count = 0u32;
    let mut forms: Vec<vk::PipelineExecutableInternalRepresentationKHR>;
    let mut buffers: Vec<Vec<u8>>;
    // SAFETY: the caller's executable; each call's array holds `count`
    // entries, and each entry's data pointer (null, then a buffer of the
    // size the driver gave) outlives the call.
    unsafe {
        get(device, info, &mut count, std::ptr::null_mut())
            .result()
            .map_err(failed)?;
        forms = vec![vk::PipelineExecutableInternalRepresentationKHR::default(); count as usize];
        // With no data buffers the driver fills in names and sizes
        // (VK_INCOMPLETE where a size is not zero).
        let sized = get(device, info, &mut count, forms.as_mut_ptr());
        if sized != vk::Result::SUCCESS && sized != vk::Result::INCOMPLETE {
            return Err(failed(sized));
        }
        buffers = forms.iter().map(|f| vec![0u8; f.data_size]).collect();
        for (form, buffer) in forms.iter_mut().zip(buffers.iter_mut()) {
            form.p_data = buffer.as_mut_ptr().cast();
        }
        let filled = get(device, info, &mut count, forms.as_mut_ptr());
        if filled != vk::Result::SUCCESS && filled != vk::Result::INCOMPLETE {
            return Err(failed(filled));
        }
    }
    Ok(forms
        .iter()
        .zip(buffers)
        .map(|(form, mut data)| {
            // The driver's written size; text ends at its terminating zero.
            data.truncate(form.data_size);
            let is_text = form.is_text == vk::TRUE;
            if is_text {
                if let Some(end) = data.iter().position(|&b| b == 0) {
                    data.truncate(end);
                }
            }
            Representation {
                name: c_text(form.name_as_c_str()),
                description: c_text(form.description_as_c_str()),
                is_text,
                data,
            }
        })
        .collect())
}

fn statistic(s: &vk::PipelineExecutableStatisticKHR) -> Statistic {
    // SAFETY: the union member read is the one `format` names.
    let value = unsafe {
        match s.format {
            vk::PipelineExecutableStatisticFormatKHR::BOOL32 => {
                StatValue::Bool(s.value.b32 == vk::TRUE)
            }
            vk::PipelineExecutableStatisticFormatKHR::INT64 => StatValue::Int(s.value.i64),
            vk::PipelineExecutableStatisticFormatKHR::FLOAT64 => StatValue::Float(s.value.f64),
            _ => StatValue::Uint(s.value.u64),
        }
    };
    Statistic {
        name: c_text(s.name_as_c_str()),
        description: c_text(s.description_as_c_str()),
        value,
    }
}

/// The device and what a compile needs to know of it.
struct OpenDevice {
    device: ash::Device,
    executables: ash::khr::pipeline_executable_properties::Device,
    name: String,
    vendor_id: u32,
    driver: String,
    traits: AdapterTraits,
    language: (u8, u8),
    zero: ZeroWorkgroupMemory,
    varying_subgroups: bool,
}

/// The objects one compile makes, destroyed together (a failed step
/// leaves null handles, which Vulkan's destroy calls ignore).
struct Made<'a> {
    device: &'a ash::Device,
    module: vk::ShaderModule,
    set_layouts: Vec<vk::DescriptorSetLayout>,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

impl<'a> Made<'a> {
    fn new(device: &'a ash::Device) -> Made<'a> {
        Made {
            device,
            module: vk::ShaderModule::null(),
            set_layouts: Vec::new(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
        }
    }
}

impl Drop for Made<'_> {
    fn drop(&mut self) {
        // SAFETY: each handle was made on this device (or is null) and is
        // destroyed once; nothing uses them after.
        unsafe {
            self.device.destroy_pipeline(self.pipeline, None);
            self.device.destroy_pipeline_layout(self.layout, None);
            for &l in &self.set_layouts {
                self.device.destroy_descriptor_set_layout(l, None);
            }
            self.device.destroy_shader_module(self.module, None);
        }
    }
}

impl Drop for StatsDevice {
    fn drop(&mut self) {
        // SAFETY: every pipeline made on the device is already destroyed.
        unsafe {
            self.open.device.destroy_device(None);
            self.instance.destroy_instance(None);
        }
    }
}
