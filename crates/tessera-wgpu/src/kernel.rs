//! What every compute stage shares: compiling a kernel with the bindings its entry point
//! uses, binding buffers by number, and dispatching any number of invocations.

use crate::error::{Error, Result};
use crate::shaders;

/// Largest x dimension dispatched; larger counts spill into y (kernels fold it back).
pub(crate) const MAX_GROUPS_X: u32 = 32768;

/// A compute pipeline and the bindings (group 0) its entry point uses.
pub(crate) struct Kernel {
    pub pipeline: wgpu::ComputePipeline,
    pub bindings: Vec<u32>,
}

impl Kernel {
    /// Compiles entry point `entry` of shader file `file` with a derived layout.
    pub fn new(device: &wgpu::Device, file: &str, entry: &str) -> Self {
        Self::with_constants(device, file, entry, &[])
    }

    /// As [`Kernel::new`], with values for the shader's `override` constants.
    pub fn with_constants(
        device: &wgpu::Device,
        file: &str,
        entry: &str,
        constants: &[(&str, f64)],
    ) -> Self {
        Self::specialised(device, file, entry, constants, &[])
    }

    /// As [`Kernel::with_constants`], with `const` values replaced in the source too
    /// ([`shaders::source_with_consts`]).
    pub fn specialised(
        device: &wgpu::Device,
        file: &str,
        entry: &str,
        constants: &[(&str, f64)],
        consts: &[(&str, u32)],
    ) -> Self {
        let module = shaders::module(device, file, consts);
        Kernel {
            pipeline: device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(file),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    ..Default::default()
                },
                cache: None,
            }),
            bindings: shaders::used_bindings(file, entry),
        }
    }

    /// A bind group of those `entries` this kernel uses.
    pub fn bind(&self, device: &wgpu::Device, entries: &[(u32, &wgpu::Buffer)]) -> wgpu::BindGroup {
        self.bind_with_textures(device, entries, &[])
    }

    /// As [`Kernel::bind`], with texture views among the entries.
    pub fn bind_with_textures(
        &self,
        device: &wgpu::Device,
        buffers: &[(u32, &wgpu::Buffer)],
        textures: &[(u32, &wgpu::TextureView)],
    ) -> wgpu::BindGroup {
        let buffers = buffers
            .iter()
            .map(|(binding, buffer)| (*binding, buffer.as_entire_binding()));
        let textures = textures
            .iter()
            .map(|(binding, view)| (*binding, wgpu::BindingResource::TextureView(view)));
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .chain(textures)
            .filter(|(binding, _)| self.bindings.contains(binding))
            .map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &entries,
        })
    }

    /// Dispatches enough workgroups of `per_group` items for `items` items; returns the
    /// dispatches recorded (none for no items).
    pub fn dispatch(
        &self,
        pass: &mut wgpu::ComputePass,
        bind_group: &wgpu::BindGroup,
        items: u32,
        per_group: u32,
    ) -> u32 {
        if items == 0 {
            return 0;
        }
        let (x, y) = groups_2d(items, per_group);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups(x, y, 1);
        1
    }
}

impl Kernel {
    /// Dispatches with workgroup counts that an earlier kernel wrote into `args` at
    /// `offset` (three `u32`); returns the dispatches recorded (one).
    pub fn dispatch_indirect(
        &self,
        pass: &mut wgpu::ComputePass,
        bind_group: &wgpu::BindGroup,
        args: &wgpu::Buffer,
        offset: u64,
    ) -> u32 {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups_indirect(args, offset);
        1
    }
}

/// Workgroups for `items` invocations, as (x, y) within the per-dimension limit.
pub(crate) fn groups_2d(items: u32, per_group: u32) -> (u32, u32) {
    let g = items.div_ceil(per_group);
    (g.min(MAX_GROUPS_X), g.div_ceil(MAX_GROUPS_X).max(1))
}

/// Fails with [`Error::OutputTooLarge`] when a storage buffer of `bytes` would exceed
/// what `device` can create and bind.
pub(crate) fn check_size(device: &wgpu::Device, what: &'static str, bytes: u64) -> Result<()> {
    let limit = storage_limit(device);
    if bytes > limit {
        return Err(Error::OutputTooLarge { what, bytes, limit });
    }
    Ok(())
}

/// Fails with [`Error::ModelTooLarge`] when an upload of `bytes` would exceed what
/// `device` can create and bind.
pub(crate) fn check_upload(device: &wgpu::Device, what: &'static str, bytes: u64) -> Result<()> {
    let limit = storage_limit(device);
    if bytes > limit {
        return Err(Error::ModelTooLarge { what, bytes, limit });
    }
    Ok(())
}

/// The largest storage buffer `device` can create and bind.
pub(crate) fn storage_limit(device: &wgpu::Device) -> u64 {
    let limits = device.limits();
    limits
        .max_buffer_size
        .min(limits.max_storage_buffer_binding_size)
}

/// A storage buffer the kernels write and tests can copy.
pub(crate) fn storage(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(4),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A 2D texture the kernels bind as a storage texture (`usage` besides). The kernels
/// read their tables from storage textures rather than storage buffers or sampled
/// textures: on a CPU device (llvmpipe) a storage-buffer read at per-lane addresses is a
/// loop over the lanes, and a sampled fetch loads its mip level's layout lane by lane
/// (see `shaders/shared/map.wgsl`).
pub(crate) fn storage_texture(
    device: &wgpu::Device,
    label: &str,
    format: wgpu::TextureFormat,
    (width, height): (u32, u32),
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::STORAGE_BINDING | usage,
        view_formats: &[],
    })
}

/// A storage texture holding `texels` (its rows, row-major, without padding), written
/// through the queue: it lands before the next submission.
pub(crate) fn upload_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &str,
    format: wgpu::TextureFormat,
    (width, height): (u32, u32),
    texels: &[u8],
) -> wgpu::Texture {
    let texture = storage_texture(
        device,
        label,
        format,
        (width, height),
        wgpu::TextureUsages::COPY_DST,
    );
    queue.write_texture(
        texture.as_image_copy(),
        texels,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some((texels.len() / height.max(1) as usize) as u32),
            rows_per_image: None,
        },
        texture.size(),
    );
    texture
}

/// A buffer holding `contents` (zero-padded to a multiple of 4 bytes, at least 4), as
/// wgpu's `create_buffer_init`, which panics when the device could not create the buffer
/// (out of memory): here the buffer is left unwritten, and the device's error (caught by
/// [`allocating`] around a stage's allocations) says why.
pub(crate) fn init_buffer(
    device: &wgpu::Device,
    label: &str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let size = (contents.len() as u64)
        .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
        .max(wgpu::COPY_BUFFER_ALIGNMENT);
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: true,
    });
    if let Ok(mut range) = buffer.get_mapped_range_mut(..) {
        range.slice(..contents.len()).copy_from_slice(contents);
    }
    buffer.unmap();
    buffer
}

/// A storage buffer holding `bytes`, written again through the queue when the points
/// move; never empty: an empty array (a model without extraordinary vertices has no
/// corners) binds 256 zero bytes, one element of any of the kernels' types.
pub(crate) fn init_storage(device: &wgpu::Device, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    match bytes {
        [] => init_buffer(device, label, &[0; 256], usage),
        _ => init_buffer(device, label, bytes, usage),
    }
}

/// Runs `make` in error scopes: an allocation the device cannot make is
/// [`Error::OutOfMemory`] naming `what`, not a stage that later runs on invalid buffers.
/// What the invalid resource then fails (views, bind groups: validation errors) is part of
/// that error, not reported apart; a validation error without one is [`Error::Wgpu`].
/// Native devices answer at once; where the answer would come later (a browser's), it is
/// not waited for and `make`'s result stands.
pub(crate) fn allocating<T>(
    device: &wgpu::Device,
    what: &'static str,
    make: impl FnOnce() -> Result<T>,
) -> Result<T> {
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let made = make();
    let (memory, validation) = (answer(memory), answer(validation));
    match (memory, validation) {
        (Some(e), _) => Err(Error::OutOfMemory {
            what,
            detail: e.to_string(),
        }),
        (None, Some(e)) => Err(Error::Wgpu(e.to_string())),
        (None, None) => made,
    }
}

/// The error `scope` caught, where the device has answered (popping it either way).
fn answer(scope: wgpu::ErrorScopeGuard) -> Option<wgpu::Error> {
    use std::future::Future as _;
    let mut answer = std::pin::pin!(scope.pop());
    let mut context = std::task::Context::from_waker(std::task::Waker::noop());
    match answer.as_mut().poll(&mut context) {
        std::task::Poll::Ready(e) => e,
        std::task::Poll::Pending => None,
    }
}

#[cfg(all(test, feature = "headless"))]
mod tests {
    use super::*;

    #[test]
    fn an_allocation_the_device_cannot_make_is_an_error() {
        let gpu = crate::headless::Gpu::new().expect("device");
        // Within every limit, and a terabyte: no device allocates it.
        let side = gpu.device.limits().max_texture_dimension_2d;
        let layers = gpu.device.limits().max_texture_array_layers;
        let made = allocating(&gpu.device, "a terabyte texture", || {
            let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: None,
                size: wgpu::Extent3d {
                    width: side,
                    height: side,
                    depth_or_array_layers: layers,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::STORAGE_BINDING,
                view_formats: &[],
            });
            // A view of the texture that could not be made fails validation too: part of
            // the same error, not one left for the device's handler.
            Ok(texture.create_view(&Default::default()))
        });
        let err = made.map(|_| ()).expect_err("out of memory");
        assert!(
            matches!(
                err,
                Error::OutOfMemory {
                    what: "a terabyte texture",
                    ..
                }
            ),
            "{err}"
        );
        // What fits is made, and the scope is gone: the device reports nothing more.
        let small = allocating(&gpu.device, "a small buffer", || {
            Ok(storage(&gpu.device, "small", 256))
        });
        assert!(small.is_ok());
        gpu.check().expect("no wgpu errors left over");
    }

    #[test]
    fn a_buffer_the_device_cannot_create_is_an_error_not_a_panic() {
        // A device whose buffers hold 256 bytes: a kilobyte of contents cannot be
        // uploaded, where wgpu's `create_buffer_init` would panic.
        let gpu = crate::headless::Gpu::with_limits(|adapter| wgpu::Limits {
            max_buffer_size: 256,
            max_storage_buffer_binding_size: 256,
            ..crate::bezier::required_limits(adapter)
        })
        .expect("device");
        let contents = [7u8; 1024];
        let made = allocating(&gpu.device, "a kilobyte", || {
            Ok(init_buffer(
                &gpu.device,
                "a kilobyte",
                &contents,
                wgpu::BufferUsages::STORAGE,
            ))
        });
        let err = made.map(|_| ()).expect_err("over the device's buffers");
        assert!(matches!(err, Error::Wgpu(_)), "{err}");
        // What fits holds its contents (an odd length, padded).
        let fits = init_buffer(
            &gpu.device,
            "thirteen bytes",
            &contents[..13],
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        assert_eq!(fits.size(), 16);
        let read = gpu.read_buffer(&fits, 0, 16).expect("read");
        assert_eq!(&read[..13], &contents[..13]);
        gpu.check().expect("no wgpu errors left over");
    }
}
