//! What the tessellation stages share: the run's status read back without blocking,
//! GPU timing of a run, and the grow-and-rerun loop for loading, tools and tests.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

use crate::error::{Error, Result};

/// Where a stage's run writes its two GPU timestamps, as wgpu's `timestamp_writes` does
/// for one pass: `beginning_index` before the run's first pass, `end_index` after its
/// last. The device needs [`wgpu::Features::TIMESTAMP_QUERY`]. [`GpuTimer`] owns such a
/// query set and turns the pair into milliseconds.
#[derive(Clone, Copy, Debug)]
pub struct RunTimestamps<'a> {
    /// A query set of type [`wgpu::QueryType::Timestamp`].
    pub query_set: &'a wgpu::QuerySet,
    /// The query written when the run starts.
    pub beginning_index: u32,
    /// The query written when the run ends.
    pub end_index: u32,
}

/// The compute passes of one run, the first and the last carrying the run's timestamps.
pub(crate) struct Passes<'a> {
    timestamps: Option<RunTimestamps<'a>>,
    started: bool,
}

impl<'a> Passes<'a> {
    pub fn new(timestamps: Option<RunTimestamps<'a>>) -> Self {
        Passes {
            timestamps,
            started: false,
        }
    }

    /// Begins a compute pass; `last` marks the run's final one.
    pub fn begin<'e>(
        &mut self,
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
        last: bool,
    ) -> wgpu::ComputePass<'e> {
        let writes = self.timestamps.and_then(|t| {
            let beginning = (!self.started).then_some(t.beginning_index);
            let end = last.then_some(t.end_index);
            (beginning.is_some() || end.is_some()).then_some(wgpu::ComputePassTimestampWrites {
                query_set: t.query_set,
                beginning_of_pass_write_index: beginning,
                end_of_pass_write_index: end,
            })
        });
        self.started = true;
        encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: writes,
        })
    }
}

/// Times a stage's runs on the GPU with a two-query timestamp set: pass
/// [`timestamps`](Self::timestamps) to the stage's `prepare_timed`, record
/// [`resolve`](Self::resolve) after it in the same encoder, submit, then read
/// [`try_read_ms`](Self::try_read_ms) in a later frame (it never waits) or
/// [`read_ms`](Self::read_ms) (it waits).
pub struct GpuTimer {
    query_set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: StatusReadback,
    /// Nanoseconds per timestamp tick.
    period: f32,
    /// The newest time read.
    latest: Option<f64>,
}

impl GpuTimer {
    /// A timer, or `None` where the device was created without
    /// [`wgpu::Features::TIMESTAMP_QUERY`] (time the submission on the CPU there).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Option<GpuTimer> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        Some(GpuTimer {
            query_set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("tessera run timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolved: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tessera run timestamps resolved"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: StatusReadback::new("tessera run timestamps readback", 16),
            period: queue.get_timestamp_period(),
            latest: None,
        })
    }

    /// Where the timed run writes its timestamps.
    pub fn timestamps(&self) -> RunTimestamps<'_> {
        RunTimestamps {
            query_set: &self.query_set,
            beginning_index: 0,
            end_index: 1,
        }
    }

    /// Records the resolution of the two timestamps, after the timed run, and their
    /// copy back (mapped when the caller submits).
    pub fn resolve(&mut self, device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.query_set, 0..2, &self.resolved, 0);
        let resolved = &self.resolved;
        self.readback.record(device, encoder, |encoder, readback| {
            encoder.copy_buffer_to_buffer(resolved, 0, readback, 0, 16)
        });
    }

    /// The GPU time of the last timed run, in milliseconds (waits for the submission that
    /// holds its [`resolve`](Self::resolve)).
    pub fn read_ms(&mut self, device: &wgpu::Device) -> Result<f64> {
        let bytes = self.readback.wait_last(device)?;
        let ms = self.ms(&bytes);
        self.latest = Some(ms);
        Ok(ms)
    }

    /// The GPU time of the newest timed run whose timestamps have arrived, without
    /// waiting (a frame or so late); `None` before the first.
    pub fn try_read_ms(&mut self, device: &wgpu::Device) -> Option<f64> {
        if let Some(bytes) = self.readback.poll(device) {
            self.latest = Some(self.ms(&bytes));
        }
        self.latest
    }

    fn ms(&self, bytes: &[u8]) -> f64 {
        let stamps: [u64; 2] = bytemuck::pod_read_unaligned(&bytes[..16]);
        stamps[1].saturating_sub(stamps[0]) as f64 * f64::from(self.period) * 1e-6
    }
}

const IDLE: u8 = 0;
const PENDING: u8 = 1;
const MAPPED: u8 = 2;

/// Sets its slot back to idle if the encoder that was to map it is dropped unsubmitted.
struct PendingGuard(Arc<AtomicU8>);

impl Drop for PendingGuard {
    fn drop(&mut self) {
        let _ = self
            .0
            .compare_exchange(PENDING, IDLE, Ordering::AcqRel, Ordering::Acquire);
    }
}

struct Slot {
    buffer: wgpu::Buffer,
    state: Arc<AtomicU8>,
    /// The run it holds (see [`StatusReadback::runs`]).
    run: u64,
    /// The buffers' generation when that run was recorded.
    generation: u64,
}

/// A run's status, copied into one of a few mappable buffers that map themselves when
/// the caller submits: the stage reads the newest without blocking at its next
/// `prepare` (a frame late), or waits for the last one in [`Self::wait_last`].
pub(crate) struct StatusReadback {
    label: &'static str,
    size: u64,
    slots: Vec<Slot>,
    /// Runs recorded so far.
    runs: u64,
    /// Bumped when the stage's buffers are reallocated: statuses of runs recorded before
    /// speak of the old sizes, and [`Self::poll`] drops them.
    generation: u64,
    /// The status [`Self::wait_last`] read, with its run and generation, until
    /// [`Self::poll`] has seen it too.
    waited: Option<(u64, u64, Vec<u8>)>,
    /// The last status [`Self::wait_last`] read, and its run: asked again, it answers
    /// the same.
    last_read: Option<(u64, Vec<u8>)>,
}

impl StatusReadback {
    /// Buffers in flight at most; a run recorded while all are busy is not read back.
    const MAX_SLOTS: usize = 4;

    pub fn new(label: &'static str, size: u64) -> Self {
        StatusReadback {
            label,
            size,
            slots: Vec::new(),
            runs: 0,
            generation: 0,
            waited: None,
            last_read: None,
        }
    }

    /// The stage's buffers were reallocated.
    pub fn new_generation(&mut self) {
        self.generation += 1;
    }

    /// Records `copy` of the run's status into a free buffer, mapped on submission.
    pub fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        copy: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::Buffer),
    ) {
        let free = self
            .slots
            .iter()
            .position(|s| s.state.load(Ordering::Acquire) == IDLE);
        let index = match free {
            Some(i) => i,
            None if self.slots.len() < Self::MAX_SLOTS => {
                self.slots.push(Slot {
                    buffer: device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(self.label),
                        size: self.size,
                        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                        mapped_at_creation: false,
                    }),
                    state: Arc::new(AtomicU8::new(IDLE)),
                    run: 0,
                    generation: 0,
                });
                self.slots.len() - 1
            }
            None => {
                self.runs += 1;
                return;
            }
        };
        let slot = &mut self.slots[index];
        slot.run = self.runs;
        slot.generation = self.generation;
        self.runs += 1;
        slot.state.store(PENDING, Ordering::Release);
        copy(encoder, &slot.buffer);
        let guard = PendingGuard(slot.state.clone());
        encoder.map_buffer_on_submit(&slot.buffer, wgpu::MapMode::Read, .., move |r| {
            let state = if r.is_ok() { MAPPED } else { IDLE };
            guard.0.store(state, Ordering::Release);
        });
    }

    /// The newest status of the current generation that has arrived since the last
    /// call, without blocking; every arrived buffer is freed.
    pub fn poll(&mut self, device: &wgpu::Device) -> Option<Vec<u8>> {
        let _ = device.poll(wgpu::PollType::Poll);
        let mut newest: Option<(u64, Vec<u8>)> = self
            .waited
            .take()
            .filter(|(_, generation, _)| *generation == self.generation)
            .map(|(run, _, bytes)| (run, bytes));
        for slot in &self.slots {
            if slot.state.load(Ordering::Acquire) != MAPPED {
                continue;
            }
            let Some(bytes) = read_mapped(slot) else {
                continue;
            };
            // The last run's status stays at hand for `wait_last`.
            if Some(slot.run) == self.runs.checked_sub(1) {
                self.last_read = Some((slot.run, bytes.clone()));
            }
            if slot.generation == self.generation
                && newest.as_ref().is_none_or(|(run, _)| slot.run > *run)
            {
                newest = Some((slot.run, bytes));
            }
        }
        newest.map(|(_, b)| b)
    }

    /// The status of the last run recorded, waiting for the GPU.
    pub fn wait_last(&mut self, device: &wgpu::Device) -> Result<Vec<u8>> {
        let last = self.runs.checked_sub(1);
        if let Some((run, bytes)) = &self.last_read {
            if Some(*run) == last {
                return Ok(bytes.clone());
            }
        }
        let slot = self
            .slots
            .iter()
            .find(|s| Some(s.run) == last && s.state.load(Ordering::Acquire) != IDLE)
            .ok_or_else(|| Error::Readback("the last run was not submitted".into()))?;
        if slot.state.load(Ordering::Acquire) == PENDING {
            device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| Error::Readback(e.to_string()))?;
        }
        if slot.state.load(Ordering::Acquire) != MAPPED {
            return Err(Error::Readback("the last run was not submitted".into()));
        }
        let (run, generation) = (slot.run, slot.generation);
        let bytes =
            read_mapped(slot).ok_or_else(|| Error::Readback("mapping the status failed".into()))?;
        self.waited = Some((run, generation, bytes.clone()));
        self.last_read = Some((run, bytes.clone()));
        Ok(bytes)
    }
}

/// A mapped slot's bytes; the slot is unmapped and free again.
fn read_mapped(slot: &Slot) -> Option<Vec<u8>> {
    let bytes = slot.buffer.get_mapped_range(..).ok().map(|r| r.to_vec());
    slot.buffer.unmap();
    slot.state.store(IDLE, Ordering::Release);
    bytes
}

/// A stage whose runs report their needs and whose buffers grow to them.
pub(crate) trait GrowingStage {
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
    ) -> Result<()>;
    /// What the last submitted run reported (waits for the GPU).
    fn status(&mut self, device: &wgpu::Device) -> Result<Self::Status>;
    /// Reallocates what `status` says was too small; whether anything changed.
    fn grow_to(&mut self, device: &wgpu::Device, status: &Self::Status) -> Result<bool>;
}

/// Runs `stage` to completion on its own submission, growing and rerunning until
/// everything fits. A renderer records the stage's `prepare` into its own frame instead.
pub(crate) fn run_blocking<S: GrowingStage>(
    stage: &mut S,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
) -> Result<S::Status> {
    for _ in 0..S::MAX_GROWTHS {
        let mut encoder = device.create_command_encoder(&Default::default());
        stage.record(device, queue, &mut encoder)?;
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
