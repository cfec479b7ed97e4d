//! # tessera-core
//!
//! The pure-data half of tessera: surfaces and their loaders, the CPU reference
//! tessellators (the twins of the WGSL kernels), error measurement, watertightness
//! checks, exporters, and the `#[repr(C)]` structs shared with the shaders. No wgpu.
//!
//! ```
//! use tessera_core::bezier::{BezierModel, PreparedBezier, AdaptiveParams, EdgeTest, tessellate_adaptive};
//! # let teapot = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/teaset/teapot");
//! let model = BezierModel::load(std::path::Path::new(teapot))?;
//! let prepared = PreparedBezier::new(&model);
//! let params = AdaptiveParams { test: EdgeTest::Map4p, threshold: 0.01, max_depth: 6 };
//! let out = tessellate_adaptive(&prepared, &params)?;
//! assert!(out.mesh.triangle_count() > 552);
//! # Ok::<(), tessera_core::Error>(())
//! ```

#![deny(missing_docs)]

pub mod bezier;
pub mod catmull_clark;
pub mod error;
pub mod gpu_types;
pub mod io;
pub mod measure;
pub mod mesh;
pub mod scan;
pub mod tolerance;
pub mod view;
pub mod watertight;
pub mod weld;

pub use error::{Error, Result};
pub use mesh::Mesh;
pub use tolerance::Tolerance;
pub use view::{Pose, View};
