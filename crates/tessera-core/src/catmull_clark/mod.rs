//! The Catmull-Clark path (Lai and Cheng 2005): exact limit evaluation and adaptive
//! tessellation with a guaranteed error bound.
//!
//! Layers, as in OpenSubdiv: [`control_mesh`] (the input) and [`topology`] (validation,
//! the first subdivision step, patches; "Far"); [`refine`] and [`local`] (the
//! subdivision rules, one-rings), [`bicubic`] and [`patch`] (exact evaluation; "Bfr");
//! then the tessellators [`adaptive`] and [`uniform`], with [`bound`] (the flatness bound),
//! [`triangle_bound`] (the distance to known triangles, CPU only), [`keys`] (canonical
//! point keys, and the charts that give every vertex its control face and that face's
//! own `(u, v)`) and [`triangulate`]; [`gpu_model`], [`gpu_uniform`], [`polygon`] and
//! [`vertex_hash`] are the CPU twins of the GPU kernels' data and of kernels; [`faces`]
//! checks an output's face coordinates against the surface.
//!
//! ```
//! use tessera_core::{catmull_clark::{load_surface, tessellate_adaptive, CcParams}, Tolerance};
//! # let cube = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/opensubdiv/catmark_cube.obj");
//! let model = load_surface(std::path::Path::new(cube))?;
//! let params = CcParams {
//!     tolerance: Tolerance::Absolute(1e-3),
//!     max_depth: 8,
//!     first_split: Default::default(),
//!     leaf_bound: Default::default(),
//! };
//! let out = tessellate_adaptive(&model, &params)?;
//! assert_eq!(out.unmet, 0);
//! assert!(out.max_bound <= 1e-3);
//! # Ok::<(), tessera_core::Error>(())
//! ```

pub mod adaptive;
pub mod bicubic;
pub mod bound;
pub mod control_mesh;
pub mod faces;
pub mod facing;
pub mod gpu_model;
pub mod gpu_uniform;
pub mod keys;
pub mod local;
pub mod patch;
pub mod polygon;
pub mod refine;
pub mod stencil;
pub mod topology;
pub mod traverse;
pub mod triangle_bound;
pub mod triangulate;
pub mod uniform;
pub mod vertex_hash;

use std::path::Path;

pub use adaptive::{
    first_splits, tessellate_adaptive, tessellate_adaptive_in_view, CcParams, CcTessellation,
    FirstSplit, LeafBound, ViewTolerance,
};
pub use control_mesh::{BoundaryRule, ControlMesh, CreaseMethod, SHARPNESS_INFINITE};
pub use patch::{PatchSurface, SurfaceModel, SurfacePoint};
pub use topology::PatchMesh;
pub use uniform::tessellate_uniform;

use glam::DVec3;

/// The most midpoint splits of the adaptive method (keys hold 20 bits per coordinate:
/// 840 · 2^10 < 2^20).
pub const MAX_DEPTH: u32 = 10;

/// Levels of each patch's quadtree. Every point of the adaptive grid (units of
/// `1 / (840 · 2^MAX_DEPTH)`, above `2^-20`) and of any uniform grid (up to 4096 segments)
/// then lies in a stored Bézier piece or is the extraordinary vertex itself, so
/// evaluation never subdivides on demand (and the GPU, which cannot, evaluates them all).
pub const TREE_DEPTH: u32 = MAX_DEPTH + 11;

/// Depth of the chain of squares stored at each extraordinary vertex (three Bézier
/// pieces per level): its innermost square, whose one-ring hull the flatness bound adds
/// as a ball, is then `λ^30` of the patch (below 3e-6 of it even at valence 64; deeper, double
/// precision no longer resolves the pieces' derivatives).
pub const CORNER_DEPTH: u32 = 30;

/// Loads a control mesh (OBJ, glTF or GLB by extension), validates it and builds its
/// patches ([`TREE_DEPTH`] levels).
pub fn load_surface(path: &Path) -> crate::Result<SurfaceModel> {
    let mesh = crate::io::load_control_mesh(path)?;
    Ok(SurfaceModel::new(PatchMesh::new(&mesh)?, TREE_DEPTH))
}

/// The patches of `control` ([`PatchMesh::new`]), cut along its non-manifold edges first
/// where `split_non_manifold` ([`ControlMesh::split_non_manifold`]); without it, the error
/// for such an edge names the `--split-non-manifold` option the tessera tools take.
pub fn patch_mesh(control: &mut ControlMesh, split_non_manifold: bool) -> crate::Result<PatchMesh> {
    if split_non_manifold {
        control.split_non_manifold()?;
    }
    PatchMesh::new(control).map_err(|e| match e {
        crate::Error::Parse { file, line, msg } if msg.starts_with("non-manifold edge") => {
            crate::Error::Parse {
                file,
                line,
                msg: format!("{msg} (--split-non-manifold cuts the mesh there)"),
            }
        }
        e => e,
    })
}

/// Exact surface points of every non-hole patch on an `n × n` grid `(i, j)/(n-1)`,
/// patch after patch, for error measurement.
pub fn surface_samples(model: &SurfaceModel, n: usize) -> Vec<DVec3> {
    let n = n.max(2);
    let mut out = Vec::new();
    for p in model.mesh.surface_patches() {
        for j in 0..n {
            for i in 0..n {
                let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                out.push(model.eval(p, u, v).position);
            }
        }
    }
    out
}
