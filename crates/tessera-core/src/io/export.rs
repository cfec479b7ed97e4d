//! Mesh writers: OBJ (`v`, `vn`, `vt`, `f`) and ASCII PLY (`x y z nx ny nz u v patch`).
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
    stage_mesh(path, mesh)?.commit()
}

/// Writes `mesh` under a temporary name beside `path`; [`StagedFile::commit`] puts it
/// in place. Lets a command write several files and keep none if one of them fails.
pub fn stage_mesh(path: &Path, mesh: &Mesh) -> Result<StagedFile> {
    let format = MeshFormat::from_path(path)?;
    stage(path, |w| match format {
        MeshFormat::Obj => write_obj(w, mesh),
        MeshFormat::Ply => write_ply(w, mesh),
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
