//! The GPU backend of the CLI: device, stage, a warm-up run that grows the buffers, then
//! the timed run (GPU work to completion) and the readback.

use std::time::Instant;

use crate::tessellate::ms;
use serde::Serialize;
use tessera_core::gpu_types::BezierStatus;
use tessera_wgpu::bezier::BezierStage;
use tessera_wgpu::catmull_clark::{CcStage, CcStatus, CcUniformStage};
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::{wgpu, Result};

/// What the CLI does with any stage: fit the buffers, record a run, read its status.
pub trait Stage {
    /// What a run reports.
    type Status;
    /// Runs to completion, growing the buffers until the output fits.
    fn fit(&mut self, gpu: &Gpu) -> Result<Self::Status>;
    /// Records one run.
    fn prepare(&mut self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) -> Result<()>;
    /// The last run's status, once submitted.
    fn status(&mut self, gpu: &Gpu) -> Result<Self::Status>;
}

impl Stage for BezierStage {
    type Status = BezierStatus;
    fn fit(&mut self, gpu: &Gpu) -> Result<BezierStatus> {
        self.run_blocking(&gpu.device, &gpu.queue)
    }
    fn prepare(&mut self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        BezierStage::prepare(self, &gpu.device, &gpu.queue, encoder)
    }
    fn status(&mut self, gpu: &Gpu) -> Result<BezierStatus> {
        self.read_status(&gpu.device)
    }
}

impl Stage for CcStage {
    type Status = CcStatus;
    fn fit(&mut self, gpu: &Gpu) -> Result<CcStatus> {
        self.run_blocking(&gpu.device, &gpu.queue)
    }
    fn prepare(&mut self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        CcStage::prepare(self, &gpu.device, &gpu.queue, encoder)
    }
    fn status(&mut self, gpu: &Gpu) -> Result<CcStatus> {
        self.read_status(&gpu.device)
    }
}

/// Its sizes follow from the parameters: it never grows, and its status is its counts.
impl Stage for CcUniformStage {
    type Status = ();
    fn fit(&mut self, gpu: &Gpu) -> Result<()> {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        Stage::prepare(self, gpu, &mut encoder)?;
        gpu.queue.submit([encoder.finish()]);
        gpu.wait()
    }
    fn prepare(&mut self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) -> Result<()> {
        CcUniformStage::prepare(self, &gpu.device, &gpu.queue, encoder)
    }
    fn status(&mut self, gpu: &Gpu) -> Result<()> {
        gpu.wait()
    }
}

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
pub fn run<S: Stage>(
    gpu: &Gpu,
    timings: &mut GpuTimings,
    build: impl FnOnce() -> Result<S>,
) -> Result<(S, S::Status)> {
    let t = Instant::now();
    let mut stage = build()?;
    gpu.check()?;
    timings.pipelines_and_upload = ms(t);
    let t = Instant::now();
    stage.fit(gpu)?;
    timings.first_run = ms(t);
    timed_run(gpu, timings, |e| stage.prepare(gpu, e))?;
    let status = stage.status(gpu)?;
    gpu.check()?;
    Ok((stage, status))
}

/// The timed run: what `record` puts in an encoder, submitted and waited for.
fn timed_run(
    gpu: &Gpu,
    timings: &mut GpuTimings,
    record: impl FnOnce(&mut wgpu::CommandEncoder) -> Result<()>,
) -> Result<()> {
    let t = Instant::now();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    record(&mut encoder)?;
    gpu.queue.submit([encoder.finish()]);
    gpu.wait()?;
    timings.tessellate = ms(t);
    Ok(())
}
