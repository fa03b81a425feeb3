//! The wgpu instance, adapter and device.
//!
//! The instance is built from the environment (`WGPU_BACKEND=vulkan`, `WGPU_ADAPTER_NAME`,
//! ...), so a machine without a Vulkan driver does not silently fall back to OpenGL when
//! Vulkan is asked for. The device is requested with the adapter's own limits (the node
//! kernel binds 11 storage buffers; the WebGPU default allows 8) and with `SHADER_F64`
//! when the adapter has it. Pipeline creation runs inside error scopes, so a shader or
//! binding error becomes an [`Error::Gpu`] instead of a panic.

use crate::error::{Error, Result};

/// A device and its queue, with what the adapter is.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    /// Whether the device was created with `SHADER_F64`.
    pub has_f64: bool,
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
        Ok(GpuContext {
            device,
            queue,
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
