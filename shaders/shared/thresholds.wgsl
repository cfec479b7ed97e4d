// Each patch's edge-test threshold (`tessera_core::bezier::patch_thresholds`): the world
// threshold, or scaled to a view's pixels, negated where the view culls the patch. Twins:
// `tessera_core::bezier::tessellate::{test_threshold, culled}`.

@group(0) @binding(18) var<storage, read> patch_thresholds: array<f32>;

fn patch_signed_threshold(p: u32) -> f32 {
    return patch_thresholds[min(p, arrayLength(&patch_thresholds) - 1u)];
}

fn patch_threshold(p: u32) -> f32 {
    return abs(patch_signed_threshold(p));
}

// The patch lies wholly outside a culling view's frustum: it emits nothing.
fn patch_culled(p: u32) -> bool {
    return patch_signed_threshold(p) < 0.0;
}
