//! The GPU prefix sum against its CPU twin, across one, two and three levels of blocks.

use tessera_core::scan::exclusive_scan;
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::scan::{PrefixSum, ScanKernels};
use wgpu::util::DeviceExt;

#[test]
fn gpu_scan_matches_the_cpu_twin_at_every_level_count() {
    let gpu = Gpu::new().expect("a wgpu adapter (CI installs Mesa's lavapipe)");
    let kernels = ScanKernels::new(&gpu.device);
    // 1 and 512: one block; 513 and 70 000: two levels; 300 000: three (> 512²).
    for n in [1usize, 5, 512, 513, 70_000, 300_000] {
        let values: Vec<u32> = (0..n as u32)
            .map(|i| i.wrapping_mul(2_654_435_761) >> 28)
            .collect();
        // One spare value past the end: the scan must not touch it.
        let mut padded = values.clone();
        padded.push(0xdead_beef);
        let buffer = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("scan test"),
                contents: bytemuck::cast_slice(&padded),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            });
        let scan = PrefixSum::new(&gpu.device, &kernels, &buffer, n as u32);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            scan.record(&mut pass, &kernels);
        }
        gpu.queue.submit([encoder.finish()]);
        let got: Vec<u32> = gpu.read_pod(&buffer, n + 1).expect("readback");
        let mut want = values.clone();
        exclusive_scan(&mut want);
        assert_eq!(&got[..n], &want[..], "n = {n}");
        assert_eq!(got[n], 0xdead_beef, "n = {n}: wrote past the end");
    }
    gpu.check().expect("no wgpu validation errors");
}
