//! Adapter selection: a hardware GPU, else a software one (lavapipe).

use super::bindings::Bindings;
use super::compile::{KernelBuild, KernelSource};
use super::precision::GpuReal;
use super::shaders::Kernel;
use super::spirv::{self, ZeroWorkgroupMemory};
use crate::engines::EngineError;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// The device engines run on, what it is, and what is built once on it:
/// the bind group layouts and the compiled pipelines of each variant. One
/// per process, shared by every engine (software drivers JIT-compile each
/// pipeline and do not give that memory back).
#[derive(Clone)]
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    /// The first uncaptured device error, if any (checked after submits).
    pub error: Arc<Mutex<Option<String>>>,
    /// Nanoseconds per timestamp tick, where the adapter has timestamp
    /// queries: each batch's compute pass is then timed on the device
    /// (`GpuEngine::device_seconds`).
    pub timestamp_period_ns: Option<f64>,
    /// Group 0 of the one-step kernels, of the persistent kernel and of the
    /// tiled kernel (their state bindings differ).
    layouts: Arc<[KernelLayout; 3]>,
    /// Group 1: the step offset (dynamic) and the batch (or the batches).
    pub batch_layout: wgpu::BindGroupLayout,
    /// Each pipeline by its key, compiled once: the map is locked only to
    /// find a key's slot, and a slot only while its own pipeline compiles,
    /// so threads building different pipelines compile side by side.
    pipelines: Arc<Mutex<HashMap<String, Arc<OnceLock<wgpu::ComputePipeline>>>>>,
    /// The SPIR-V the engine writes for this device itself, where it may
    /// (`KernelBuild::workgroup_barriers`).
    spirv: Option<SpirvTarget>,
    /// Why the device refused a module of the engine's own SPIR-V, if it
    /// did: from then on wgpu writes every module (`refuse_own_spirv`).
    own_spirv_refused: Arc<Mutex<Option<String>>>,
    /// The device was opened with VK_KHR_shader_clock's subgroup clock:
    /// the engine's own SPIR-V may read the multiprocessor's cycle
    /// counter (`KernelBuild::phase_clocks`).
    shader_clock: bool,
}

/// What the engine's own SPIR-V for a device must be: the version wgpu
/// would write for it, with workgroup memory zeroed by the driver.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SpirvTarget {
    pub language: (u8, u8),
}

impl SpirvTarget {
    /// The target of `adapter` opened with `features`: a Vulkan device
    /// that takes SPIR-V as given (PASSTHROUGH_SHADERS) and zeroes
    /// workgroup memory itself, as Vulkan 1.3 requires of every device
    /// (wgpu zeroes it, natively there; naga's polyfill elsewhere would
    /// make one thread zero a tile each dispatch). None elsewhere: wgpu
    /// writes the modules.
    fn of(adapter: &wgpu::Adapter, features: wgpu::Features) -> Option<SpirvTarget> {
        if !features.contains(wgpu::Features::PASSTHROUGH_SHADERS)
            || adapter.get_info().backend != wgpu::Backend::Vulkan
        {
            return None;
        }
        // SAFETY: the handle is only read (its properties), while the
        // adapter lives.
        let api = unsafe {
            adapter
                .as_hal::<wgpu::hal::api::Vulkan>()
                .map(|a| a.physical_device_capabilities().properties().api_version)
        }?;
        let (major, minor) = (
            ash::vk::api_version_major(api),
            ash::vk::api_version_minor(api),
        );
        ((major, minor) >= (1, 3)).then(|| SpirvTarget {
            language: spirv::language_version(major, minor),
        })
    }
}

static SHARED: OnceLock<Result<GpuContext, String>> = OnceLock::new();

/// The process-wide context, opened on first use.
pub fn shared() -> Result<GpuContext, EngineError> {
    SHARED
        .get_or_init(|| {
            // Keep the bare message: `EngineError::Gpu` adds its own prefix.
            GpuContext::open().map_err(|e| match e {
                EngineError::Gpu(why) => why,
                other => other.to_string(),
            })
        })
        .clone()
        .map_err(EngineError::Gpu)
}

/// Storage bindings the tiled kernel's pipeline layout holds (the most of
/// any kernel: the scenes' constants and batches, the state, its halo's
/// published copies and the record buffers). Held to the modules by
/// `shaders::tests::every_kernel_binds_at_most_the_storage_arrays_the_adapter_is_asked_for`:
/// it had stood at 21 while the kernels grew to 26.
pub(super) const STORAGE_BINDINGS: u32 = 28;

/// Group 0's layout of one kernel family and the pipeline layout using it.
struct KernelLayout {
    group: wgpu::BindGroupLayout,
    pipeline: wgpu::PipelineLayout,
    /// What the kernels of this family declare (`bindings::Bindings`).
    bindings: Bindings,
    /// Where wgpu's Vulkan backend puts each binding of the layout
    /// (`spirv::vulkan_binding_map`): the engine's own SPIR-V must agree.
    vulkan_bindings: naga::back::spv::BindingMap,
}

/// The batch group's binding that takes a dynamic offset per dispatch.
pub const STEP_OFFSET: &str = "step_offset";

/// The immediates a pipeline layout holds where the adapter has them: the
/// step offset, one u32.
pub const STEP_IMMEDIATE_BYTES: u32 = 4;

/// Index in `GpuContext::layouts`.
fn layout_index(kernel: Kernel) -> usize {
    match kernel {
        Kernel::OneStep | Kernel::OneStepLanes => 0,
        Kernel::Persistent | Kernel::Resident => 1,
        Kernel::Tiled => 2,
    }
}

/// `adapter` opened as `desc` asks, with VK_KHR_shader_clock's subgroup
/// clock enabled besides, where its Vulkan device has it; None where it
/// has not, or where opening so fails (wgpu then opens it as usual).
fn open_with_shader_clock(
    adapter: &wgpu::Adapter,
    desc: &wgpu::DeviceDescriptor,
) -> Option<(wgpu::Device, wgpu::Queue)> {
    use ash::vk;
    // SAFETY: the hal adapter is used while `adapter` lives; the device it
    // opens is handed to wgpu at once, with the features and limits wgpu
    // checks for `desc` (the ones request_device would open).
    unsafe {
        let hal = adapter.as_hal::<wgpu::hal::api::Vulkan>()?;
        if !hal
            .physical_device_capabilities()
            .supports_extension(vk::KHR_SHADER_CLOCK_NAME)
        {
            return None;
        }
        let instance = hal.shared_instance().raw_instance();
        let mut has = vk::PhysicalDeviceShaderClockFeaturesKHR::default();
        let mut query = vk::PhysicalDeviceFeatures2::default().push_next(&mut has);
        instance.get_physical_device_features2(hal.raw_physical_device(), &mut query);
        if has.shader_subgroup_clock == vk::FALSE {
            return None;
        }
        let mut enable =
            vk::PhysicalDeviceShaderClockFeaturesKHR::default().shader_subgroup_clock(true);
        let enable = &mut enable;
        let callback: Box<wgpu::hal::vulkan::CreateDeviceCallback> =
            Box::new(move |args: wgpu::hal::vulkan::CreateDeviceCallbackArgs| {
                args.extensions.push(vk::KHR_SHADER_CLOCK_NAME);
                let info = std::mem::take(args.create_info);
                *args.create_info = info.push_next(enable);
            });
        let open = hal
            .open_with_callback(
                desc.required_features,
                &desc.required_limits,
                &desc.memory_hints,
                Some(callback),
            )
            .ok()?;
        drop(hal);
        adapter.create_device_from_hal(open, desc).ok()
    }
}

/// Lists the adapters with Vulkan/Metal/DX12 support, hardware first.
pub fn adapters() -> Vec<wgpu::Adapter> {
    // Without GL: its adapters are never used here, and starting EGL makes
    // Mesa warn about XDG_RUNTIME_DIR on every headless run.
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::PRIMARY;
    let instance = wgpu::Instance::new(desc.with_env());
    let mut list = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY));
    list.retain(|a| a.get_info().backend != wgpu::Backend::Gl);
    let rank = |a: &wgpu::Adapter| match a.get_info().device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    };
    list.sort_by_key(rank);
    list
}

impl GpuContext {
    /// Opens the best adapter, with its full limits.
    pub fn open() -> Result<GpuContext, EngineError> {
        let adapter = adapters().into_iter().next().ok_or_else(|| {
            EngineError::Gpu(
                "no GPU adapter found (not even a software one): install Mesa's Vulkan \
                 driver (apt-get install mesa-vulkan-drivers) or use --backend cpu"
                    .into(),
            )
        })?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        if limits.max_storage_buffers_per_shader_stage < STORAGE_BINDINGS {
            return Err(EngineError::Gpu(format!(
                "{} allows {} storage buffers per shader stage; slipfront needs {STORAGE_BINDINGS}",
                info.name, limits.max_storage_buffers_per_shader_stage
            )));
        }
        // f64 kernels where the adapter has them (`--precision f64`); the
        // mixed kernels need no feature.
        // Timestamp queries where the adapter has them: the device time of
        // each batch, beside its wall time (what the output costs on the
        // device, against what it costs the host), and inside passes, of
        // each dispatch (GpuEngine::time_each_dispatch).
        // Subgroup operations where the adapter has them: the junction
        // lanes' sums merged in registers (lane_shuffle.wgsl).
        // Coherent storage where the adapter has it (every Vulkan one): the
        // tiled kernel's halos read within a chained dispatch.
        // Immediates (push constants) where the adapter has room for the
        // step offset: a dispatch sets it without rebinding group 1.
        // SPIR-V as the engine writes it, where the adapter takes it: the
        // storage barriers between a step's phases at workgroup scope
        // (`KernelBuild::workgroup_barriers`).
        let mut features = adapter.features()
            & (wgpu::Features::SHADER_F64
                | wgpu::Features::TIMESTAMP_QUERY
                | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
                | wgpu::Features::SUBGROUP
                | wgpu::Features::MEMORY_DECORATION_COHERENT
                | wgpu::Features::IMMEDIATES
                | wgpu::Features::PASSTHROUGH_SHADERS);
        if limits.max_immediate_size < STEP_IMMEDIATE_BYTES {
            features.remove(wgpu::Features::IMMEDIATES);
        }
        let desc = wgpu::DeviceDescriptor {
            label: Some("slipfront"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        };
        let spirv = SpirvTarget::of(&adapter, features);
        // The multiprocessor's clock, where the engine writes the SPIR-V
        // and the device has it: opened through wgpu's Vulkan backend with
        // the extension added; elsewhere (or if that fails) as wgpu opens it.
        let clocked = match spirv {
            Some(_) => open_with_shader_clock(&adapter, &desc),
            None => None,
        };
        let shader_clock = clocked.is_some();
        let (device, queue) = match clocked {
            Some(opened) => opened,
            None => pollster::block_on(adapter.request_device(&desc))
                .map_err(|e| EngineError::Gpu(format!("cannot open {}: {e}", info.name)))?,
        };
        let error = Arc::new(Mutex::new(None));
        let sink = error.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let mut slot = sink.lock().expect("error slot");
            if slot.is_none() {
                *slot = Some(e.to_string());
            }
        }));
        let layout = |label: &str, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        };
        // Group 1 (the step offset, with a dynamic offset per dispatch, and
        // the batch) is the same in every kernel. Where the adapter has
        // immediates, every pipeline layout also has room for the step
        // offset as one; a module that declares it a binding leaves that
        // room unused, and one that declares it an immediate leaves
        // group 1's binding 0 unused.
        let immediate_size = match features.contains(wgpu::Features::IMMEDIATES) {
            true => STEP_IMMEDIATE_BYTES,
            false => 0,
        };
        let reflect = |kernel: Kernel| {
            Bindings::reflect(&kernel.source::<f32>())
                .expect("the kernels parse (tested with naga)")
        };
        let batch_entries = reflect(Kernel::OneStep).layout(1, &[STEP_OFFSET]);
        let batch_layout = layout("batch", &batch_entries);
        let kernel_layout = |kernel: Kernel| {
            // Group 0 as the kernel's module declares it: the constants (one
            // record per scene), the state, and the record buffers. The
            // one-step kernels share a layout: what either uses.
            let bindings = match kernel {
                Kernel::OneStep | Kernel::OneStepLanes => {
                    reflect(Kernel::OneStep).union(reflect(Kernel::OneStepLanes))
                }
                // The resident kernel declares the same bindings (tested).
                Kernel::Persistent | Kernel::Resident => reflect(Kernel::Persistent),
                Kernel::Tiled => reflect(Kernel::Tiled),
            };
            let entries = bindings.layout(0, &[]);
            let group = layout(kernel.entry_point(), &entries);
            let vulkan_bindings = spirv::vulkan_binding_map(&[&entries, &batch_entries]);
            let pipeline = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("slipfront"),
                bind_group_layouts: &[Some(&group), Some(&batch_layout)],
                immediate_size,
            });
            KernelLayout {
                group,
                pipeline,
                bindings,
                vulkan_bindings,
            }
        };
        let layouts = Arc::new([
            kernel_layout(Kernel::OneStep),
            kernel_layout(Kernel::Persistent),
            kernel_layout(Kernel::Tiled),
        ]);
        let timestamp_period_ns = features
            .contains(wgpu::Features::TIMESTAMP_QUERY)
            .then(|| queue.get_timestamp_period() as f64);
        Ok(GpuContext {
            device,
            queue,
            info,
            limits,
            error,
            timestamp_period_ns,
            layouts,
            batch_layout,
            pipelines: Arc::new(Mutex::new(HashMap::new())),
            spirv,
            own_spirv_refused: Arc::new(Mutex::new(None)),
            shader_clock,
        })
    }

    /// Group 0's layout of `kernel`.
    pub fn state_layout(&self, kernel: Kernel) -> &wgpu::BindGroupLayout {
        &self.layouts[layout_index(kernel)].group
    }

    /// The bindings the kernels of `kernel`'s family declare.
    pub fn bindings(&self, kernel: Kernel) -> &Bindings {
        &self.layouts[layout_index(kernel)].bindings
    }

    /// The pipeline of `kernel` in precision `T` with `constants`, compiled
    /// once per process.
    pub fn pipeline<T: GpuReal>(
        &self,
        kernel: Kernel,
        build: KernelBuild,
        constants: &[(&str, f64)],
    ) -> wgpu::ComputePipeline {
        self.pipeline_of::<T>(kernel, build, kernel.entry_point(), constants)
    }

    /// Whether the adapter was opened with `@coherent` storage buffers
    /// (the chained tiled kernel's published halos).
    pub fn has_coherent_storage(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::MEMORY_DECORATION_COHERENT)
    }

    /// Whether the adapter was opened with immediates for the step offset
    /// (`KernelBuild::step_immediate`).
    pub fn has_immediates(&self) -> bool {
        self.device.features().contains(wgpu::Features::IMMEDIATES)
    }

    /// Whether the engine writes this device's SPIR-V itself where a
    /// kernel's build asks (`KernelBuild::workgroup_barriers`).
    pub fn has_own_spirv(&self) -> bool {
        self.spirv.is_some() && self.own_spirv_refused().is_none()
    }

    /// Whether the engine's kernels may read the multiprocessor's clock
    /// (`GpuOptions::phase_clocks`): the device opened with
    /// VK_KHR_shader_clock, and taking the engine's own SPIR-V.
    pub fn has_shader_clock(&self) -> bool {
        self.shader_clock && self.has_own_spirv()
    }

    /// Why the device refused the engine's own SPIR-V, where it did.
    pub fn own_spirv_refused(&self) -> Option<String> {
        self.own_spirv_refused.lock().expect("refusal slot").clone()
    }

    /// Stops giving the device the engine's own SPIR-V, for `why` (the
    /// first reason is kept and printed once): the kernels already built
    /// keep their modules, and every later build is wgpu's, with the phase
    /// barriers at device scope. Engines built after this describe
    /// themselves so.
    pub fn refuse_own_spirv(&self, why: String) {
        let mut slot = self.own_spirv_refused.lock().expect("refusal slot");
        if slot.is_none() {
            eprintln!(
                "slipfront: {} refused the engine's own SPIR-V ({why}); the kernels' phase \
                 barriers keep wgpu's device scope",
                self.info.name
            );
            *slot = Some(why);
        }
    }

    /// Whether the adapter was opened with subgroup operations.
    pub fn has_subgroups(&self) -> bool {
        self.device.features().contains(wgpu::Features::SUBGROUP)
    }

    /// The pipeline of entry point `entry` of `kernel`'s module (the tiled
    /// kernel's gather beside its steps).
    pub fn pipeline_of<T: GpuReal>(
        &self,
        kernel: Kernel,
        build: KernelBuild,
        entry: &str,
        constants: &[(&str, f64)],
    ) -> wgpu::ComputePipeline {
        let layout = &self.layouts[layout_index(kernel)].pipeline;
        let KernelBuild {
            lanes,
            checks,
            chained_tiles,
            step_immediate,
            workgroup_barriers,
            phase_clocks,
            strict_arithmetic,
        } = build;
        let key = format!(
            "{}{kernel:?}{lanes:?}{checks:?}{chained_tiles}{step_immediate}{workgroup_barriers}\
             {phase_clocks}{strict_arithmetic}{entry}{constants:?}",
            T::NAME
        );
        let slot = self
            .pipelines
            .lock()
            .expect("pipeline cache")
            .entry(key)
            .or_default()
            .clone();
        slot.get_or_init(|| {
            let own = match self.spirv.filter(|_| {
                (workgroup_barriers || phase_clocks || strict_arithmetic) && self.has_own_spirv()
            }) {
                Some(target) => {
                    let own = KernelSource::of::<T>(kernel, build, entry, constants);
                    let layout_bindings = &self.layouts[layout_index(kernel)].vulkan_bindings;
                    spirv::kernel_spirv(
                        &own,
                        target.language,
                        ZeroWorkgroupMemory::Native,
                        layout_bindings,
                    )
                    .and_then(|(words, _)| self.pipeline_from_spirv(kernel, entry, words))
                    .map_err(|why| self.refuse_own_spirv(format!("{entry}: {why}")))
                    .ok()
                }
                None => None,
            };
            own.unwrap_or_else(|| {
                let source = build.source::<T>(kernel);
                let module = checks.module(&self.device, kernel.entry_point(), source);
                self.device
                    .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(entry),
                        layout: Some(layout),
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants,
                            ..Default::default()
                        },
                        cache: None,
                    })
            })
        })
        .clone()
    }

    /// The pipeline of `entry` of `kernel` from SPIR-V `words` the engine
    /// wrote (`spirv::kernel_spirv`: its override constants applied, its
    /// bindings placed as `kernel`'s layout places them), given to the
    /// driver as they are; the device's error where it refuses them
    /// (caught in error scopes, so none is left for `check`).
    pub fn pipeline_from_spirv(
        &self,
        kernel: Kernel,
        entry: &str,
        words: Vec<u32>,
    ) -> Result<wgpu::ComputePipeline, String> {
        // Never hand a driver words that are not SPIR-V at all.
        if words.len() < 5 || words[0] != spirv::MAGIC {
            return Err(format!(
                "{entry}: not a SPIR-V module ({} words, first {:#x?})",
                words.len(),
                words.first()
            ));
        }
        // wgpu's error scopes are the calling thread's: another thread's
        // errors meanwhile never land in these.
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let entry_points = [wgpu::PassthroughShaderEntryPoint {
            name: entry.into(),
            workgroup_size: (0, 0, 0),
        }];
        // SAFETY: the SPIR-V is naga's, written from a module naga
        // validated, with the options wgpu's Vulkan backend uses for this
        // device (its runtime checks as the build says); the one change,
        // a barrier's memory scope from Device to Workgroup, keeps it
        // valid SPIR-V (`spirv` tests). A module the driver refuses all
        // the same is an error in the scopes above, not undefined
        // behaviour.
        let module = unsafe {
            self.device
                .create_shader_module_passthrough(wgpu::ShaderModuleDescriptorPassthrough {
                    label: Some(entry),
                    entry_points: entry_points[..].into(),
                    spirv: Some(words.into()),
                    ..Default::default()
                })
        };
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&self.layouts[layout_index(kernel)].pipeline),
                module: &module,
                entry_point: Some(entry),
                // The override constants are applied in the SPIR-V.
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                cache: None,
            });
        let internal = pollster::block_on(internal.pop());
        let validation = pollster::block_on(validation.pop());
        match internal.or(validation) {
            Some(error) => Err(error.to_string()),
            None => Ok(pipeline),
        }
    }

    /// Adapter name, type and driver.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?}, driver {} {})",
            self.info.name,
            self.info.device_type,
            self.info.backend,
            self.info.driver,
            self.info.driver_info
        )
    }

    /// Fails unless the device can run kernels in precision `T` (f64
    /// needs SHADER_F64), naming the adapter and the alternatives.
    pub fn check_precision<T: GpuReal>(&self) -> Result<(), EngineError> {
        if self.device.features().contains(T::FEATURES) {
            return Ok(());
        }
        Err(EngineError::Gpu(format!(
            "--precision {}: {} has no {:?} shader support: use --precision f32 (mixed, \
             every adapter) or --backend cpu",
            T::NAME,
            self.info.name,
            T::FEATURES
        )))
    }

    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Fails with the first device error seen, if any.
    pub fn check(&self) -> Result<(), EngineError> {
        match self.error.lock().expect("error slot").take() {
            Some(e) => Err(EngineError::Gpu(format!("device error: {e}"))),
            None => Ok(()),
        }
    }
}
