//! A headless wgpu device.

use std::sync::{Arc, Mutex};

/// A headless wgpu device.
#[derive(Debug)]
pub struct Gpu {
    pub adapter: wgpu::AdapterInfo,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// The first thing the device met outside an error scope that is not
    /// a bug of ours (out of memory, a driver's internal error, a lost
    /// device), kept for [`Gpu::fault`] rather than wgpu's default of a
    /// panic.
    fault: Arc<Mutex<Option<String>>>,
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
        let fault: Arc<Mutex<Option<String>>> = Arc::default();
        // The first fault is the one to report: what follows it is its
        // consequence.
        let keep_first = |slot: &Mutex<Option<String>>, fault: String| {
            if let Ok(mut slot) = slot.lock() {
                slot.get_or_insert(fault);
            }
        };
        let uncaptured = fault.clone();
        device.on_uncaptured_error(Arc::new(move |err: wgpu::Error| {
            let fault = match err {
                wgpu::Error::OutOfMemory { .. } => "the device ran out of memory".to_string(),
                wgpu::Error::Internal { description, .. } => {
                    format!("the driver failed: {description}")
                }
                // A command wgpu rejects outside an error scope is a bug
                // of ours, as it is to wgpu's own default handler, which
                // panics: so does this one (the command reports it as an
                // internal error).
                #[allow(clippy::panic)]
                wgpu::Error::Validation { description, .. } => {
                    panic!("wgpu rejected a command: {description}")
                }
            };
            keep_first(&uncaptured, fault);
        }));
        let lost = fault.clone();
        device.set_device_lost_callback(move |reason, message| {
            // Dropping the device at the end of a run loses it too.
            if reason != wgpu::DeviceLostReason::Destroyed {
                keep_first(&lost, format!("the device was lost: {message}"));
            }
        });
        Ok(Some(Gpu {
            adapter: adapter.get_info(),
            device,
            queue,
            fault,
        }))
    }

    /// The adapter and its driver as one line: `llvmpipe (LLVM 15.0.6,
    /// 256 bits), llvmpipe Mesa 25.0.7 (LLVM 15.0.6), Vulkan`.
    pub fn describe(&self) -> String {
        describe_adapter(&self.adapter)
    }

    /// The first fault since the device was opened, if any: what the
    /// driver or wgpu said outside an error scope.
    pub fn fault(&self) -> Result<(), String> {
        let fault = self
            .fault
            .lock()
            .map_err(|_| "a fault handler panicked".to_string())?;
        match fault.as_ref() {
            None => Ok(()),
            Some(fault) => Err(format!("{fault} on {}", self.describe())),
        }
    }
}

/// An adapter's driver and its version as one line (`llvmpipe Mesa 25.0.7
/// (LLVM 15.0.6)`), empty where the adapter names neither: what every
/// report and diagnostic says of the driver.
pub fn driver_line(adapter: &wgpu::AdapterInfo) -> String {
    format!("{} {}", adapter.driver, adapter.driver_info)
        .trim()
        .to_string()
}

/// An adapter and its driver as one line, for diagnostics.
pub fn describe_adapter(adapter: &wgpu::AdapterInfo) -> String {
    let driver = driver_line(adapter);
    let driver = if driver.is_empty() {
        "driver unnamed"
    } else {
        driver.as_str()
    };
    format!("{}, {driver}, {:?}", adapter.name, adapter.backend)
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
