//! What one memory-bound operation costs on this machine: a bilinear displacement-map
//! read, the operation the Bézier decision kernels are built from. The CPU twin
//! (`tessera_core::bezier::prepare::map_read`, one thread) against the same arithmetic run
//! by the adapter with every lane busy and no branches, three ways: the kernels' own
//! `map_read` (`shaders/shared/map.wgsl`: one fetch from the `rgba16float` atlas of
//! cells, `MapAtlas`, a read-only storage texture), the same fetch from the same atlas
//! bound as a sampled texture (how the kernels read it before), four reads from a storage
//! buffer (how the kernels read the maps before the atlas), and four fetches from an
//! `r32float` sampled texture.
//!
//! It bounds what the kernels can gain over their CPU twins while they read the maps
//! this way: a twin does the same reads, so when a straight-line read with every lane
//! busy costs the adapter about what it costs the CPU thread, no reorganisation of the
//! kernels makes them several times faster than the twins.

use std::time::Instant;

use serde::Serialize;
use tessera_wgpu::wgpu;
use wgpu::util::DeviceExt;

use bytemuck::Zeroable;
use tessera_core::bezier::prepare::map_read;
use tessera_core::bezier::{BezierModel, PreparedBezier};
use tessera_core::gpu_types::{BezierParams, MapAtlas};
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::shaders;

use crate::{median, write_results};

/// Reads per invocation (GPU) and per map visit (CPU).
const READS: u32 = 64;
/// Maps in the probe: the teapot's 32, repeated.
const MAPS: u32 = 2048;
/// Atlas layout of the texture variant: 64 maps per row of 16×16 texels.
const ATLAS_MAPS_PER_ROW: u32 = 64;

#[derive(Serialize)]
struct ProbeRow {
    path: String,
    reads: u64,
    ms: f64,
    ns_per_read: f64,
    /// CPU ns per read / this row's.
    speed_vs_cpu: f64,
}

#[derive(Serialize)]
struct ProbeReport {
    adapter: String,
    /// `LP_NUM_THREADS` when set (llvmpipe's thread count).
    lp_num_threads: Option<String>,
    rows: Vec<ProbeRow>,
}

/// The `(u, v)` of read `k` of invocation `i`: the same hash on both sides.
fn probe_uv(i: u32, k: u32) -> (f32, f32) {
    let mut h = i.wrapping_mul(READS).wrapping_add(k);
    h = h.wrapping_mul(747796405).wrapping_add(2891336453);
    h = ((h >> ((h >> 28) + 4)) ^ h).wrapping_mul(277803737);
    h ^= h >> 22;
    ((h & 0xffff) as f32 / 65535.0, (h >> 16) as f32 / 65535.0)
}

const PROBE_MAIN: &str = r#"
struct DisplacementMap {
    d: array<f32, 256>,
}

@group(0) @binding(1) var nets: texture_storage_2d<rgba32float, read>;
@group(0) @binding(2) var maps: texture_storage_2d<rgba16float, read>;
@group(0) @binding(3) var<storage, read_write> probe_out: array<f32>;
@group(0) @binding(4) var atlas: texture_2d<f32>;
@group(0) @binding(5) var<storage, read> map_buffer: array<DisplacementMap>;
@group(0) @binding(6) var sampled_maps: texture_2d<f32>;

const PROBE_READS: u32 = 64u;
const ATLAS_MAPS_PER_ROW: u32 = 64u;

fn probe_uv(i: u32, k: u32) -> vec2f {
    var h = i * PROBE_READS + k;
    h = h * 747796405u + 2891336453u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    h = h ^ (h >> 22u);
    return vec2f(f32(h & 0xffffu) / 65535.0, f32(h >> 16u) / 65535.0);
}

// `map_read` from a storage buffer: four reads.
fn map_read_storage(p: u32, u: f32, v: f32) -> f32 {
    let cell = map_cell(u, v);
    let k = MAP_RES * cell.ij.y + cell.ij.x;
    let row0 = vec2f(map_buffer[p].d[k], map_buffer[p].d[k + 1u]);
    let row1 = vec2f(map_buffer[p].d[k + MAP_RES], map_buffer[p].d[k + MAP_RES + 1u]);
    return map_bilinear(row0, row1, cell.f);
}

// `map_read` with the atlas bound as a sampled texture: one fetch, as the kernels
// before they read it as a storage texture.
fn map_read_sampled(p: u32, u: f32, v: f32) -> f32 {
    let cell = map_cell(u, v);
    let tile = vec2u(p % MAP_ATLAS_TILES_PER_ROW, p / MAP_ATLAS_TILES_PER_ROW) * (MAP_RES - 1u);
    let corners = textureLoad(sampled_maps, tile + cell.ij, 0) * params.map_scale;
    return map_bilinear(corners.xy, corners.zw, cell.f);
}

// `map_read` from an `r32float` texture atlas of whole maps: four fetches.
fn map_read_texture(p: u32, u: f32, v: f32) -> f32 {
    let cell = map_cell(u, v);
    let o = vec2i(i32((p % ATLAS_MAPS_PER_ROW) * MAP_RES), i32((p / ATLAS_MAPS_PER_ROW) * MAP_RES))
        + vec2i(cell.ij);
    let row0 = vec2f(textureLoad(atlas, o, 0).x, textureLoad(atlas, o + vec2i(1, 0), 0).x);
    let row1 = vec2f(textureLoad(atlas, o + vec2i(0, 1), 0).x, textureLoad(atlas, o + vec2i(1, 1), 0).x);
    return map_bilinear(row0, row1, cell.f);
}

@compute @workgroup_size(64)
fn probe_atlas(@builtin(global_invocation_id) gid: vec3u) {
    var acc = 0.0;
    for (var k = 0u; k < PROBE_READS; k++) {
        let uv = probe_uv(gid.x, k);
        acc += map_read(gid.x / 18u, uv.x, uv.y);
    }
    probe_out[gid.x] = acc;
}

@compute @workgroup_size(64)
fn probe_sampled(@builtin(global_invocation_id) gid: vec3u) {
    var acc = 0.0;
    for (var k = 0u; k < PROBE_READS; k++) {
        let uv = probe_uv(gid.x, k);
        acc += map_read_sampled(gid.x / 18u, uv.x, uv.y);
    }
    probe_out[gid.x] = acc;
}

@compute @workgroup_size(64)
fn probe_buffer(@builtin(global_invocation_id) gid: vec3u) {
    var acc = 0.0;
    for (var k = 0u; k < PROBE_READS; k++) {
        let uv = probe_uv(gid.x, k);
        acc += map_read_storage(gid.x / 18u, uv.x, uv.y);
    }
    probe_out[gid.x] = acc;
}

@compute @workgroup_size(64)
fn probe_texture(@builtin(global_invocation_id) gid: vec3u) {
    var acc = 0.0;
    for (var k = 0u; k < PROBE_READS; k++) {
        let uv = probe_uv(gid.x, k);
        acc += map_read_texture(gid.x / 18u, uv.x, uv.y);
    }
    probe_out[gid.x] = acc;
}
"#;

pub fn run(assets: &std::path::Path, out_dir: &std::path::Path, quick: bool) {
    let teapot = BezierModel::load(&assets.join("teapot")).unwrap_or_else(|e| panic!("{e}"));
    let prep = PreparedBezier::new(&teapot);
    let maps: Vec<_> = (0..MAPS as usize)
        .map(|p| prep.maps[p % prep.maps.len()])
        .collect();
    // 18 invocations per map, as one per coarse triangle.
    let invocations = MAPS * 18;
    let reads = invocations as u64 * READS as u64;
    let repeats = if quick { 3 } else { 7 };

    // CPU twin, one thread, the same reads in the same order.
    let mut sums = vec![0.0f32; invocations as usize];
    let cpu_ms = median(
        (0..repeats)
            .map(|_| {
                let t = Instant::now();
                for (i, sum) in sums.iter_mut().enumerate() {
                    let map = &maps[i / 18];
                    let mut acc = 0.0;
                    for k in 0..READS {
                        let (u, v) = probe_uv(i as u32, k);
                        acc += map_read(std::hint::black_box(map), u, v);
                    }
                    *sum = acc;
                }
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect(),
    );
    let cpu_ns = cpu_ms * 1e6 / reads as f64;
    let mut rows = vec![ProbeRow {
        path: "CPU twin (`map_read`, one thread)".into(),
        reads,
        ms: cpu_ms,
        ns_per_read: cpu_ns,
        speed_vs_cpu: 1.0,
    }];

    let gpu = match Gpu::new() {
        Ok(g) => g,
        Err(e) => {
            eprintln!("bench: no GPU adapter ({e}); the probe has the CPU row only");
            write(out_dir, String::new(), None, rows);
            return;
        }
    };
    let device = &gpu.device;
    let source = [
        shaders::source("shared/types.wgsl"),
        shaders::source("shared/patch.wgsl"),
        shaders::source("shared/map.wgsl"),
        PROBE_MAIN.to_string(),
    ]
    .concat();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("probe"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let map_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("probe maps"),
        contents: bytemuck::cast_slice(&maps),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let res = tessera_core::gpu_types::MAP_RES as u32;
    let (width, height) = (
        ATLAS_MAPS_PER_ROW * res,
        MAPS.div_ceil(ATLAS_MAPS_PER_ROW) * res,
    );
    let mut texels = vec![0.0f32; (width * height) as usize];
    for (p, map) in maps.iter().enumerate() {
        let (x0, y0) = (
            (p as u32 % ATLAS_MAPS_PER_ROW) * res,
            (p as u32 / ATLAS_MAPS_PER_ROW) * res,
        );
        for j in 0..res {
            for i in 0..res {
                texels[((y0 + j) * width + x0 + i) as usize] = map.d[(j * res + i) as usize];
            }
        }
    }
    let atlas = device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some("probe atlas"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&texels),
    );
    let atlas_view = atlas.create_view(&Default::default());
    // The kernels' atlas of cells (`MapAtlas`), uploaded directly (the bench has a queue).
    let cells = MapAtlas::new(&maps, prep.map_scale);
    let cells_view = device
        .create_texture_with_data(
            &gpu.queue,
            &wgpu::TextureDescriptor {
                label: Some("probe map atlas"),
                size: wgpu::Extent3d {
                    width: cells.width,
                    height: cells.height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba16Float,
                usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&cells.texels),
        )
        .create_view(&Default::default());
    // The kernels' `map_read` scales the atlas's values by `params.map_scale`.
    let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("probe params"),
        contents: bytemuck::bytes_of(&BezierParams {
            map_scale: prep.map_scale,
            ..Zeroable::zeroed()
        }),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probe out"),
        size: invocations as u64 * 4,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let mut gpu_sums = Vec::new();
    for (entry, label) in [
        (
            "probe_atlas",
            "GPU, the kernels' `map_read` (one fetch from the `rgba16float` atlas of cells, a storage texture)",
        ),
        (
            "probe_sampled",
            "GPU, the same fetch with the atlas bound as a sampled texture",
        ),
        (
            "probe_buffer",
            "GPU, four reads from a storage buffer (the kernels before the atlas)",
        ),
        (
            "probe_texture",
            "GPU, four fetches from an `r32float` texture",
        ),
    ] {
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: None,
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
        let params_entry = wgpu::BindGroupEntry {
            binding: 0,
            resource: params.as_entire_binding(),
        };
        let map_entry = match entry {
            "probe_buffer" => wgpu::BindGroupEntry {
                binding: 5,
                resource: map_buffer.as_entire_binding(),
            },
            "probe_texture" => wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::TextureView(&atlas_view),
            },
            "probe_sampled" => wgpu::BindGroupEntry {
                binding: 6,
                resource: wgpu::BindingResource::TextureView(&cells_view),
            },
            _ => wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(&cells_view),
            },
        };
        let mut entries = vec![
            map_entry,
            wgpu::BindGroupEntry {
                binding: 3,
                resource: out.as_entire_binding(),
            },
        ];
        if entry == "probe_atlas" || entry == "probe_sampled" {
            entries.push(params_entry);
        }
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(entry),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let dispatch = || {
            let mut encoder = device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.dispatch_workgroups(invocations.div_ceil(64), 1, 1);
            }
            let t = Instant::now();
            gpu.queue.submit([encoder.finish()]);
            device
                .poll(wgpu::PollType::wait_indefinitely())
                .expect("poll");
            t.elapsed().as_secs_f64() * 1e3
        };
        dispatch(); // compile and warm up
        let ms = median((0..repeats).map(|_| dispatch()).collect());
        let ns = ms * 1e6 / reads as f64;
        rows.push(ProbeRow {
            path: label.into(),
            reads,
            ms,
            ns_per_read: ns,
            speed_vs_cpu: cpu_ns / ns,
        });
        gpu_sums.push(
            gpu.read_pod::<f32>(&out, invocations as usize)
                .expect("probe readback"),
        );
    }
    gpu.check().expect("wgpu errors in the probe");
    // The probe measures the same reads on every path or it measures nothing.
    for sums_gpu in &gpu_sums {
        let worst = sums
            .iter()
            .zip(sums_gpu)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(
            worst < 1e-3,
            "probe: GPU sums differ from the CPU's by {worst}"
        );
    }
    write(
        out_dir,
        gpu.adapter_name(),
        std::env::var("LP_NUM_THREADS").ok(),
        rows,
    );
}

fn write(
    out_dir: &std::path::Path,
    adapter: String,
    lp_num_threads: Option<String>,
    rows: Vec<ProbeRow>,
) {
    let mut md = format!(
        "Measured by `cargo xtask bench` on {} ({} invocations × {READS} bilinear map reads, \
         18 invocations per map, medians; GPU time = submit + wait{}).\n\n",
        if adapter.is_empty() {
            "the CPU only"
        } else {
            &adapter
        },
        rows[0].reads / READS as u64,
        match &lp_num_threads {
            Some(t) => format!(", LP_NUM_THREADS={t}"),
            None => String::new(),
        },
    );
    md += "| path | ms | ns per read | speed against the CPU twin |\n|---|---:|---:|---:|\n";
    for r in &rows {
        md += &format!(
            "| {} | {:.2} | {:.2} | {:.2}× |\n",
            r.path, r.ms, r.ns_per_read, r.speed_vs_cpu
        );
    }
    let report = ProbeReport {
        adapter,
        lp_num_threads,
        rows,
    };
    write_results(out_dir, "memory_probe", &report, md);
}
