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
pub use tessellate::{
    patch_thresholds, tessellate_adaptive, tessellate_adaptive_in_view, AdaptiveParams, BezierView,
    Tessellation,
};
pub use uniform::tessellate_uniform;

#[cfg(test)]
pub(crate) mod test_support {
    use super::refine::{tri_mark, TriContext, TriScratch};
    use super::tessellate::{edge_decide, tri_context};
    use super::{AdaptiveParams, BezierModel, EdgeTest, PreparedBezier};

    /// Every coarse triangle of the named teaset models, marked, at each (test,
    /// threshold): `visit` gets a label, its context and its scratch.
    pub(crate) fn for_each_marked_triangle(
        models: &[&str],
        settings: &[(EdgeTest, f32)],
        mut visit: impl FnMut(&str, &TriContext, &TriScratch),
    ) {
        for name in models {
            let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../assets/teaset")
                .join(name);
            let prep = PreparedBezier::new(&BezierModel::load(&dir).expect("model"));
            let l = prep.layout;
            let cps: Vec<_> = (0..l.patches).map(|p| prep.control_points(p)).collect();
            for &(test, threshold) in settings {
                let params = AdaptiveParams {
                    test,
                    threshold,
                    max_depth: AdaptiveParams::DEFAULT_MAX_DEPTH,
                };
                let bits: Vec<_> = (0..l.coarse_edges)
                    .map(|e| edge_decide(&prep, &cps, &params, e).0)
                    .collect();
                for t in 0..l.coarse_triangles {
                    let ctx = tri_context(&prep, &cps, &bits, &params, t);
                    let mut s = TriScratch::new(params.max_depth);
                    tri_mark(&ctx, &mut s);
                    let what = format!("{name} {test:?} {threshold}, coarse triangle {t}");
                    visit(&what, &ctx, &s);
                }
            }
        }
    }
}
