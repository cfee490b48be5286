//! Adapter selection: a hardware GPU, else a software one (lavapipe).

use super::shaders::Phase;
use crate::engine::EngineError;
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
    pub state_layout: wgpu::BindGroupLayout,
    pub step_layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    pipelines: Arc<Mutex<HashMap<String, wgpu::ComputePipeline>>>,
}

static SHARED: OnceLock<Result<GpuContext, String>> = OnceLock::new();

/// The process-wide context, opened on first use.
pub fn shared() -> Result<GpuContext, EngineError> {
    SHARED
        .get_or_init(|| GpuContext::open().map_err(|e| e.to_string()))
        .clone()
        .map_err(EngineError::Gpu)
}

/// Size of one step's loads in the dynamically offset step buffer.
pub const STEP_LOADS_SIZE: u64 = std::mem::size_of::<super::layout::GpuStep>() as u64;

/// Lists the adapters with Vulkan/Metal/DX12 support, hardware first.
pub fn adapters() -> Vec<wgpu::Adapter> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let mut list = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
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
        // 8 state buffers plus the per-step loads.
        if limits.max_storage_buffers_per_shader_stage < 9 {
            return Err(EngineError::Gpu(format!(
                "{} allows {} storage buffers per shader stage; slipfront needs 9",
                info.name, limits.max_storage_buffers_per_shader_stage
            )));
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("slipfront"),
            required_features: wgpu::Features::empty(),
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| EngineError::Gpu(format!("cannot open {}: {e}", info.name)))?;
        let error = Arc::new(Mutex::new(None));
        let sink = error.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let mut slot = sink.lock().expect("error slot");
            if slot.is_none() {
                *slot = Some(e.to_string());
            }
        }));
        let storage_entry = |binding: u32| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }];
        entries.extend((1..=8).map(storage_entry));
        let state_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("state"),
            entries: &entries,
        });
        let step_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("step"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: true,
                    min_binding_size: wgpu::BufferSize::new(STEP_LOADS_SIZE),
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("slipfront"),
            bind_group_layouts: &[Some(&state_layout), Some(&step_layout)],
            immediate_size: 0,
        });
        Ok(GpuContext {
            device,
            queue,
            info,
            limits,
            error,
            state_layout,
            step_layout,
            pipeline_layout,
            pipelines: Arc::new(Mutex::new(HashMap::new())),
        })
    }

    /// The pipeline of `phase` with `constants`, compiled once per process.
    pub fn pipeline(&self, phase: Phase, constants: &[(&str, f64)]) -> wgpu::ComputePipeline {
        let key = format!("{}{constants:?}", phase.entry_point());
        let mut cache = self.pipelines.lock().expect("pipeline cache");
        cache
            .entry(key)
            .or_insert_with(|| {
                let module = self
                    .device
                    .create_shader_module(wgpu::ShaderModuleDescriptor {
                        label: Some(phase.entry_point()),
                        source: wgpu::ShaderSource::Wgsl(phase.source().into()),
                    });
                self.device
                    .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(phase.entry_point()),
                        layout: Some(&self.pipeline_layout),
                        module: &module,
                        entry_point: Some(phase.entry_point()),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants,
                            ..Default::default()
                        },
                        cache: None,
                    })
            })
            .clone()
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
