//! Readers and writers of files.

pub mod export;
pub mod gltf;
pub mod obj;
pub mod teaset;

/// Loads a Catmull-Clark control mesh, choosing the reader by extension: `.gltf` and
/// `.glb` through [`gltf`], anything else as OBJ.
pub fn load_control_mesh(
    path: &std::path::Path,
) -> crate::Result<crate::catmull_clark::ControlMesh> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("gltf" | "glb") => gltf::load_gltf(path),
        _ => obj::load_obj(path),
    }
}

/// Whether `path` names a Catmull-Clark control mesh (`.obj`, `.gltf`, `.glb`, any case)
/// rather than a Newell teaset file: how the tools tell the two kinds of input apart.
pub fn is_control_mesh(path: &std::path::Path) -> bool {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    matches!(ext.as_deref(), Some("obj" | "gltf" | "glb"))
}

/// Input coordinates beyond this are refused: squared distances of single-precision
/// points (what the GPU computes) would overflow.
pub const MAX_COORDINATE: f64 = 1e18;

/// Reads a whole input file; the error names it.
pub(crate) fn read_file(path: &std::path::Path) -> crate::Result<Vec<u8>> {
    std::fs::read(path).map_err(|source| crate::Error::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The bytes of a text format as UTF-8, or an error saying it is not text.
pub(crate) fn utf8_text<'a>(path: &std::path::Path, bytes: &'a [u8]) -> crate::Result<&'a str> {
    std::str::from_utf8(bytes).map_err(|e| {
        crate::Error::input(
            path,
            format!(
                "not a text file (invalid UTF-8 at byte {})",
                e.valid_up_to()
            ),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::is_control_mesh;
    use std::path::Path;

    #[test]
    fn control_meshes_are_told_by_extension() {
        for p in ["a.obj", "b.OBJ", "dir/c.gltf", "d.Glb"] {
            assert!(is_control_mesh(Path::new(p)), "{p}");
        }
        for p in ["teapot", "teacup.txt", "obj", "x.objx", "dir.obj/teapot"] {
            assert!(!is_control_mesh(Path::new(p)), "{p}");
        }
    }
}
