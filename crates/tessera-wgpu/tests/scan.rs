//! The GPU prefix sum against its CPU twin, from one block to several blocks per chunk,
//! over a whole buffer and as far as a count written on the GPU.

use tessera_core::scan::exclusive_scan;
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::scan::{PrefixSum, ScanKernels};
use wgpu::util::DeviceExt;

#[test]
fn gpu_scan_matches_the_cpu_twin_at_every_chunk_size() {
    let gpu = Gpu::new().expect("a wgpu adapter (CI installs Mesa's lavapipe)");
    let kernels = ScanKernels::new(&gpu.device);
    // 1 and 512: one block; 513 and 70 000: one block per chunk at most; 300 000:
    // three blocks per chunk (> 512 · 256).
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

#[test]
fn a_scan_bounded_by_a_live_count_scans_that_many_and_leaves_the_rest() {
    let gpu = Gpu::new().expect("a wgpu adapter (CI installs Mesa's lavapipe)");
    let kernels = ScanKernels::new(&gpu.device);
    // Several blocks per chunk for the capacity; the live count (a word written on the
    // GPU, here at slot 1) sets how many values are scanned.
    let n = 300_000usize;
    let values: Vec<u32> = (0..n as u32)
        .map(|i| i.wrapping_mul(2_654_435_761) >> 28)
        .collect();
    for live in [0u32, 1, 511, 512, 70_000, 299_999] {
        let buffer = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("scan test"),
                contents: bytemuck::cast_slice(&values),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            });
        let counts = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("live count"),
                contents: bytemuck::cast_slice(&[7u32, live]),
                usage: wgpu::BufferUsages::STORAGE,
            });
        let scan =
            PrefixSum::with_live_count(&gpu.device, &kernels, &buffer, n as u32, (&counts, 1));
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            scan.record(&mut pass, &kernels);
        }
        gpu.queue.submit([encoder.finish()]);
        let got: Vec<u32> = gpu.read_pod(&buffer, n).expect("readback");
        // `live + 1` values: the list and the total after it.
        let scanned = (live as usize + 1).min(n);
        let mut want = values[..scanned].to_vec();
        exclusive_scan(&mut want);
        assert_eq!(&got[..scanned], &want[..], "live = {live}");
        assert_eq!(
            &got[scanned..],
            &values[scanned..],
            "live = {live}: touched the rest"
        );
    }
    gpu.check().expect("no wgpu validation errors");
}

#[test]
fn a_scan_of_keys_sums_the_counts_they_pack() {
    let gpu = Gpu::new().expect("a wgpu adapter (CI installs Mesa's lavapipe)");
    let kernels = ScanKernels::new(&gpu.device);
    // Keys as marking leaves them: !(count << 5 | trial).
    let n = 70_000usize;
    let counts: Vec<u32> = (0..n as u32)
        .map(|i| i.wrapping_mul(2_654_435_761) >> 26)
        .collect();
    let keys: Vec<u32> = counts
        .iter()
        .enumerate()
        .map(|(i, &c)| !((c << 5) | (i as u32 % 18)))
        .collect();
    let buffer = gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scan test"),
            contents: bytemuck::cast_slice(&keys),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
    let scan = PrefixSum::of_keys(&gpu.device, &kernels, &buffer, n as u32, (!0, 5));
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        scan.record(&mut pass, &kernels);
    }
    gpu.queue.submit([encoder.finish()]);
    let got: Vec<u32> = gpu.read_pod(&buffer, n).expect("readback");
    let mut want = counts;
    exclusive_scan(&mut want);
    assert_eq!(got, want);
    gpu.check().expect("no wgpu validation errors");
}
