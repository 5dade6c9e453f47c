//! A headless wgpu device.

/// A headless wgpu device.
#[derive(Debug)]
pub struct Gpu {
    pub adapter: wgpu::AdapterInfo,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

impl Gpu {
    /// The first adapter any backend offers, with default limits but for
    /// colour attachments. `None`
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
        // 32-bit float depth with stencil where it has it: the deferred
        // variant's depth buffer holds each draw's ordinal in the stencil.
        let features = adapter.features()
            & (wgpu_profiler::GpuProfiler::ALL_WGPU_TIMER_FEATURES
                | wgpu::Features::DEPTH32FLOAT_STENCIL8);
        // The deferred variant's G-buffer takes as many colour targets, and
        // bytes of them per pixel, as the adapter grants (WebGPU's defaults
        // are 8 targets and 32 bytes).
        let granted = adapter.limits();
        let limits = wgpu::Limits {
            max_color_attachments: granted.max_color_attachments,
            max_color_attachment_bytes_per_sample: granted.max_color_attachment_bytes_per_sample,
            // The scene-assisted B-frame binds the I-frames in the group
            // after the twins': a fifth for shaders that use all four.
            max_bind_groups: granted.max_bind_groups.min(8),
            // The I-frame twins the per-instance inputs its position
            // reads, once per other I-frame: the wgpu tutorial's 11
            // inputs and 4 model-matrix columns twice take 19.
            max_vertex_attributes: granted.max_vertex_attributes,
            ..wgpu::Limits::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("shadecache"),
            required_features: features,
            required_limits: limits,
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

/// What `make` creates on `device`, or what wgpu's validation said of it:
/// `make` runs in a validation error scope, so a rejected shader, pipeline
/// or bind group is an error to report rather than a panic in wgpu's
/// default handler. Waits for the scope (native backends answer at once).
pub fn validated<T>(device: &wgpu::Device, make: impl FnOnce() -> T) -> Result<T, String> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let made = make();
    match pollster::block_on(scope.pop()) {
        None => Ok(made),
        Some(err) => Err(err.to_string()),
    }
}
