//! The Bézier path (Espino et al. 2005): bicubic patches, their coarse tessellation and
//! displacement maps, the map-based edge tests and the refinement of each coarse triangle.
//!
//! Folders follow the pipeline: [`model`]/[`topology`] (what the surface is and how its
//! patches connect), [`patch`] (evaluation), [`prepare`] (what is uploaded once), then
//! the CPU twins of the kernels: [`edge_tests`], [`coarse_edges`], [`lattice`]/[`refine`] and
//! the stage script [`tessellate`]. [`uniform`] is the peer every result is compared to.

pub mod coarse_edges;
pub mod edge_tests;
pub mod lattice;
pub mod model;
pub mod patch;
pub mod prepare;
pub mod refine;
pub mod search;
pub mod tessellate;
pub mod topology;
pub mod uniform;

pub use edge_tests::EdgeTest;
pub use model::BezierModel;
pub use patch::BezierPatch;
pub use prepare::PreparedBezier;
pub use tessellate::{tessellate_adaptive, AdaptiveParams, Tessellation};
pub use uniform::tessellate_uniform;
