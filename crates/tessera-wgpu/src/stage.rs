//! What the tessellation stages share: a recorded run that reports what it needed, and
//! growing the buffers that were too small. [`run_blocking`] is the one grow-and-rerun
//! loop both stages use for loading, tools and tests.

use crate::error::{Error, Result};

/// A stage whose runs report their needs and whose buffers grow to them.
pub trait GrowingStage {
    /// What a run reports (counters, overflow).
    type Status;
    /// How many times [`run_blocking`] grows before it gives up.
    const MAX_GROWTHS: u32;
    /// Records one run into `encoder` (the stage's `prepare`).
    fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
    );
    /// What the last submitted run reported (waits for the GPU).
    fn status(&self, device: &wgpu::Device) -> Result<Self::Status>;
    /// Reallocates what `status` says was too small; whether anything changed.
    fn grow_to(&mut self, device: &wgpu::Device, status: &Self::Status) -> Result<bool>;
}

/// Runs `stage` to completion on its own submission, growing and rerunning until
/// everything fits. A renderer records the stage's `prepare` into its own frame instead.
pub fn run_blocking<S: GrowingStage>(
    stage: &mut S,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
) -> Result<S::Status> {
    for _ in 0..S::MAX_GROWTHS {
        let mut encoder = device.create_command_encoder(&Default::default());
        stage.record(device, queue, &mut encoder);
        queue.submit([encoder.finish()]);
        let status = stage.status(device)?;
        if !stage.grow_to(device, &status)? {
            return Ok(status);
        }
    }
    Err(Error::Wgpu(format!(
        "still overflowing after growing {} times",
        S::MAX_GROWTHS
    )))
}
