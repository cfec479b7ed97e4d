// The bound of each quad control face taken whole, for the face leaves of a view: one
// invocation per patch; the first patch of each quad face computes its face's bound once
// and keeps it in the marks until the control points move (`cc_face_bound_at`), and
// marking reads it there (`cc_traverse.wgsl`). A face with a hole among its patches has
// none (CC_INFINITY). Twin: `tessera_core::catmull_clark::bound::face_bound`, through
// `SurfaceModel::face_bound`.

#include "shared/cc_tess.wgsl"
#include "shared/cc_bound.wgsl"

// Marking's words (`shared/cc_tess.wgsl`): here the face bounds kept.
@group(0) @binding(57) var<storage, read_write> marks: array<u32>;
@group(0) @binding(59) var<storage, read> topo: array<CcPatchTopo>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let p = cc_invocation(gid, groups);
    if cc_params.view.face_leaves == 0u || p >= cc_params.patch_count || p >= arrayLength(&topo) {
        return;
    }
    let face_corner = topo[p].face_corner;
    // Quad faces only, at their first patch, and once.
    if (face_corner >> 8u) != 4u || (face_corner & 0xffu) != 0u || marks[cc_face_bound_at(p)] != 0u {
        return;
    }
    var whole = p + 3u < cc_params.patch_count;
    for (var k = 0u; k < 4u && whole; k++) {
        whole = cc_roots[p + k].node != CC_NO_ROOT;
    }
    var bound = CC_INFINITY;
    if whole {
        let corners = array<vec3f, 4>(cc_eval(CcPoint(p, 0u, 0u)).position,
            cc_eval(CcPoint(p + 1u, 0u, 0u)).position, cc_eval(CcPoint(p + 2u, 0u, 0u)).position,
            cc_eval(CcPoint(p + 3u, 0u, 0u)).position);
        bound = cc_face_bound(p, corners);
    }
    // Plus one in its bits: 0 is none yet.
    marks[cc_face_bound_at(p)] = bitcast<u32>(bound) + 1u;
}
