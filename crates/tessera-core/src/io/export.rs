//! Mesh writers: OBJ (`v`, `vn`, `vt`, `f`), ASCII PLY (`x y z nx ny nz u v face`) and
//! binary glTF (`.glb`: `POSITION`, `NORMAL`, `TEXCOORD_0` = the face's (u, v), `_FACE`).
//!
//! `face` and `(u, v)` are [`OutVertex`](crate::gpu_types::OutVertex)'s: for a
//! Catmull-Clark surface the control face (in the input's order) and its own `(u, v)` in
//! OpenSubdiv Bfr's parameterisation (Ptex's for quads), so per-face textures and
//! displacement apply directly; for Bézier patches the patch and its `(u, v)`. Points on
//! edges between faces come once per face, with the same position. OBJ has no per-vertex
//! attribute for the face: its `vt` is the face's `(u, v)` and the face is not written.
//!
//! Files are written to a temporary name beside the target and renamed into place, so a
//! failure never leaves a partial file behind.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::mesh::Mesh;

/// Output formats, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ (`.obj`).
    Obj,
    /// ASCII PLY (`.ply`).
    Ply,
    /// Binary glTF (`.glb`).
    Glb,
}

impl MeshFormat {
    /// The format named by `path`'s extension (case-insensitive); an error for any other.
    pub fn from_path(path: &Path) -> Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("obj") => Ok(MeshFormat::Obj),
            Some("ply") => Ok(MeshFormat::Ply),
            Some("glb") => Ok(MeshFormat::Glb),
            _ => Err(Error::Param(format!(
                "{}: unsupported output format (use .obj, .ply or .glb)",
                path.display()
            ))),
        }
    }
}

/// Writes `mesh` in the format named by the extension of `path`.
pub fn write_mesh(path: &Path, mesh: &Mesh) -> Result<()> {
    stage_mesh(path, mesh)?.commit()
}

/// Writes `mesh` under a temporary name beside `path`; [`StagedFile::commit`] puts it
/// in place. Lets a command write several files and keep none if one of them fails.
pub fn stage_mesh(path: &Path, mesh: &Mesh) -> Result<StagedFile> {
    let format = MeshFormat::from_path(path)?;
    stage(path, |w| match format {
        MeshFormat::Obj => write_obj(w, mesh),
        MeshFormat::Ply => write_ply(w, mesh),
        MeshFormat::Glb => write_glb(w, mesh),
    })
}

/// Writes through `fill` into a temporary file, then renames it to `path`.
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    stage(path, fill)?.commit()
}

/// A file written completely under a temporary name, not yet in place. Dropping it
/// without [`commit`](Self::commit) removes it.
#[derive(Debug)]
pub struct StagedFile {
    tmp: PathBuf,
    path: PathBuf,
    committed: bool,
}

impl StagedFile {
    /// Renames the file into place.
    pub fn commit(mut self) -> Result<()> {
        std::fs::rename(&self.tmp, &self.path).map_err(|source| Error::Io {
            path: self.path.clone(),
            source,
        })?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for StagedFile {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Puts every staged file in place, or, if a rename fails, removes the ones already
/// placed and the rest: a command leaves all its output files or none.
pub fn commit_all(files: Vec<StagedFile>) -> Result<()> {
    let mut placed: Vec<PathBuf> = Vec::new();
    for f in files {
        let path = f.path.clone();
        if let Err(e) = f.commit() {
            for p in &placed {
                let _ = std::fs::remove_file(p);
            }
            return Err(e);
        }
        placed.push(path);
    }
    Ok(())
}

/// Writes through `fill` into a temporary file beside `path`.
pub fn stage(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<StagedFile> {
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let file_name = path
        .file_name()
        .ok_or_else(|| Error::Param(format!("{}: not a file path", path.display())))?;
    let staged = StagedFile {
        tmp: path.with_file_name(format!(".{}.tmp", file_name.to_string_lossy())),
        path: path.to_path_buf(),
        committed: false,
    };
    (|| {
        let file = std::fs::File::create(&staged.tmp)?;
        let mut w = std::io::BufWriter::new(file);
        fill(&mut w)?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()
    })()
    .map_err(io_err)?;
    Ok(staged)
}

/// Writes `mesh` as OBJ: positions, normals, each vertex's `(u, v)` on its face as
/// texture coordinates (the face id itself has no place in OBJ), faces indexing all
/// three alike.
pub fn write_obj(w: &mut dyn Write, mesh: &Mesh) -> std::io::Result<()> {
    writeln!(
        w,
        "# tessera: {} vertices, {} triangles",
        mesh.vertices.len(),
        mesh.triangle_count()
    )?;
    for v in &mesh.vertices {
        writeln!(w, "v {} {} {}", v.position[0], v.position[1], v.position[2])?;
    }
    for v in &mesh.vertices {
        writeln!(w, "vn {} {} {}", v.normal[0], v.normal[1], v.normal[2])?;
    }
    for v in &mesh.vertices {
        writeln!(w, "vt {} {}", v.uv[0], v.uv[1])?;
    }
    for t in mesh.triangles() {
        let [a, b, c] = t.map(|i| i + 1);
        writeln!(w, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")?;
    }
    Ok(())
}

/// Writes `mesh` as ASCII PLY: per vertex position, normal, `(u, v)` on its face and the
/// face (`property uint face`).
pub fn write_ply(w: &mut dyn Write, mesh: &Mesh) -> std::io::Result<()> {
    writeln!(w, "ply\nformat ascii 1.0\ncomment tessera")?;
    writeln!(w, "element vertex {}", mesh.vertices.len())?;
    for p in ["x", "y", "z", "nx", "ny", "nz", "u", "v"] {
        writeln!(w, "property float {p}")?;
    }
    writeln!(w, "property uint face")?;
    writeln!(w, "element face {}", mesh.triangle_count())?;
    writeln!(w, "property list uchar uint vertex_indices\nend_header")?;
    for v in &mesh.vertices {
        let [x, y, z] = v.position;
        let [nx, ny, nz] = v.normal;
        writeln!(
            w,
            "{x} {y} {z} {nx} {ny} {nz} {} {} {}",
            v.uv[0], v.uv[1], v.face
        )?;
    }
    for [a, b, c] in mesh.triangles() {
        writeln!(w, "3 {a} {b} {c}")?;
    }
    Ok(())
}

/// glTF accessor component types and buffer-view targets.
const GL_FLOAT: u32 = 5126;
const GL_UNSIGNED_INT: u32 = 5125;
const GL_ARRAY_BUFFER: u32 = 34962;
const GL_ELEMENT_ARRAY_BUFFER: u32 = 34963;
/// Face ids are stored as floats (glTF allows unsigned ints only for indices): exact
/// below 2^24.
pub const GLB_MAX_FACE: u32 = 1 << 24;

/// Binary glTF 2.0: one mesh, one triangle primitive. The vertices are interleaved as
/// the GPU writes them (36 bytes: position, normal, the face's u v, face id),
/// `TEXCOORD_0` the face's `(u, v)`, the face id as a float in the application-specific
/// attribute `_FACE`; indices are `u32`.
pub fn write_glb(w: &mut dyn Write, mesh: &Mesh) -> std::io::Result<()> {
    const STRIDE: usize = 36;
    if let Some(v) = mesh.vertices.iter().find(|v| v.face >= GLB_MAX_FACE) {
        return Err(std::io::Error::other(format!(
            "face id {} does not fit the glTF float attribute _FACE (below 2^24)",
            v.face
        )));
    }
    let mut bin = Vec::with_capacity(mesh.vertices.len() * STRIDE + mesh.indices.len() * 4);
    for v in &mesh.vertices {
        for x in v.position.iter().chain(&v.normal).chain(&v.uv) {
            bin.extend_from_slice(&x.to_le_bytes());
        }
        bin.extend_from_slice(&(v.face as f32).to_le_bytes());
    }
    let vertex_bytes = bin.len();
    for i in &mesh.indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let (lo, hi) = mesh.bounds();
    let n = mesh.vertices.len();
    let attribute = |offset: usize, kind: &str| {
        serde_json::json!({"bufferView": 0, "byteOffset": offset, "componentType": GL_FLOAT,
            "count": n, "type": kind})
    };
    let mut position = attribute(0, "VEC3");
    position["min"] = serde_json::json!(lo.to_array());
    position["max"] = serde_json::json!(hi.to_array());
    // glTF forbids empty accessors: an empty mesh is a scene with one empty node.
    let json = if mesh.indices.is_empty() {
        serde_json::json!({
            "asset": {"version": "2.0", "generator": "tessera"},
            "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{}],
        })
    } else {
        serde_json::json!({
            "asset": {"version": "2.0", "generator": "tessera"},
            "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{
                "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2, "_FACE": 3},
                "indices": 4, "mode": 4}]}],
            "buffers": [{"byteLength": bin.len()}],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": vertex_bytes,
                 "byteStride": STRIDE, "target": GL_ARRAY_BUFFER},
                {"buffer": 0, "byteOffset": vertex_bytes,
                 "byteLength": bin.len() - vertex_bytes, "target": GL_ELEMENT_ARRAY_BUFFER},
            ],
            "accessors": [
                position,
                attribute(12, "VEC3"),
                attribute(24, "VEC2"),
                attribute(32, "SCALAR"),
                {"bufferView": 1, "componentType": GL_UNSIGNED_INT,
                 "count": mesh.indices.len(), "type": "SCALAR"},
            ],
        })
    };
    let mut json = serde_json::to_vec(&json).map_err(std::io::Error::other)?;
    // Chunks are 4-byte aligned: JSON padded with spaces, binary with zeros.
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let has_bin = !mesh.indices.is_empty();
    let total = 12 + 8 + json.len() + if has_bin { 8 + bin.len() } else { 0 };
    let too_big = || std::io::Error::other("mesh too large for one GLB file (4 GiB)");
    let u32_len = |n: usize| u32::try_from(n).map_err(|_| too_big());
    let (total, json_len, bin_len) = (u32_len(total)?, u32_len(json.len())?, u32_len(bin.len())?);
    w.write_all(b"glTF")?;
    w.write_all(&2u32.to_le_bytes())?;
    w.write_all(&total.to_le_bytes())?;
    w.write_all(&json_len.to_le_bytes())?;
    w.write_all(b"JSON")?;
    w.write_all(&json)?;
    if has_bin {
        w.write_all(&bin_len.to_le_bytes())?;
        w.write_all(b"BIN\0")?;
        w.write_all(&bin)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu_types::OutVertex;

    fn quad() -> Mesh {
        let v = |x: f32, y: f32, face| OutVertex {
            position: [x, y, 0.5],
            normal: [0.0, 0.0, 1.0],
            uv: [x, y],
            face,
        };
        Mesh {
            vertices: vec![
                v(0.0, 0.0, 7),
                v(1.0, 0.0, 7),
                v(1.0, 1.0, 8),
                v(0.0, 1.0, 9),
            ],
            indices: vec![0, 1, 2, 0, 2, 3],
        }
    }

    #[test]
    fn glb_reads_back_through_the_gltf_crate() {
        let mesh = quad();
        let mut bytes = Vec::new();
        write_glb(&mut bytes, &mesh).unwrap();
        assert_eq!(bytes.len() % 4, 0);
        // `from_slice` validates the document (accessor bounds, semantics, views).
        let gltf = gltf::Gltf::from_slice(&bytes).unwrap();
        let blob = gltf.blob.clone().unwrap();
        let prim = gltf.meshes().next().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|_| Some(&blob[..]));
        let positions: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        let normals: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
        let uvs: Vec<[f32; 2]> = reader.read_tex_coords(0).unwrap().into_f32().collect();
        let indices: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        assert_eq!(indices, mesh.indices);
        for (k, v) in mesh.vertices.iter().enumerate() {
            assert_eq!(
                (positions[k], normals[k], uvs[k]),
                (v.position, v.normal, v.uv)
            );
        }
        // `_FACE`: the float at offset 32 of each 36-byte vertex.
        let face = prim
            .attributes()
            .find(|(s, _)| *s == gltf::Semantic::Extras("FACE".into()))
            .map(|(_, a)| a)
            .unwrap();
        assert_eq!((face.offset(), face.count()), (32, 4));
        let ids: Vec<f32> = (0..4)
            .map(|k| f32::from_le_bytes(blob[k * 36 + 32..k * 36 + 36].try_into().unwrap()))
            .collect();
        assert_eq!(ids, [7.0, 7.0, 8.0, 9.0]);
        // An empty mesh is still a valid file.
        let mut empty = Vec::new();
        write_glb(&mut empty, &Mesh::default()).unwrap();
        assert_eq!(gltf::Gltf::from_slice(&empty).unwrap().meshes().count(), 0);
    }

    #[test]
    fn a_failed_write_leaves_nothing() {
        let dir = std::env::temp_dir().join(format!("tessera-export-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("m.obj");
        let staged = stage_mesh(&out, &quad()).unwrap();
        drop(staged);
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            0,
            "temporary left"
        );
        // Two files: the second cannot be written, so neither is placed.
        let mesh_file = stage_mesh(&out, &quad()).unwrap();
        assert!(stage(&dir.join("missing/s.json"), |_| Ok(())).is_err());
        drop(mesh_file);
        assert!(!out.exists());
        let a = stage_mesh(&out, &quad()).unwrap();
        let b = stage(&dir.join("s.json"), |w| writeln!(w, "{{}}")).unwrap();
        commit_all(vec![a, b]).unwrap();
        assert!(out.exists() && dir.join("s.json").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
