//! Every shader parses and validates with naga, and every struct shared with Rust has
//! the layout of its `#[repr(C)]` twin.

use std::mem::{offset_of, size_of};

use tessera_core::gpu_types::*;
use tessera_wgpu::shaders;

/// Parses and validates WGSL as the tests check every kernel; the error text if either
/// step fails.
fn check(src: &str) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let module = naga::front::wgsl::parse_str(src).map_err(|e| e.emit_to_string(src))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| e.emit_to_string(src))?;
    Ok((module, info))
}

fn parse(name: &str) -> (naga::Module, naga::valid::ModuleInfo) {
    check(&shaders::source(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn every_shader_parses_and_validates() {
    let mut n = 0;
    for name in shaders::entry_files() {
        let (module, _) = parse(name);
        assert!(!module.entry_points.is_empty(), "{name} has no entry point");
        n += 1;
    }
    assert!(n >= 8, "only {n} shader files");
}

#[test]
fn the_triangle_kernels_validate_at_every_array_depth() {
    for file in ["bezier_tri_mark.wgsl", "bezier_tri_emit.wgsl"] {
        for depth in 0..=tessera_core::gpu_types::MAX_DEPTH_LIMIT {
            let src = shaders::source_with_consts(file, &[("ARRAY_DEPTH", depth)]);
            assert!(src.contains(&format!("const ARRAY_DEPTH: u32 = {depth}u;")));
            check(&src).unwrap_or_else(|e| panic!("{file} at array depth {depth}: {e}"));
        }
        // Deeper than the lattice's limit is refused by the shader's own const_assert.
        let src = shaders::source_with_consts(file, &[("ARRAY_DEPTH", 9)]);
        assert!(check(&src).is_err(), "{file} accepted array depth 9");
    }
}

#[test]
#[should_panic(expected = "declares no `const NO_SUCH_CONST: u32 = ...;`")]
fn replacing_an_undeclared_const_is_refused() {
    shaders::source_with_consts("bezier_tri_emit.wgsl", &[("NO_SUCH_CONST", 1)]);
}

#[test]
fn an_invalid_shader_is_rejected() {
    // The check is not a formality: a type error fails the parser, and a module that
    // parses but breaks a rule only the validator knows (a store through a read-only
    // storage binding) fails the validation step.
    let type_error = "@compute @workgroup_size(1) fn main() { let x: u32 = 1.5; }";
    assert!(naga::front::wgsl::parse_str(type_error).is_err());
    assert!(check(type_error).is_err());
    let store_to_read_only = "@group(0) @binding(0) var<storage, read> b: array<u32>;
        @compute @workgroup_size(1) fn main() { b[0] = 1u; }";
    assert!(naga::front::wgsl::parse_str(store_to_read_only).is_ok());
    let err = check(store_to_read_only).expect_err("validation must fail");
    assert!(
        err.contains("Entry point main at Compute is invalid"),
        "{err}"
    );
}

/// (name, size, [(member, offset)]) of a struct in a module.
fn layout(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    for (handle, ty) in module.types.iter() {
        if ty.name.as_deref() != Some(name) {
            continue;
        }
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("{name} is not a struct");
        };
        assert_eq!(layouter[handle].size, *span);
        return (
            *span,
            members
                .iter()
                .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                .collect(),
        );
    }
    panic!("struct {name} not found");
}

#[test]
fn shared_structs_match_their_rust_twins() {
    let (module, _) = parse("bezier_tri_emit.wgsl");
    let (finish, _) = parse("bezier_finish.wgsl");
    let (vertex, _) = parse("bezier_vertex_eval.wgsl");
    let check = |m: &naga::Module, name: &str, size: usize, offsets: &[(&str, usize)]| {
        let (wgsl_size, members) = layout(m, name);
        assert_eq!(wgsl_size as usize, size, "size of {name}");
        assert_eq!(members.len(), offsets.len(), "members of {name}");
        for ((wname, woff), (rname, roff)) in members.iter().zip(offsets) {
            // `patch` is a reserved word in WGSL.
            let rname = if *rname == "patch" { "patch_id" } else { rname };
            assert_eq!(wname, rname, "{name}: member order");
            assert_eq!(*woff as usize, *roff, "{name}.{wname} offset");
        }
    };
    check(
        &module,
        "GpuPatch",
        size_of::<GpuPatch>(),
        &[("cp", offset_of!(GpuPatch, cp))],
    );
    check(
        &module,
        "GpuPatchTopo",
        size_of::<GpuPatchTopo>(),
        &[
            ("corners", offset_of!(GpuPatchTopo, corners)),
            ("sides", offset_of!(GpuPatchTopo, sides)),
            ("flags", offset_of!(GpuPatchTopo, flags)),
        ],
    );
    check(
        &module,
        "GpuCurve",
        size_of::<GpuCurve>(),
        &[
            ("owner", offset_of!(GpuCurve, owner)),
            ("flags", offset_of!(GpuCurve, flags)),
            ("coarse_vertex", offset_of!(GpuCurve, coarse_vertex)),
            ("other", offset_of!(GpuCurve, other)),
        ],
    );
    check(
        &module,
        "VertexRecord",
        size_of::<VertexRecord>(),
        &[
            ("patch", offset_of!(VertexRecord, patch)),
            ("u", offset_of!(VertexRecord, u)),
            ("v", offset_of!(VertexRecord, v)),
        ],
    );
    check(
        &vertex,
        "OutVertex",
        size_of::<OutVertex>(),
        &[
            ("position", offset_of!(OutVertex, position)),
            ("normal", offset_of!(OutVertex, normal)),
            ("uv", offset_of!(OutVertex, uv)),
            ("face", offset_of!(OutVertex, face)),
        ],
    );
    check(
        &finish,
        "DrawIndexedIndirectArgs",
        size_of::<DrawIndexedIndirectArgs>(),
        &[
            (
                "index_count",
                offset_of!(DrawIndexedIndirectArgs, index_count),
            ),
            (
                "instance_count",
                offset_of!(DrawIndexedIndirectArgs, instance_count),
            ),
            (
                "first_index",
                offset_of!(DrawIndexedIndirectArgs, first_index),
            ),
            (
                "base_vertex",
                offset_of!(DrawIndexedIndirectArgs, base_vertex),
            ),
            (
                "first_instance",
                offset_of!(DrawIndexedIndirectArgs, first_instance),
            ),
        ],
    );
    let (cc, _) = parse("cc_vertex_eval.wgsl");
    check(
        &cc,
        "CcNode",
        size_of::<CcNode>(),
        &[
            ("kind", offset_of!(CcNode, kind)),
            ("index", offset_of!(CcNode, index)),
        ],
    );
    check(
        &cc,
        "CcCorner",
        size_of::<CcCorner>(),
        &[
            ("limit", offset_of!(CcCorner, limit)),
            ("corner", offset_of!(CcCorner, corner)),
            ("normal", offset_of!(CcCorner, normal)),
            ("hull_radius", offset_of!(CcCorner, hull_radius)),
        ],
    );
    check(
        &cc,
        "CcPoint",
        size_of::<CcPoint>(),
        &[
            ("patch_id", offset_of!(CcPoint, patch_id)),
            ("u", offset_of!(CcPoint, u)),
            ("v", offset_of!(CcPoint, v)),
        ],
    );
    let (uniform, _) = parse("cc_uniform_cells.wgsl");
    check(
        &uniform,
        "CcUniformPatch",
        size_of::<CcUniformPatch>(),
        &[
            ("patch_id", offset_of!(CcUniformPatch, patch_id)),
            ("corners", offset_of!(CcUniformPatch, corners)),
            ("edges", offset_of!(CcUniformPatch, edges)),
            ("flags", offset_of!(CcUniformPatch, flags)),
            ("face", offset_of!(CcUniformPatch, face)),
            ("face_corner", offset_of!(CcUniformPatch, face_corner)),
            ("corner_homes", offset_of!(CcUniformPatch, corner_homes)),
            ("edge_homes", offset_of!(CcUniformPatch, edge_homes)),
        ],
    );
    let (keys, _) = parse("cc_leaf_keys.wgsl");
    check(
        &keys,
        "CcPatchTopo",
        size_of::<CcPatchTopo>(),
        &[
            ("quad", offset_of!(CcPatchTopo, quad)),
            ("edges", offset_of!(CcPatchTopo, edges)),
            ("across", offset_of!(CcPatchTopo, across)),
            ("face", offset_of!(CcPatchTopo, face)),
            ("face_corner", offset_of!(CcPatchTopo, face_corner)),
            ("pad0", offset_of!(CcPatchTopo, pad)),
            ("pad1", offset_of!(CcPatchTopo, pad) + 4),
        ],
    );
    check(
        &keys,
        "CcVertexPoint",
        size_of::<CcVertexPoint>(),
        &[
            ("patch_id", offset_of!(CcVertexPoint, patch_id)),
            ("u", offset_of!(CcVertexPoint, u)),
            ("v", offset_of!(CcVertexPoint, v)),
            ("face", offset_of!(CcVertexPoint, face)),
            ("face_u", offset_of!(CcVertexPoint, face_u)),
            ("face_v", offset_of!(CcVertexPoint, face_v)),
        ],
    );
    check(
        &uniform,
        "CcUniformParams",
        size_of::<CcUniformParams>(),
        &[
            ("segments", offset_of!(CcUniformParams, segments)),
            ("patch_count", offset_of!(CcUniformParams, patch_count)),
            ("corner_count", offset_of!(CcUniformParams, corner_count)),
            ("edge_count", offset_of!(CcUniformParams, edge_count)),
        ],
    );
    let (hash, _) = parse("cc_hash_number.wgsl");
    check(
        &hash,
        "CcHashSlot",
        size_of::<CcHashSlot>(),
        &[
            ("key_hi", offset_of!(CcHashSlot, key_hi)),
            ("key_lo", offset_of!(CcHashSlot, key_lo)),
            ("first", offset_of!(CcHashSlot, first)),
        ],
    );
    check(
        &hash,
        "CcHashStatus",
        size_of::<CcHashStatus>(),
        &[
            ("items", offset_of!(CcHashStatus, items)),
            ("overflow", offset_of!(CcHashStatus, overflow)),
            ("unique", offset_of!(CcHashStatus, unique)),
            ("pad", offset_of!(CcHashStatus, pad)),
        ],
    );
    let (wgsl_size, members) = layout(&finish, "BezierParams");
    assert_eq!(wgsl_size as usize, size_of::<BezierParams>());
    let names: Vec<&str> = members.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, BezierParams::FIELD_NAMES);
    for (k, (_, off)) in members.iter().enumerate() {
        assert_eq!(
            *off as usize,
            4 * k,
            "BezierParams fields are consecutive u32/f32"
        );
    }
    let (wgsl_size, members) = layout(&finish, "BezierStatus");
    assert_eq!(wgsl_size as usize, size_of::<BezierStatus>());
    let dispatch = members
        .iter()
        .find(|(n, _)| n == "dispatch_x")
        .expect("dispatch_x");
    assert_eq!(dispatch.1 as usize, offset_of!(BezierStatus, dispatch));
    for (name, offset) in [
        (
            "general_triangles",
            offset_of!(BezierStatus, general_triangles),
        ),
        ("emit_dispatch_x", offset_of!(BezierStatus, emit_dispatch)),
        ("plain_dispatch_x", offset_of!(BezierStatus, plain_dispatch)),
        ("mark_dispatch_x", offset_of!(BezierStatus, mark_dispatch)),
        ("culled_patches", offset_of!(BezierStatus, culled_patches)),
    ] {
        let member = members.iter().find(|(n, _)| n == name).expect(name);
        assert_eq!(member.1 as usize, offset, "{name}");
    }
    let overflow = members
        .iter()
        .find(|(n, _)| n == "overflow")
        .expect("overflow");
    assert_eq!(overflow.1 as usize, offset_of!(BezierStatus, overflow));
}

#[test]
fn catmull_clark_parameters_and_counters_match_their_rust_twins() {
    let (module, _) = parse("cc_traverse.wgsl");
    let (size, members) = layout(&module, "CcTessParams");
    assert_eq!(size as usize, size_of::<CcTessParams>());
    let rust = [
        ("grid", offset_of!(CcTessParams, grid)),
        ("max_depth", offset_of!(CcTessParams, max_depth)),
        ("tolerance", offset_of!(CcTessParams, tolerance)),
        ("patch_count", offset_of!(CcTessParams, patch_count)),
        ("leaf_capacity", offset_of!(CcTessParams, leaf_capacity)),
        ("poly_capacity", offset_of!(CcTessParams, poly_capacity)),
        ("index_capacity", offset_of!(CcTessParams, index_capacity)),
        ("trials", offset_of!(CcTessParams, trials)),
        ("points", offset_of!(CcTessParams, points)),
        ("vertex_capacity", offset_of!(CcTessParams, vertex_capacity)),
        ("pad0", offset_of!(CcTessParams, pad)),
        ("pad1", offset_of!(CcTessParams, pad) + 4),
        ("view", offset_of!(CcTessParams, view)),
    ];
    let members: Vec<(&str, usize)> = members
        .iter()
        .map(|(n, o)| (n.as_str(), *o as usize))
        .collect();
    assert_eq!(members, rust, "CcTessParams");
    for (name, rust) in [
        ("CC_VIEW_CULL_FRUSTUM", CC_VIEW_CULL_FRUSTUM),
        ("CC_VIEW_CULL_BACKFACES", CC_VIEW_CULL_BACKFACES),
        ("CC_CELL_CULLED", CC_CELL_CULLED),
        ("CC_CELL_PATCH_CULLED", CC_CELL_PATCH_CULLED),
        ("CC_CELL_FACE", CC_CELL_FACE),
        ("CC_CHOSEN_FACE_LEAF", CC_CHOSEN_FACE_LEAF),
        ("CC_ROOT_CREASED", CC_ROOT_CREASED),
        ("CC_ROOT_QUAD_FACE", CC_ROOT_QUAD_FACE),
        ("CC_ROOT_CORNER_SHIFT", CC_ROOT_CORNER_SHIFT),
        (
            "CC_FACING_STACK",
            tessera_core::catmull_clark::facing::FACING_STACK as u32,
        ),
        // The nets' pages as laid out for WebGPU's default limits (a device's own layout
        // replaces them when a kernel is built).
        (
            "CC_NETS_PER_ROW",
            CcNetLayout::new(wgpu::Limits::default().max_texture_dimension_2d).nets_per_row,
        ),
        (
            "CC_NET_PAGE_ROWS",
            CcNetLayout::new(wgpu::Limits::default().max_texture_dimension_2d).rows,
        ),
        ("CC_NET_PAGES_USED", CC_NET_PAGES),
    ] {
        assert_eq!(wgsl_u32(&module, name), rust, "{name}");
    }
    let (size, members) = layout(&module, "CcCounters");
    assert_eq!(size as usize, size_of::<CcState>());
    let rust = [
        ("drawn_vertices", offset_of!(CcState, drawn_vertices)),
        ("leaves", offset_of!(CcState, leaves)),
        ("overflow", offset_of!(CcState, overflow)),
        ("need_poly", offset_of!(CcState, need_poly)),
        ("need_indices", offset_of!(CcState, need_indices)),
        ("unmet", offset_of!(CcState, unmet)),
        ("max_bound_bits", offset_of!(CcState, max_bound_bits)),
        ("vertices", offset_of!(CcState, vertices)),
        ("bounds", offset_of!(CcState, bounds)),
        ("proven", offset_of!(CcState, proven)),
        ("decision_blocks", offset_of!(CcState, decision_blocks)),
        ("culled_leaves", offset_of!(CcState, culled_leaves)),
        ("culled_patches", offset_of!(CcState, culled_patches)),
    ];
    let members: Vec<(&str, usize)> = members
        .iter()
        .map(|(n, o)| (n.as_str(), *o as usize))
        .collect();
    assert_eq!(members, rust, "CcCounters");
    let (size, members) = layout(&module, "CcView");
    assert_eq!(size as usize, size_of::<CcView>());
    let rust = [
        ("clip", offset_of!(CcView, clip)),
        ("viewport", offset_of!(CcView, viewport)),
        ("pixels", offset_of!(CcView, pixels)),
        ("near_w", offset_of!(CcView, near_w)),
        ("cull", offset_of!(CcView, cull)),
        ("face_leaves", offset_of!(CcView, face_leaves)),
        ("pad1", offset_of!(CcView, pad)),
        ("pad2", offset_of!(CcView, pad) + 4),
    ];
    let members: Vec<(&str, usize)> = members
        .iter()
        .map(|(n, o)| (n.as_str(), *o as usize))
        .collect();
    assert_eq!(members, rust, "CcView");
}

#[test]
fn every_kernel_fits_webgpu_default_limits() {
    // An embedding application may bring a device with WebGPU's default limits: at most
    // 8 storage buffers and 4 storage textures per stage (and one bind group).
    let default = wgpu::Limits::default().max_storage_buffers_per_shader_stage as usize;
    let default_textures = wgpu::Limits::default().max_storage_textures_per_shader_stage as usize;
    for name in shaders::entry_files().filter(|n| *n != "render_mesh.wgsl") {
        let (module, _) = parse(name);
        for ep in &module.entry_points {
            let used = shaders::used_bindings(name, &ep.name);
            let storage = module
                .global_variables
                .iter()
                .filter(|(_, g)| matches!(g.space, naga::AddressSpace::Storage { .. }))
                .filter(|(_, g)| {
                    g.binding
                        .as_ref()
                        .is_some_and(|b| used.contains(&b.binding))
                })
                .count();
            eprintln!(
                "{name} {}: {storage} storage buffers, bindings {used:?}",
                ep.name
            );
            assert!(
                storage <= default,
                "{name} {} uses {storage} storage buffers, over the default {default}",
                ep.name
            );
            let textures = module
                .global_variables
                .iter()
                .filter(|(_, g)| {
                    matches!(
                        module.types[g.ty].inner,
                        naga::TypeInner::Image {
                            class: naga::ImageClass::Storage { .. },
                            ..
                        }
                    )
                })
                .filter(|(_, g)| {
                    g.binding
                        .as_ref()
                        .is_some_and(|b| used.contains(&b.binding))
                })
                .count();
            assert!(
                textures <= default_textures,
                "{name} {} uses {textures} storage textures, over the default {default_textures}",
                ep.name
            );
            let groups: Vec<u32> = module
                .global_variables
                .iter()
                .filter_map(|(_, g)| g.binding.as_ref().map(|b| b.group))
                .collect();
            assert!(
                groups.iter().all(|&g| g == 0),
                "{name}: bind groups other than 0"
            );
        }
    }
}

/// The value of WGSL `const NAME: u32` in `module`.
fn wgsl_u32(module: &naga::Module, name: &str) -> u32 {
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no WGSL constant {name}"));
    match module.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => v,
        ref e => panic!("{name} is not a u32 literal: {e:?}"),
    }
}

#[test]
fn bezier_constants_match_their_rust_twins() {
    let (module, _) = parse("bezier_tri_mark.wgsl");
    for (name, rust) in [
        ("MAP_RES", MAP_RES as u32),
        ("MAP_ATLAS_TILES_PER_ROW", MAP_ATLAS_TILES_PER_ROW),
        ("NET_TEXTURE_PATCHES_PER_ROW", NET_TEXTURE_PATCHES_PER_ROW),
        ("TOPOLOGY_TEXTURE_WIDTH", TOPOLOGY_TEXTURE_WIDTH),
        ("TOPO_TEXELS", TOPO_TEXELS),
        ("COARSE_SEGMENTS", COARSE_SEGMENTS as u32),
        (
            "COARSE_TRIANGLES_PER_PATCH",
            COARSE_TRIANGLES_PER_PATCH as u32,
        ),
        ("INTERIOR_EDGES_PER_PATCH", INTERIOR_EDGES_PER_PATCH as u32),
        (
            "INTERIOR_COARSE_VERTICES_PER_PATCH",
            INTERIOR_COARSE_VERTICES_PER_PATCH as u32,
        ),
        ("MAX_DEPTH_LIMIT", MAX_DEPTH_LIMIT),
        ("EDGE_BIT_WORDS", EDGE_BIT_WORDS as u32),
        ("DYADIC_SCALE", 1 << MAX_DEPTH_LIMIT),
        ("TALLY_EVALUATIONS", tally::EVALUATIONS as u32),
        ("TALLY_ORDER", tally::ORDER as u32),
        ("ORDER_BUCKETS", tally::ORDER_BUCKETS),
        ("TALLY_MARKED", tally::MARKED as u32),
        ("TALLY_CULLED", tally::CULLED as u32),
        ("TALLY_USED", tally::USED as u32),
        ("TALLY_USED_BITS", tally::USED_BITS as u32),
        (
            "STATUS_MARK_DISPATCH",
            (offset_of!(BezierStatus, mark_dispatch) / 4) as u32,
        ),
    ] {
        assert_eq!(wgsl_u32(&module, name), rust, "{name}");
    }
    // The atlas's tile lookup divides by a power of two (a shift).
    assert!(MAP_ATLAS_TILES_PER_ROW.is_power_of_two());
    assert!(NET_TEXTURE_PATCHES_PER_ROW.is_power_of_two());
    assert!(TOPOLOGY_TEXTURE_WIDTH.is_power_of_two());
}
