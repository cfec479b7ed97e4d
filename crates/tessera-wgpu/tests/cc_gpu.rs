//! The Catmull-Clark kernels against their CPU twins, and the twins against the
//! double-precision reference. Any wgpu validation error fails.

use glam::Vec3;
use tessera_core::catmull_clark::gpu_model::{fixed_param, vertex_eval, CcGpuModel};
use tessera_core::catmull_clark::stencil::CcStencils;
use tessera_core::catmull_clark::vertex_hash::{number_keys, split_key};
use tessera_core::catmull_clark::{tessellate_uniform, SurfaceModel};
use tessera_core::gpu_types::{CcCorner, CcHashStatus, CcVertexPoint, GpuPatch, OutVertex};
use tessera_wgpu::catmull_clark::{
    CcHashKernels, CcModelBuffers, CcStencilBuffers, CcVertexEval, CcVertexHash,
};
use tessera_wgpu::headless::Gpu;
use wgpu::util::DeviceExt;

fn gpu() -> Gpu {
    Gpu::new().expect("a wgpu adapter (CI installs Mesa's lavapipe; see `cargo xtask test`)")
}

/// The smooth surface of a shipped mesh (its creases and corners dropped).
fn model(name: &str) -> SurfaceModel {
    tessera_tests::smooth_cc_model(name)
}

/// Grid points of every surface patch, plus the adaptive grid's points nearest each
/// corner (where the pieces around extraordinary vertices are smallest), each with its
/// face coordinates (which the kernel passes through).
fn points(model: &SurfaceModel) -> Vec<CcVertexPoint> {
    let fine = 840.0 * 1024.0;
    let mut params: Vec<f64> = (0..=6).map(|k| k as f64 / 6.0).collect();
    params.extend([1.0 / fine, 3.0 / fine, 1.0 - 1.0 / fine, 0.5 + 1.0 / fine]);
    let mut out = Vec::new();
    for p in model.mesh.surface_patches() {
        for &v in &params {
            for &u in &params {
                let (face, fu, fv) = model.mesh.face_point_at(p, u, v);
                out.push(CcVertexPoint {
                    patch_id: p as u32,
                    u: fixed_param(u),
                    v: fixed_param(v),
                    face,
                    face_u: fu as f32,
                    face_v: fv as f32,
                });
            }
        }
    }
    out
}

fn run_gpu(gpu: &Gpu, model: &CcGpuModel, points: &[CcVertexPoint]) -> Vec<OutVertex> {
    let device = &gpu.device;
    let buffers = CcModelBuffers::new(device, &gpu.queue, model).expect("upload fits");
    let eval = CcVertexEval::new(device, buffers.pages);
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
            assert_eq!((t.uv, t.face), (g.uv, g.face), "{name}");
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

/// A device whose textures cannot hold the nets refuses the model with an error that
/// says so, before wgpu sees an oversized texture.
#[test]
fn nets_past_the_pages_capacity_are_an_error() {
    // A device of 24-texel sides: pages of 2 nets per row and 24 rows, 192 nets in all.
    let gpu = Gpu::with_limits(|adapter| wgpu::Limits {
        max_texture_dimension_2d: 24,
        ..tessera_wgpu::bezier::required_limits(adapter)
    })
    .expect("device");
    let flat = CcGpuModel::new(&model("opensubdiv/catmark_cube.obj"));
    assert_eq!(flat.nets.len(), 2160);
    let err = CcModelBuffers::new(&gpu.device, &gpu.queue, &flat)
        .err()
        .expect("the nets do not fit");
    assert!(
        matches!(
            err,
            tessera_wgpu::Error::TooManyNets {
                nets: 2160,
                capacity: 192,
            }
        ),
        "{err}"
    );
    let mut small = flat.clone();
    small.nets.truncate(193);
    assert!(CcModelBuffers::new(&gpu.device, &gpu.queue, &small).is_err());
    small.nets.truncate(192);
    let buffers = CcModelBuffers::new(&gpu.device, &gpu.queue, &small).expect("192 nets fit");
    assert_eq!(buffers.pages, tessera_wgpu::catmull_clark::NetPages::Four);
    // Every page is full, and reads back the nets uploaded into it.
    assert!(buffers.nets.iter().all(|page| page.size().height == 24));
    let (nets, _) = read_model(&gpu, &buffers, small.nets.len(), 0);
    for (k, (a, b)) in nets.iter().zip(&small.nets).enumerate() {
        assert_eq!(a.cp, b.cp, "net {k}: the pages hold the nets uploaded");
    }
    gpu.check().expect("no wgpu validation errors");
}

#[test]
fn moved_control_points_reupload_in_place_and_a_new_shape_is_refused() {
    let gpu = gpu();
    let a = model("opensubdiv/catmark_cube.obj");
    let flat = CcGpuModel::new(&a);
    let buffers = CcModelBuffers::new(&gpu.device, &gpu.queue, &flat).expect("upload fits");
    // Scaling the control points moves every piece but keeps the trees' shape.
    let scaled: Vec<_> = a.mesh.control_points.iter().map(|p| *p * 2.0).collect();
    let moved = CcGpuModel::new(&a.with_control_points(&scaled).expect("same count"));
    assert_ne!(moved, flat);
    buffers.update(&gpu.queue, &moved).expect("same shape");
    let other = CcGpuModel::new(&model("opensubdiv/catmark_pyramid.obj"));
    assert!(buffers.update(&gpu.queue, &other).is_err());
    gpu.check().expect("no wgpu errors");
}

/// Keys of every grid point of every patch in its chart, patch after patch: each point
/// on a patch edge or corner comes several times (once per patch around it).
fn grid_keys(model: &SurfaceModel, n: u32) -> Vec<[u32; 2]> {
    use tessera_core::catmull_clark::keys::chart_key;
    let mut keys = Vec::new();
    for p in model.mesh.surface_patches() {
        for j in 0..=n {
            for i in 0..=n {
                keys.push(split_key(chart_key(&model.mesh, p, i, j, n)));
            }
        }
    }
    keys
}

/// Runs the hash on the GPU, growing and retrying on overflow; returns the ids, the
/// distinct keys and how many times it grew.
fn hash_on_gpu(gpu: &Gpu, keys: &[[u32; 2]], capacity: u32) -> (Vec<u32>, Vec<[u32; 2]>, u32) {
    let device = &gpu.device;
    let kernels = CcHashKernels::new(device);
    let key_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(keys),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let mut hash = CcVertexHash::new(device, &kernels, keys.len() as u32, capacity);
    let mut grew = 0;
    loop {
        hash.start(&gpu.queue, keys.len() as u32);
        let mut encoder = device.create_command_encoder(&Default::default());
        hash.record(device, &mut encoder, &kernels, &key_buf);
        gpu.queue.submit([encoder.finish()]);
        let status = gpu
            .read_pod::<CcHashStatus>(&hash.status, 1)
            .expect("status")[0];
        gpu.check().expect("no wgpu errors");
        if status.overflow == 0 {
            let ids = gpu.read_pod::<u32>(&hash.ids, keys.len()).expect("ids");
            let unique = gpu
                .read_pod::<[u32; 2]>(&hash.unique_keys, status.unique as usize)
                .expect("keys");
            return (ids, unique, grew);
        }
        hash.grow(device).expect("grows");
        grew += 1;
    }
}

#[test]
fn the_vertex_hash_numbers_like_its_twin_and_the_cpu_reference() {
    let gpu = gpu();
    for (name, n) in [
        ("opensubdiv/catmark_cube.obj", 5),
        ("catmull_clark/spot_control_mesh.obj", 3),
    ] {
        let model = model(name);
        let keys = grid_keys(&model, n);
        // The reference: the uniform tessellation numbers its vertices by the same keys.
        let vertices = tessellate_uniform(&model, n)
            .expect("uniform")
            .mesh
            .vertices
            .len();
        let (twin_ids, twin_keys) = number_keys(&keys, 2 * keys.len() as u32).expect("fits");
        assert_eq!(twin_keys.len(), vertices, "{name}: distinct points");
        let (ids, unique, grew) = hash_on_gpu(&gpu, &keys, 2 * keys.len() as u32);
        assert_eq!(grew, 0);
        assert_eq!(ids, twin_ids, "{name}: vertex numbers");
        assert_eq!(unique, twin_keys, "{name}: distinct keys in order");
        // Every item's number names its own key.
        for (k, id) in keys.iter().zip(&ids) {
            assert_eq!(unique[*id as usize], *k);
        }
        // A second run gives the same buffers, whatever the timing.
        let again = hash_on_gpu(&gpu, &keys, 2 * keys.len() as u32);
        assert_eq!((again.0, again.1), (ids, unique));
    }
}

#[test]
fn a_tiny_hash_overflows_then_grows_to_the_same_numbering() {
    let gpu = gpu();
    let model = model("opensubdiv/catmark_cube.obj");
    let keys = grid_keys(&model, 4);
    assert!(
        number_keys(&keys, 8).is_none(),
        "the twin reports the overflow too"
    );
    let (twin_ids, twin_keys) = number_keys(&keys, 4096).expect("fits");
    let (ids, unique, grew) = hash_on_gpu(&gpu, &keys, 8);
    assert!(
        grew >= 1,
        "8 slots for {} keys must overflow",
        twin_keys.len()
    );
    assert_eq!(ids, twin_ids);
    assert_eq!(unique, twin_keys);
}

#[test]
fn the_hash_twin_catches_a_planted_collision() {
    // Test the tester: two different keys with equal high words must stay apart, and a
    // key differing in one bit must get its own number. Items without a key take no
    // slot and no number, the last one included.
    let none = tessera_core::gpu_types::CC_NO_KEY;
    let keys = [[7, 1], [7, 2], none, [7, 1], [8, 1], [7, 2], [7, 3], none];
    assert!(
        number_keys(&keys, 2).is_none(),
        "4 distinct keys cannot fit 2 slots"
    );
    assert!(number_keys(&keys, 4).is_some(), "4 keys fit 4 slots");
    let (ids, unique) = number_keys(&keys, 16).expect("fits");
    let no = tessera_core::gpu_types::CC_NO_SLOT;
    assert_eq!(ids, [0, 1, no, 0, 2, 1, 3, no]);
    assert_eq!(unique, [[7, 1], [7, 2], [8, 1], [7, 3]]);
    let gpu = gpu();
    let (g_ids, g_unique, _) = hash_on_gpu(&gpu, &keys, 2);
    assert_eq!((g_ids, g_unique), (ids.clone(), unique));
}

/// The nets (from their pages) and the corners of `buffers`, read back.
fn read_model(
    gpu: &Gpu,
    buffers: &CcModelBuffers,
    nets: usize,
    corners: usize,
) -> (Vec<GpuPatch>, Vec<CcCorner>) {
    let device = &gpu.device;
    let pages: Vec<(u32, Vec<[f32; 4]>)> = buffers
        .nets
        .iter()
        .map(|page| {
            let size = page.size();
            // Rows of a copy are padded to 256 bytes.
            let row = (16 * size.width).next_multiple_of(256);
            let texels = device.create_buffer(&wgpu::BufferDescriptor {
                label: None,
                size: (row * size.height) as u64,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            let mut encoder = device.create_command_encoder(&Default::default());
            encoder.copy_texture_to_buffer(
                page.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &texels,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row),
                        rows_per_image: None,
                    },
                },
                size,
            );
            gpu.queue.submit([encoder.finish()]);
            let texels: Vec<[f32; 4]> =
                bytemuck::pod_collect_to_vec(&gpu.map_and_copy(&texels).expect("texels"));
            (row / 16, texels)
        })
        .collect();
    let out_nets = (0..nets as u32)
        .map(|k| {
            let mut cp = [0f32; 48];
            for t in 0..12 {
                let (page, x, y) = buffers.layout.texel_of(k, t);
                let (stride, texels) = &pages[page as usize];
                cp[4 * t as usize..4 * t as usize + 4]
                    .copy_from_slice(&texels[(y * stride + x) as usize]);
            }
            GpuPatch { cp }
        })
        .collect();
    let out_corners = match corners {
        0 => Vec::new(),
        _ => gpu
            .read_pod::<CcCorner>(&buffers.corners, corners)
            .expect("corners"),
    };
    (out_nets, out_corners)
}

#[test]
fn the_stencil_kernels_derive_their_twins_quadtrees_from_the_control_points() {
    // Both steps of `cc_stencil` against `stencil::{level1, pieces}`: every net, ball and
    // corner, on meshes with valences 3 to 5, boundaries, holes and triangles; moved
    // points (not the loaded ones) on the second run. Single-precision sums in the same
    // order: equal up to the rounding of a fused multiply-add.
    derive_as_the_twin_does(
        &gpu(),
        &[
            "opensubdiv/catmark_pyramid.obj",
            "opensubdiv/catmark_edgecorner.obj",
            "opensubdiv/catmark_hole_test1.obj",
            "catmull_clark/spot_control_mesh.obj",
        ],
    );
}

#[test]
fn the_stencil_kernels_write_the_nets_across_pages() {
    // A device of 84-texel sides: pages of 7 nets per row and 84 rows (588 nets), so the
    // cube's 2160 nets fill three pages and part of the fourth.
    let gpu = Gpu::with_limits(|adapter| wgpu::Limits {
        max_texture_dimension_2d: 84,
        ..tessera_wgpu::bezier::required_limits(adapter)
    })
    .expect("device");
    let pages = derive_as_the_twin_does(&gpu, &["opensubdiv/catmark_cube.obj"]);
    assert_eq!(pages, 4);
}

/// Derives each model's quadtrees on `gpu` and compares them with the twin's; the pages
/// the last model's nets took.
fn derive_as_the_twin_does(gpu: &Gpu, names: &[&str]) -> usize {
    let kernels = tessera_wgpu::Kernels::new(&gpu.device);
    let mut pages = 0;
    for name in names {
        let m = model(name);
        let stencils = CcStencils::new(&m.mesh, m.depth);
        let loaded = m.mesh.control_points_f32();
        let buffers =
            CcModelBuffers::derived(&gpu.device, &gpu.queue, &stencils.structure).expect("fits");
        let mut control = m.mesh.control_points_f32();
        let steps = CcStencilBuffers::new(&gpu.device, &stencils, &control).expect("fits");
        assert_eq!(steps.run(&gpu.device, &gpu.queue, &kernels, &buffers), 2);
        for (i, p) in control.iter_mut().enumerate() {
            *p += 0.02 * Vec3::new((i % 5) as f32, (i % 3) as f32, (i % 7) as f32);
        }
        steps.update(&gpu.queue, &control).expect("same count");
        steps.run(&gpu.device, &gpu.queue, &kernels, &buffers);
        gpu.check().expect("no wgpu errors");
        let want = stencils.model(&control);
        let (nets, corners) = read_model(gpu, &buffers, want.nets.len(), want.corners.len());
        // The second run did derive the moved surface.
        assert_ne!(
            nets,
            stencils.model(&loaded).nets,
            "{name}: the points moved"
        );
        let size = m.mesh.bbox_diag() as f32;
        let close = |a: f32, b: f32, scale: f32| (a - b).abs() <= 1e-6 * scale;
        for (k, (a, b)) in nets.iter().zip(&want.nets).enumerate() {
            let extent = b.cp[3..].iter().fold(0f32, |m, x| m.max(x.abs()));
            for i in 0..48 {
                let scale = if i < 3 { size } else { extent };
                assert!(
                    close(a.cp[i], b.cp[i], scale),
                    "{name}: net {k} word {i}: {} against {}",
                    a.cp[i],
                    b.cp[i]
                );
            }
        }
        for (k, (a, b)) in corners.iter().zip(&want.corners).enumerate() {
            assert_eq!(a.corner, b.corner, "{name}: corner {k}");
            for i in 0..3 {
                assert!(
                    close(a.limit[i], b.limit[i], size),
                    "{name}: corner {k} limit"
                );
                assert!(
                    close(a.normal[i], b.normal[i], 1.0),
                    "{name}: corner {k} normal"
                );
            }
            assert!(
                close(a.hull_radius, b.hull_radius, b.hull_radius),
                "{name}: corner {k} radius"
            );
        }
        pages = (0..want.nets.len() as u32)
            .map(|k| buffers.layout.texel_of(k, 0).0 as usize + 1)
            .max()
            .unwrap_or(0);
    }
    pages
}
