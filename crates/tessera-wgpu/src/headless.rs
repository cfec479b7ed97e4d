//! A device without a window (CLI, tests, benchmarks): adapter selection, wgpu errors
//! collected instead of panicking, and buffer readback.
//!
//! Embedding applications bring their own `Device` and never need this module.

use std::sync::{Arc, Mutex};

use crate::error::{Error, Result};
use crate::readback::{map_read, read_buffer};

/// An adapter, its device and queue, and the wgpu errors the device has reported.
pub struct Gpu {
    /// The adapter wgpu chose.
    pub adapter: wgpu::Adapter,
    /// Its device.
    pub device: wgpu::Device,
    /// The device's queue.
    pub queue: wgpu::Queue,
    errors: Arc<Mutex<Vec<String>>>,
}

impl Gpu {
    /// The first adapter wgpu finds (`WGPU_BACKEND` and `WGPU_ADAPTER_NAME` narrow the
    /// choice), with the limits the stage needs raised to what the adapter allows, and
    /// the renderer's optional features (wireframe) and timestamp queries
    /// ([`crate::GpuTimer`]) where the adapter has them.
    pub fn new() -> Result<Gpu> {
        Self::with_optional_features(Self::optional_features())
    }

    fn optional_features() -> wgpu::Features {
        crate::render::MeshRenderer::required_features(wgpu::Features::all())
            | wgpu::Features::TIMESTAMP_QUERY
    }

    /// As [`new`](Self::new), with those of the `optional` features that the adapter has
    /// (`Features::empty()` to test what happens without them).
    pub fn with_optional_features(optional: wgpu::Features) -> Result<Gpu> {
        Self::build(optional, crate::bezier::required_limits)
    }

    /// As [`new`](Self::new), with the device's limits chosen by `limits` from the
    /// adapter's (tests use it to play a device smaller than the one at hand).
    pub fn with_limits(limits: impl FnOnce(&wgpu::Limits) -> wgpu::Limits) -> Result<Gpu> {
        Self::build(Self::optional_features(), limits)
    }

    fn build(
        optional: wgpu::Features,
        limits: impl FnOnce(&wgpu::Limits) -> wgpu::Limits,
    ) -> Result<Gpu> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        if std::env::var_os("WGPU_BACKEND").is_none() {
            // Vulkan, Metal, DX12: the GL backend without a display only adds noise
            // (EGL complaining about XDG_RUNTIME_DIR) and is never the better choice.
            desc.backends = wgpu::Backends::PRIMARY;
        }
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| Error::NoAdapter(e.to_string()))?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("tessera"),
            required_features: adapter.features() & optional,
            required_limits: limits(&adapter.limits()),
            ..Default::default()
        }))
        .map_err(|e| Error::RequestDevice(e.to_string()))?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        Ok(Gpu {
            adapter,
            device,
            queue,
            errors,
        })
    }

    /// A one-line description of the adapter, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu)`.
    pub fn adapter_name(&self) -> String {
        let i = self.adapter.get_info();
        format!("{} ({:?}, {:?})", i.name, i.backend, i.device_type)
    }

    /// Fails with every wgpu error reported since the last call (validation errors
    /// included), after waiting for the queue.
    pub fn check(&self) -> Result<()> {
        self.wait()?;
        let errs: Vec<String> = self
            .errors
            .lock()
            .map(|mut v| std::mem::take(&mut *v))
            .unwrap_or_default();
        if errs.is_empty() {
            Ok(())
        } else {
            Err(Error::Wgpu(errs.join("; ")))
        }
    }

    /// Blocks until the GPU has finished all submitted work.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| Error::Readback(e.to_string()))
    }

    /// Copies `size` bytes of `buffer` from `offset` (both multiples of 4) to the CPU.
    /// The buffer needs `COPY_SRC` usage.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer, offset: u64, size: u64) -> Result<Vec<u8>> {
        read_buffer(&self.device, &self.queue, buffer, offset, size)
    }

    /// Maps a `MAP_READ` buffer whose copies have been submitted and returns its bytes.
    pub fn map_and_copy(&self, staging: &wgpu::Buffer) -> Result<Vec<u8>> {
        map_read(&self.device, staging)
    }

    /// Reads a buffer of Pod values.
    pub fn read_pod<T: bytemuck::Pod>(
        &self,
        buffer: &wgpu::Buffer,
        count: usize,
    ) -> Result<Vec<T>> {
        let bytes = self.read_buffer(buffer, 0, (count * std::mem::size_of::<T>()) as u64)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}
