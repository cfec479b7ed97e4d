//! Copies from the GPU to the CPU: files, tests and the stages' status reads.

use crate::error::{Error, Result};

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
