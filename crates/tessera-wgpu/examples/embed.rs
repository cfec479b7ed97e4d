//! tessera inside a renderer of your own: the renderer creates its device, keeps its
//! pipeline and its render pass, and puts two tessera stages in front of that pass.
//!
//! ```text
//! cargo run --release -p tessera-wgpu --example embed -- OUT.png
//! ```
//!
//! Each frame records, into one command encoder, the stages' compute passes and then the
//! renderer's own render pass, which draws the stages' buffers with
//! `draw_indexed_indirect`: the Utah teapot (Bézier patches) on the left, a Catmull-Clark
//! torus whose control points move from frame to frame (`update_points`) on the right.
//! The last frame is written to OUT.png.

use std::path::Path;

use tessera_wgpu::bezier::BezierStage;
use tessera_wgpu::catmull_clark::CcStage;
use tessera_wgpu::glam::{Mat4, Vec3};
use tessera_wgpu::tessera_core::bezier::{AdaptiveParams, BezierModel, EdgeTest, PreparedBezier};
use tessera_wgpu::tessera_core::catmull_clark::{load_surface, CcParams, ViewTolerance};
use tessera_wgpu::tessera_core::{io::load_control_mesh, Tolerance};
use tessera_wgpu::{wgpu, Kernels, MeshBuffers, View};

/// Width and height of the frame.
pub const SIZE: (u32, u32) = (640, 320);
/// Frames rendered; the control points move between them.
pub const FRAMES: u32 = 4;

const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The renderer's own shader: tessera's vertices at its locations 0 (position) and
/// 1 (normal), lit from the camera.
const SHADER: &str = r#"
struct Uniforms { view_proj: mat4x4<f32>, color: vec4<f32> }
@group(0) @binding(0) var<uniform> u: Uniforms;

struct Out { @builtin(position) clip: vec4<f32>, @location(0) normal: vec3<f32> }

@vertex
fn vs(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> Out {
    return Out(u.view_proj * vec4(position, 1.0), normal);
}

@fragment
fn fs(in: Out) -> @location(0) vec4<f32> {
    let light = abs(dot(normalize(in.normal), normalize(vec3(0.3, -0.8, 0.5))));
    return vec4(u.color.rgb * (0.25 + 0.75 * light), 1.0);
}
"#;

fn main() -> std::process::ExitCode {
    let Some(out) = std::env::args_os().nth(1) else {
        eprintln!("usage: embed OUT.png");
        return std::process::ExitCode::from(2);
    };
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let result = run(&assets, FRAMES).and_then(|frame| {
        frame
            .save(&out)
            .map_err(|e| format!("{}: {e}", Path::new(&out).display()).into())
    });
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

type Error = Box<dyn std::error::Error>;

/// Renders `frames` frames and returns the last one. Any wgpu validation error fails it.
pub fn run(assets: &Path, frames: u32) -> Result<tessera_wgpu::image::RgbaImage, Error> {
    // The renderer's device: tessera only borrows it.
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("embedding renderer"),
        // tessera's kernels bind large storage buffers for large models.
        required_limits: wgpu::Limits {
            max_storage_buffer_binding_size: adapter.limits().max_storage_buffer_binding_size,
            max_buffer_size: adapter.limits().max_buffer_size,
            ..wgpu::Limits::default()
        },
        ..Default::default()
    }))?;
    let errors = device.push_error_scope(wgpu::ErrorFilter::Validation);

    // Once: load, prepare on the CPU, upload. One kernel set serves both stages.
    let kernels = Kernels::new(&device);
    let teapot = BezierModel::load(&assets.join("teaset/teapot"))?;
    let mut bezier = BezierStage::new(
        &device,
        &queue,
        &kernels,
        &PreparedBezier::new(&teapot),
        &AdaptiveParams {
            test: EdgeTest::Map4p,
            threshold: 0.002 * teapot.bbox_diag() as f32,
            max_depth: AdaptiveParams::DEFAULT_MAX_DEPTH,
        },
    )?;
    let torus_path = assets.join("opensubdiv/catmark_torus.obj");
    let torus = load_surface(&torus_path)?;
    let rest: Vec<Vec3> = load_control_mesh(&torus_path)?
        .positions
        .iter()
        .map(|p| p.as_vec3())
        .collect();
    let mut cc = CcStage::new(
        &device,
        &queue,
        &kernels,
        &torus,
        &CcParams {
            tolerance: Tolerance::Relative(2e-3),
            max_depth: 8,
            first_split: Default::default(),
            leaf_bound: Default::default(),
        },
    )?;
    // After loading, grow the buffers to fit before the first frame (later growth, when
    // the points move, happens in `prepare`, a frame late).
    bezier.run_blocking(&device, &queue)?;
    cc.run_blocking(&device, &queue)?;

    // The renderer's own pipeline and targets.
    let renderer = Renderer::new(&device);
    let teapot_view = view(&teapot.bounds(), Vec3::Z).clip_matrix().as_mat4();
    let torus_camera = view(&bounds(&rest), Vec3::Z);
    let torus_view = torus_camera.clip_matrix().as_mat4();

    for frame in 0..frames {
        // A breathing torus: only its control points go up.
        let t = frame as f32 / frames.max(1) as f32 * std::f32::consts::TAU;
        let moved: Vec<Vec3> = rest
            .iter()
            .map(|p| *p * (1.0 + 0.15 * (t + 2.0 * p.z).sin()))
            .collect();
        cc.update_points(&queue, &moved)?;
        // The camera of this frame: detail within a pixel of it, at most 2e-3 of the
        // model's size, patches out of view culled (a camera that moves writes its view
        // the same way).
        cc.set_view(
            &queue,
            Some(&ViewTolerance {
                view: torus_camera,
                pixels: Some(1.0),
                cull: true,
                cull_backfaces: false,
                max_triangles: Some(500_000),
                face_leaves: false,
            }),
        )?;

        let mut encoder = device.create_command_encoder(&Default::default());
        // The teapot is still: tessellated once, drawn every frame.
        if frame == 0 {
            bezier.prepare(&device, &queue, &mut encoder)?;
        }
        cc.prepare(&device, &queue, &mut encoder)?;
        renderer.draw(
            &queue,
            &mut encoder,
            [
                (bezier.output(), teapot_view, [0.85, 0.55, 0.35]),
                (cc.output(), torus_view, [0.35, 0.55, 0.85]),
            ],
        );
        queue.submit([encoder.finish()]);
    }
    let last = cc.read_status(&device)?;
    if last.overflowed() {
        return Err("the last frame's tessellation did not fit its buffers".into());
    }
    let image = renderer.read_frame(&device, &queue)?;
    if let Some(e) = pollster::block_on(errors.pop()) {
        return Err(format!("wgpu: {e}").into());
    }
    Ok(image)
}

/// A camera framing `bounds` in one half of the frame.
fn view(bounds: &(Vec3, Vec3), up: Vec3) -> View {
    let half = (SIZE.0 / 2, SIZE.1);
    let (lo, hi) = (bounds.0.as_dvec3(), bounds.1.as_dvec3());
    View::framing_along(lo, hi, half, View::FRAMING_DIRECTION, up.as_dvec3())
}

fn bounds(points: &[Vec3]) -> (Vec3, Vec3) {
    points.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

/// A minimal forward renderer: one pipeline over tessera's vertex layout, a uniform
/// buffer per model, an sRGB colour target and a depth buffer.
struct Renderer {
    pipeline: wgpu::RenderPipeline,
    uniforms: [(wgpu::Buffer, wgpu::BindGroup); 2],
    color: wgpu::Texture,
    depth: wgpu::TextureView,
}

impl Renderer {
    fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("embedding renderer"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("embedding renderer"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(MeshBuffers::VERTEX_LAYOUT)],
            },
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(COLOR_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let uniform = || {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("embedding renderer uniforms"),
                size: 80,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }],
            });
            (buffer, bind_group)
        };
        let target = |format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: None,
                size: wgpu::Extent3d {
                    width: SIZE.0,
                    height: SIZE.1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | usage,
                view_formats: &[],
            })
        };
        Renderer {
            uniforms: [uniform(), uniform()],
            color: target(COLOR_FORMAT, wgpu::TextureUsages::COPY_SRC),
            depth: target(DEPTH_FORMAT, wgpu::TextureUsages::empty())
                .create_view(&Default::default()),
            pipeline,
        }
    }

    /// The renderer's render pass: each mesh in its half of the frame, drawn with the
    /// draw arguments the GPU wrote.
    fn draw(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        meshes: [(&MeshBuffers, Mat4, [f32; 3]); 2],
    ) {
        for ((_, view_proj, color), (buffer, _)) in meshes.iter().zip(&self.uniforms) {
            let mut bytes = view_proj.to_cols_array().to_vec();
            bytes.extend([color[0], color[1], color[2], 1.0]);
            queue.write_buffer(buffer, 0, bytemuck::cast_slice(&bytes));
        }
        let color = self.color.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("embedding renderer"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &color,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 0.9,
                        g: 0.9,
                        b: 0.92,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        let half = SIZE.0 as f32 / 2.0;
        for (i, ((mesh, _, _), (_, bind_group))) in meshes.iter().zip(&self.uniforms).enumerate() {
            pass.set_viewport(i as f32 * half, 0.0, half, SIZE.1 as f32, 0.0, 1.0);
            pass.set_bind_group(0, bind_group, &[]);
            pass.set_vertex_buffer(0, mesh.vertices().slice(..));
            pass.set_index_buffer(mesh.indices().slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed_indirect(mesh.indirect(), 0);
        }
    }

    /// The colour target's pixels (a renderer presents them; the example saves them).
    fn read_frame(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<tessera_wgpu::image::RgbaImage, Error> {
        let row = 4 * SIZE.0;
        let padded = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame readback"),
            size: (padded * SIZE.1) as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            self.color.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: None,
                },
            },
            self.color.size(),
        );
        queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        device.poll(wgpu::PollType::wait_indefinitely())?;
        rx.recv()??;
        let pixels: Vec<u8> = staging
            .get_mapped_range(..)?
            .chunks(padded as usize)
            .flat_map(|r| r[..row as usize].to_vec())
            .collect();
        tessera_wgpu::image::RgbaImage::from_raw(SIZE.0, SIZE.1, pixels)
            .ok_or_else(|| "frame size".into())
    }
}
