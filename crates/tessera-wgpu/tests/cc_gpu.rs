//! The Catmull-Clark kernels against their CPU twins, and the twins against the
//! double-precision reference. Any wgpu validation error fails.

use tessera_core::catmull_clark::gpu_model::{fixed_param, vertex_eval, CcGpuModel};
use tessera_core::catmull_clark::{load_surface, SurfaceModel};
use tessera_core::gpu_types::{CcPoint, OutVertex};
use tessera_wgpu::catmull_clark::{CcModelBuffers, CcVertexEval};
use tessera_wgpu::headless::Gpu;
use wgpu::util::DeviceExt;

fn gpu() -> Gpu {
    Gpu::new().expect("a wgpu adapter (CI installs Mesa's lavapipe; see `cargo xtask test`)")
}

fn model(name: &str) -> SurfaceModel {
    let path = format!("{}/../../assets/{name}", env!("CARGO_MANIFEST_DIR"));
    load_surface(std::path::Path::new(&path)).expect("model loads")
}

/// Grid points of every surface patch, plus the adaptive grid's points nearest each
/// corner (where the pieces around extraordinary vertices are smallest).
fn points(model: &SurfaceModel) -> Vec<CcPoint> {
    let fine = 840.0 * 1024.0;
    let mut params: Vec<f64> = (0..=6).map(|k| k as f64 / 6.0).collect();
    params.extend([1.0 / fine, 3.0 / fine, 1.0 - 1.0 / fine, 0.5 + 1.0 / fine]);
    let mut out = Vec::new();
    for p in model.mesh.surface_patches() {
        for &v in &params {
            for &u in &params {
                out.push(CcPoint {
                    patch_id: p as u32,
                    u: fixed_param(u),
                    v: fixed_param(v),
                });
            }
        }
    }
    out
}

fn run_gpu(gpu: &Gpu, model: &CcGpuModel, points: &[CcPoint]) -> Vec<OutVertex> {
    let device = &gpu.device;
    let buffers = CcModelBuffers::new(device, model);
    let eval = CcVertexEval::new(device);
    let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let point_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(points),
        usage: storage,
    });
    let counts = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(&[points.len() as u32]),
        usage: storage,
    });
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (points.len() * std::mem::size_of::<OutVertex>()) as u64,
        usage: storage,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    let n = points.len() as u32;
    eval.record(device, &mut encoder, &buffers, &point_buf, &counts, &out, n);
    gpu.queue.submit([encoder.finish()]);
    let result = gpu
        .read_pod::<OutVertex>(&out, points.len())
        .expect("readback");
    gpu.check().expect("no wgpu errors");
    result
}

#[test]
fn gpu_evaluation_matches_its_twin_and_the_exact_surface() {
    let gpu = gpu();
    for name in [
        "catmull_clark/spot_control_mesh.obj",
        "opensubdiv/catmark_cube.obj",
        "opensubdiv/catmark_edgecorner.obj",
        "opensubdiv/catmark_pole64.obj",
        "opensubdiv/catmark_nonquads.obj",
        "opensubdiv/catmark_hole_test1.obj",
    ] {
        let model = model(name);
        let flat = CcGpuModel::new(&model);
        assert_eq!(flat.byte_size(), model.upload_bytes(), "{name}");
        let points = points(&model);
        let twin = vertex_eval(&flat, &points);
        let on_gpu = run_gpu(&gpu, &flat, &points);
        let size = model
            .mesh
            .points
            .iter()
            .fold(0f64, |m, p| m.max(p.abs().max_element()));
        let (mut worst_gpu, mut worst_exact) = (0f64, 0f64);
        for ((point, t), g) in points.iter().zip(&twin).zip(&on_gpu) {
            let d = |a: [f32; 3], b: [f32; 3]| {
                (0..3)
                    .map(|k| (a[k] as f64 - b[k] as f64).abs())
                    .fold(0.0, f64::max)
            };
            worst_gpu = worst_gpu.max(d(t.position, g.position) / size);
            assert_eq!((t.uv, t.patch), (g.uv, g.patch), "{name}");
            let dot: f32 = (0..3).map(|k| t.normal[k] * g.normal[k]).sum();
            assert!(dot > 0.9999, "{name} {point:?}: normals {t:?} {g:?}");
            let one = tessera_core::gpu_types::CC_PARAM_ONE as f64;
            let exact = model.eval(
                point.patch_id as usize,
                point.u as f64 / one,
                point.v as f64 / one,
            );
            let e = exact.position.as_vec3().to_array();
            worst_exact = worst_exact.max(d(t.position, e) / size);
            let dot = exact.normal.as_vec3().dot(glam::Vec3::from(t.normal));
            assert!(
                dot > 0.9999,
                "{name} {point:?}: normal {:?} against {:?}",
                t.normal,
                exact.normal
            );
        }
        assert!(
            worst_gpu < 1e-6,
            "{name}: GPU against its twin {worst_gpu:e} of the size"
        );
        assert!(
            worst_exact < 1e-5,
            "{name}: twin against f64 {worst_exact:e} of the size"
        );
        eprintln!(
            "{name}: {} points, GPU/twin {worst_gpu:.1e}, twin/exact {worst_exact:.1e}",
            points.len()
        );
    }
}

#[test]
fn moved_control_points_reupload_in_place_and_a_new_shape_is_refused() {
    let gpu = gpu();
    let mut a = model("opensubdiv/catmark_cube.obj");
    let flat = CcGpuModel::new(&a);
    let buffers = CcModelBuffers::new(&gpu.device, &flat);
    // Scaling the control points moves every piece but keeps the trees' shape.
    for p in &mut a.mesh.points {
        *p *= 2.0;
    }
    let moved = CcGpuModel::new(&SurfaceModel::new(a.mesh.clone(), a.depth));
    assert_ne!(moved, flat);
    buffers.update(&gpu.queue, &moved).expect("same shape");
    let other = CcGpuModel::new(&model("opensubdiv/catmark_pyramid.obj"));
    assert!(buffers.update(&gpu.queue, &other).is_err());
    gpu.check().expect("no wgpu errors");
}
