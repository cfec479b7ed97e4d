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
/// at `(i, j)`), u-difference by u-difference, as the kernel takes them; each
/// [`product_normal`] at `size`, the extent of the box the surface lies in.
pub fn net_normals(net: &Net, size: f64) -> impl Iterator<Item = DVec3> + '_ {
    let du = (0..12).map(move |k| {
        let (j, i) = (k / 3, k % 3);
        net[4 * j + i + 1] - net[4 * j + i]
    });
    du.flat_map(move |a| (0..12).map(move |k| product_normal(a, net[k + 4] - net[k], size)))
}

/// Differences closer to parallel than this sine, or shorter than this fraction of the
/// surface's box, give no normal ([`product_normal`]).
pub const NEGLIGIBLE_SINE: f64 = 1e-5;

/// `a × b`, or zero where `a` and `b` are parallel to within [`NEGLIGIBLE_SINE`] or one
/// of them is shorter than that fraction of `size` (the extent of the surface's box).
/// Exactly parallel differences (a flat strip) and zero ones (a side or a whole piece
/// collapsed to a point) span no normal, but the nets'
/// rounding, in single precision on the GPU and in double here, leaves their product as
/// noise in any direction: taken as zero on both sides alike, so that noise decides
/// nothing. A product dropped so is a sliver of surface turned by less than that angle,
/// and back-face culling is outside the guarantee.
pub fn product_normal(a: DVec3, b: DVec3, size: f64) -> DVec3 {
    let n = a.cross(b);
    let s2 = NEGLIGIBLE_SINE * NEGLIGIBLE_SINE;
    let (a2, b2, l2) = (a.length_squared(), b.length_squared(), size * size);
    if n.length_squared() <= s2 * a2 * b2 || a2 <= s2 * l2 || b2 <= s2 * l2 {
        DVec3::ZERO
    } else {
        n
    }
}

/// Nodes the walk keeps pending at most, as the kernel's stack: past it the patch is
/// taken as facing the eye.
pub const FACING_STACK: usize = 128;

/// Whether patch `surface`, whose surface lies in the box `[lo, hi]`, faces away from
/// the eye of `view` everywhere. Its quadtree is walked depth first from the root, in
/// the kernel's order.
pub fn patch_back_facing(view: &View, surface: &PatchSurface, lo: DVec3, hi: DVec3) -> bool {
    if surface.nodes.is_empty() {
        return false;
    }
    let f = view.box_facing(lo, hi);
    let size = (hi - lo).length();
    let mut stack = vec![0u32];
    while let Some(k) = stack.pop() {
        let away = match &surface.nodes[k as usize] {
            Node::Split(children) => {
                if stack.len() + 4 > FACING_STACK {
                    return false;
                }
                stack.extend(children);
                continue;
            }
            Node::Bezier(net) => net_normals(net, size).all(|n| f.faces_away(n)),
            Node::Corner(c) => f.faces_away(c.normal),
        };
        if !away {
            return false;
        }
    }
    true
}
