//! Offscreen rendering of [`MeshBuffers`] to an RGBA image, and PNG files written
//! atomically (CLI output, snapshot tests).

use std::io::Write;
use std::path::Path;

use glam::Vec3;
use image::RgbaImage;

use crate::error::{Error, Result};
use crate::headless::Gpu;
use crate::output::MeshBuffers;
use crate::readback::TextureReadback;
use crate::render::{MeshRenderer, RenderOptions};
use tessera_core::View;

/// Colour format of the offscreen target: 8-bit sRGB, what PNG files hold.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Depth format of the offscreen target.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The light background the model is drawn on, sRGB.
pub const BACKGROUND: [u8; 3] = [236, 238, 242];

/// Renders `mesh` framed by [`View::framing`] of `bounds` (usually the model's
/// bounding box) into a `width` × `height` image.
pub fn render_to_rgba(
    gpu: &Gpu,
    mesh: &MeshBuffers,
    bounds: (Vec3, Vec3),
    width: u32,
    height: u32,
    options: &RenderOptions,
) -> Result<RgbaImage> {
    let view = View::framing(bounds.0.as_dvec3(), bounds.1.as_dvec3(), (width, height));
    render_view_to_rgba(gpu, mesh, &view, width, height, options)
}

/// Renders `mesh` seen from `view` (whose viewport is usually `width` × `height`) into a
/// `width` × `height` image: an sRGB colour target
/// (4× multisampled where the format allows it) and a depth buffer, cleared to
/// [`BACKGROUND`], read back without the row padding wgpu's copies need. Fails on any
/// wgpu error the device reported meanwhile.
pub fn render_view_to_rgba(
    gpu: &Gpu,
    mesh: &MeshBuffers,
    view: &View,
    width: u32,
    height: u32,
    options: &RenderOptions,
) -> Result<RgbaImage> {
    let max = gpu.device.limits().max_texture_dimension_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(Error::Render(format!(
            "image size {width}x{height} is outside 1..={max}"
        )));
    }
    // Errors from earlier work are not this render's.
    gpu.check()?;
    let device = &gpu.device;
    let samples = sample_count(&gpu.adapter);
    let size = wgpu::Extent3d {
        width,
        height,
        depth_or_array_layers: 1,
    };
    let texture = |label, format, sample_count, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size,
            mip_level_count: 1,
            sample_count,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let resolved = texture(
        "tessera image",
        COLOR_FORMAT,
        1,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let multisampled = (samples > 1).then(|| {
        texture(
            "tessera image (multisampled)",
            COLOR_FORMAT,
            samples,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        )
    });
    let depth = texture(
        "tessera depth",
        DEPTH_FORMAT,
        samples,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let resolved_view = resolved.create_view(&Default::default());
    let multisampled_view = multisampled
        .as_ref()
        .map(|t| t.create_view(&Default::default()));
    let depth_view = depth.create_view(&Default::default());
    let (target_view, resolve_target) = match &multisampled_view {
        Some(ms) => (ms, Some(&resolved_view)),
        None => (&resolved_view, None),
    };

    let renderer = MeshRenderer::new(device, COLOR_FORMAT, Some(DEPTH_FORMAT), samples);
    renderer.prepare(&gpu.queue, view, options);

    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("tessera image"),
    });
    {
        let mut pass = begin_scene_pass(&mut encoder, target_view, resolve_target, &depth_view);
        renderer.draw(&mut pass, mesh);
    }
    let readback = TextureReadback::record(device, &mut encoder, &resolved);
    gpu.queue.submit([encoder.finish()]);
    let pixels = readback.read(device)?;
    gpu.check()?;
    RgbaImage::from_raw(width, height, pixels)
        .ok_or_else(|| Error::Readback("image buffer has the wrong size".into()))
}

/// The render pass these images are drawn in: `color` cleared to [`BACKGROUND`] (resolved
/// into `resolve_target` when it is multisampled), `depth` cleared to 1 and discarded.
/// A window that draws its frames as these images are drawn begins the same pass.
pub fn begin_scene_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    color: &wgpu::TextureView,
    resolve_target: Option<&wgpu::TextureView>,
    depth: &wgpu::TextureView,
) -> wgpu::RenderPass<'e> {
    let [r, g, b] = BACKGROUND.map(|c| srgb_to_linear(c) as f64);
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("tessera scene"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: color,
            depth_slice: None,
            resolve_target,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a: 1.0 }),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Discard,
            }),
            stencil_ops: None,
        }),
        ..Default::default()
    })
}

/// Parses an image size `WIDTHxHEIGHT` (each in `1..=16384`), as the command lines take it.
pub fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size {s:?} is not WIDTHxHEIGHT"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| (1..=16384).contains(&n))
            .ok_or_else(|| format!("size {s:?}: {v:?} is not a number in 1..=16384"))
    };
    Ok((parse(w)?, parse(h)?))
}

/// The samples per pixel of [`render_view_to_rgba`] on `adapter`: 4 where
/// [`COLOR_FORMAT`] and [`DEPTH_FORMAT`] both allow it, else 1. A window that draws its
/// frames as these images are drawn (the demo's) takes the same.
pub fn sample_count(adapter: &wgpu::Adapter) -> u32 {
    let color = adapter.get_texture_format_features(COLOR_FORMAT).flags;
    let depth = adapter.get_texture_format_features(DEPTH_FORMAT).flags;
    [4, 1]
        .into_iter()
        .find(|&n| color.sample_count_supported(n) && depth.sample_count_supported(n))
        .unwrap_or(1)
}

/// The pixels of an 8-bit RGBA texture (`Rgba8Unorm` or `Rgba8UnormSrgb`, one sample,
/// `COPY_SRC` usage), copied on their own submission after the work already submitted:
/// a window's last frame, saved as these images are.
pub fn read_rgba(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<RgbaImage> {
    let format = texture.format();
    if format.remove_srgb_suffix() != wgpu::TextureFormat::Rgba8Unorm || texture.sample_count() != 1
    {
        return Err(Error::Render(format!(
            "read_rgba reads single-sampled 8-bit RGBA textures, not {format:?} with {} samples",
            texture.sample_count()
        )));
    }
    let pixels = crate::readback::read_texture(device, queue, texture)?;
    RgbaImage::from_raw(texture.width(), texture.height(), pixels)
        .ok_or_else(|| Error::Readback("image buffer has the wrong size".into()))
}

/// The linear value of an 8-bit sRGB channel.
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Writes `img` as a PNG file at `path`, atomically: the image goes to a temporary file
/// in the same folder, which is renamed over `path` only once complete, so `path` never
/// holds half an image (and an existing file is left alone on error).
pub fn save_png(img: &RgbaImage, path: &Path) -> Result<()> {
    let err = |msg: String| Error::Image {
        path: path.display().to_string(),
        msg,
    };
    let name = path
        .file_name()
        .ok_or_else(|| err("not a file path".into()))?
        .to_string_lossy();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let write = || -> std::result::Result<(), String> {
        let file = std::fs::File::create(&tmp).map_err(|e| e.to_string())?;
        let mut out = std::io::BufWriter::new(file);
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut out),
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| e.to_string())?;
        out.flush().map_err(|e| e.to_string())?;
        out.into_inner()
            .map_err(|e| e.to_string())?
            .sync_all()
            .map_err(|e| e.to_string())?;
        std::fs::rename(&tmp, path).map_err(|e| e.to_string())
    };
    write().map_err(|msg| {
        let _ = std::fs::remove_file(&tmp);
        err(msg)
    })
}

/// Reads a PNG (or any format the `image` build supports) as RGBA.
pub fn load_png(path: &Path) -> Result<RgbaImage> {
    image::open(path)
        .map(|i| i.to_rgba8())
        .map_err(|e| Error::Image {
            path: path.display().to_string(),
            msg: e.to_string(),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> std::path::PathBuf {
        let d =
            std::env::temp_dir().join(format!("tessera-image-out-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn png_round_trips_and_leaves_no_temporary() {
        let dir = temp_dir("roundtrip");
        let img = RgbaImage::from_fn(7, 5, |x, y| {
            image::Rgba([x as u8 * 30, y as u8 * 50, 9, 255])
        });
        let path = dir.join("a.png");
        save_png(&img, &path).unwrap();
        assert_eq!(load_png(&path).unwrap(), img);
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.png")]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failed_save_leaves_nothing_behind() {
        let dir = temp_dir("fail");
        let img = RgbaImage::from_fn(2, 2, |_, _| image::Rgba([0, 0, 0, 255]));
        // A folder that does not exist.
        let e = save_png(&img, &dir.join("missing/c.png")).unwrap_err();
        assert!(matches!(e, Error::Image { .. }), "{e}");
        // The rename fails (a folder is in the way): the temporary file is removed.
        std::fs::create_dir(dir.join("d.png")).unwrap();
        assert!(save_png(&img, &dir.join("d.png")).is_err());
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("d.png")]);
        assert!(dir.join("d.png").is_dir());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn srgb_decoding_matches_known_values() {
        assert_eq!(srgb_to_linear(0), 0.0);
        assert_eq!(srgb_to_linear(255), 1.0);
        assert!((srgb_to_linear(188) - 0.5029).abs() < 1e-3);
    }
}
