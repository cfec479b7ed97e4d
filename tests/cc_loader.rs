//! The OBJ reader: every reference form, OpenSubdiv tags, and bad input reported with
//! file, line and problem.

use std::path::Path;

use tessera_core::catmull_clark::{BoundaryRule, CreaseMethod, PatchMesh};
use tessera_core::io::obj::parse_obj;
use tessera_tests::control_mesh;

fn parse(text: &str) -> Result<tessera_core::catmull_clark::ControlMesh, String> {
    parse_obj(Path::new("test.obj"), text.as_bytes()).map_err(|e| e.to_string())
}

/// Parses and validates; the error text when either fails.
fn check(text: &str) -> Result<(), String> {
    let mesh = parse(text)?;
    PatchMesh::new(&mesh).map(|_| ()).map_err(|e| e.to_string())
}

const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

#[test]
fn reads_every_face_reference_form_and_negative_indices() {
    let text = format!(
        "{SQUARE}vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nv 2 0 0\nv 2 1 0\n\
         f 1/1 2/2 3/3 4/1\nf 2//1 5//1 6//1 3//1\nf -4/1/1 -2/2/1 -1/3/1\n"
    );
    let mesh = parse(&text).unwrap();
    assert_eq!(
        mesh.faces,
        vec![vec![0, 1, 2, 3], vec![1, 4, 5, 2], vec![2, 4, 5]]
    );
    assert_eq!(mesh.face_lines, vec![11, 12, 13]);
    // A pentagon and comments, groups and materials are fine.
    let pent = "# c\no x\ng y\nusemtl m\ns 1\nv 0 0 0\nv 1 0 0\nv 1.5 1 0\nv 0.5 2 0\nv -0.5 1 0\nf 1 2 3 4 5 # tail\n";
    assert_eq!(parse(pent).unwrap().faces, vec![vec![0, 1, 2, 3, 4]]);
}

#[test]
fn applies_boundary_and_hole_tags_and_warns_about_the_rest() {
    let m = control_mesh("opensubdiv/catmark_edgeonly.obj");
    assert_eq!(m.boundary, BoundaryRule::EdgeOnly);
    assert_eq!(m.corners.len(), 6);
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    assert_eq!(
        control_mesh("opensubdiv/catmark_edgecorner.obj").boundary,
        BoundaryRule::EdgeAndCorner
    );
    // No tag: the SPEC's default, edge-and-corner.
    assert_eq!(
        control_mesh("opensubdiv/catmark_flap.obj").boundary,
        BoundaryRule::EdgeAndCorner
    );
    let holes = control_mesh("opensubdiv/catmark_hole_test1.obj");
    assert_eq!(holes.holes, vec![false, true, false, false, false, false]);
    // Hierarchical edits are not applied, and say so with file and line.
    let edits = control_mesh("opensubdiv/catmark_square_hedit0.obj");
    let edit = edits
        .warnings
        .iter()
        .find(|w| w.contains("edit\""))
        .expect("edit warning");
    assert!(
        edit.contains("catmark_square_hedit0.obj:") && edit.contains("not supported"),
        "{edit}"
    );
    assert!(control_mesh("opensubdiv/catmark_cube.obj")
        .warnings
        .is_empty());
}

#[test]
fn reads_creases_corners_and_the_subdivision_options() {
    let car = control_mesh("opensubdiv/catmark_car.obj");
    assert!(car.warnings.is_empty(), "{:?}", car.warnings);
    assert_eq!(car.creases.len(), 314);
    assert!(car.creases.iter().all(|c| c.1 > 0.0));
    // Indices are 0-based: the first tag of the car is `t crease 2/1/0 16 17 10`.
    let first = std::fs::read_to_string(tessera_tests::asset("opensubdiv/catmark_car.obj"))
        .unwrap()
        .lines()
        .find(|l| l.starts_with("t crease"))
        .unwrap()
        .to_string();
    let w: Vec<&str> = first.split_whitespace().collect();
    assert_eq!(
        car.creases[0],
        (
            [w[3].parse().unwrap(), w[4].parse().unwrap()],
            w[5].parse().unwrap()
        )
    );
    let chaikin = control_mesh("opensubdiv/catmark_chaikin1.obj");
    assert_eq!(chaikin.crease_method, CreaseMethod::Chaikin);
    assert_eq!(
        control_mesh("opensubdiv/catmark_chaikin0.obj").crease_method,
        CreaseMethod::Normal
    );
    assert!(control_mesh("opensubdiv/catmark_smoothtris1.obj").smooth_triangles);
    assert!(!control_mesh("opensubdiv/catmark_smoothtris0.obj").smooth_triangles);
    let corners = control_mesh("opensubdiv/catmark_cube_corner1.obj");
    assert!(!corners.corners.is_empty() && corners.has_creases());
    // Shared and per-element sharpness; negative is smooth.
    let square = format!("{SQUARE}v 2 0 0\nv 2 1 0\nf 1 2 3 4\nf 2 5 6 3\n");
    let m = parse(&format!(
        "{square}t crease 4/1/0 1 2 0 3 2.5\nt corner 2/2/0 0 4 1 -3\n"
    ))
    .unwrap();
    assert_eq!(m.creases, vec![([1, 2], 2.5), ([0, 3], 2.5)]);
    assert_eq!(m.corners, vec![(0, 1.0), (4, 0.0)]);
    let m = parse(&format!("{square}t crease 4/2/0 1 2 0 3 1 2\n")).unwrap();
    assert_eq!(m.creases, vec![([1, 2], 1.0), ([0, 3], 2.0)]);
    let mut dropped = m.clone();
    dropped.drop_creases("--no-creases");
    assert!(!dropped.has_creases());
    assert!(dropped.warnings.iter().any(|w| w.contains("--no-creases")));
}

#[test]
fn bad_crease_tags_name_the_line() {
    let square = format!("{SQUARE}f 1 2 3 4\n");
    for (tag, problem) in [
        ("t crease 2/1/0 0 2 1", "not an edge"),
        ("t crease 2/1/0 0 9 1", "out of range"),
        ("t crease 3/1/0 0 1 2 1", "pairs"),
        ("t crease 4/3/0 0 1 1 2 1 1 1", "sharpness values"),
        ("t corner 1/1/0 -1 1", "out of range"),
        ("t crease 2/1/0 0 1 x", "not a number"),
        ("t creasemethod 0/0/1 fast", "normal or chaikin"),
        ("t smoothtriangles 0/0/0", "smooth or catmark"),
    ] {
        let e = parse(&format!("{square}{tag}\n")).unwrap_err();
        assert!(
            e.starts_with("test.obj:6:") && e.contains(problem),
            "{tag}: {e}"
        );
    }
}

#[test]
fn hole_faces_make_no_patches() {
    let m = control_mesh("opensubdiv/catmark_hole_test1.obj");
    let mesh = PatchMesh::new(&m).unwrap();
    let holes = m.holes.iter().filter(|&&h| h).count();
    assert_eq!(
        mesh.surface_patches().count(),
        mesh.patch_count() - 4 * holes
    );
}

#[test]
fn bad_input_names_file_line_and_problem() {
    let cases: Vec<(String, &str)> = vec![
        (String::new(), "test.obj: empty file"),
        ("v 0 0 0\0\n".into(), "test.obj: not a text file"),
        ("\u{0}\u{1}binary".into(), "not a text file"),
        (
            format!("{SQUARE}f 1 2 3 9\n"),
            "test.obj:5: vertex index 9 out of range",
        ),
        (format!("{SQUARE}f 1 2 0 3\n"), "test.obj:5: vertex index 0"),
        (
            format!("{SQUARE}f 1 2 -7\n"),
            "test.obj:5: vertex index -7 out of range",
        ),
        (
            format!("{SQUARE}f 1/5 2 3\n"),
            "test.obj:5: texture coordinate index 5 out of range",
        ),
        (
            "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".into(),
            "test.obj:1: coordinate \"nan\" is not finite",
        ),
        (
            "v 0 0 inf\n".into(),
            "test.obj:1: coordinate \"inf\" is not finite",
        ),
        ("v 0 0\n".into(), "test.obj:1: vertex has 2 coordinates"),
        ("v 0 0 x\n".into(), "test.obj:1: \"x\" is not a number"),
        (
            format!("{SQUARE}f 1 2\n"),
            "test.obj:5: face has 2 vertices",
        ),
        (
            format!("{SQUARE}f 1 2 1\n"),
            "test.obj:5: face has only 2 distinct vertices",
        ),
        (
            format!("{SQUARE}f 1 2 3 2\n"),
            "test.obj:5: face uses vertex 2 twice",
        ),
        (SQUARE.into(), "test.obj: no faces"),
        (
            format!("{SQUARE}f 1 2 3 4\nt interpolateboundary 1/0/0\n"),
            "test.obj:6: tag \"interpolateboundary\" announces 1 values but has 0",
        ),
        (
            format!("{SQUARE}f 1 2 3 4\nt hole 1/0/0 3\n"),
            "test.obj:6: hole face 3 out of range",
        ),
        // Counts whose sum wraps around usize must not pass the length check.
        (
            format!("{SQUARE}f 1 2 3 4\nt foo 18446744073709551615/1/0 1\n"),
            "test.obj:6: tag \"foo\" announces too many values but has 1",
        ),
        (
            format!("{SQUARE}f 1 2 3 4\nt foo 9223372036854775807/9223372036854775807/2 1\n"),
            "test.obj:6: tag \"foo\" announces",
        ),
        (
            format!("{SQUARE}f 1 2 3 4\nt interpolateboundary 1/0/0 7\n"),
            "test.obj:6: interpolateboundary 7: expected 0, 1 or 2",
        ),
        (
            format!("{SQUARE}f 1 2 3 4\nt hole 1/0/0 0\n"),
            "test.obj: every face is tagged as a hole",
        ),
        (
            "v 0 0 2e18\n".into(),
            "test.obj:1: coordinate 2e18 is beyond ±1e18",
        ),
        // Three faces on the edge 1-2.
        (
            format!("{SQUARE}v 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 5\nf 1 2 6\n"),
            "non-manifold edge 1-2",
        ),
        // Two faces meeting only at a vertex.
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv -1 0 0\nv 0 -1 0\nf 1 2 3\nf 1 4 5\n".into(),
            "non-manifold vertex 1",
        ),
        (
            format!("{SQUARE}f 1 2 3 4\nf 1 2 3\n"),
            "inconsistent orientation",
        ),
    ];
    for (text, expect) in &cases {
        let err = check(text).expect_err(expect);
        assert!(err.contains(expect), "expected {expect:?}, got {err:?}");
        assert_eq!(err.lines().count(), 1, "{err}");
    }
}

#[test]
fn non_manifold_edges_are_reported_as_such() {
    // OpenSubdiv's fan: three sheets on one chain of edges. Its second sheet also runs
    // the shared edges the same way as the first, which must not mask the real problem.
    let err = PatchMesh::new(&control_mesh("opensubdiv/catmark_fan.obj"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("catmark_fan.obj:") && err.contains("non-manifold edge"),
        "{err}"
    );
}

/// Positions of a uniform tessellation (4 segments per patch side) that lie in exactly
/// `copies` sheets (connected sets of faces), to 1e-9: where sheets cut apart meet again.
/// By sheet, not by vertex: within a sheet a point between faces is a vertex per face.
fn shared_points(control: &tessera_core::catmull_clark::ControlMesh, copies: usize) -> usize {
    use tessera_core::catmull_clark::{tessellate_uniform, SurfaceModel, TREE_DEPTH};
    let model = SurfaceModel::new(
        PatchMesh::new(control).expect("valid after the cut"),
        TREE_DEPTH,
    );
    let mesh = tessellate_uniform(&model, 4).expect("uniform").mesh;
    // Sheets: faces joined through shared vertices.
    let mut parent: Vec<usize> = (0..control.positions.len()).collect();
    fn root(parent: &mut [usize], mut v: usize) -> usize {
        while parent[v] != v {
            parent[v] = parent[parent[v]];
            v = parent[v];
        }
        v
    }
    for f in &control.faces {
        for w in f.windows(2) {
            let (a, b) = (
                root(&mut parent, w[0] as usize),
                root(&mut parent, w[1] as usize),
            );
            parent[a] = b;
        }
    }
    let mut seen: std::collections::HashMap<[i64; 3], Vec<usize>> = Default::default();
    for v in &mesh.vertices {
        let p = glam::DVec3::from_array(v.position.map(f64::from));
        let sheet = root(&mut parent, control.faces[v.face as usize][0] as usize);
        let sheets = seen
            .entry((p * 1e6).round().to_array().map(|x| x as i64))
            .or_default();
        if !sheets.contains(&sheet) {
            sheets.push(sheet);
        }
    }
    seen.values().filter(|s| s.len() == copies).count()
}

#[test]
fn cutting_non_manifold_edges_gives_sheets_that_meet_along_the_cut() {
    // The fan's three sheets share a chain of four edges whose ends are corners in every
    // sheet: cut apart, each sheet ends in the same boundary curve there, so the uniform
    // grids of the three meet point for point along it: 4 edges, 2 patch sides each, 4
    // segments per side, 33 points, each in all three sheets.
    let mut fan = control_mesh("opensubdiv/catmark_fan.obj");
    let vertices = fan.positions.len();
    assert_eq!(fan.split_non_manifold().expect("the fan can be cut"), 4);
    // The chain's 5 vertices, copied for the second and third sheet.
    assert_eq!(fan.positions.len(), vertices + 2 * 5);
    assert_eq!(shared_points(&fan, 3), 33);
    // The check has teeth: move one sheet's copy of a vertex inside the chain, and the
    // curves part around it.
    let mut moved = fan.clone();
    // Copies are made in face order: the second sheet's of vertices 8, 9, 10, 11, 12,
    // then the third sheet's of 9, 8, 10, ...: its copy of vertex 10 is the eighth.
    let copy = vertices + 7;
    assert_eq!(fan.positions[copy], fan.positions[9]);
    assert!(
        fan.faces[10].contains(&(copy as u32)),
        "{:?}",
        fan.faces[10]
    );
    moved.positions[copy].z += 1e-3;
    let after = shared_points(&moved, 3);
    assert!(after < 33, "{after} points still shared");
    // Cutting twice changes nothing; a manifold mesh is left as it is.
    assert_eq!(fan.split_non_manifold().unwrap(), 0);
    let mut cube = control_mesh("opensubdiv/catmark_cube.obj");
    let before = (cube.positions.clone(), cube.faces.clone());
    assert_eq!(cube.split_non_manifold().unwrap(), 0);
    assert_eq!((cube.positions, cube.faces), before);
}

#[test]
fn a_cut_whose_sheets_would_part_is_an_error() {
    // Edge 1-2 has three faces; in the third sheet vertex 1 has two faces and a boundary
    // edge that is not cut, so that sheet's boundary curve leaves the cut there while the
    // other two make vertex 1 a corner: refused, naming the vertex.
    let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 -1 0\nv 0 -1 0\nv 1 0 1\nv 0 0 1\nv 0 0 2\nv -1 0 1\n\
                f 1 2 3 4\nf 2 1 6 5\nf 1 2 7 8\nf 1 8 9 10\n";
    let mut mesh = parse(text).expect("parses");
    let err = mesh.split_non_manifold().unwrap_err().to_string();
    assert!(err.contains("non-manifold edges at vertex 1:"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn valence_limits_are_errors() {
    // OpenSubdiv's pole with valence 360.
    let m = control_mesh("opensubdiv/catmark_pole360.obj");
    let err = PatchMesh::new(&m).unwrap_err().to_string();
    assert!(
        err.contains("catmark_pole360.obj:") && err.contains("valence 360; at most 64"),
        "{err}"
    );
    // Valence 64 is accepted.
    assert!(PatchMesh::new(&control_mesh("opensubdiv/catmark_pole64.obj")).is_ok());
    // An interior vertex of valence 2 (two quads glued along two edges) is not.
    let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n\
                f 1 2 3 4\nf 2 5 6 3\nf 4 3 6 5 2 1\n";
    let err = check(text).unwrap_err();
    assert!(err.contains("valence 2"), "{err}");
}

fn base64(data: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            s.push(if k <= c.len() {
                A[(n >> (18 - 6 * k) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    s
}

/// A cube as glTF exports it: 24 vertices (4 per face, split by normal), 12 triangles.
fn split_cube() -> (Vec<u8>, usize, usize) {
    let corners = |f: usize| -> [[f32; 3]; 4] {
        let (axis, sign) = (f / 2, if f.is_multiple_of(2) { 1.0 } else { -1.0 });
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut out = [[0f32; 3]; 4];
        for (k, (s, t)) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .into_iter()
            .enumerate()
        {
            let mut p = [0f32; 3];
            p[axis] = sign;
            p[a] = s;
            p[b] = t * sign;
            out[k] = p;
        }
        out
    };
    let mut bin = Vec::new();
    for f in 0..6 {
        for p in corners(f) {
            for c in p {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    let pos_len = bin.len();
    for f in 0..6u16 {
        for i in [0, 1, 2, 0, 2, 3] {
            bin.extend_from_slice(&(4 * f + i).to_le_bytes());
        }
    }
    (bin, pos_len, 36)
}

fn gltf_json(uri: Option<&str>, bin_len: usize, pos_len: usize, count: usize) -> String {
    let uri = uri.map(|u| format!(r#""uri":"{u}","#)).unwrap_or_default();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"mesh":0,"translation":[10,0,0]}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "buffers":[{{{uri}"byteLength":{bin_len}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}},{{"buffer":0,"byteOffset":{pos_len},"byteLength":{}}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":24,"type":"VEC3","min":[-1,-1,-1],"max":[1,1,1]}},
                     {{"bufferView":1,"componentType":5123,"count":{count},"type":"SCALAR"}}]}}"#,
        bin_len - pos_len
    )
}

#[test]
fn gltf_and_glb_triangle_meshes_are_welded_by_position() {
    use tessera_core::io::gltf::parse_gltf;
    let (bin, pos_len, count) = split_cube();
    let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    let gltf = gltf_json(Some(&uri), bin.len(), pos_len, count);
    // GLB: header, JSON chunk padded with spaces, BIN chunk padded with zeros.
    let mut json = gltf_json(None, bin.len(), pos_len, count).into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin_padded = bin.clone();
    while !bin_padded.len().is_multiple_of(4) {
        bin_padded.push(0);
    }
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((12 + 8 + json.len() + 8 + bin_padded.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin_padded.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin_padded);
    // Also through `load_control_mesh`, which picks the reader by extension (what the
    // CLI calls), from files on disk.
    let dir = std::env::temp_dir().join(format!("tessera-gltf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes) in [("cube.gltf", gltf.into_bytes()), ("cube.glb", glb)] {
        let file = dir.join(name);
        std::fs::write(&file, &bytes).unwrap();
        let loaded = tessera_core::io::load_control_mesh(&file).unwrap();
        assert_eq!(loaded.faces.len(), 12, "{name} from disk");
        let mesh = parse_gltf(Path::new(name), &bytes).unwrap();
        assert_eq!(mesh.positions.len(), 8, "{name}: welded");
        assert_eq!(mesh.faces.len(), 12, "{name}");
        // The node's translation is applied.
        assert!(
            mesh.positions.iter().all(|p| (p.x - 10.0).abs() == 1.0),
            "{name}"
        );
        let patches = PatchMesh::new(&mesh).expect("closed and manifold once welded");
        assert_eq!(
            patches.edge_uses.iter().filter(|&&u| u == 1).count(),
            0,
            "{name}: no boundary"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    // Bad glTF: one line naming the file.
    for (bytes, expect) in [
        (&b"{\"asset\":"[..], "not a valid glTF file"),
        (&b""[..], "empty file"),
    ] {
        let err = parse_gltf(Path::new("bad.glb"), bytes)
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("bad.glb: ") && err.contains(expect) && err.lines().count() == 1,
            "{err}"
        );
    }
}
