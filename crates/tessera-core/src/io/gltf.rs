//! glTF 2.0 (`.gltf`, `.glb`) triangle meshes as Catmull-Clark control meshes.
//!
//! Every triangle primitive of the default scene (or of every mesh when there is no
//! scene) is read with its node transforms applied. glTF splits a vertex wherever its
//! attributes differ (normals, texture seams); a control mesh needs one vertex per
//! point, so vertices are welded back by exact position. Buffers come from the GLB
//! binary chunk, `data:` URIs (base64) or files next to the input.

use std::collections::HashMap;
use std::path::Path;

use glam::{DMat4, DVec3};

use crate::catmull_clark::ControlMesh;
use crate::error::{Error, Result};

/// Reads a glTF or GLB file as a control mesh.
pub fn load_gltf(path: &Path) -> Result<ControlMesh> {
    let bytes = super::read_file(path)?;
    parse_gltf(path, &bytes)
}

/// Parses glTF/GLB bytes; external buffers are looked up next to `path`.
pub fn parse_gltf(path: &Path, bytes: &[u8]) -> Result<ControlMesh> {
    if bytes.is_empty() {
        return Err(Error::input(path, "empty file"));
    }
    let gltf = gltf::Gltf::from_slice(bytes)
        .map_err(|e| Error::input(path, format!("not a valid glTF file: {e}")))?;
    let mut buffers = Vec::new();
    for buffer in gltf.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| {
                Error::input(path, "buffer refers to a GLB binary chunk the file lacks")
            })?,
            gltf::buffer::Source::Uri(uri) => read_uri(path, uri)?,
        };
        if data.len() < buffer.length() {
            return Err(Error::input(
                path,
                format!(
                    "buffer {} holds {} bytes, {} declared",
                    buffer.index(),
                    data.len(),
                    buffer.length()
                ),
            ));
        }
        buffers.push(data);
    }

    let mut mesh = ControlMesh {
        source: path.to_path_buf(),
        ..ControlMesh::default()
    };
    let mut weld: HashMap<[u64; 3], u32> = HashMap::new();
    let mut skipped = 0usize;
    let mut add_mesh = |m: gltf::Mesh, transform: DMat4, mesh: &mut ControlMesh| -> Result<()> {
        for prim in m.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                skipped += 1;
                continue;
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| d.as_slice()));
            let positions: Vec<DVec3> = reader
                .read_positions()
                .ok_or_else(|| {
                    Error::input(
                        path,
                        format!("mesh {} has a primitive without positions", m.index()),
                    )
                })?
                .map(|p| {
                    transform.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
                })
                .collect();
            let mut ids = Vec::with_capacity(positions.len());
            for p in &positions {
                if !p.is_finite() || p.abs().max_element() > super::MAX_COORDINATE {
                    return Err(Error::input(
                        path,
                        format!(
                            "mesh {}: position {p} is not finite or beyond ±{:e}",
                            m.index(),
                            super::MAX_COORDINATE
                        ),
                    ));
                }
                let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
                let next = mesh.positions.len() as u32;
                let id = *weld.entry(key).or_insert(next);
                if id == next {
                    mesh.positions.push(*p);
                }
                ids.push(id);
            }
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(Error::input(
                    path,
                    format!(
                        "mesh {}: {} indices is not a multiple of 3",
                        m.index(),
                        indices.len()
                    ),
                ));
            }
            for t in indices.chunks_exact(3) {
                let face = t
                    .iter()
                    .map(|&i| {
                        ids.get(i as usize).copied().ok_or_else(|| {
                            Error::input(
                                path,
                                format!(
                                    "mesh {}: index {i} out of range ({} vertices)",
                                    m.index(),
                                    ids.len()
                                ),
                            )
                        })
                    })
                    .collect::<Result<Vec<u32>>>()?;
                mesh.faces.push(face);
            }
        }
        Ok(())
    };
    match gltf.default_scene().or_else(|| gltf.scenes().next()) {
        Some(scene) => {
            let mut stack: Vec<(gltf::Node, DMat4)> =
                scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
            while let Some((node, parent)) = stack.pop() {
                let local =
                    DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
                let world = parent * local;
                if let Some(m) = node.mesh() {
                    add_mesh(m, world, &mut mesh)?;
                }
                stack.extend(node.children().map(|c| (c, world)));
            }
        }
        None => {
            for m in gltf.meshes() {
                add_mesh(m, DMat4::IDENTITY, &mut mesh)?;
            }
        }
    }
    if skipped > 0 {
        mesh.warnings.push(format!(
            "{}: {skipped} non-triangle primitives (points, lines, strips) ignored",
            path.display()
        ));
    }
    if mesh.faces.is_empty() {
        return Err(Error::input(path, "no triangles"));
    }
    mesh.face_lines = vec![0; mesh.faces.len()];
    mesh.holes = vec![false; mesh.faces.len()];
    Ok(mesh)
}

fn read_uri(path: &Path, uri: &str) -> Result<Vec<u8>> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, data) = rest
            .split_once(";base64,")
            .ok_or_else(|| Error::input(path, "buffer data URI is not base64"))?;
        return base64_decode(data)
            .ok_or_else(|| Error::input(path, "buffer data URI: invalid base64"));
    }
    super::read_file(&path.parent().unwrap_or(Path::new(".")).join(uri))
}

/// Standard base64 (with or without padding).
fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let bytes: Vec<u8> = s
        .bytes()
        .filter(|&c| c != b'=' && !c.is_ascii_whitespace())
        .collect();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        let mut n = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            n |= value(c)? << (18 - 6 * k);
        }
        let take = match chunk.len() {
            4 => 3,
            3 => 2,
            2 => 1,
            _ => return None,
        };
        out.extend_from_slice(&n.to_be_bytes()[1..1 + take]);
    }
    Some(out)
}
