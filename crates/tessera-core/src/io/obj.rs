//! Wavefront OBJ control meshes with OpenSubdiv tag lines.
//!
//! Read: `v x y z`, `vt`, `vn` (counted so that face references can be checked), and
//! `f` with `v`, `v/vt`, `v//vn` or `v/vt/vn` references, 1-based or negative (relative
//! to the vertices read so far), polygons of any size. Tag lines
//! `t <name> <nint>/<nfloat>/<nstring> <ints> <floats> <strings>` (0-based indices):
//! `interpolateboundary` (1 edge-and-corner, 2 edge-only), `hole`, `crease` (vertex
//! pairs, one sharpness for all or one per pair), `corner` (vertices, likewise),
//! `creasemethod` (`normal`, `chaikin`) and `smoothtriangles` (`smooth`, `catmark`) are
//! applied with OpenSubdiv's meaning; every other tag (hierarchical edits, face-varying
//! options, ...) is ignored with a warning in [`ControlMesh::warnings`]. Other OBJ statements (`o`, `g`, `s`, `usemtl`, ...) carry
//! nothing a surface needs.

use std::collections::BTreeMap;
use std::path::Path;

use glam::DVec3;

use crate::catmull_clark::{BoundaryRule, ControlMesh, CreaseMethod};

/// A tag line: `t <name> <nint>/<nfloat>/<nstring> <ints> <floats> <strings>`.
struct Tag {
    line: usize,
    name: String,
    ints: Vec<i64>,
    floats: Vec<f32>,
    strings: Vec<String>,
}
use crate::error::{Error, Result};

/// Reads an OBJ control mesh from disk.
pub fn load_obj(path: &Path) -> Result<ControlMesh> {
    let bytes = super::read_file(path)?;
    parse_obj(path, &bytes)
}

/// Parses OBJ text; `path` names the file in errors and warnings.
pub fn parse_obj(path: &Path, bytes: &[u8]) -> Result<ControlMesh> {
    if bytes.is_empty() {
        return Err(Error::input(path, "empty file"));
    }
    if bytes.contains(&0) {
        return Err(Error::input(path, "not a text file (contains NUL bytes)"));
    }
    let text = super::utf8_text(path, bytes)?;

    let mut mesh = ControlMesh {
        source: path.to_path_buf(),
        ..ControlMesh::default()
    };
    let (mut texcoords, mut normals) = (0usize, 0usize);
    // Tags to apply once all faces are known: (line, name, ints).
    let mut tags: Vec<Tag> = Vec::new();
    let mut ignored: BTreeMap<String, (usize, usize)> = BTreeMap::new();

    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        let mut words = content.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        let err = |msg: String| Error::parse(path, line, msg);
        match keyword {
            "v" => {
                let mut xyz = [0f64; 3];
                for (k, c) in xyz.iter_mut().enumerate() {
                    let w = words
                        .next()
                        .ok_or_else(|| err(format!("vertex has {k} coordinates, expected 3")))?;
                    *c = parse_finite(w).map_err(err)?;
                }
                mesh.positions.push(DVec3::from_array(xyz));
            }
            "vt" => texcoords += 1,
            "vn" => normals += 1,
            "f" => {
                let mut face = Vec::new();
                for w in words {
                    face.push(
                        parse_reference(w, mesh.positions.len(), texcoords, normals)
                            .map_err(err)?,
                    );
                }
                if face.len() < 3 {
                    return Err(err(format!(
                        "face has {} vertices, at least 3 are needed",
                        face.len()
                    )));
                }
                mesh.faces.push(face);
                mesh.face_lines.push(line);
            }
            "t" => {
                let name = words
                    .next()
                    .ok_or_else(|| err("tag without a name".into()))?;
                let counts = words.next().ok_or_else(|| {
                    err(format!(
                        "tag {name:?} without its nint/nfloat/nstring counts"
                    ))
                })?;
                let counts: Vec<usize> = counts
                    .split('/')
                    .map(|c| c.parse::<usize>())
                    .collect::<Result<_, _>>()
                    .ok()
                    .filter(|c: &Vec<usize>| c.len() == 3)
                    .ok_or_else(|| {
                        err(format!(
                            "tag {name:?}: counts {counts:?} are not nint/nfloat/nstring"
                        ))
                    })?;
                let rest: Vec<&str> = words.collect();
                // Checked: counts near usize::MAX must not wrap into a small total.
                let announced = counts[0]
                    .checked_add(counts[1])
                    .and_then(|n| n.checked_add(counts[2]));
                if announced.is_none_or(|n| rest.len() < n) {
                    return Err(err(format!(
                        "tag {name:?} announces {} values but has {}",
                        announced.map_or("too many".into(), |n| n.to_string()),
                        rest.len()
                    )));
                }
                let ints = rest[..counts[0]]
                    .iter()
                    .map(|w| {
                        w.parse::<i64>()
                            .map_err(|_| err(format!("tag {name:?}: {w:?} is not an integer")))
                    })
                    .collect::<Result<Vec<_>>>()?;
                let floats = rest[counts[0]..counts[0] + counts[1]]
                    .iter()
                    .map(|w| {
                        w.parse::<f32>()
                            .ok()
                            .filter(|x| !x.is_nan())
                            .ok_or_else(|| err(format!("tag {name:?}: {w:?} is not a number")))
                    })
                    .collect::<Result<Vec<_>>>()?;
                let strings = rest[counts[0] + counts[1]..counts[0] + counts[1] + counts[2]]
                    .iter()
                    .map(|w| w.to_string())
                    .collect();
                tags.push(Tag {
                    line,
                    name: name.to_string(),
                    ints,
                    floats,
                    strings,
                });
            }
            "vp" | "o" | "g" | "s" | "mtllib" | "usemtl" | "l" | "p" | "cstype" | "deg" => {}
            other => {
                let e = ignored
                    .entry(format!("unknown statement {other:?}"))
                    .or_insert((line, 0));
                e.1 += 1;
            }
        }
    }

    if mesh.faces.is_empty() {
        return Err(Error::input(path, "no faces"));
    }
    let nv = mesh.positions.len();
    for (face, &line) in mesh.faces.iter_mut().zip(&mesh.face_lines) {
        for v in face.iter_mut() {
            // References were checked against the vertices read before the face; forward
            // references (positive indices past that) are resolved here.
            if *v as usize >= nv {
                return Err(Error::parse(
                    path,
                    line,
                    format!(
                        "vertex index {} out of range (the file has {nv} vertices)",
                        *v + 1
                    ),
                ));
            }
        }
    }
    mesh.holes = vec![false; mesh.faces.len()];

    let vertex = |i: i64, line: usize, what: &str| {
        usize::try_from(i)
            .ok()
            .filter(|&i| i < nv)
            .map(|i| i as u32)
            .ok_or_else(|| {
                Error::parse(
                    path,
                    line,
                    format!(
                        "{what} vertex {i} out of range ({nv} vertices; tag indices start at 0)"
                    ),
                )
            })
    };
    let mut edges: Option<std::collections::HashSet<(u32, u32)>> = None;
    for Tag {
        line,
        name,
        ints,
        floats,
        strings,
    } in tags
    {
        let err = |msg: String| Error::parse(path, line, msg);
        // One sharpness for all, or one per element (negative sharpness is smooth, as
        // OpenSubdiv reads it).
        let sharpness = |k: usize, elements: usize| -> Result<f32> {
            match floats.len() {
                1 => Ok(floats[0].max(0.0)),
                n if n == elements => Ok(floats[k].max(0.0)),
                n => Err(err(format!(
                    "{name} tag with {elements} element{} has {n} sharpness values: expected 1 or {elements}",
                    if elements == 1 { "" } else { "s" }
                ))),
            }
        };
        match name.as_str() {
            "interpolateboundary" => match ints.first() {
                Some(1) => mesh.boundary = BoundaryRule::EdgeAndCorner,
                Some(2) => mesh.boundary = BoundaryRule::EdgeOnly,
                Some(0) => mesh.warnings.push(format!(
                    "{}:{line}: interpolateboundary 0 (no boundary interpolation) is not supported; boundaries use the edge-and-corner rule",
                    path.display()
                )),
                Some(other) => return Err(err(format!("interpolateboundary {other}: expected 0, 1 or 2"))),
                None => return Err(err("interpolateboundary without a value: expected 0, 1 or 2".into())),
            },
            "hole" => {
                for &f in &ints {
                    let slot = usize::try_from(f)
                        .ok()
                        .and_then(|f| mesh.holes.get_mut(f))
                        .ok_or_else(|| err(format!("hole face {f} out of range ({} faces)", mesh.faces.len())))?;
                    *slot = true;
                }
            }
            "crease" => {
                if ints.len() % 2 != 0 || ints.is_empty() {
                    return Err(err(format!(
                        "crease tag with {} vertex indices: expected pairs, one per edge",
                        ints.len()
                    )));
                }
                let edges = edges.get_or_insert_with(|| {
                    mesh.faces
                        .iter()
                        .flat_map(|f| (0..f.len()).map(|k| (f[k], f[(k + 1) % f.len()])))
                        .map(|(a, b)| (a.min(b), a.max(b)))
                        .collect()
                });
                for (k, pair) in ints.chunks(2).enumerate() {
                    let (a, b) = (vertex(pair[0], line, "crease")?, vertex(pair[1], line, "crease")?);
                    if !edges.contains(&(a.min(b), a.max(b))) {
                        return Err(err(format!(
                            "crease {a}-{b} is not an edge of the mesh (tag indices start at 0)"
                        )));
                    }
                    mesh.creases.push(([a, b], sharpness(k, ints.len() / 2)?));
                }
            }
            "corner" => {
                if ints.is_empty() {
                    return Err(err("corner tag without a vertex".into()));
                }
                for (k, &v) in ints.iter().enumerate() {
                    mesh.corners.push((vertex(v, line, "corner")?, sharpness(k, ints.len())?));
                }
            }
            "creasemethod" => match strings.first().map(String::as_str) {
                Some("normal") => mesh.crease_method = CreaseMethod::Normal,
                Some("chaikin") => mesh.crease_method = CreaseMethod::Chaikin,
                other => {
                    return Err(err(format!(
                        "creasemethod {}: expected normal or chaikin",
                        other.map_or("without a value".into(), |o| format!("{o:?}"))
                    )))
                }
            },
            "smoothtriangles" => match strings.first().map(String::as_str) {
                Some("smooth") => mesh.smooth_triangles = true,
                Some("catmark") => mesh.smooth_triangles = false,
                other => {
                    return Err(err(format!(
                        "smoothtriangles {}: expected smooth or catmark",
                        other.map_or("without a value".into(), |o| format!("{o:?}"))
                    )))
                }
            },
            other => {
                let e = ignored.entry(format!("tag {other:?}")).or_insert((line, 0));
                e.1 += 1;
            }
        }
    }
    for (what, (line, count)) in ignored {
        let hint = if what.contains("edit") {
            " (hierarchical edits are not supported: the surface is tessellated without them)"
        } else if what.contains("facevarying") {
            " (face-varying data is not read)"
        } else {
            ""
        };
        mesh.warnings.push(format!(
            "{}:{line}: {what} ignored ({count} line{}){hint}",
            path.display(),
            if count == 1 { "" } else { "s" }
        ));
    }
    Ok(mesh)
}

fn parse_finite(w: &str) -> Result<f64, String> {
    let x: f64 = w.parse().map_err(|_| format!("{w:?} is not a number"))?;
    if !x.is_finite() {
        Err(format!("coordinate {w:?} is not finite"))
    } else if x.abs() > super::MAX_COORDINATE {
        Err(format!(
            "coordinate {w} is beyond ±{:e}, where single-precision distances overflow",
            super::MAX_COORDINATE
        ))
    } else {
        Ok(x)
    }
}

/// One `f` reference (`v`, `v/vt`, `v//vn`, `v/vt/vn`) to a 0-based vertex index.
fn parse_reference(
    w: &str,
    positions: usize,
    texcoords: usize,
    normals: usize,
) -> Result<u32, String> {
    let mut parts = w.split('/');
    let v = parts.next().unwrap_or("");
    let index = resolve(v, positions, "vertex", true)?;
    if let Some(vt) = parts.next() {
        if !vt.is_empty() {
            resolve(vt, texcoords, "texture coordinate", false)?;
        }
    }
    if let Some(vn) = parts.next() {
        if !vn.is_empty() {
            resolve(vn, normals, "normal", false)?;
        }
    }
    if parts.next().is_some() {
        return Err(format!("face reference {w:?} has more than 3 parts"));
    }
    Ok(index)
}

/// A 1-based or negative OBJ index to 0-based. Positive vertex indices may point forward
/// (checked when the file is read); everything else must exist already.
fn resolve(s: &str, count: usize, what: &str, forward_ok: bool) -> Result<u32, String> {
    let i: i64 = s
        .parse()
        .map_err(|_| format!("{what} index {s:?} is not an integer"))?;
    let resolved = match i {
        0 => return Err(format!("{what} index 0 (OBJ indices start at 1)")),
        i if i < 0 => count as i64 + i,
        i => i - 1,
    };
    if resolved < 0 || (!forward_ok && resolved >= count as i64) {
        return Err(format!(
            "{what} index {i} out of range ({count} defined so far)"
        ));
    }
    u32::try_from(resolved).map_err(|_| format!("{what} index {i} too large"))
}
