//! The WGSL sources, embedded at build time, with `#include "shared/NAME.wgsl"` lines
//! replaced by the named shared file (each file included at most once per module).

use tessera_core::gpu_types::CcNetLayout;

/// Every shader file under `shaders/`, by its path relative to that folder.
pub const SOURCES: &[(&str, &str)] = &[
    (
        "shared/types.wgsl",
        include_str!("../../../shaders/shared/types.wgsl"),
    ),
    (
        "shared/patch.wgsl",
        include_str!("../../../shaders/shared/patch.wgsl"),
    ),
    (
        "shared/map.wgsl",
        include_str!("../../../shaders/shared/map.wgsl"),
    ),
    (
        "shared/lattice.wgsl",
        include_str!("../../../shaders/shared/lattice.wgsl"),
    ),
    (
        "shared/topo.wgsl",
        include_str!("../../../shaders/shared/topo.wgsl"),
    ),
    (
        "shared/coarse.wgsl",
        include_str!("../../../shaders/shared/coarse.wgsl"),
    ),
    (
        "shared/need.wgsl",
        include_str!("../../../shaders/shared/need.wgsl"),
    ),
    (
        "shared/refine.wgsl",
        include_str!("../../../shaders/shared/refine.wgsl"),
    ),
    (
        "shared/cc_patch.wgsl",
        include_str!("../../../shaders/shared/cc_patch.wgsl"),
    ),
    (
        "shared/cc_hash.wgsl",
        include_str!("../../../shaders/shared/cc_hash.wgsl"),
    ),
    (
        "shared/cc_hash_key.wgsl",
        include_str!("../../../shaders/shared/cc_hash_key.wgsl"),
    ),
    (
        "shared/cc_bound.wgsl",
        include_str!("../../../shaders/shared/cc_bound.wgsl"),
    ),
    (
        "shared/cc_tess.wgsl",
        include_str!("../../../shaders/shared/cc_tess.wgsl"),
    ),
    (
        "shared/cc_view.wgsl",
        include_str!("../../../shaders/shared/cc_view.wgsl"),
    ),
    (
        "shared/thresholds.wgsl",
        include_str!("../../../shaders/shared/thresholds.wgsl"),
    ),
    (
        "shared/cc_facing.wgsl",
        include_str!("../../../shaders/shared/cc_facing.wgsl"),
    ),
    (
        "shared/cc_poly.wgsl",
        include_str!("../../../shaders/shared/cc_poly.wgsl"),
    ),
    (
        "shared/lane_order.wgsl",
        include_str!("../../../shaders/shared/lane_order.wgsl"),
    ),
    (
        "cc_stencil.wgsl",
        include_str!("../../../shaders/cc_stencil.wgsl"),
    ),
    (
        "cc_face_bound.wgsl",
        include_str!("../../../shaders/cc_face_bound.wgsl"),
    ),
    (
        "cc_traverse.wgsl",
        include_str!("../../../shaders/cc_traverse.wgsl"),
    ),
    (
        "cc_leaf_keys.wgsl",
        include_str!("../../../shaders/cc_leaf_keys.wgsl"),
    ),
    (
        "cc_polygon.wgsl",
        include_str!("../../../shaders/cc_polygon.wgsl"),
    ),
    (
        "cc_triangulate.wgsl",
        include_str!("../../../shaders/cc_triangulate.wgsl"),
    ),
    ("scan.wgsl", include_str!("../../../shaders/scan.wgsl")),
    (
        "cc_hash_insert.wgsl",
        include_str!("../../../shaders/cc_hash_insert.wgsl"),
    ),
    (
        "cc_hash_number.wgsl",
        include_str!("../../../shaders/cc_hash_number.wgsl"),
    ),
    (
        "cc_vertex_eval.wgsl",
        include_str!("../../../shaders/cc_vertex_eval.wgsl"),
    ),
    (
        "shared/cc_face.wgsl",
        include_str!("../../../shaders/shared/cc_face.wgsl"),
    ),
    (
        "shared/cc_uniform.wgsl",
        include_str!("../../../shaders/shared/cc_uniform.wgsl"),
    ),
    (
        "cc_uniform_points.wgsl",
        include_str!("../../../shaders/cc_uniform_points.wgsl"),
    ),
    (
        "cc_uniform_cells.wgsl",
        include_str!("../../../shaders/cc_uniform_cells.wgsl"),
    ),
    (
        "bezier_edge_decide.wgsl",
        include_str!("../../../shaders/bezier_edge_decide.wgsl"),
    ),
    (
        "bezier_tri_roots.wgsl",
        include_str!("../../../shaders/bezier_tri_roots.wgsl"),
    ),
    (
        "bezier_tri_mark.wgsl",
        include_str!("../../../shaders/bezier_tri_mark.wgsl"),
    ),
    (
        "bezier_tri_emit.wgsl",
        include_str!("../../../shaders/bezier_tri_emit.wgsl"),
    ),
    (
        "bezier_map_cells.wgsl",
        include_str!("../../../shaders/bezier_map_cells.wgsl"),
    ),
    (
        "bezier_tri_emit_plain.wgsl",
        include_str!("../../../shaders/bezier_tri_emit_plain.wgsl"),
    ),
    (
        "bezier_tri_order.wgsl",
        include_str!("../../../shaders/bezier_tri_order.wgsl"),
    ),
    (
        "bezier_edge_emit.wgsl",
        include_str!("../../../shaders/bezier_edge_emit.wgsl"),
    ),
    (
        "bezier_vertex_eval.wgsl",
        include_str!("../../../shaders/bezier_vertex_eval.wgsl"),
    ),
    (
        "bezier_finish.wgsl",
        include_str!("../../../shaders/bezier_finish.wgsl"),
    ),
    (
        "render_mesh.wgsl",
        include_str!("../../../shaders/render_mesh.wgsl"),
    ),
];

/// The kernels and render shaders (files that are not shared includes).
pub fn entry_files() -> impl Iterator<Item = &'static str> {
    SOURCES
        .iter()
        .map(|(name, _)| *name)
        .filter(|n| !n.starts_with("shared/"))
}

fn raw(name: &str) -> Option<&'static str> {
    SOURCES.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
}

/// The source of `name` with its includes resolved.
///
/// # Panics
/// If `name` or an include is not in [`SOURCES`]: a build-time inconsistency, caught
/// by the shader validation test.
pub fn source(name: &str) -> String {
    let mut out = String::new();
    let mut seen = Vec::new();
    expand(name, &mut out, &mut seen);
    out
}

fn expand(name: &str, out: &mut String, seen: &mut Vec<String>) {
    if seen.iter().any(|s| s == name) {
        return;
    }
    seen.push(name.to_string());
    let text = raw(name).unwrap_or_else(|| panic!("shader {name} is not embedded"));
    for line in text.lines() {
        match line.trim().strip_prefix("#include") {
            Some(rest) => expand(rest.trim().trim_matches('"'), out, seen),
            None => {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
}

/// The source of `name` with the value of each `const NAME: u32 = ...;` in `consts`
/// replaced: for sizes WGSL cannot take from an `override` (private arrays).
///
/// # Panics
/// If the source declares no such constant: a build-time inconsistency, caught by the
/// shader validation test.
pub fn source_with_consts(name: &str, consts: &[(&str, u32)]) -> String {
    let mut src = source(name);
    for (constant, value) in consts {
        let decl = format!("const {constant}: u32 = ");
        let start = src
            .find(&decl)
            .unwrap_or_else(|| panic!("{name} declares no `{decl}...;`"));
        let end = start + src[start..].find(';').expect("a declaration ends");
        src.replace_range(start..end, &format!("{decl}{value}u"));
    }
    src
}

/// A shader module for `name`, with `consts` as in [`source_with_consts`], and the
/// Catmull-Clark nets' pages laid out for `device` ([`CcNetLayout`], as the stages
/// allocate them).
///
/// [`CcNetLayout`]: tessera_core::gpu_types::CcNetLayout
pub fn module(device: &wgpu::Device, name: &str, consts: &[(&str, u32)]) -> wgpu::ShaderModule {
    let layout = CcNetLayout::new(device.limits().max_texture_dimension_2d);
    let pages = [
        ("CC_NETS_PER_ROW", layout.nets_per_row),
        ("CC_NET_PAGE_ROWS", layout.rows),
    ];
    // Every kernel that includes the shared types declares them; the others (scan,
    // render) read no nets.
    let declared = source(name).contains("const CC_NETS_PER_ROW: u32 = ");
    let consts: Vec<(&str, u32)> = consts
        .iter()
        .copied()
        .chain(pages.into_iter().filter(|_| declared))
        .collect();
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(name),
        source: wgpu::ShaderSource::Wgsl(source_with_consts(name, &consts).into()),
    })
}

/// The binding numbers (group 0) that entry point `entry` of `name` uses, by naga's
/// reflection: pipelines with derived layouts expect exactly these in a bind group.
pub fn used_bindings(name: &str, entry: &str) -> Vec<u32> {
    let src = source(name);
    let module = naga::front::wgsl::parse_str(&src)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
    let index = module
        .entry_points
        .iter()
        .position(|e| e.name == entry)
        .unwrap_or_else(|| panic!("{name} has no entry point {entry}"));
    let ep = info.get_entry_point(index);
    let mut used: Vec<u32> = module
        .global_variables
        .iter()
        .filter(|(h, _)| !ep[*h].is_empty())
        .filter_map(|(_, g)| g.binding.as_ref().map(|b| b.binding))
        .collect();
    used.sort_unstable();
    used
}
