//! GPU time of a run, the public way: a [`GpuTimer`]'s timestamps around each stage's
//! `prepare_timed`, on every stage; the timed run draws what an untimed one draws.

use tessera_core::bezier::{AdaptiveParams, BezierModel, EdgeTest, PreparedBezier};
use tessera_core::catmull_clark::{load_surface, CcParams};
use tessera_core::Tolerance;
use tessera_wgpu::bezier::BezierStage;
use tessera_wgpu::catmull_clark::{CcStage, CcUniformStage, UniformParams};
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::{GpuTimer, Kernels};

fn asset(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets")
        .join(name)
}

/// Records `record` timed, submits, and returns the GPU milliseconds.
fn timed(
    gpu: &Gpu,
    timer: &mut GpuTimer,
    record: impl FnOnce(&mut wgpu::CommandEncoder, tessera_wgpu::RunTimestamps),
) -> f64 {
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    record(&mut encoder, timer.timestamps());
    timer.resolve(&gpu.device, &mut encoder);
    gpu.queue.submit([encoder.finish()]);
    let ms = timer.read_ms(&gpu.device).expect("timestamps");
    // The same time, read again later without waiting.
    gpu.wait().expect("idle");
    assert_eq!(timer.try_read_ms(&gpu.device), Some(ms));
    ms
}

#[test]
fn every_stage_times_its_run_on_the_gpu() {
    let gpu = Gpu::new().expect("a wgpu adapter");
    let has = gpu
        .device
        .features()
        .contains(wgpu::Features::TIMESTAMP_QUERY);
    let Some(mut timer) = GpuTimer::new(&gpu.device, &gpu.queue) else {
        assert!(
            !has,
            "the device has timestamp queries but no timer was made"
        );
        eprintln!(
            "no TIMESTAMP_QUERY on {}: nothing to time",
            gpu.adapter_name()
        );
        return;
    };
    let kernels = Kernels::new(&gpu.device);
    let plausible = |what: &str, ms: f64| {
        assert!(
            ms.is_finite() && ms > 0.0 && ms < 60_000.0,
            "{what}: {ms} ms"
        );
        eprintln!("{what}: {ms:.3} ms");
    };

    let teapot = BezierModel::load(&asset("teaset/teapot")).expect("teapot");
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: 0.01,
        max_depth: 6,
    };
    let mut bezier = BezierStage::new(
        &gpu.device,
        &gpu.queue,
        &kernels,
        &PreparedBezier::new(&teapot),
        &params,
    )
    .expect("stage");
    let untimed = bezier.run_blocking(&gpu.device, &gpu.queue).expect("run");
    let ms = timed(&gpu, &mut timer, |e, t| {
        bezier
            .prepare_timed(&gpu.device, &gpu.queue, e, t)
            .expect("prepare")
    });
    plausible("bezier", ms);
    let status = bezier.read_status(&gpu.device).expect("status");
    assert_eq!(
        (status.vertices, status.indices),
        (untimed.vertices, untimed.indices)
    );

    let torus = load_surface(&asset("opensubdiv/catmark_torus.obj")).expect("torus");
    let cc_params = CcParams {
        tolerance: Tolerance::Relative(3e-3),
        max_depth: 6,
        first_split: Default::default(),
        leaf_bound: Default::default(),
    };
    let mut cc =
        CcStage::new(&gpu.device, &gpu.queue, &kernels, &torus, &cc_params).expect("stage");
    let untimed = cc.run_blocking(&gpu.device, &gpu.queue).expect("run");
    let ms = timed(&gpu, &mut timer, |e, t| {
        cc.prepare_timed(&gpu.device, &gpu.queue, e, t)
            .expect("prepare")
    });
    plausible("catmull-clark", ms);
    let status = cc.read_status(&gpu.device).expect("status");
    assert_eq!(status.indices, untimed.indices);

    let mut uniform = CcUniformStage::new(
        &gpu.device,
        &gpu.queue,
        &kernels,
        &torus,
        &UniformParams { segments: 4 },
    )
    .expect("stage");
    let ms = timed(&gpu, &mut timer, |e, t| {
        uniform
            .prepare_timed(&gpu.device, &gpu.queue, e, t)
            .expect("prepare")
    });
    plausible("uniform", ms);
    gpu.check().expect("no wgpu errors");
}

#[test]
fn kernels_of_another_device_are_refused() {
    // Pipelines belong to the device that made them: a stage given another device's
    // kernels (a second device of the same adapter) is an error, not a wgpu failure.
    let a = Gpu::new().expect("a wgpu adapter");
    let (device_b, queue_b) =
        pollster::block_on(a.adapter.request_device(&wgpu::DeviceDescriptor {
            required_limits: a.device.limits(),
            ..Default::default()
        }))
        .expect("a second device");
    let kernels = Kernels::new(&a.device);
    let teapot = BezierModel::load(&asset("teaset/teapot")).expect("teapot");
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: 0.01,
        max_depth: 6,
    };
    let prepared = PreparedBezier::new(&teapot);
    let err = BezierStage::new(&device_b, &queue_b, &kernels, &prepared, &params)
        .err()
        .expect("refused");
    assert!(matches!(err, tessera_wgpu::Error::ForeignKernels), "{err}");
    let torus = load_surface(&asset("opensubdiv/catmark_torus.obj")).expect("torus");
    let uniform = CcUniformStage::new(
        &device_b,
        &queue_b,
        &kernels,
        &torus,
        &UniformParams { segments: 2 },
    );
    assert!(matches!(uniform, Err(tessera_wgpu::Error::ForeignKernels)));
    // On its own device the same set works.
    BezierStage::new(&a.device, &a.queue, &kernels, &prepared, &params).expect("stage");
    a.check().expect("no wgpu errors");
}
