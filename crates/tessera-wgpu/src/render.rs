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
use glam::{Mat4, Vec3};

use crate::output::MeshBuffers;

/// A perspective camera (right-handed, depth 0 at `near` to 1 at `far`, as wgpu expects).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Where the camera is.
    pub eye: Vec3,
    /// The point it looks at.
    pub target: Vec3,
    /// Up on the screen.
    pub up: Vec3,
    /// Vertical field of view, radians.
    pub fovy: f32,
    /// Width over height.
    pub aspect: f32,
    /// Distance of the near clipping plane.
    pub near: f32,
    /// Distance of the far clipping plane.
    pub far: f32,
}

impl Camera {
    /// Vertical field of view of [`framing`](Self::framing): a mild telephoto, so that the
    /// model is not distorted.
    pub const FRAMING_FOVY: f32 = 30.0 * std::f32::consts::PI / 180.0;

    /// The direction [`framing`](Self::framing) looks from, from the target toward the eye:
    /// front (−Y), a little from the right (+X) and from above (+Z).
    pub const FRAMING_DIRECTION: Vec3 = Vec3::new(0.5, -1.0, 0.45);

    /// World to view space (`look_at_rh`).
    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.eye, self.target, self.up)
    }

    /// View to clip space (`perspective_rh`).
    pub fn projection(&self) -> Mat4 {
        Mat4::perspective_rh(self.fovy, self.aspect, self.near, self.far)
    }

    /// World to clip space.
    pub fn view_proj(&self) -> Mat4 {
        self.projection() * self.view()
    }

    /// A 3/4 view of the box `min..max` for models with +Z up (the Newell teaset): from
    /// the front-right and above, looking at the box's centre, at the distance where
    /// every corner of the box is inside the view with a small margin.
    pub fn framing(min: Vec3, max: Vec3, aspect: f32) -> Camera {
        Self::framing_along(min, max, aspect, Self::FRAMING_DIRECTION, Vec3::Z)
    }

    /// Frames the box `min..max` from `direction` (target toward eye) with `up` up.
    /// Near and far planes enclose the box's bounding sphere. A box that is empty or not
    /// finite is treated as the unit cube around the origin; a point as a unit sphere.
    pub fn framing_along(min: Vec3, max: Vec3, aspect: f32, direction: Vec3, up: Vec3) -> Camera {
        let (min, max) = if min.is_finite() && max.is_finite() && min.cmple(max).all() {
            (min, max)
        } else {
            (Vec3::splat(-0.5), Vec3::splat(0.5))
        };
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let center = 0.5 * (min + max);
        let radius = match 0.5 * (max - min).length() {
            r if r > 0.0 => r,
            _ => 1.0,
        };
        let back = direction
            .try_normalize()
            .unwrap_or(Self::FRAMING_DIRECTION.normalize());
        let up = if up.cross(back).length_squared() > 1e-6 {
            up.normalize()
        } else {
            back.any_orthonormal_vector()
        };
        // Camera basis: `back` toward the eye, `right`, `cam_up`.
        let right = up.cross(back).normalize();
        let cam_up = back.cross(right);
        const MARGIN: f32 = 0.95;
        let tan_y = (0.5 * Self::FRAMING_FOVY).tan() * MARGIN;
        let tan_x = tan_y * aspect;
        // A corner at (x, y, z) in the camera basis relative to the centre is at depth
        // d − z from an eye at distance d; it fits when |x| ≤ (d − z)·tan_x and likewise y.
        let mut distance = 0.0f32;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            ) - center;
            let (x, y, z) = (corner.dot(right), corner.dot(cam_up), corner.dot(back));
            distance = distance.max(z + x.abs() / tan_x).max(z + y.abs() / tan_y);
        }
        let distance = distance.max(radius * 1.05);
        Camera {
            eye: center + back * distance,
            target: center,
            up,
            fovy: Self::FRAMING_FOVY,
            aspect,
            near: (distance - radius * 1.05).max(radius * 0.01),
            far: distance + radius * 1.05,
        }
    }
}

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

    /// Writes the camera and options for the next [`draw`](Self::draw)s.
    pub fn prepare(&self, queue: &wgpu::Queue, camera: &Camera, options: &RenderOptions) {
        let view = camera.view().inverse();
        // Lights fixed relative to the camera: the key from the upper left and in front,
        // a weaker fill from the right and slightly below.
        let to_world = |x: f32, y: f32, z: f32| {
            view.transform_vector3(Vec3::new(x, y, z))
                .normalize_or(Vec3::Z)
                .extend(0.0)
                .to_array()
        };
        let mut key = to_world(-0.45, 0.65, 0.6);
        key[3] = 0.85;
        let mut fill = to_world(0.7, -0.15, 0.45);
        fill[3] = 0.25;
        let up = camera.up.normalize_or(Vec3::Z);
        let [r, g, b] = options.base_color;
        let u = Uniforms {
            view_proj: camera.view_proj().to_cols_array_2d(),
            eye: camera.eye.extend(WIRE_PULL).to_array(),
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

    /// Draws `mesh` with the last prepared camera and options: shaded, then the wireframe
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

    fn corners(min: Vec3, max: Vec3) -> impl Iterator<Item = Vec3> {
        (0..8).map(move |i| {
            Vec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            )
        })
    }

    #[test]
    fn framing_keeps_every_corner_in_view_and_depth_range() {
        let boxes = [
            (Vec3::new(-3.0, -2.0, 0.0), Vec3::new(3.4, 2.0, 3.15)), // teapot-like
            (Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 10.0, 0.1)),
            (Vec3::splat(2.0), Vec3::splat(2.0)),
        ];
        for (min, max) in boxes {
            for aspect in [0.5, 1.0, 4.0 / 3.0, 2.0] {
                let cam = Camera::framing(min, max, aspect);
                let vp = cam.view_proj();
                let mut widest = 0.0f32;
                for c in corners(min, max) {
                    let p = vp.project_point3(c);
                    assert!(
                        p.x.abs() <= 1.0 && p.y.abs() <= 1.0,
                        "{min} {max} {aspect}: {p}"
                    );
                    assert!((0.0..=1.0).contains(&p.z), "{min} {max} {aspect}: {p}");
                    widest = widest.max(p.x.abs()).max(p.y.abs());
                }
                if min != max {
                    // Framed, not lost in the middle of the image.
                    assert!(widest > 0.8, "{min} {max} {aspect}: {widest}");
                }
            }
        }
    }

    #[test]
    fn framing_looks_from_front_right_above_with_z_up() {
        let cam = Camera::framing(Vec3::splat(-1.0), Vec3::splat(1.0), 1.0);
        let d = cam.eye - cam.target;
        assert!(d.x > 0.0 && d.y < 0.0 && d.z > 0.0, "{d}");
        assert_eq!(cam.up, Vec3::Z);
        // +Z projects upward on screen.
        let vp = cam.view_proj();
        assert!(vp.project_point3(Vec3::Z).y > vp.project_point3(Vec3::ZERO).y);
    }

    #[test]
    fn framing_survives_degenerate_input() {
        for (min, max) in [
            (Vec3::splat(f32::NAN), Vec3::ONE),
            (Vec3::ONE, Vec3::ZERO),
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::INFINITY)),
        ] {
            let cam = Camera::framing_along(min, max, 0.0, Vec3::ZERO, Vec3::ZERO);
            assert!(cam.view_proj().is_finite(), "{min} {max}");
            assert!(cam.near > 0.0 && cam.far > cam.near);
        }
    }

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
