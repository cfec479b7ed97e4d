//! Snapshot tests of the renderer: the teapot, tessellated on the CPU and drawn through
//! wgpu (lavapipe in CI), shaded and with its wireframe, against reference PNGs.
//!
//! The references live in `tests/snapshots/`. After an intended change to the rendering,
//! rewrite them with
//!
//! ```text
//! TESSERA_BLESS=1 cargo test -p tessera-wgpu --test render_snapshot
//! ```
//!
//! then look at the PNGs and commit them. Without the variable a missing reference is a
//! failure. A failed comparison writes `<name>.actual.png` and `<name>.diff.png` into
//! `target/snapshots/`.
//!
//! There is no skipping: without any adapter (install Mesa's lavapipe,
//! `mesa-vulkan-drivers`) every test fails and says so.

use std::path::{Path, PathBuf};

use image::{Rgba, RgbaImage};
use tessera_core::bezier::{
    tessellate_adaptive, AdaptiveParams, BezierModel, EdgeTest, PreparedBezier,
};
use tessera_wgpu::glam::Vec3;
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::image_out::{load_png, render_to_rgba, render_view_to_rgba, BACKGROUND};
use tessera_wgpu::snapshot::{
    self, check_images, check_snapshot, delta_e, failure_paths, Tolerance,
};
use tessera_wgpu::{wgpu, Error, MeshBuffers, MeshRenderer, RenderOptions, View};

const WIDTH: u32 = 160;
const HEIGHT: u32 = 120;

fn gpu() -> Gpu {
    let gpu = Gpu::new().unwrap_or_else(|e| {
        panic!(
            "no wgpu adapter, so the renderer cannot be tested: {e}. \
             Install a Vulkan driver (Mesa's lavapipe: apt-get install mesa-vulkan-drivers)."
        )
    });
    eprintln!("adapter: {}", gpu.adapter_name());
    gpu
}

/// `model` from the shipped teaset and the parameters every snapshot uses: map4p,
/// threshold 1% of the bounding-box diagonal.
fn snapshot_model(model: &str) -> (BezierModel, AdaptiveParams) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/teaset")
        .join(model);
    let model = BezierModel::load(&path).expect("shipped model loads");
    let (min, max) = model.bounds();
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: 0.01 * (max - min).length(),
        max_depth: AdaptiveParams::DEFAULT_MAX_DEPTH,
    };
    (model, params)
}

/// `model` from the shipped teaset, tessellated on the CPU (map4p, threshold 1% of the
/// bounding-box diagonal: coarse enough that the wireframe reads at this size) and
/// uploaded, with the mesh's bounds.
fn upload(gpu: &Gpu, model: &str) -> (MeshBuffers, (Vec3, Vec3)) {
    let (model, params) = snapshot_model(model);
    let mesh = tessellate_adaptive(&PreparedBezier::new(&model), &params)
        .expect("tessellation succeeds")
        .mesh;
    assert!(
        mesh.triangle_count() > 100,
        "{} triangles",
        mesh.triangle_count()
    );
    (MeshBuffers::from_mesh(&gpu.device, &mesh), mesh.bounds())
}

/// `model` framed by [`View::framing`] (Z up, as the teapot is).
fn render(gpu: &Gpu, model: &str, options: &RenderOptions) -> RgbaImage {
    let (mesh, bounds) = upload(gpu, model);
    render_to_rgba(gpu, &mesh, bounds, WIDTH, HEIGHT, options)
        .unwrap_or_else(|e| panic!("rendering {model} failed: {e}"))
}

/// The teacup, which is Y up in the teaset data, upright in the same 3/4 view.
fn render_teacup(gpu: &Gpu) -> RgbaImage {
    let (mesh, (min, max)) = upload(gpu, "teacup");
    let d = View::FRAMING_DIRECTION;
    let view = View::framing_along(
        min.as_dvec3(),
        max.as_dvec3(),
        (WIDTH, HEIGHT),
        tessera_wgpu::glam::DVec3::new(d.x, d.z, -d.y),
        tessera_wgpu::glam::DVec3::Y,
    );
    render_view_to_rgba(gpu, &mesh, &view, WIDTH, HEIGHT, &shaded())
        .unwrap_or_else(|e| panic!("rendering the teacup failed: {e}"))
}

fn shaded() -> RenderOptions {
    RenderOptions::default()
}

fn wireframe() -> RenderOptions {
    RenderOptions {
        wireframe: true,
        ..RenderOptions::default()
    }
}

fn reference(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/snapshots")
        .join(format!("{name}.png"))
}

/// `target/snapshots/`.
fn out_dir() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .expect("target/tmp has a parent")
        .join("snapshots")
}

/// Fraction of pixels clearly not the background.
fn coverage(img: &RgbaImage) -> f64 {
    let [r, g, b] = BACKGROUND;
    let bg = Rgba([r, g, b, 255]);
    img.pixels().filter(|p| delta_e(**p, bg) > 10.0).count() as f64 / img.pixels().len() as f64
}

/// The model is in the picture, large, and not cut off. On failure the render is written
/// to `target/snapshots/<name>.actual.png`.
fn assert_framed(name: &str, img: &RgbaImage) {
    let (actual, _) = failure_paths(name, &out_dir());
    let fail = |msg: String| -> ! {
        let _ = std::fs::create_dir_all(out_dir());
        let _ = tessera_wgpu::image_out::save_png(img, &actual);
        panic!("{name}: {msg} (render written to {})", actual.display())
    };
    let c = coverage(img);
    if !(0.1..0.8).contains(&c) {
        fail(format!("the model covers {:.1}% of the image", 100.0 * c));
    }
    // Every border row and column is background: nothing is cut off.
    let (w, h) = img.dimensions();
    let border = (0..w)
        .flat_map(|x| [(x, 0), (x, h - 1)])
        .chain((0..h).flat_map(|y| [(0, y), (w - 1, y)]));
    let [r, g, b] = BACKGROUND;
    for (x, y) in border {
        let p = *img.get_pixel(x, y);
        if delta_e(p, Rgba([r, g, b, 255])) >= 2.0 {
            fail(format!("the model touches the border at ({x}, {y})"));
        }
    }
}

fn assert_snapshot(name: &str, img: &RgbaImage) {
    let bless = snapshot::bless_requested();
    match check_snapshot(
        name,
        img,
        &reference(name),
        &out_dir(),
        &Tolerance::DEFAULT,
        bless,
    ) {
        Ok(c) if bless => eprintln!(
            "{name}: reference written (against the old one: {})",
            c.summary()
        ),
        Ok(c) => eprintln!("{name}: {}", c.summary()),
        Err(e) => panic!("{e}"),
    }
}

#[test]
fn teapot_shaded_matches_snapshot() {
    let gpu = gpu();
    let img = render(&gpu, "teapot", &shaded());
    assert_framed("teapot_shaded", &img);
    assert_snapshot("teapot_shaded", &img);
}

#[test]
fn teapot_wireframe_matches_snapshot() {
    let gpu = gpu();
    let renderer = MeshRenderer::new(
        &gpu.device,
        tessera_wgpu::image_out::COLOR_FORMAT,
        Some(tessera_wgpu::image_out::DEPTH_FORMAT),
        1,
    );
    assert!(
        renderer.wireframe_available(),
        "{} lacks POLYGON_MODE_LINE, which the wireframe needs (lavapipe has it)",
        gpu.adapter_name()
    );
    let img = render(&gpu, "teapot", &wireframe());
    assert_framed("teapot_wireframe", &img);
    // The lines are there: a good share of the model's pixels change.
    let plain = render(&gpu, "teapot", &shaded());
    let lined = img
        .pixels()
        .zip(plain.pixels())
        .filter(|(a, b)| delta_e(**a, **b) > 10.0)
        .count() as f64
        / img.pixels().len() as f64;
    assert!(
        lined > 0.05,
        "the wireframe changes only {:.2}% of the pixels",
        100.0 * lined
    );
    gpu.check().expect("no wgpu errors");
    assert_snapshot("teapot_wireframe", &img);
}

/// Without `POLYGON_MODE_LINE` the wireframe is reported unavailable and the mesh is
/// drawn shaded only, without wgpu errors.
#[test]
fn wireframe_without_line_mode_renders_shaded_only() {
    let gpu = Gpu::with_optional_features(wgpu::Features::empty())
        .unwrap_or_else(|e| panic!("no wgpu adapter: {e}"));
    assert!(!gpu
        .device
        .features()
        .contains(wgpu::Features::POLYGON_MODE_LINE));
    let renderer = MeshRenderer::new(
        &gpu.device,
        tessera_wgpu::image_out::COLOR_FORMAT,
        Some(tessera_wgpu::image_out::DEPTH_FORMAT),
        1,
    );
    assert!(!renderer.wireframe_available());
    let with = render(&gpu, "teapot", &wireframe());
    let without = render(&gpu, "teapot", &shaded());
    gpu.check().expect("no wgpu errors");
    assert_eq!(with, without);
}

/// A wgpu validation error (here: a vertex buffer without `VERTEX` usage) fails the
/// render instead of giving a picture.
#[test]
fn validation_errors_fail_the_render() {
    let gpu = gpu();
    let (good, bounds) = upload(&gpu, "teapot");
    let not_vertices = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("not a vertex buffer"),
        size: good.vertices().size(),
        usage: wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mesh = tessera_wgpu::MeshBuffers::from_buffers(
        not_vertices,
        good.indices().clone(),
        good.indirect().clone(),
    );
    match render_to_rgba(&gpu, &mesh, bounds, WIDTH, HEIGHT, &shaded()) {
        Err(Error::Wgpu(msg)) => eprintln!("as expected: {msg}"),
        other => panic!(
            "expected a wgpu error, got {:?}",
            other.map(|i| i.dimensions())
        ),
    }
    // The errors were reported once; the device still renders.
    render(&gpu, "teapot", &shaded());
}

/// Tests the tester: another model must not pass as the teapot.
#[test]
fn teacup_fails_against_teapot_snapshot() {
    let gpu = gpu();
    // While blessing, the teapot reference may be being rewritten: render it afresh.
    let teapot = if snapshot::bless_requested() {
        render(&gpu, "teapot", &shaded())
    } else {
        load_png(&reference("teapot_shaded"))
            .unwrap_or_else(|e| panic!("{e} (create the references with TESSERA_BLESS=1)"))
    };
    let teacup = render_teacup(&gpu);
    assert_framed("teacup_shaded", &teacup);
    let dir = out_dir().join("expected-failures");
    let (actual, diff) = failure_paths("teacup_vs_teapot", &dir);
    let _ = std::fs::remove_file(&actual);
    let _ = std::fs::remove_file(&diff);
    match check_images(
        "teacup_vs_teapot",
        &teapot,
        &teacup,
        &dir,
        &Tolerance::DEFAULT,
    ) {
        Err(Error::Snapshot { msg, .. }) => eprintln!("as expected: {msg}"),
        other => panic!("the teacup passed as the teapot: {other:?}"),
    }
    assert_eq!(load_png(&actual).expect("actual written"), teacup);
    assert_eq!(
        load_png(&diff).expect("diff written").dimensions(),
        teacup.dimensions()
    );
}

/// The same teapot tessellated by the GPU stage and drawn straight from its buffers (the
/// index count comes from the draw arguments the kernels wrote; nothing is read back)
/// matches the snapshot made from the CPU reference's mesh.
#[test]
fn teapot_tessellated_on_the_gpu_matches_the_wireframe_snapshot() {
    let gpu = gpu();
    let (model, params) = snapshot_model("teapot");
    let prepared = PreparedBezier::new(&model);
    let mut stage = tessera_wgpu::bezier::BezierStage::new(
        &gpu.device,
        &gpu.queue,
        &tessera_wgpu::Kernels::new(&gpu.device),
        &prepared,
        &params,
    )
    .expect("stage");
    stage
        .run_blocking(&gpu.device, &gpu.queue)
        .expect("stage runs");
    // Framing only: the snapshot was framed on the mesh's bounds.
    let bounds = tessellate_adaptive(&prepared, &params)
        .expect("cpu")
        .mesh
        .bounds();
    let img =
        render_to_rgba(&gpu, stage.output(), bounds, WIDTH, HEIGHT, &wireframe()).expect("render");
    gpu.check().expect("no wgpu errors");
    assert_snapshot("teapot_wireframe", &img);
}

#[test]
fn a_frame_drawn_into_the_callers_target_reads_back_as_the_image() {
    // A window draws into its own target, with the samples, formats and background of
    // `render_view_to_rgba`, and saves it through `read_rgba`: the same pixels.
    let gpu = gpu();
    let (mesh, (min, max)) = upload(&gpu, "teapot");
    let view = View::framing(min.as_dvec3(), max.as_dvec3(), (WIDTH, HEIGHT));
    let want =
        render_view_to_rgba(&gpu, &mesh, &view, WIDTH, HEIGHT, &wireframe()).expect("render");

    let samples = tessera_wgpu::image_out::sample_count(&gpu.adapter);
    assert!(samples == 4 || samples == 1, "{samples}");
    let size = wgpu::Extent3d {
        width: WIDTH,
        height: HEIGHT,
        depth_or_array_layers: 1,
    };
    let target = |format, sample_count, usage| {
        gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size,
            mip_level_count: 1,
            sample_count,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | usage,
            view_formats: &[],
        })
    };
    use tessera_wgpu::image_out::{COLOR_FORMAT, DEPTH_FORMAT};
    let frame = target(COLOR_FORMAT, 1, wgpu::TextureUsages::COPY_SRC);
    let ms = target(COLOR_FORMAT, samples, wgpu::TextureUsages::empty());
    let depth = target(DEPTH_FORMAT, samples, wgpu::TextureUsages::empty());
    let (frame_view, ms_view, depth_view) = (
        frame.create_view(&Default::default()),
        ms.create_view(&Default::default()),
        depth.create_view(&Default::default()),
    );
    let renderer = MeshRenderer::new(&gpu.device, COLOR_FORMAT, Some(DEPTH_FORMAT), samples);
    renderer.prepare(&gpu.queue, &view, &wireframe());
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let (view, resolve_target) = if samples > 1 {
            (&ms_view, Some(&frame_view))
        } else {
            (&frame_view, None)
        };
        let mut pass = tessera_wgpu::image_out::begin_scene_pass(
            &mut encoder,
            view,
            resolve_target,
            &depth_view,
        );
        renderer.draw(&mut pass, &mesh);
    }
    gpu.queue.submit([encoder.finish()]);
    let got = tessera_wgpu::image_out::read_rgba(&gpu.device, &gpu.queue, &frame).expect("read");
    assert!(got == want, "the caller's frame differs from the image");

    // Only what it can hand over as RGBA pixels.
    let bgra = target(
        wgpu::TextureFormat::Bgra8Unorm,
        1,
        wgpu::TextureUsages::COPY_SRC,
    );
    let e = tessera_wgpu::image_out::read_rgba(&gpu.device, &gpu.queue, &bgra).unwrap_err();
    assert!(matches!(e, Error::Render(_)), "{e}");
    gpu.check().expect("no wgpu validation errors");
}
