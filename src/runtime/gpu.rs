//! A headless wgpu device.

/// A headless wgpu device.
#[derive(Debug)]
pub struct Gpu {
    pub adapter: wgpu::AdapterInfo,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

impl Gpu {
    /// The first adapter any backend offers, with default limits. `None`
    /// when the machine has no GPU and no software driver.
    pub fn new() -> Result<Option<Gpu>, String> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = match pollster::block_on(
            instance.request_adapter(&wgpu::RequestAdapterOptions::default()),
        ) {
            Ok(adapter) => adapter,
            Err(_) => return Ok(None),
        };
        // Timestamp queries where the adapter has them (lavapipe does): the
        // profiler times each pass with them.
        let features = adapter.features() & wgpu_profiler::GpuProfiler::ALL_WGPU_TIMER_FEATURES;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("shadecache"),
            required_features: features,
            ..wgpu::DeviceDescriptor::default()
        }))
        .map_err(|err| format!("cannot open a device on {}: {err}", adapter.get_info().name))?;
        Ok(Some(Gpu {
            adapter: adapter.get_info(),
            device,
            queue,
        }))
    }
}
