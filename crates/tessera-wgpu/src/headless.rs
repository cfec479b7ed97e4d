//! A device without a window (CLI, tests, benchmarks): adapter selection, wgpu errors
//! collected instead of panicking, and buffer readback.
//!
//! Embedding applications bring their own `Device` and never need this module.

use std::sync::{Arc, Mutex};

use crate::error::{Error, Result};

/// An adapter, its device and queue, and the wgpu errors the device has reported.
pub struct Gpu {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    errors: Arc<Mutex<Vec<String>>>,
}

impl Gpu {
    /// The first adapter wgpu finds (`WGPU_BACKEND` and `WGPU_ADAPTER_NAME` narrow the
    /// choice), with the limits the stage needs raised to what the adapter allows and the
    /// renderer's optional features (wireframe) where the adapter has them.
    pub fn new() -> Result<Gpu> {
        Self::with_optional_features(crate::render::MeshRenderer::required_features(
            wgpu::Features::all(),
        ))
    }

    /// As [`new`](Self::new), with those of the `optional` features that the adapter has
    /// (`Features::empty()` to test what happens without them).
    pub fn with_optional_features(optional: wgpu::Features) -> Result<Gpu> {
        Self::build(optional, crate::bezier::required_limits)
    }

    /// As [`new`](Self::new), with the device's limits chosen by `limits` from the
    /// adapter's (tests use it to play a device smaller than the one at hand).
    pub fn with_limits(limits: impl FnOnce(&wgpu::Limits) -> wgpu::Limits) -> Result<Gpu> {
        Self::build(
            crate::render::MeshRenderer::required_features(wgpu::Features::all()),
            limits,
        )
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

/// Copies `size` bytes of `buffer` from `offset` to the CPU on its own submission and
/// waits for them.
pub(crate) fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    offset: u64,
    size: u64,
) -> Result<Vec<u8>> {
    if size == 0 {
        return Ok(Vec::new());
    }
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("tessera readback"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, offset, &staging, 0, size);
    queue.submit([encoder.finish()]);
    map_read(device, &staging)
}

/// Maps a `MAP_READ` buffer whose copies have been submitted, waits, and returns its
/// bytes (the buffer is unmapped again).
pub(crate) fn map_read(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::Readback(e.to_string()))?;
    rx.recv()
        .map_err(|e| Error::Readback(e.to_string()))?
        .map_err(|e| Error::Readback(e.to_string()))?;
    let bytes = buffer
        .get_mapped_range(..)
        .map_err(|e| Error::Readback(e.to_string()))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// A texture's texels copied, inside a caller's encoder, into a mappable buffer whose
/// rows are padded to the copy alignment; [`read`](Self::read) returns them unpadded,
/// row-major, once the encoder has been submitted.
pub(crate) struct TextureReadback {
    staging: wgpu::Buffer,
    row: usize,
    padded_row: usize,
}

impl TextureReadback {
    /// Records the copy of mip level 0 of `texture` (a format with one plane).
    pub fn record(
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
    ) -> Self {
        let texel = texture
            .format()
            .block_copy_size(None)
            .expect("a single-plane format");
        let row = texel * texture.width();
        let padded_row = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tessera texture readback"),
            size: padded_row as u64 * texture.height() as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row),
                    rows_per_image: None,
                },
            },
            wgpu::Extent3d {
                depth_or_array_layers: 1,
                ..texture.size()
            },
        );
        TextureReadback {
            staging,
            row: row as usize,
            padded_row: padded_row as usize,
        }
    }

    /// The texels, unpadded (waits for the submitted copy).
    pub fn read(self, device: &wgpu::Device) -> Result<Vec<u8>> {
        let padded = map_read(device, &self.staging)?;
        Ok(padded
            .chunks(self.padded_row)
            .flat_map(|r| &r[..self.row])
            .copied()
            .collect())
    }
}

/// The texels of mip level 0 of `texture` (a format with one plane, `COPY_SRC` usage),
/// row-major and unpadded, copied on their own submission.
pub(crate) fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<Vec<u8>> {
    let mut encoder = device.create_command_encoder(&Default::default());
    let readback = TextureReadback::record(device, &mut encoder, texture);
    queue.submit([encoder.finish()]);
    readback.read(device)
}
