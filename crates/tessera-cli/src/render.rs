//! `tessera render`: tessellate on the GPU and draw the result headless into a PNG.

use std::time::Instant;

use tessera_core::bezier::{AdaptiveParams, EdgeTest, PreparedBezier};
use tessera_core::Error as CoreError;
use tessera_wgpu::glam::Vec3;
use tessera_wgpu::image_out::{render_camera_to_rgba, save_png};
use tessera_wgpu::render::Camera;
use tessera_wgpu::{Error, RenderOptions};

use crate::cli::{Axis, Method, RenderArgs};
use crate::gpu::GpuTimings;

pub fn render(args: RenderArgs) -> Result<(), Error> {
    let t_total = Instant::now();
    let test = match args.method {
        Method::Map2p => EdgeTest::Map2p,
        Method::Map4p => EdgeTest::Map4p,
        Method::Map8p => EdgeTest::Map8p,
        Method::Flat => EdgeTest::Flat,
        Method::Uniform | Method::Adaptive => {
            return Err(CoreError::Param(
                "tessera render takes the GPU methods map2p, map4p, map8p or flat".into(),
            )
            .into())
        }
    };
    if args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        != Some("png".into())
    {
        return Err(CoreError::Param(format!(
            "{}: the render output must be a .png file",
            args.output.display()
        ))
        .into());
    }
    let model = crate::tessellate::load(&args.input)?;
    let prep = PreparedBezier::new(&model);
    let (lo, hi) = model.bounds();
    let params = AdaptiveParams {
        test,
        threshold: args.threshold.unwrap_or(0.002 * (hi - lo).length()),
        max_depth: args.max_depth,
    };
    params.validate()?;
    let mut timings = GpuTimings::default();
    let gpu = crate::gpu::open(&mut timings)?;
    let (stage, status) = crate::gpu::run(&gpu, &prep, &params, &mut timings)?;
    let options = RenderOptions {
        wireframe: args.wireframe,
        patch_tint: args.patch_tint,
        ..RenderOptions::default()
    };
    let t = Instant::now();
    let (w, h) = args.size;
    let aspect = w as f32 / h as f32;
    // The default view (front-right, above) expressed for the chosen up axis.
    let d = Camera::FRAMING_DIRECTION;
    let (direction, up) = match args.up {
        Axis::Z => (d, Vec3::Z),
        Axis::Y => (Vec3::new(d.x, d.z, -d.y), Vec3::Y),
        Axis::X => (Vec3::new(d.z, d.x, d.y), Vec3::X),
    };
    let camera = Camera::framing_along(lo, hi, aspect, direction, up);
    let image = render_camera_to_rgba(&gpu, stage.output(), &camera, w, h, &options)?;
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    save_png(&image, &args.output)?;
    println!(
        "{}: {} {} triangles, {} vertices on {}; tessellate {:.2} ms, render {:.1} ms, total {:.0} ms -> {}",
        args.input.display(),
        test.name(),
        status.indices / 3,
        status.vertices,
        gpu.adapter_name(),
        timings.tessellate,
        render_ms,
        t_total.elapsed().as_secs_f64() * 1e3,
        args.output.display()
    );
    Ok(())
}
