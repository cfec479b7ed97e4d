//! A lit renderer for the stage's output, embeddable in any render pass in the style of
//! glyphon or egui-wgpu: create a [`MeshRenderer`] once for the pass's formats, call
//! [`prepare`](MeshRenderer::prepare) before the pass and [`draw`](MeshRenderer::draw)
//! inside it. The draw is `draw_indexed_indirect` on the stage's buffers, so the index
//! count written by the GPU is never read back.
//!
//! Shading: two-sided Lambert from a key and a fill light fixed relative to the camera,
//! hemispheric ambient and a Blinn-Phong highlight on a neutral material; back faces (the
//! side the normals point away from) in a second colour, so holes and flipped patches
//! show; optionally each face (Bézier patch, Catmull-Clark control face) is tinted by its
//! id.
//!
//! Wireframe: WebGPU has no `primitive_index` or barycentrics without extra features, and
//! the triangles share indexed vertices, so the triangle edges cannot be found in the
//! fragment shader. The overlay is instead the same indirect draw a second time through a
//! [`wgpu::PolygonMode::Line`] pipeline, which needs [`wgpu::Features::POLYGON_MODE_LINE`]
//! (Vulkan, Metal, DX12 and lavapipe have it). Its vertices are pulled toward the eye by a
//! small fraction of their distance so the lines pass the depth test on the surface they
//! lie on. Without the feature [`MeshRenderer::wireframe_available`] is `false` and the
//! mesh is drawn shaded only.

use std::sync::atomic::{AtomicBool, Ordering};

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use tessera_core::View;

use crate::output::MeshBuffers;

/// What [`MeshRenderer::prepare`] sets for the following draws.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Draw the triangle edges over the surface (when [`MeshRenderer::wireframe_available`]).
    pub wireframe: bool,
    /// Tint each face (a Bézier patch, a Catmull-Clark control face: the vertices' face
    /// id) by a colour hashed from its id, so faces can be told apart.
    pub patch_tint: bool,
    /// Base colour of the surface, linear RGB.
    pub base_color: [f32; 3],
    /// Colour of back faces (the side the normals point away from, seen through holes
    /// and inside open models), linear RGB; the base colour to not distinguish them.
    pub back_color: [f32; 3],
    /// Strength of the specular highlight (0: none).
    pub specular: f32,
    /// Colour and opacity of the wireframe, linear RGBA.
    pub wire_color: [f32; 4],
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            wireframe: false,
            patch_tint: false,
            // A soft blue-grey glaze (sRGB about #8fa3bd).
            base_color: [0.27, 0.36, 0.51],
            // Muted terracotta, darker than the front.
            back_color: [0.36, 0.16, 0.08],
            specular: 0.35,
            wire_color: [0.02, 0.03, 0.08, 0.55],
        }
    }
}

/// The uniform block of `render_mesh.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Uniforms {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    key: [f32; 4],
    fill: [f32; 4],
    up: [f32; 4],
    base: [f32; 4],
    back: [f32; 4],
    wire: [f32; 4],
    flags: [u32; 4],
}

/// Fraction of its distance to the eye by which a wire vertex moves toward the eye.
const WIRE_PULL: f32 = 1.0 / 400.0;

/// Pipelines and uniforms to draw [`MeshBuffers`] into a pass with the formats given to
/// [`new`](Self::new).
pub struct MeshRenderer {
    shaded: wgpu::RenderPipeline,
    wire: Option<wgpu::RenderPipeline>,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    encode_srgb: bool,
    wire_enabled: AtomicBool,
}

impl MeshRenderer {
    /// The features the renderer uses when the adapter has them: `POLYGON_MODE_LINE` for
    /// the wireframe. Add them to `DeviceDescriptor::required_features`.
    pub fn required_features(adapter_features: wgpu::Features) -> wgpu::Features {
        adapter_features & wgpu::Features::POLYGON_MODE_LINE
    }

    /// Pipelines for a pass with one colour attachment of `color_format`, an optional
    /// depth attachment of `depth_format` (depth test `Less`, written), and
    /// `sample_count` samples. Colours are encoded to sRGB in the shader when
    /// `color_format` is not an sRGB format.
    pub fn new(
        device: &wgpu::Device,
        color_format: wgpu::TextureFormat,
        depth_format: Option<wgpu::TextureFormat>,
        sample_count: u32,
    ) -> Self {
        let module = crate::shaders::module(device, "render_mesh.wgsl", &[]);
        let bind_group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tessera render uniforms"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<Uniforms>() as u64),
                },
                count: None,
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("tessera render"),
            bind_group_layouts: &[Some(&bind_group_layout)],
            immediate_size: 0,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tessera render uniforms"),
            size: std::mem::size_of::<Uniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tessera render uniforms"),
            layout: &bind_group_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            }],
        });

        let pipeline = |label, vs, fs, polygon_mode, blend, depth_write| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers: &[Some(MeshBuffers::VERTEX_LAYOUT)],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: None,
                    polygon_mode,
                    ..Default::default()
                },
                depth_stencil: depth_format.map(|format| wgpu::DepthStencilState {
                    format,
                    depth_write_enabled: Some(depth_write),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: wgpu::MultisampleState {
                    count: sample_count,
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: color_format,
                        blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let shaded = pipeline(
            "tessera shaded",
            "vs_main",
            "fs_shaded",
            wgpu::PolygonMode::Fill,
            None,
            true,
        );
        let wire = device
            .features()
            .contains(wgpu::Features::POLYGON_MODE_LINE)
            .then(|| {
                pipeline(
                    "tessera wireframe",
                    "vs_wire",
                    "fs_wire",
                    wgpu::PolygonMode::Line,
                    Some(wgpu::BlendState::ALPHA_BLENDING),
                    false,
                )
            });
        MeshRenderer {
            shaded,
            wire,
            uniforms,
            bind_group,
            encode_srgb: !color_format.is_srgb(),
            wire_enabled: AtomicBool::new(false),
        }
    }

    /// Whether the device has `POLYGON_MODE_LINE`, which the wireframe overlay needs.
    pub fn wireframe_available(&self) -> bool {
        self.wire.is_some()
    }

    /// Writes the view and options for the next [`draw`](Self::draw)s: the mesh is drawn
    /// in the view's model space ([`View::with_model`]).
    pub fn prepare(&self, queue: &wgpu::Queue, view: &View, options: &RenderOptions) {
        // Lit in model space: the eye, the lights and up brought there from the view.
        let model_to_view = (view.view_matrix() * view.model_matrix()).as_mat4();
        let view_to_model = model_to_view.inverse();
        let world_to_model = view.model_matrix().inverse().as_mat4();
        // Lights fixed relative to the camera: the key from the upper left and in front,
        // a weaker fill from the right and slightly below.
        let to_model = |x: f32, y: f32, z: f32| {
            view_to_model
                .transform_vector3(Vec3::new(x, y, z))
                .normalize_or(Vec3::Z)
                .extend(0.0)
                .to_array()
        };
        let mut key = to_model(-0.45, 0.65, 0.6);
        key[3] = 0.85;
        let mut fill = to_model(0.7, -0.15, 0.45);
        fill[3] = 0.25;
        let eye = view_to_model.transform_point3(Vec3::ZERO);
        let up = world_to_model
            .transform_vector3(view.up().as_vec3())
            .normalize_or(Vec3::Z);
        let [r, g, b] = options.base_color;
        let u = Uniforms {
            view_proj: view.clip_matrix().as_mat4().to_cols_array_2d(),
            eye: eye.extend(WIRE_PULL).to_array(),
            key,
            fill,
            up: up.extend(0.22).to_array(),
            base: [r, g, b, options.specular.max(0.0)],
            back: [
                options.back_color[0],
                options.back_color[1],
                options.back_color[2],
                0.0,
            ],
            wire: options.wire_color,
            flags: [options.patch_tint as u32, self.encode_srgb as u32, 0, 0],
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        self.wire_enabled
            .store(options.wireframe, Ordering::Relaxed);
    }

    /// Draws `mesh` with the last prepared view and options: shaded, then the wireframe
    /// when it was asked for and is available. Sets the pipeline, bind group 0, vertex
    /// buffer 0 and the index buffer of `pass`.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, mesh: &MeshBuffers) {
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, mesh.vertices().slice(..));
        pass.set_index_buffer(mesh.indices().slice(..), wgpu::IndexFormat::Uint32);
        pass.set_pipeline(&self.shaded);
        pass.draw_indexed_indirect(mesh.indirect(), 0);
        if let (Some(wire), true) = (&self.wire, self.wire_enabled.load(Ordering::Relaxed)) {
            pass.set_pipeline(wire);
            pass.draw_indexed_indirect(mesh.indirect(), 0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn render_shader_validates() {
        let src = crate::shaders::source("render_mesh.wgsl");
        let module = naga::front::wgsl::parse_str(&src).expect("render_mesh.wgsl parses");
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&module)
        .expect("render_mesh.wgsl validates");
    }

    #[test]
    fn uniforms_match_the_shader_block() {
        // mat4 + 8 vec4: the WGSL struct has no padding.
        assert_eq!(std::mem::size_of::<Uniforms>(), 64 + 8 * 16);
    }
}
