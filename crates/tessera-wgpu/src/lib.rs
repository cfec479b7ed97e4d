//! # tessera-wgpu
//!
//! The embeddable wgpu stage of tessera. Surfaces go up to the GPU once; WGSL compute
//! kernels decide where detail is needed and write a vertex buffer, an index buffer and
//! indexed indirect draw arguments that any render pass can draw.
//!
//! Every stage has one shape, as glyphon's and egui-wgpu's renderers do:
//! `new(&Device, &Queue, &Kernels, model, &params)` uploads at once;
//! `prepare(&Device, &Queue, &mut CommandEncoder)` records a run into the caller's
//! encoder (parameters written through the queue, buffers grown through the device);
//! [`MeshBuffers`] from `output()` draw with `draw_indexed_indirect`. Nothing is ever
//! submitted on the caller's behalf.
//!
//! | item | what |
//! |---|---|
//! | [`bezier::BezierStage`] | Bézier patches, displacement-map edge tests (Espino et al. 2005) |
//! | [`catmull_clark::CcStage`] | Catmull-Clark surfaces, adaptive with a guaranteed error (Lai and Cheng 2005) |
//! | [`catmull_clark::CcUniformStage`] | Catmull-Clark surfaces on a uniform grid: the adaptive stage's peer |
//! | [`Kernels`] | the compiled kernels of one device, shared by its stages |
//! | [`MeshBuffers`] | the vertex, index and indirect-draw buffers a stage leaves |
//! | [`GpuTimer`], [`RunTimestamps`] | the GPU time of a run, by timestamp queries |
//! | [`MeshRenderer`] | a lit (optionally wireframe) renderer for a stage's output |
//! | [`headless`], [`image_out`], [`snapshot`] | feature `headless` (default): a device without a window, offscreen PNG renders, image comparison |
//!
//! ```no_run
//! use tessera_wgpu::{bezier::BezierStage, tessera_core::bezier::{AdaptiveParams, BezierModel, EdgeTest, PreparedBezier}, Kernels};
//! # fn frame(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), Box<dyn std::error::Error>> {
//! let model = BezierModel::load(std::path::Path::new("assets/teaset/teapot"))?;
//! let params = AdaptiveParams { test: EdgeTest::Map4p, threshold: 0.01, max_depth: 6 };
//! let kernels = Kernels::new(device);
//! let mut stage = BezierStage::new(device, queue, &kernels, &PreparedBezier::new(&model), &params)?;
//! let mut encoder = device.create_command_encoder(&Default::default());
//! stage.prepare(device, queue, &mut encoder)?;
//! // … then a render pass that binds `stage.output().vertices()` and `indices()` and calls
//! // `draw_indexed_indirect(stage.output().indirect(), 0)`, then the caller submits.
//! queue.submit([encoder.finish()]);
//! # Ok(()) }
//! ```

#![deny(missing_docs)]

pub use tessera_core;
pub use wgpu;
// In the public API: models, views and bounds are glam vectors.
pub use glam;
/// Renders are `image` buffers (feature `headless`).
#[cfg(feature = "headless")]
pub use image;

pub mod bezier;
pub mod catmull_clark;
mod error;
#[cfg(feature = "headless")]
pub mod headless;
#[cfg(feature = "headless")]
pub mod image_out;
mod kernel;
mod kernels;
mod output;
mod readback;
mod render;
// The prefix sum and the shader sources are public for the tests that compare the scan
// with its CPU twin and validate every kernel with naga; they are not the embedding API.
#[doc(hidden)]
pub mod scan;
#[doc(hidden)]
pub mod shaders;
#[cfg(feature = "headless")]
pub mod snapshot;
mod stage;

pub use error::{Error, Result};
pub use kernels::Kernels;
pub use output::MeshBuffers;
pub use render::{MeshRenderer, RenderOptions};
pub use stage::{GpuTimer, RunTimestamps};
pub use tessera_core::{Pose, View};
