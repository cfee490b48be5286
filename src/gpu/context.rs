//! Adapter selection: a hardware GPU, else a software one (lavapipe).

use crate::engine::EngineError;

/// The device an engine runs on, and what it is.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    /// The first uncaptured device error, if any (checked after submits).
    pub error: std::sync::Arc<std::sync::Mutex<Option<String>>>,
}

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
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("slipfront"),
            required_features: wgpu::Features::empty(),
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| EngineError::Gpu(format!("cannot open {}: {e}", info.name)))?;
        let error = std::sync::Arc::new(std::sync::Mutex::new(None));
        let sink = error.clone();
        device.on_uncaptured_error(std::sync::Arc::new(move |e: wgpu::Error| {
            let mut slot = sink.lock().expect("error slot");
            if slot.is_none() {
                *slot = Some(e.to_string());
            }
        }));
        Ok(GpuContext {
            device,
            queue,
            info,
            limits,
            error,
        })
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
