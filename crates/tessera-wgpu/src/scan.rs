//! Exclusive prefix sum of `u32` on the GPU, in place, over any length, in
//! [`PrefixSum::DISPATCHES`] dispatches: chunk sums, then each chunk scanned after the
//! chunks before it (`shaders/scan.wgsl`). CPU twin: [`tessera_core::scan`].

use tessera_core::scan::{scan_groups, SCAN_GROUPS};

use crate::kernel::{init_buffer, storage, Kernel};

/// The two scan kernels of one device.
pub struct ScanKernels {
    reduce: Kernel,
    scan_chunks: Kernel,
}

impl ScanKernels {
    pub fn new(device: &wgpu::Device) -> Self {
        ScanKernels {
            reduce: Kernel::new(device, "scan.wgsl", "reduce"),
            scan_chunks: Kernel::new(device, "scan.wgsl", "scan_chunks"),
        }
    }
}

/// A scan of the first `n` values of one buffer, recorded as many times as needed.
pub struct PrefixSum {
    reduce: wgpu::BindGroup,
    scan_chunks: wgpu::BindGroup,
    /// Workgroups of each dispatch, from the lists' capacities.
    groups: u32,
    // Kept alive for the bind groups.
    _uniform: wgpu::Buffer,
    _sums: wgpu::Buffer,
}

impl PrefixSum {
    /// Dispatches one scan records, whatever the length.
    pub const DISPATCHES: u32 = 2;

    /// Plans the scan of the first `n` `u32` of `data` (which needs `STORAGE` usage).
    pub fn new(device: &wgpu::Device, kernels: &ScanKernels, data: &wgpu::Buffer, n: u32) -> Self {
        Self::plan(device, kernels, data, n, None, (0, 0))
    }

    /// Plans the scan of the first `n` values of `data` read as `(x ^ xor) >> shift`,
    /// in place: keys that pack a count with other bits are scanned as their counts.
    pub fn of_keys(
        device: &wgpu::Device,
        kernels: &ScanKernels,
        data: &wgpu::Buffer,
        n: u32,
        transform: (u32, u32),
    ) -> Self {
        Self::plan(device, kernels, data, n, None, transform)
    }

    /// Plans the scan of the first `live[slot] + 1` (at most `n`) values of `data`, the
    /// count written by an earlier kernel: a list sized for its capacity costs what it
    /// holds. Values beyond are left as they are.
    pub fn with_live_count(
        device: &wgpu::Device,
        kernels: &ScanKernels,
        data: &wgpu::Buffer,
        n: u32,
        live: (&wgpu::Buffer, u32),
    ) -> Self {
        Self::plan(device, kernels, data, n, Some(live), (0, 0))
    }

    /// Plans the scans of two lists, each as [`with_live_count`](Self::with_live_count),
    /// in the same two dispatches (half the workgroups each).
    pub fn pair(
        device: &wgpu::Device,
        kernels: &ScanKernels,
        a: (&wgpu::Buffer, u32, (&wgpu::Buffer, u32)),
        b: (&wgpu::Buffer, u32, (&wgpu::Buffer, u32)),
    ) -> Self {
        let (data, n, (live, slot)) = a;
        Self::bind(device, kernels, (data, n, slot, live), Some(b), (0, 0))
    }

    fn plan(
        device: &wgpu::Device,
        kernels: &ScanKernels,
        data: &wgpu::Buffer,
        n: u32,
        live: Option<(&wgpu::Buffer, u32)>,
        transform: (u32, u32),
    ) -> Self {
        let no_live = storage(device, "tessera scan no live count", 4);
        let (live_buffer, slot) = live.unwrap_or((&no_live, u32::MAX));
        Self::bind(
            device,
            kernels,
            (data, n, slot, live_buffer),
            None,
            transform,
        )
    }

    fn bind(
        device: &wgpu::Device,
        kernels: &ScanKernels,
        (data, n, slot, live): (&wgpu::Buffer, u32, u32, &wgpu::Buffer),
        b: Option<(&wgpu::Buffer, u32, (&wgpu::Buffer, u32))>,
        (xor, shift): (u32, u32),
    ) -> Self {
        // A single list binds two small buffers of its own in the second list's place.
        let unused = storage(device, "tessera scan no second list", 4);
        let unused_live = storage(device, "tessera scan no second live count", 4);
        let (data_b, n_b, (live_b, slot_b), lists) = match b {
            Some((d, n, live)) => (d, n, live, 2),
            None => (&unused, 0, (&unused_live, u32::MAX), 1),
        };
        let uniform = init_buffer(
            device,
            "tessera scan params",
            bytemuck::bytes_of(&[n, slot, n_b, slot_b, lists, xor, shift, 0]),
            wgpu::BufferUsages::UNIFORM,
        );
        let sums = storage(device, "tessera scan sums", 4 * SCAN_GROUPS as u64);
        let entries = [
            (0, &uniform),
            (1, data),
            (2, &sums),
            (3, live),
            (4, data_b),
            (5, live_b),
        ];
        PrefixSum {
            reduce: kernels.reduce.bind(device, &entries),
            scan_chunks: kernels.scan_chunks.bind(device, &entries),
            groups: scan_groups(n.max(n_b) as usize, lists as usize) as u32,
            _uniform: uniform,
            _sums: sums,
        }
    }

    /// Records the scan into `pass`: [`DISPATCHES`](Self::DISPATCHES) dispatches of
    /// [`scan_groups`] workgroups each for the lists' capacities, whatever the live
    /// count. Returns the dispatches recorded.
    pub fn record(&self, pass: &mut wgpu::ComputePass, kernels: &ScanKernels) -> u32 {
        kernels.reduce.dispatch(pass, &self.reduce, self.groups, 1)
            + kernels
                .scan_chunks
                .dispatch(pass, &self.scan_chunks, self.groups, 1)
    }
}
