//! Back-facing patches: a patch whose every normal faces away from the eye over its whole
//! box emits nothing (twin of `shaders/shared/cc_facing.wgsl`).
//!
//! The normal of a Bézier piece, `S_u × S_v`, is a sum with non-negative (Bernstein)
//! weights of the products `a × b` of its u-differences `a` and v-differences `b`: the
//! 144 products span a cone holding every normal of the piece, and the cones of a
//! patch's pieces, with the limit normal of each extraordinary vertex, hold all of its
//! normals. [`View::box_back_facing`] tests that cone against the patch's box. The
//! innermost square at an extraordinary vertex, `λ^30` of the patch, is taken at its
//! limit normal, which the pieces around it approach. Culling the back is outside the
//! pixel guarantee, which speaks of every point of the surface in the frustum.

use glam::DVec3;

use super::bicubic::Net;
use super::patch::{Node, PatchSurface};
use crate::view::View;

/// The 144 products `a × b` of a net's u-differences and v-differences (point `4j + i`
/// at `(i, j)`), u-difference by u-difference, as the kernel takes them.
pub fn net_normals(net: &Net) -> impl Iterator<Item = DVec3> + '_ {
    let du = (0..12).map(move |k| {
        let (j, i) = (k / 3, k % 3);
        net[4 * j + i + 1] - net[4 * j + i]
    });
    du.flat_map(move |a| (0..12).map(move |k| a.cross(net[k + 4] - net[k])))
}

/// Whether patch `surface`, whose surface lies in the box `[lo, hi]`, faces away from
/// the eye of `view` everywhere.
pub fn patch_back_facing(view: &View, surface: &PatchSurface, lo: DVec3, hi: DVec3) -> bool {
    let normals = surface
        .nodes
        .iter()
        .flat_map(|node| -> Box<dyn Iterator<Item = DVec3> + '_> {
            match node {
                Node::Bezier(net) => Box::new(net_normals(net)),
                Node::Corner(c) => Box::new(std::iter::once(c.normal)),
                Node::Split(_) => Box::new(std::iter::empty()),
            }
        });
    view.box_back_facing(lo, hi, normals)
}
