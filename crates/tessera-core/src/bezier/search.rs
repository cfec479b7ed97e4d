//! Finding the threshold that gives a wanted triangle count, so methods can be compared
//! at equal triangle counts as in the paper's Table 2.

use super::prepare::PreparedBezier;
use super::tessellate::{tessellate_adaptive, AdaptiveParams, Tessellation};
use crate::error::{Error, Result};

/// Relative tolerance on the triangle count.
pub const TARGET_TOLERANCE: f64 = 0.02;

/// The result of a search: the threshold used and the mesh it gave.
pub struct TargetResult {
    /// The threshold that gave `tessellation`, model units.
    pub threshold: f32,
    /// The tessellation at that threshold.
    pub tessellation: Tessellation,
    /// Whether the count is within [`TARGET_TOLERANCE`] of the target.
    pub within_tolerance: bool,
}

/// Bisects `log(threshold)` (the count falls as the threshold grows) until the triangle
/// count is within 2% of `target`, or returns the closest count found.
pub fn threshold_for_triangles(
    prep: &PreparedBezier,
    base: AdaptiveParams,
    scale: f32,
    target: usize,
) -> Result<TargetResult> {
    if target == 0 {
        return Err(Error::Param(
            "target triangle count must be positive".into(),
        ));
    }
    let run = |th: f32| {
        tessellate_adaptive(
            prep,
            &AdaptiveParams {
                threshold: th,
                ..base
            },
        )
    };
    let close = |n: usize| (n as f64 - target as f64).abs() <= TARGET_TOLERANCE * target as f64;
    // Bracket: a threshold as large as the model refines nothing; a tiny one refines to
    // the depth limit.
    let (mut lo, mut hi) = ((scale * 1e-7).ln(), (scale * 10.0).ln());
    let mut best: Option<(f32, Tessellation)> = None;
    let consider = |th: f32, t: Tessellation, best: &mut Option<(f32, Tessellation)>| {
        let n = t.mesh.triangle_count();
        let better = best.as_ref().is_none_or(|(_, b)| {
            (n as i64 - target as i64).abs()
                < (b.mesh.triangle_count() as i64 - target as i64).abs()
        });
        if better {
            *best = Some((th, t));
        }
        close(n)
    };
    for _ in 0..64 {
        let mid = 0.5 * (lo + hi);
        let th = mid.exp();
        let t = run(th)?;
        let n = t.mesh.triangle_count();
        if consider(th, t, &mut best) {
            break;
        }
        if n > target {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-6 {
            break;
        }
    }
    let (threshold, tessellation) = best.expect("at least one run");
    let within_tolerance = close(tessellation.mesh.triangle_count());
    Ok(TargetResult {
        threshold,
        tessellation,
        within_tolerance,
    })
}

/// The uniform segment count whose triangle count is nearest `target`.
pub fn segments_for_triangles(
    model: &super::BezierModel,
    prep: &PreparedBezier,
    target: usize,
) -> Result<(u32, Tessellation)> {
    let count = |n: u32| super::tessellate_uniform(model, prep, n);
    // Triangles grow as n²: start from the estimate and walk to the nearest.
    let per_n1 = count(1)?.mesh.triangle_count().max(1);
    let mut n = ((target as f64 / per_n1 as f64).sqrt().round() as u32)
        .clamp(1, super::uniform::MAX_SEGMENTS);
    let mut best = (n, count(n)?);
    loop {
        let here = best.1.mesh.triangle_count() as i64;
        let step: i64 = if here < target as i64 { 1 } else { -1 };
        let next = n as i64 + step;
        if next < 1 || next > super::uniform::MAX_SEGMENTS as i64 {
            break;
        }
        let t = count(next as u32)?;
        if (t.mesh.triangle_count() as i64 - target as i64).abs() >= (here - target as i64).abs() {
            break;
        }
        n = next as u32;
        best = (n, t);
    }
    Ok(best)
}
