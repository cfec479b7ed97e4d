//! Mesh writers: OBJ (`v`, `vn`, `vt`, `f`) and ASCII PLY (`x y z nx ny nz u v patch`).
//!
//! Files are written to a temporary name beside the target and renamed into place, so a
//! failure never leaves a partial file behind.

use std::io::Write;
use std::path::Path;

use crate::error::{Error, Result};
use crate::mesh::Mesh;

/// Output formats, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    Obj,
    Ply,
}

impl MeshFormat {
    pub fn from_path(path: &Path) -> Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("obj") => Ok(MeshFormat::Obj),
            Some("ply") => Ok(MeshFormat::Ply),
            _ => Err(Error::Param(format!(
                "{}: unsupported output format (use .obj or .ply)",
                path.display()
            ))),
        }
    }
}

/// Writes `mesh` in the format named by the extension of `path`.
pub fn write_mesh(path: &Path, mesh: &Mesh) -> Result<()> {
    let format = MeshFormat::from_path(path)?;
    write_atomically(path, |w| match format {
        MeshFormat::Obj => write_obj(w, mesh),
        MeshFormat::Ply => write_ply(w, mesh),
    })
}

/// Writes through `fill` into a temporary file, then renames it to `path`.
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let file_name = path
        .file_name()
        .ok_or_else(|| Error::Param(format!("{}: not a file path", path.display())))?;
    let tmp = path.with_file_name(format!(".{}.tmp", file_name.to_string_lossy()));
    let result = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut w = std::io::BufWriter::new(file);
        fill(&mut w)?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io_err)
}

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

pub fn write_ply(w: &mut dyn Write, mesh: &Mesh) -> std::io::Result<()> {
    writeln!(w, "ply\nformat ascii 1.0\ncomment tessera")?;
    writeln!(w, "element vertex {}", mesh.vertices.len())?;
    for p in ["x", "y", "z", "nx", "ny", "nz", "u", "v"] {
        writeln!(w, "property float {p}")?;
    }
    writeln!(w, "property uint patch")?;
    writeln!(w, "element face {}", mesh.triangle_count())?;
    writeln!(w, "property list uchar uint vertex_indices\nend_header")?;
    for v in &mesh.vertices {
        let [x, y, z] = v.position;
        let [nx, ny, nz] = v.normal;
        writeln!(
            w,
            "{x} {y} {z} {nx} {ny} {nz} {} {} {}",
            v.uv[0], v.uv[1], v.patch
        )?;
    }
    for [a, b, c] in mesh.triangles() {
        writeln!(w, "3 {a} {b} {c}")?;
    }
    Ok(())
}
