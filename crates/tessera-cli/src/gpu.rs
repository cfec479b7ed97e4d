//! The GPU backend of the CLI: device, stage, a warm-up run that grows the buffers, then
//! the timed run (GPU work to completion) and the readback.

use std::time::Instant;

use crate::tessellate::ms;
use serde::Serialize;
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::stage::{run_blocking, GrowingStage};
use tessera_wgpu::{wgpu, Result};

/// Stages of a GPU run, ms. `tessellate` is the tessellation alone.
#[derive(Serialize, Default, Clone, Copy, Debug)]
pub struct GpuTimings {
    /// Adapter and device creation.
    pub device: f64,
    /// Kernel compilation and the model's upload.
    pub pipelines_and_upload: f64,
    /// First run: grows the output buffers to fit (and warms the driver's caches).
    pub first_run: f64,
    /// Recording, submitting and waiting for the kernels to finish.
    pub tessellate: f64,
    /// Copying the mesh back (only for files and measurement; drawing needs none).
    pub readback: f64,
}

pub fn open(timings: &mut GpuTimings) -> Result<Gpu> {
    let t = Instant::now();
    let gpu = Gpu::new()?;
    timings.device = ms(t);
    Ok(gpu)
}

/// Builds a stage and runs it: once to fit the buffers, once timed.
pub fn run<S: GrowingStage>(
    gpu: &Gpu,
    timings: &mut GpuTimings,
    build: impl FnOnce() -> Result<S>,
) -> Result<(S, S::Status)> {
    let t = Instant::now();
    let mut stage = build()?;
    gpu.check()?;
    timings.pipelines_and_upload = ms(t);
    let t = Instant::now();
    run_blocking(&mut stage, &gpu.device, &gpu.queue)?;
    timings.first_run = ms(t);
    timed_run(gpu, timings, |e| stage.record(&gpu.device, &gpu.queue, e))?;
    let status = stage.status(&gpu.device)?;
    gpu.check()?;
    Ok((stage, status))
}

/// The timed run: what `record` puts in an encoder, submitted and waited for.
fn timed_run(
    gpu: &Gpu,
    timings: &mut GpuTimings,
    record: impl FnOnce(&mut wgpu::CommandEncoder),
) -> Result<()> {
    let t = Instant::now();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    record(&mut encoder);
    gpu.queue.submit([encoder.finish()]);
    gpu.wait()?;
    timings.tessellate = ms(t);
    Ok(())
}
