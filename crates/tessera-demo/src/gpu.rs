//! The window's device and surface, and the frame: the scene drawn as `tessera render`
//! draws an image (4× multisampled sRGB target, depth, the same background), the panel
//! over it, then copied to the surface. The frame texture is what a screenshot saves.

use std::sync::{Arc, Mutex};

use tessera_wgpu::image_out::{begin_scene_pass, sample_count, COLOR_FORMAT, DEPTH_FORMAT};
use tessera_wgpu::{wgpu, MeshRenderer};
use winit::window::Window;

/// wgpu errors kept (the first ones: later ones are usually their consequences).
const MAX_ERRORS: usize = 100;

/// The adapter, device, queue and the window's surface, with every wgpu error the device
/// reported (validation errors included) collected for the panel.
pub struct Gpu {
    instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// Whether `config` has been applied (never with a zero size).
    configured: bool,
    /// The surface's format without sRGB encoding: the copy writes the frame's bytes.
    pub view_format: wgpu::TextureFormat,
    pub errors: Arc<Mutex<Vec<String>>>,
}

impl Gpu {
    /// Opens the device for `window`'s surface: the first adapter wgpu finds that can
    /// present to it (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME` narrow the choice), with the
    /// stage's limits, the wireframe's feature and timestamp queries where the adapter
    /// has them.
    pub fn new(
        display: winit::event_loop::OwnedDisplayHandle,
        window: Arc<Window>,
        vsync: bool,
    ) -> Result<Gpu, String> {
        let mut desc =
            wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(display));
        if std::env::var_os("WGPU_BACKEND").is_none() {
            // As the CLI: Vulkan, Metal, DX12; the stage's kernels are not for GL.
            desc.backends = wgpu::Backends::PRIMARY;
        }
        let instance = wgpu::Instance::new(desc);
        let surface = instance
            .create_surface(window.clone())
            // No backend at all (no Vulkan loader, say) is no adapter to the user.
            .map_err(|e| {
                tessera_wgpu::Error::NoAdapter(format!("no backend can draw to the window: {e}"))
                    .to_string()
            })?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|e| tessera_wgpu::Error::NoAdapter(e.to_string()).to_string())?;
        let features = MeshRenderer::required_features(adapter.features())
            | (adapter.features() & wgpu::Features::TIMESTAMP_QUERY);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("tessera-demo"),
            required_features: features,
            required_limits: tessera_wgpu::bezier::required_limits(&adapter.limits()),
            ..Default::default()
        }))
        .map_err(|e| tessera_wgpu::Error::RequestDevice(e.to_string()).to_string())?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                // One line each: the panel lists them and stderr prints them. An error
                // repeated every frame must not grow the list without end.
                if v.len() < MAX_ERRORS {
                    v.push(
                        e.to_string()
                            .split_whitespace()
                            .collect::<Vec<_>>()
                            .join(" "),
                    );
                }
            }
        }));
        let caps = surface.get_capabilities(&adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f.remove_srgb_suffix(),
                    wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
                )
            })
            .ok_or_else(|| {
                format!(
                    "the window's surface offers no 8-bit RGBA or BGRA format ({:?})",
                    caps.formats
                )
            })?;
        let view_format = format.remove_srgb_suffix();
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.width,
            height: size.height,
            present_mode: if vsync {
                wgpu::PresentMode::AutoVsync
            } else {
                wgpu::PresentMode::AutoNoVsync
            },
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: if view_format == format {
                vec![]
            } else {
                vec![view_format]
            },
        };
        let mut gpu = Gpu {
            instance,
            adapter,
            device,
            queue,
            surface,
            config,
            configured: false,
            view_format,
            errors,
        };
        gpu.resize(size.width, size.height);
        Ok(gpu)
    }

    pub fn adapter_name(&self) -> String {
        let i = self.adapter.get_info();
        format!("{} ({:?}, {:?})", i.name, i.backend, i.device_type)
    }

    /// The surface's size (what the frame is drawn at).
    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// Configures the surface for a new window size; a zero size (minimised) is kept
    /// for later and never configured.
    pub fn resize(&mut self, width: u32, height: u32) {
        // A window larger than the device's textures is drawn at the largest size and
        // stretched by the presentation.
        let max = self.device.limits().max_texture_dimension_2d;
        self.config.width = width.min(max);
        self.config.height = height.min(max);
        self.configured = false;
        self.configure();
    }

    fn configure(&mut self) {
        if self.config.width > 0 && self.config.height > 0 {
            self.surface.configure(&self.device, &self.config);
            self.configured = true;
        }
    }

    /// The surface's next texture, or `None` to skip this frame: the surface was
    /// reconfigured (outdated, suboptimal) or made anew (lost) for the next one, or the
    /// window is hidden or timed out.
    pub fn acquire(&mut self, window: &Arc<Window>) -> Option<wgpu::SurfaceTexture> {
        if !self.configured {
            return None;
        }
        match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => Some(t),
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                // Draw this one; the next is acquired from a fresh configuration.
                self.configured = false;
                Some(t)
            }
            wgpu::CurrentSurfaceTexture::Outdated => {
                self.sync_size(window);
                None
            }
            wgpu::CurrentSurfaceTexture::Lost => {
                match self.instance.create_surface(window.clone()) {
                    Ok(surface) => {
                        self.surface = surface;
                        self.sync_size(window);
                    }
                    Err(e) => self.push_error(format!("the surface was lost: {e}")),
                }
                None
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => None,
            wgpu::CurrentSurfaceTexture::Validation => {
                // The error itself reached the uncaptured-error handler.
                None
            }
        }
    }

    /// Reconfigures if a suboptimal frame asked for it.
    pub fn reconfigure_if_needed(&mut self) {
        if !self.configured {
            self.configure();
        }
    }

    fn sync_size(&mut self, window: &Window) {
        let s = window.inner_size();
        self.resize(s.width, s.height);
    }

    pub fn push_error(&self, e: String) {
        if let Ok(mut v) = self.errors.lock() {
            if v.len() < MAX_ERRORS {
                v.push(e);
            }
        }
    }

    /// Every wgpu error so far.
    pub fn errors(&self) -> Vec<String> {
        self.errors.lock().map(|v| v.clone()).unwrap_or_default()
    }
}

/// The textures of one frame size: the frame (what is presented and saved), the
/// multisampled colour and depth targets, and the copy's binding of the frame.
pub struct Targets {
    pub size: (u32, u32),
    pub frame: wgpu::Texture,
    pub frame_view: wgpu::TextureView,
    multisampled: Option<wgpu::TextureView>,
    depth: wgpu::TextureView,
    copy_source: wgpu::BindGroup,
}

/// The pipelines that do not depend on the frame's size.
pub struct Painter {
    pub samples: u32,
    pub mesh: MeshRenderer,
    copy: wgpu::RenderPipeline,
    copy_layout: wgpu::BindGroupLayout,
}

/// Copies the frame's bytes to the surface, texel for texel.
const COPY_SHADER: &str = r#"
@group(0) @binding(0) var frame: texture_2d<f32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(p * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(frame, vec2<i32>(p.xy), 0);
}
"#;

/// The frame's bytes as they are (an sRGB-encoded frame read through a plain view).
const RAW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

impl Painter {
    pub fn new(gpu: &Gpu) -> Painter {
        let device = &gpu.device;
        let samples = sample_count(&gpu.adapter);
        let copy_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tessera-demo frame copy"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("tessera-demo frame copy"),
            source: wgpu::ShaderSource::Wgsl(COPY_SHADER.into()),
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("tessera-demo frame copy"),
            bind_group_layouts: &[Some(&copy_layout)],
            immediate_size: 0,
        });
        let copy = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("tessera-demo frame copy"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(gpu.view_format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        Painter {
            samples,
            mesh: MeshRenderer::new(device, COLOR_FORMAT, Some(DEPTH_FORMAT), samples),
            copy,
            copy_layout,
        }
    }

    pub fn targets(&self, device: &wgpu::Device, (width, height): (u32, u32)) -> Targets {
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let texture = |label, format, sample_count, usage, view_formats: &[wgpu::TextureFormat]| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | usage,
                view_formats,
            })
        };
        let frame = texture(
            "tessera-demo frame",
            COLOR_FORMAT,
            1,
            wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
            &[RAW_FORMAT],
        );
        let multisampled = (self.samples > 1).then(|| {
            texture(
                "tessera-demo frame (multisampled)",
                COLOR_FORMAT,
                self.samples,
                wgpu::TextureUsages::empty(),
                &[],
            )
            .create_view(&Default::default())
        });
        let depth = texture(
            "tessera-demo depth",
            DEPTH_FORMAT,
            self.samples,
            wgpu::TextureUsages::empty(),
            &[],
        )
        .create_view(&Default::default());
        let raw = frame.create_view(&wgpu::TextureViewDescriptor {
            format: Some(RAW_FORMAT),
            ..Default::default()
        });
        let copy_source = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tessera-demo frame copy"),
            layout: &self.copy_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&raw),
            }],
        });
        Targets {
            size: (width, height),
            frame_view: frame.create_view(&Default::default()),
            frame,
            multisampled,
            depth,
            copy_source,
        }
    }

    /// The scene's pass: the whole frame cleared to `tessera render`'s background, the
    /// mesh (if any) drawn in `viewport` (x, y, width, height in pixels).
    pub fn draw_scene(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets,
        mesh: Option<&tessera_wgpu::MeshBuffers>,
        viewport: [f32; 4],
    ) {
        let (view, resolve_target) = match &targets.multisampled {
            Some(ms) => (ms, Some(&targets.frame_view)),
            None => (&targets.frame_view, None),
        };
        let mut pass = begin_scene_pass(encoder, view, resolve_target, &targets.depth);
        let [x, y, w, h] = viewport;
        if let Some(mesh) = mesh.filter(|_| w >= 1.0 && h >= 1.0) {
            pass.set_viewport(x, y, w, h, 0.0, 1.0);
            self.mesh.draw(&mut pass, mesh);
        }
    }

    /// Copies the frame to the surface's texture.
    pub fn present_copy(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets,
        surface_view: &wgpu::TextureView,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tessera-demo present"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: surface_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&self.copy);
        pass.set_bind_group(0, &targets.copy_source, &[]);
        pass.draw(0..3, 0..1);
    }
}
