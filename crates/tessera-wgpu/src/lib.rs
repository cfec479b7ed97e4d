//! # tessera-wgpu
//!
//! The embeddable wgpu stage of tessera. Surfaces go up to the GPU once; WGSL compute
//! kernels decide where detail is needed and write a vertex buffer, an index buffer and
//! indexed indirect draw arguments that any render pass can draw.
//!
//! The stage borrows the caller's `Device` and `Queue`, records its passes into the
//! caller's `CommandEncoder`, and never submits on its own.
//!
//! | module | what |
//! |---|---|
//! | [`bezier`] | the Bézier (displacement-map) tessellation stage |
//! | [`catmull_clark`] | the Catmull-Clark stage (in progress: upload and exact evaluation) |
//! | [`output`] | [`MeshBuffers`]: the vertex, index and indirect-draw buffers a stage leaves |
//! | [`render`] | a lit (optionally wireframe) renderer for the stage's output |
//! | [`headless`] | device creation without a window, readback |
//! | [`image_out`] | offscreen rendering to an RGBA image, PNG files |
//! | [`snapshot`] | image comparison with a perceptual tolerance, for snapshot tests |
//! | [`scan`] | the GPU exclusive prefix sum the stages use |
//! | [`shaders`] | the WGSL sources with their shared includes resolved |

pub use tessera_core;
pub use wgpu;
// In the public API: `Camera` and bounds are glam vectors, renders are `image` buffers.
pub use glam;
pub use image;

pub mod bezier;
pub mod catmull_clark;
pub mod error;
pub mod headless;
pub mod image_out;
mod kernel;
pub mod output;
pub mod render;
pub mod scan;
pub mod shaders;
pub mod snapshot;
pub mod stage;

pub use error::{Error, Result};
pub use output::MeshBuffers;
pub use render::{Camera, MeshRenderer, RenderOptions};
