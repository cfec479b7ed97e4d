//! The GPU kernels against their CPU twins on the shipped models, stage by stage, and
//! the grow-and-retry path from tiny capacities. Any wgpu validation error fails.
//!
//! Ties: float rounding may differ between the CPU and the GPU (fused multiply-adds,
//! division accuracy), which can flip a decision whose tested value is within rounding
//! of the threshold. A mismatch counts as a tie only when the CPU twin, run at the
//! threshold moved by `TIE_REL` (0.1%) either way, reproduces the GPU's decision;
//! anything else fails. Ties must stay under 0.1% of the decisions.

use glam::Vec3;
use tessera_core::bezier::patch::eval_frame_f32;
use tessera_core::bezier::refine::{tri_mark, TriScratch};
use tessera_core::bezier::tessellate::{
    edge_decide, emit_order, euler_count, is_plain, order_bucket, root_known_leaf, tri_context,
    tri_count,
};
use tessera_core::bezier::{
    tessellate_adaptive, AdaptiveParams, BezierModel, EdgeTest, PreparedBezier,
};
use tessera_core::gpu_types::{BezierStatus, MapAtlas, OutVertex, EDGE_BIT_WORDS};
use tessera_wgpu::bezier::{BezierStage, Intermediates};
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::Kernels;

const TIE_REL: f32 = 1e-3;

fn gpu() -> Gpu {
    Gpu::new().expect("a wgpu adapter (CI installs Mesa's lavapipe; see `cargo xtask test`)")
}

fn load(name: &str) -> BezierModel {
    BezierModel::load(&tessera_tests::asset(&format!("teaset/{name}"))).expect("model loads")
}

fn model(name: &str) -> PreparedBezier {
    PreparedBezier::new(&load(name))
}

fn with_threshold(p: &AdaptiveParams, th: f32) -> AdaptiveParams {
    AdaptiveParams {
        threshold: th,
        ..*p
    }
}

struct Comparison {
    decisions: usize,
    ties: usize,
}

/// Compares the edge and triangle decisions of the GPU with the CPU twins; panics on a
/// mismatch that is not a tie.
fn compare_decisions(
    gpu: &Gpu,
    stage: &mut BezierStage,
    prep: &PreparedBezier,
    params: &AdaptiveParams,
) -> Comparison {
    let inter = stage
        .read_intermediates(&gpu.device, &gpu.queue)
        .expect("readback");
    let l = prep.layout;
    // The atlas the device built from the uploaded maps, texel for texel.
    assert!(
        inter.map_atlas == MapAtlas::new(&prep.maps, prep.map_scale).texels,
        "the map atlas built on the device differs from its twin"
    );
    let cps: Vec<[Vec3; 16]> = (0..l.patches).map(|p| prep.control_points(p)).collect();
    let lo = with_threshold(params, params.threshold * (1.0 - TIE_REL));
    let hi = with_threshold(params, params.threshold * (1.0 + TIE_REL));
    let mut ties = 0;
    let gpu_bits: Vec<[u32; EDGE_BIT_WORDS]> = (0..l.coarse_edges as usize)
        .map(|e| std::array::from_fn(|w| inter.edge_bits[e * EDGE_BIT_WORDS + w]))
        .collect();
    for e in 0..l.coarse_edges {
        let g = gpu_bits[e as usize];
        if edge_decide(prep, &cps, params, e).0 != g {
            let tie =
                edge_decide(prep, &cps, &lo, e).0 == g || edge_decide(prep, &cps, &hi, e).0 == g;
            assert!(
                tie,
                "edge {e}: GPU bits {g:08x?} differ from the CPU twin beyond a tie"
            );
            ties += 1;
        }
    }
    // Triangles, from the GPU's own edge decisions, so that each stage is compared alone.
    let stride = inter.stride as usize;
    for t in 0..l.coarse_triangles {
        let gpu_words = &inter.scratch[t as usize * stride..(t as usize + 1) * stride];
        let cpu_words = |p: &AdaptiveParams| {
            let ctx = tri_context(prep, &cps, &gpu_bits, p, t);
            let mut s = TriScratch::new(p.max_depth);
            tri_mark(&ctx, &mut s);
            s.words()
        };
        if cpu_words(params) != gpu_words {
            let tie = cpu_words(&lo) == gpu_words || cpu_words(&hi) == gpu_words;
            assert!(
                tie,
                "coarse triangle {t}: GPU lattice points differ from the CPU twin beyond a tie"
            );
            ties += 1;
        }
    }
    compare_order(&inter, prep, &cps, &gpu_bits, params);
    compare_dispatches(
        &stage.read_status(&gpu.device).expect("status"),
        prep,
        &cps,
        &gpu_bits,
        params,
    );
    Comparison {
        decisions: (l.coarse_edges + l.coarse_triangles) as usize,
        ties,
    }
}

/// The GPU's emit order against its twin, from the GPU's own counts and edge
/// decisions: each triangle's bucket as the twin chooses it, the buckets in order, and
/// the same triangles in each (the atomics take a bucket's slots in any order).
fn compare_order(
    inter: &Intermediates,
    prep: &PreparedBezier,
    cps: &[[Vec3; 16]],
    gpu_bits: &[[u32; EDGE_BIT_WORDS]],
    params: &AdaptiveParams,
) {
    let l = prep.layout;
    let (edges, triangles) = (l.coarse_edges as usize, l.coarse_triangles as usize);
    let count = |first: usize, t: usize| inter.counts[first + t + 1] - inter.counts[first + t];
    let buckets: Vec<u32> = (0..triangles)
        .map(|t| {
            let ctx = tri_context(prep, cps, gpu_bits, params, t as u32);
            let (inner, made) = (count(edges, t), count(edges + triangles, t));
            order_bucket(made, is_plain(&ctx, inner, made))
        })
        .collect();
    assert_eq!(
        inter.order_buckets, buckets,
        "the GPU's emit-order buckets differ from the twin's"
    );
    let bucket = |t: &u32| buckets[*t as usize];
    let mut gpu = inter.order.clone();
    assert!(
        gpu.iter().all(|&t| (t as usize) < triangles) && gpu.is_sorted_by_key(bucket),
        "the GPU's emit order leaves the buckets' order"
    );
    gpu.sort_by_key(|t| (bucket(t), *t));
    assert_eq!(
        gpu,
        emit_order(&buckets),
        "the GPU's emit order is not a bucketing of the triangles"
    );
}

/// The sizes the device chose for its indirect kernels against the twins, from the
/// GPU's own edge decisions: the mark kernel's list (the coarse triangles whose root is
/// not known to be a leaf, or whose count Euler's formula does not give) and the
/// triangles the general emit kernel takes (those not plain). A device that sent every
/// triangle down the slow paths would still make the right mesh; this catches it.
fn compare_dispatches(
    status: &BezierStatus,
    prep: &PreparedBezier,
    cps: &[[Vec3; 16]],
    gpu_bits: &[[u32; EDGE_BIT_WORDS]],
    params: &AdaptiveParams,
) {
    let l = prep.layout;
    let (mut marked, mut general) = (0u32, 0u32);
    for t in 0..l.coarse_triangles {
        let ctx = tri_context(prep, cps, gpu_bits, params, t);
        let mut s = TriScratch::new(params.max_depth);
        let known = root_known_leaf(&ctx) && euler_count(&ctx, &s).is_some();
        marked += u32::from(!known);
        tri_mark(&ctx, &mut s);
        general += u32::from(!is_plain(&ctx, s.inner_count(), tri_count(&ctx, &s)));
    }
    assert_eq!(
        status.general_triangles, general,
        "plain and general triangles"
    );
    assert_eq!(
        status.mark_dispatch[0],
        marked.div_ceil(64),
        "the mark kernel's workgroups ({marked} coarse triangles)"
    );
}

fn bbox_diagonal(prep: &PreparedBezier) -> f32 {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for p in 0..prep.layout.patches {
        for c in prep.control_points(p) {
            lo = lo.min(c);
            hi = hi.max(c);
        }
    }
    (hi - lo).length()
}

/// How far the GPU's normal may be from the CPU's at `v`: 1e-3, or more where the
/// normal is ill-conditioned. The normal is cross(S_u, S_v) normalized; where a side
/// nearly collapses (the teaspoon's tip: |S_u| is 2e-4 of the coordinates) a few ulps of
/// rounding in S_u, which a GPU's fused multiply-add changes, turn it by
/// ulps × |coordinates| / |S_u|.
fn normal_tolerance(prep: &PreparedBezier, v: &OutVertex) -> f32 {
    let cp = prep.control_points(v.face);
    let f = eval_frame_f32(&cp, v.uv[0], v.uv[1]);
    let coords = cp.iter().map(|c| c.abs().max_element()).fold(0.0, f32::max);
    // The shortest derivative the normal is built from (the mixed one stands in for a
    // vanished side, as in `frame_normal`).
    let tiny = (f.du.length() + f.dv.length() + f.duv.length()) * 1e-5;
    let side = |d: Vec3| {
        if d.length() <= tiny {
            f.duv.length()
        } else {
            d.length()
        }
    };
    let shortest = side(f.du).min(side(f.dv));
    (32.0 * f32::EPSILON * coords / shortest).clamp(1e-3, 0.1)
}

#[test]
fn gpu_matches_the_cpu_reference_on_every_shipped_model() {
    let gpu = gpu();
    let (mut decisions, mut ties) = (0usize, 0usize);
    let mut compared_meshes = 0;
    for name in ["teapot", "teacup", "teaspoon"] {
        let prep = model(name);
        let diag = bbox_diagonal(&prep);
        let mut stage: Option<BezierStage> = None;
        for (test, rel) in [
            (EdgeTest::Map4p, 0.002),
            (EdgeTest::Map2p, 0.001),
            (EdgeTest::Map8p, 0.004),
            (EdgeTest::Flat, 0.001),
        ] {
            let params = AdaptiveParams {
                test,
                threshold: rel * diag,
                max_depth: 5,
            };
            // One stage per model, its parameters changed between runs (as an
            // application would, and pipelines compile once).
            let stage = match &mut stage {
                Some(s) => {
                    s.set_params(&gpu.device, &gpu.queue, &params)
                        .expect("params");
                    s
                }
                None => stage.insert(
                    BezierStage::new(
                        &gpu.device,
                        &gpu.queue,
                        &Kernels::new(&gpu.device),
                        &prep,
                        &params,
                    )
                    .expect("stage"),
                ),
            };
            let t0 = std::time::Instant::now();
            let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
            gpu.check().expect("no wgpu validation errors");
            let gpu_time = t0.elapsed();
            let t0 = std::time::Instant::now();
            let cmp = compare_decisions(&gpu, stage, &prep, &params);
            eprintln!(
                "{name} {}: GPU run {gpu_time:?}, CPU comparison {:?}",
                test.name(),
                t0.elapsed()
            );
            decisions += cmp.decisions;
            ties += cmp.ties;
            if cmp.ties > 0 {
                // The meshes legitimately differ where a tie flipped.
                continue;
            }
            let mesh = stage
                .read_mesh(&gpu.device, &gpu.queue, &status)
                .expect("mesh");
            let cpu_run = tessellate_adaptive(&prep, &params).expect("cpu");
            let what = format!("{name} {}", test.name());
            assert_eq!(
                status.evaluations as u64, cpu_run.evaluations,
                "{what}: evaluations"
            );
            let cpu = cpu_run.mesh;
            assert_eq!(
                mesh.triangle_count(),
                cpu.triangle_count(),
                "{what}: triangles"
            );
            assert_eq!(mesh.vertices.len(), cpu.vertices.len(), "{what}: vertices");
            // The numbering is the same by construction (scan order), so the topology
            // is compared index for index.
            assert_eq!(mesh.indices, cpu.indices, "{what}: topology");
            let tol = 1e-5 * diag;
            for (k, (g, c)) in mesh.vertices.iter().zip(&cpu.vertices).enumerate() {
                let d = (Vec3::from_array(g.position) - Vec3::from_array(c.position)).length();
                assert!(
                    d <= tol,
                    "{what}: vertex {k} is {d} from the CPU's (tolerance {tol})"
                );
                assert_eq!(g.face, c.face, "{what}: vertex {k} patch");
                let dn = (Vec3::from_array(g.normal) - Vec3::from_array(c.normal)).length();
                let tol = normal_tolerance(&prep, c);
                assert!(
                    dn < tol,
                    "{what}: vertex {k} normal differs by {dn} (tolerance {tol})"
                );
            }
            compared_meshes += 1;
        }
    }
    gpu.check().expect("no wgpu validation errors");
    eprintln!(
        "{ties} ties in {decisions} decisions; {compared_meshes} meshes compared vertex by vertex"
    );
    assert!(
        (ties as f64) <= 0.001 * decisions as f64,
        "{ties} ties in {decisions} decisions: above 0.1%"
    );
    assert!(
        compared_meshes >= 6,
        "only {compared_meshes} meshes compared exactly"
    );
}

#[test]
fn tiny_capacities_overflow_cleanly_then_grow_to_the_same_mesh() {
    let gpu = gpu();
    let prep = model("teapot");
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: 0.02,
        max_depth: 6,
    };
    let kernels = Kernels::new(&gpu.device);
    let l = prep.layout;
    let mut roomy = BezierStage::with_capacity(
        &gpu.device,
        &gpu.queue,
        &kernels,
        &prep,
        &params,
        (4 * l.coarse_vertices, 24 * l.coarse_triangles),
    )
    .expect("stage");
    let want_status = roomy.run_blocking(&gpu.device, &gpu.queue).expect("run");
    let want = roomy
        .read_mesh(&gpu.device, &gpu.queue, &want_status)
        .expect("mesh");

    // The smallest vertex capacity a stage accepts is the coarse vertices (copied in
    // every run); the refined mesh needs more, so both buffers overflow.
    let mut tiny =
        BezierStage::with_capacity(&gpu.device, &gpu.queue, &kernels, &prep, &params, (1, 3))
            .expect("stage");
    assert_eq!(tiny.output().vertex_capacity(), l.coarse_vertices);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    tiny.prepare(&gpu.device, &gpu.queue, &mut encoder)
        .expect("prepare");
    gpu.queue.submit([encoder.finish()]);
    let status = tiny.read_status(&gpu.device).expect("status");
    assert!(status.vertices > l.coarse_vertices);
    assert_eq!(
        status.overflow, 3,
        "vertices and indices must both overflow"
    );
    let vertices: Vec<u32> = gpu
        .read_pod(tiny.output().vertices(), 9 * l.coarse_vertices as usize)
        .expect("vertices");
    assert!(
        vertices.iter().all(|&w| w == 0),
        "an overflowed run evaluates no vertex"
    );
    assert_eq!(
        status.vertices, want_status.vertices,
        "the needed size is reported"
    );
    assert_eq!(status.indices, want_status.indices);
    // Nothing was drawn or written: zero indices in the draw, and the 3-index buffer
    // still holds what it was created with (zeros).
    let args: Vec<u32> = gpu.read_pod(tiny.output().indirect(), 5).expect("args");
    assert_eq!(args[0], 0, "an overflowed run draws nothing");
    let idx: Vec<u32> = gpu.read_pod(tiny.output().indices(), 3).expect("indices");
    assert_eq!(idx, [0, 0, 0], "an overflowed run writes no index");
    assert!(tiny.read_mesh(&gpu.device, &gpu.queue, &status).is_err());

    // The next frame's `prepare` grows from that status (read back without waiting, or
    // as read here), so the run it records fits.
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    tiny.prepare(&gpu.device, &gpu.queue, &mut encoder)
        .expect("grows");
    gpu.queue.submit([encoder.finish()]);
    let grown = tiny.read_status(&gpu.device).expect("status");
    assert_eq!(grown.overflow, 0, "the run after an overflow fits");
    let got = tiny
        .read_mesh(&gpu.device, &gpu.queue, &grown)
        .expect("mesh");
    assert_eq!(got, want, "grown run gives the same mesh");
    let args: Vec<u32> = gpu.read_pod(tiny.output().indirect(), 5).expect("args");
    assert_eq!(args[0] as usize, want.indices.len());
    assert_eq!(args[1], 1);
    gpu.check().expect("no wgpu validation errors");
}

#[test]
fn an_invalid_threshold_is_an_error_not_a_panic() {
    let gpu = gpu();
    let prep = model("teacup");
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: f32::NAN,
        max_depth: 6,
    };
    assert!(BezierStage::new(
        &gpu.device,
        &gpu.queue,
        &Kernels::new(&gpu.device),
        &prep,
        &params
    )
    .is_err());
    let deep = AdaptiveParams {
        threshold: 0.01,
        max_depth: 99,
        ..params
    };
    assert!(BezierStage::new(
        &gpu.device,
        &gpu.queue,
        &Kernels::new(&gpu.device),
        &prep,
        &deep
    )
    .is_err());
}

#[test]
fn changing_the_depth_resizes_the_scratch_and_matches_the_cpu() {
    let gpu = gpu();
    let prep = model("teacup");
    let mut params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: 0.004,
        max_depth: 3,
    };
    let mut stage = BezierStage::new(
        &gpu.device,
        &gpu.queue,
        &Kernels::new(&gpu.device),
        &prep,
        &params,
    )
    .expect("stage");
    for depth in [3, 8, 0, 7, 2] {
        params.max_depth = depth;
        stage
            .set_params(&gpu.device, &gpu.queue, &params)
            .expect("params");
        let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
        let mesh = stage
            .read_mesh(&gpu.device, &gpu.queue, &status)
            .expect("mesh");
        let cpu = tessellate_adaptive(&prep, &params).expect("cpu").mesh;
        assert_eq!(mesh.indices, cpu.indices, "depth {depth}: topology");
    }
    gpu.check().expect("no wgpu validation errors");
}

#[test]
fn growing_past_the_device_limits_is_an_error_not_a_wgpu_failure() {
    let gpu = gpu();
    let prep = model("teacup");
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: 0.01,
        max_depth: 4,
    };
    let mut stage = BezierStage::new(
        &gpu.device,
        &gpu.queue,
        &Kernels::new(&gpu.device),
        &prep,
        &params,
    )
    .expect("stage");
    let impossible = tessera_core::gpu_types::BezierStatus {
        vertices: u32::MAX / 2,
        indices: 3,
        overflow: 1,
        ..Default::default()
    };
    let err = stage
        .grow(&gpu.device, &impossible)
        .expect_err("cannot fit");
    assert!(err.to_string().contains("vertex buffer"), "{err}");
    // The stage still works with the buffers it had.
    let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
    assert_eq!(status.overflow, 0);
    gpu.check().expect("no wgpu validation errors");
}

/// A patch with two collapsed sides meeting at a corner: the mark kernel's triangle
/// count falls back to the replay there (Euler's formula does not apply), and the mesh
/// still equals the CPU twin's, index for index.
#[test]
fn two_collapsed_sides_count_by_replay_and_match_the_cpu() {
    let gpu = gpu();
    let prep = PreparedBezier::new(&tessera_tests::two_collapsed_sides());
    for test in [EdgeTest::Map4p, EdgeTest::Flat] {
        let params = AdaptiveParams {
            test,
            threshold: 0.01,
            max_depth: AdaptiveParams::DEFAULT_MAX_DEPTH,
        };
        let (mesh, cpu) = gpu_and_cpu_meshes(&gpu, &prep, &params);
        assert!(cpu.triangle_count() > 0);
        assert_eq!(mesh.indices, cpu.indices, "{test:?}: topology");
    }
    gpu.check().expect("no wgpu validation errors");
}

/// The mesh of a fresh stage run to completion, and the CPU reference's.
/// A stage in `view`, run once and read back.
fn run_in_view(
    gpu: &Gpu,
    prep: &PreparedBezier,
    params: &AdaptiveParams,
    view: &tessera_core::bezier::BezierView,
) -> (BezierStage, BezierStatus, tessera_core::Mesh) {
    let mut stage = BezierStage::new(
        &gpu.device,
        &gpu.queue,
        &Kernels::new(&gpu.device),
        prep,
        params,
    )
    .expect("stage");
    stage.set_view(&gpu.queue, Some(view)).expect("view");
    let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
    let mesh = stage
        .read_mesh(&gpu.device, &gpu.queue, &status)
        .expect("mesh");
    (stage, status, mesh)
}

fn gpu_and_cpu_meshes(
    gpu: &Gpu,
    prep: &PreparedBezier,
    params: &AdaptiveParams,
) -> (tessera_core::Mesh, tessera_core::Mesh) {
    let mut stage = BezierStage::new(
        &gpu.device,
        &gpu.queue,
        &Kernels::new(&gpu.device),
        prep,
        params,
    )
    .expect("stage");
    let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
    let mesh = stage
        .read_mesh(&gpu.device, &gpu.queue, &status)
        .expect("mesh");
    (mesh, tessellate_adaptive(prep, params).expect("cpu").mesh)
}

/// `copies` teapots side by side, each taller than the one before, so that no two have
/// the same maps (a patch reading another's map changes the mesh).
fn teapots(copies: usize) -> PreparedBezier {
    let base = load("teapot");
    let (mut points, mut nets) = (Vec::new(), Vec::new());
    for c in 0..copies {
        let offset = Vec3::new(8.0 * c as f32, 0.0, 0.0);
        let stretch = Vec3::new(1.0, 1.0, 1.0 + 0.15 * c as f32);
        let first = points.len() as u32;
        points.extend(base.points.iter().map(|p| *p * stretch + offset));
        nets.extend(base.nets.iter().map(|n| n.map(|i| i + first)));
    }
    PreparedBezier::new(&BezierModel::from_nets(points, nets))
}

/// The maps of patches 256 and up lie in the atlas's second row of tiles: a model that
/// long gives the CPU's mesh, index for index.
#[test]
fn a_model_past_one_atlas_row_matches_the_cpu() {
    let gpu = gpu();
    let prep = teapots(9);
    assert!(prep.layout.patches > tessera_core::gpu_types::MAP_ATLAS_TILES_PER_ROW);
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: 0.002 * bbox_diagonal(&model("teapot")),
        max_depth: 4,
    };
    let (mesh, cpu) = gpu_and_cpu_meshes(&gpu, &prep, &params);
    assert!(cpu.triangle_count() > 9 * 32 * 18, "the threshold refines");
    assert_eq!(mesh.triangle_count(), cpu.triangle_count(), "triangles");
    assert!(
        mesh.indices == cpu.indices,
        "the topology differs from the CPU's"
    );
    for (k, (g, c)) in mesh.vertices.iter().zip(&cpu.vertices).enumerate() {
        let d = (Vec3::from_array(g.position) - Vec3::from_array(c.position)).length();
        assert!(d <= 1e-4, "vertex {k} is {d} from the CPU's");
    }
    gpu.check().expect("no wgpu validation errors");
}

/// A device whose textures cannot hold the atlas or the triangles' bit sets refuses the
/// model with an error that says so, before wgpu sees an oversized texture.
#[test]
fn textures_past_the_texture_limit_are_an_error() {
    let gpu = Gpu::with_limits(|adapter| tessera_wgpu::wgpu::Limits {
        max_texture_dimension_2d: 256,
        ..tessera_wgpu::bezier::required_limits(adapter)
    })
    .expect("device");
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: 0.01,
        max_depth: 4,
    };
    // The teapot's 32 patches make an atlas 32 · 15 = 480 texels wide.
    let err = BezierStage::new(
        &gpu.device,
        &gpu.queue,
        &Kernels::new(&gpu.device),
        &model("teapot"),
        &params,
    )
    .err()
    .expect("the atlas does not fit");
    assert!(
        matches!(
            err,
            tessera_wgpu::Error::MapAtlasTooLarge {
                patches: 32,
                width: 480,
                limit: 256,
                ..
            }
        ),
        "{err}"
    );
    // Sixteen patches fit (240 texels).
    let teapot = load("teapot");
    let small = PreparedBezier::new(&BezierModel::from_nets(
        teapot.points,
        teapot.nets[..16].to_vec(),
    ));
    let mut stage = BezierStage::new(
        &gpu.device,
        &gpu.queue,
        &Kernels::new(&gpu.device),
        &small,
        &params,
    )
    .expect("sixteen patches fit");
    // At depth 8 their 288 coarse triangles' bit sets take 1063 words each: 1196 rows of
    // 256 texels, before the edges' sets.
    let deep = AdaptiveParams {
        max_depth: 8,
        ..params
    };
    for err in [
        BezierStage::new(
            &gpu.device,
            &gpu.queue,
            &Kernels::new(&gpu.device),
            &small,
            &deep,
        )
        .err(),
        stage.set_params(&gpu.device, &gpu.queue, &deep).err(),
    ] {
        let err = err.expect("the scratch does not fit");
        assert!(
            matches!(
                err,
                tessera_wgpu::Error::OutputTooLarge {
                    what: "scratch",
                    ..
                }
            ),
            "{err}"
        );
    }
    // The refused change left the stage as it was.
    assert_eq!(stage.params().max_depth, 4);
    stage
        .run_blocking(&gpu.device, &gpu.queue)
        .expect("the stage still runs");
    gpu.check().expect("no wgpu validation errors");
}

#[test]
fn moved_patches_are_written_in_place_and_tessellate_as_on_the_cpu() {
    // Animation of Bézier input: the CPU prepares the moved patches again and the stage
    // writes only their nets, coarse vertices and maps; the next run is what a stage
    // made from the moved model gives, byte for byte, and the CPU reference's triangle
    // count. A model of another layout is refused.
    let gpu = gpu();
    let teapot = load("teapot");
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: 0.01,
        max_depth: 6,
    };
    let kernels = Kernels::new(&gpu.device);
    let prepared = PreparedBezier::new(&teapot);
    let mut stage =
        BezierStage::new(&gpu.device, &gpu.queue, &kernels, &prepared, &params).expect("stage");
    let before = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
    let moved_points: Vec<Vec3> = teapot
        .points
        .iter()
        .map(|p| Vec3::new(p.x * (1.0 + 0.3 * p.z.sin()), p.y, 1.5 * p.z))
        .collect();
    let moved = PreparedBezier::new(&tessera_core::bezier::BezierModel::from_nets(
        moved_points,
        teapot.nets.clone(),
    ));
    stage.update_model(&gpu.queue, &moved).expect("same layout");
    let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
    let mesh = stage
        .read_mesh(&gpu.device, &gpu.queue, &status)
        .expect("mesh");
    let mut fresh =
        BezierStage::new(&gpu.device, &gpu.queue, &kernels, &moved, &params).expect("stage");
    let fresh_status = fresh.run_blocking(&gpu.device, &gpu.queue).expect("run");
    let want = fresh
        .read_mesh(&gpu.device, &gpu.queue, &fresh_status)
        .expect("mesh");
    assert_eq!(mesh, want, "updated in place = made anew");
    let cpu = tessellate_adaptive(&moved, &params).expect("cpu").mesh;
    let (gpu_tris, cpu_tris) = (mesh.triangle_count() as f64, cpu.triangle_count() as f64);
    assert!(
        (gpu_tris - cpu_tris).abs() <= 0.01 * cpu_tris,
        "{gpu_tris} triangles against the CPU's {cpu_tris}"
    );
    assert_ne!(
        (before.vertices, before.indices),
        (status.vertices, status.indices),
        "moving the patches changes the tessellation"
    );
    let teacup = model("teacup");
    assert!(stage.update_model(&gpu.queue, &teacup).is_err());
    gpu.check().expect("no wgpu validation errors");
}

#[test]
fn a_loop_that_tessellates_on_change_reruns_once_after_an_overflow() {
    // A viewer's loop: one run, then another only while `grow_pending` says the newest
    // status overflowed and the buffers have not grown for it. Statuses arrive without
    // waiting; the stale overflow still held after the growth must not ask again.
    let gpu = gpu();
    let prep = model("teapot");
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: 0.02,
        max_depth: 6,
    };
    let kernels = Kernels::new(&gpu.device);
    let mut stage =
        BezierStage::with_capacity(&gpu.device, &gpu.queue, &kernels, &prep, &params, (1, 3))
            .expect("stage");
    let record = |stage: &mut BezierStage| {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        stage
            .prepare(&gpu.device, &gpu.queue, &mut encoder)
            .expect("prepare");
        gpu.queue.submit([encoder.finish()]);
    };
    assert!(!stage.grow_pending());
    record(&mut stage);
    let mut runs = 1;
    for _frame in 0..10 {
        gpu.wait().expect("frame done");
        let polled = stage
            .poll_status(&gpu.device)
            .expect("a status has arrived");
        if stage.grow_pending() {
            assert_ne!(polled.overflow, 0);
            record(&mut stage);
            runs += 1;
            assert!(!stage.grow_pending(), "the prepare grew for it");
        }
    }
    // Both buffers are told the sizes the first run needed: one growth, one rerun.
    assert_eq!((runs, stage.growths()), (2, 1));
    let status = stage.read_status(&gpu.device).expect("status");
    assert_eq!(status.overflow, 0);
    let got = stage
        .read_mesh(&gpu.device, &gpu.queue, &status)
        .expect("mesh");
    let want = tessellate_adaptive(&prep, &params).expect("cpu").mesh;
    assert_eq!(got.triangle_count(), want.triangle_count());
    gpu.check().expect("no wgpu validation errors");
}

#[test]
fn in_a_view_the_thresholds_follow_the_distance_crack_free_and_as_on_the_cpu() {
    // Each patch's threshold in pixels of a close view of the teapot, scaled from its
    // control points' box: the GPU gives the CPU reference's mesh, the mesh stays
    // watertight, the near patches get more triangles than at the far patches'
    // threshold everywhere and fewer than at the near ones', and the thresholds move
    // with the view.
    use tessera_core::bezier::{patch_thresholds, tessellate_adaptive_in_view, BezierView};
    use tessera_core::watertight::{bezier_open_boundary, check_watertight};
    use tessera_core::View;
    let gpu = gpu();
    let model = load("teapot");
    let prep = PreparedBezier::new(&model);
    let (lo, hi) = model.bounds();
    let diag = (hi - lo).length() as f64;
    let centre = ((lo + hi) / 2.0).as_dvec3();
    let close = View::look_at(
        centre + glam::DVec3::new(0.35, -0.6, 0.25) * diag,
        centre,
        glam::DVec3::Z,
        40f64.to_radians(),
        (640, 480),
        0.01 * diag,
    )
    .expect("view");
    let view = BezierView {
        view: close,
        pixels: 1.0,
        cull: false,
        cull_backfaces: false,
    };
    for test in [EdgeTest::Map4p, EdgeTest::Flat] {
        let params = AdaptiveParams {
            test,
            threshold: 0.05 * diag as f32,
            max_depth: 6,
        };
        let cpu = tessellate_adaptive_in_view(&prep, &params, &view).expect("cpu");
        let (mut stage, _, mesh) = run_in_view(&gpu, &prep, &params, &view);
        assert_eq!(mesh.indices, cpu.mesh.indices, "{}: topology", test.name());
        let positions: Vec<Vec3> = mesh.positions().collect();
        let report = check_watertight(
            &positions,
            &mesh.indices,
            &bezier_open_boundary(&model, 4096),
            1e-6 * diag,
        );
        assert!(report.is_watertight(), "{}: {report:?}", test.name());
        // Between the one threshold of its farthest patch and that of its nearest.
        let cps: Vec<_> = (0..prep.layout.patches)
            .map(|p| prep.control_points(p))
            .collect();
        let flipped: Vec<bool> = prep.topo.iter().map(|t| t.flipped()).collect();
        let th =
            patch_thresholds(&cps, &flipped, params.threshold, Some(&view)).expect("thresholds");
        let (near, far) = th
            .iter()
            .fold((f32::INFINITY, 0f32), |(a, b), &t| (a.min(t), b.max(t)));
        assert!(far > 2.0 * near, "{near} {far}");
        let at = |threshold| {
            tessellate_adaptive(
                &prep,
                &AdaptiveParams {
                    threshold,
                    ..params
                },
            )
            .expect("cpu")
            .mesh
            .triangle_count()
        };
        let n = mesh.triangle_count();
        eprintln!(
            "{}: {n} triangles in the view, {} at its far threshold, {} at its near one",
            test.name(),
            at(far),
            at(near)
        );
        assert!(at(far) < n && n < at(near), "{}", test.name());
        // Without the view the world threshold's mesh comes back.
        let (world, _) = gpu_and_cpu_meshes(&gpu, &prep, &params);
        stage.set_view(&gpu.queue, None).expect("no view");
        let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
        let back = stage
            .read_mesh(&gpu.device, &gpu.queue, &status)
            .expect("mesh");
        assert_eq!(back.indices, world.indices, "{}", test.name());
    }
    gpu.check().expect("no wgpu validation errors");
}

#[test]
fn in_a_culling_view_the_gpu_culls_the_cpu_references_patches() {
    // The teapot close up with its handle out of view: the same triangles, the same
    // culled patches and evaluations, the same vertices (those no triangle in view uses
    // left unevaluated on both), and looking away nothing at all, not one evaluation.
    use tessera_core::bezier::{tessellate_adaptive_in_view, BezierView};
    let gpu = gpu();
    let model = load("teapot");
    let prep = PreparedBezier::new(&model);
    let (lo, hi) = model.bounds();
    let diag = (hi - lo).length();
    let view = tessera_tests::bezier_close_view(&model, true);
    for test in [EdgeTest::Map4p, EdgeTest::Flat] {
        let what = test.name();
        let params = AdaptiveParams {
            test,
            threshold: 0.05 * diag,
            max_depth: 6,
        };
        let cpu = tessellate_adaptive_in_view(&prep, &params, &view).expect("cpu");
        assert!(cpu.culled_patches > 0, "{what}");
        let (mut stage, status, mesh) = run_in_view(&gpu, &prep, &params, &view);
        assert_eq!(
            status.culled_patches as usize, cpu.culled_patches,
            "{what}: culled patches"
        );
        assert_eq!(
            status.evaluations as u64, cpu.evaluations,
            "{what}: evaluations"
        );
        assert_eq!(mesh.indices, cpu.mesh.indices, "{what}: topology");
        assert_eq!(mesh.vertices.len(), cpu.mesh.vertices.len(), "{what}");
        for (g, c) in mesh.vertices.iter().zip(&cpu.mesh.vertices) {
            let d = (Vec3::from(g.position) - Vec3::from(c.position)).length();
            assert!(d <= 1e-5 * diag, "{what}: {g:?} against {c:?}");
            assert_eq!(g.face, c.face, "{what}");
        }
        let away = BezierView {
            view: tessera_core::View::look_at(
                glam::DVec3::new(0.0, -2.0 * diag as f64, 0.0),
                glam::DVec3::new(0.0, -3.0 * diag as f64, 0.0),
                glam::DVec3::Z,
                30f64.to_radians(),
                (640, 480),
                0.01,
            )
            .expect("view"),
            ..view
        };
        stage.set_view(&gpu.queue, Some(&away)).expect("view");
        let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
        assert_eq!(status.indices, 0, "{what}: nothing drawn");
        assert_eq!(
            status.culled_patches as usize,
            model.patches.len(),
            "{what}"
        );
        assert_eq!(status.evaluations, 0, "{what}: nothing evaluated");
        // Back faces culled too, from above the far side: the CPU's patches and mesh.
        let c = ((lo + hi) / 2.0).as_dvec3();
        let backs = BezierView {
            view: tessera_core::View::look_at(
                c + glam::DVec3::new(0.6, -0.9, 0.7) * diag as f64,
                c,
                glam::DVec3::Z,
                40f64.to_radians(),
                (640, 480),
                0.01,
            )
            .expect("view"),
            cull_backfaces: true,
            ..view
        };
        let cpu = tessellate_adaptive_in_view(&prep, &params, &backs).expect("cpu");
        assert!(cpu.culled_patches > 0, "{what}: back faces");
        stage.set_view(&gpu.queue, Some(&backs)).expect("view");
        let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
        let mesh = stage
            .read_mesh(&gpu.device, &gpu.queue, &status)
            .expect("mesh");
        assert_eq!(
            status.culled_patches as usize, cpu.culled_patches,
            "{what}: back faces"
        );
        assert_eq!(mesh.indices, cpu.mesh.indices, "{what}: back faces");
    }
    gpu.check().expect("no wgpu validation errors");
}
