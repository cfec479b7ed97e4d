//! Exclusive prefix sum of `u32` on the GPU, in place, over any length: blocks of 512
//! values per workgroup, their totals scanned the same way level by level, then added
//! back. CPU twin: [`tessera_core::scan`].

use tessera_core::scan::SCAN_BLOCK;
use wgpu::util::DeviceExt;

use crate::kernel::{storage, Kernel};

/// The two scan kernels of one device.
pub struct ScanKernels {
    scan_blocks: Kernel,
    add_offsets: Kernel,
    dispatch_args: Kernel,
}

impl ScanKernels {
    pub fn new(device: &wgpu::Device) -> Self {
        ScanKernels {
            scan_blocks: Kernel::new(device, "scan.wgsl", "scan_blocks"),
            add_offsets: Kernel::new(device, "scan.wgsl", "add_offsets"),
            dispatch_args: Kernel::new(device, "scan.wgsl", "dispatch_args"),
        }
    }
}

/// One level: `n` values scanned per block, block totals to `sums` (the next level).
struct Level {
    n: u32,
    blocks: wgpu::BindGroup,
    add: wgpu::BindGroup,
    // Kept alive for the bind groups.
    _uniform: wgpu::Buffer,
    _sums: wgpu::Buffer,
}

/// A scan of the first `n` values of one buffer, recorded as many times as needed.
pub struct PrefixSum {
    levels: Vec<Level>,
    /// For a scan bounded by a live count: the kernel's bind group writing each level's
    /// dispatch size, and the buffer it writes.
    indirect: Option<(wgpu::BindGroup, wgpu::Buffer)>,
}

impl PrefixSum {
    /// Plans the scan of the first `n` `u32` of `data` (which needs `STORAGE` usage).
    pub fn new(device: &wgpu::Device, kernels: &ScanKernels, data: &wgpu::Buffer, n: u32) -> Self {
        Self::plan(device, kernels, data, n, None)
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
        Self::plan(device, kernels, data, n, Some(live))
    }

    fn plan(
        device: &wgpu::Device,
        kernels: &ScanKernels,
        data: &wgpu::Buffer,
        n: u32,
        live: Option<(&wgpu::Buffer, u32)>,
    ) -> Self {
        let first_n = n;
        let block = SCAN_BLOCK as u32;
        let mut levels: Vec<Level> = Vec::new();
        let mut n = n;
        let no_live = storage(device, "tessera scan no live count", 4);
        let mut level_count = 1;
        while n.div_ceil(block).max(1) > 1 {
            n = n.div_ceil(block);
            level_count += 1;
        }
        n = first_n;
        let args = live.map(|_| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tessera scan dispatch args"),
                size: 12 * level_count as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
                mapped_at_creation: false,
            })
        });
        let mut indirect = None;
        loop {
            let count = n.div_ceil(block).max(1);
            // Only the first level is bounded by the live count; the block sums above it
            // are few.
            let (live_buffer, slot) = match (levels.is_empty(), live) {
                (true, Some((b, s))) => (b, s),
                _ => (&no_live, u32::MAX),
            };
            let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("tessera scan params"),
                contents: bytemuck::bytes_of(&[n, slot, level_count, 0]),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let sums = storage(device, "tessera scan sums", 4 * count as u64);
            let input = levels.last().map_or(data, |l| &l._sums);
            let entries = [(0, &uniform), (1, input), (2, &sums), (3, live_buffer)];
            if let (true, Some(args)) = (levels.is_empty(), &args) {
                let bind = kernels
                    .dispatch_args
                    .bind(device, &[(0, &uniform), (3, live_buffer), (4, args)]);
                indirect = Some((bind, args.clone()));
            }
            let level = Level {
                n,
                blocks: kernels.scan_blocks.bind(device, &entries),
                add: kernels.add_offsets.bind(device, &entries),
                _uniform: uniform,
                _sums: sums,
            };
            levels.push(level);
            if count == 1 {
                return PrefixSum { levels, indirect };
            }
            n = count;
        }
    }

    /// Records the scan into `pass`: every level's blocks upward, then the offsets back
    /// down (the top level is a single block and needs none). A scan bounded by a live
    /// count first writes each level's dispatch size for that count (`dispatch_args`, a
    /// one-invocation kernel) and dispatches indirectly, so that a list sized for its
    /// capacity costs what it holds.
    pub fn record(&self, pass: &mut wgpu::ComputePass, kernels: &ScanKernels) {
        let block = SCAN_BLOCK as u32;
        if let Some((bind, args)) = &self.indirect {
            kernels.dispatch_args.dispatch(pass, bind, 1, 1);
            for (l, level) in self.levels.iter().enumerate() {
                kernels
                    .scan_blocks
                    .dispatch_indirect(pass, &level.blocks, args, 12 * l as u64);
            }
            for (l, level) in self.levels.iter().enumerate().rev().skip(1) {
                kernels
                    .add_offsets
                    .dispatch_indirect(pass, &level.add, args, 12 * l as u64);
            }
            return;
        }
        for level in &self.levels {
            kernels
                .scan_blocks
                .dispatch(pass, &level.blocks, level.n, block);
        }
        for level in self.levels.iter().rev().skip(1) {
            kernels
                .add_offsets
                .dispatch(pass, &level.add, level.n, block);
        }
    }
}
