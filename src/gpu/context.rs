//! The wgpu instance, adapter and device.
//!
//! The instance is built from the environment (`WGPU_BACKEND=vulkan`, `WGPU_ADAPTER_NAME`,
//! ...), so a machine without a Vulkan driver does not silently fall back to OpenGL when
//! Vulkan is asked for. The device is requested with the adapter's own limits (the node
//! kernel binds 11 storage buffers; the WebGPU default allows 8) and with `SHADER_F64`
//! when the adapter has it. Pipeline creation runs inside error scopes, so a shader or
//! binding error becomes an [`Error::Gpu`] instead of a panic.

use crate::error::{Error, Result};
use std::sync::{Arc, Mutex};

/// A device and its queue, with what the adapter is.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    /// Whether the device was created with `SHADER_F64`.
    pub has_f64: bool,
    /// The first device error outside an error scope (wgpu would panic on it by default).
    uncaptured: Arc<Mutex<Option<String>>>,
}

impl GpuContext {
    /// The first adapter the environment allows (high performance preferred), or an error
    /// saying why there is none. Never panics.
    pub fn new() -> Result<GpuContext> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| Error::Gpu(format!("no GPU adapter: {e}")))?;
        let info = adapter.get_info();
        let features = adapter.features() & wgpu::Features::SHADER_F64;
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("sticky-lips"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| Error::Gpu(format!("{}: cannot create a device: {e}", info.name)))?;
        let uncaptured = Arc::new(Mutex::new(None));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut first) = sink.lock() {
                first.get_or_insert_with(|| e.to_string());
            }
        }));
        Ok(GpuContext {
            device,
            queue,
            uncaptured,
            has_f64: features.contains(wgpu::Features::SHADER_F64),
            info,
            limits,
        })
    }

    /// One line naming the adapter, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu)`.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }

    /// `Err` with the first device error that no error scope caught, if any (checked after
    /// every submission's wait, so a failed submission is an error, never a silent result).
    pub fn check_uncaptured(&self) -> Result<()> {
        let first = self.uncaptured.lock().ok().and_then(|mut e| e.take());
        match first {
            Some(m) => Err(Error::Gpu(format!("device error: {m}"))),
            None => Ok(()),
        }
    }

    /// Runs `f` inside validation and out-of-memory error scopes; an error caught there
    /// becomes `Err(Error::Gpu)` naming `what`.
    pub fn scoped<R>(&self, what: &str, f: impl FnOnce() -> R) -> Result<R> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let val = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let r = f();
        let e_val = pollster::block_on(val.pop());
        let e_oom = pollster::block_on(oom.pop());
        match e_val.or(e_oom) {
            Some(e) => Err(Error::Gpu(format!("{what}: {e}"))),
            None => Ok(r),
        }
    }
}

/// Whether an adapter exists (for `--backend auto`), without keeping a device.
pub fn adapter_available() -> bool {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default())).is_ok()
}
