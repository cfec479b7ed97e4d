//! Readers and writers of files.

pub mod export;
pub mod gltf;
pub mod obj;
pub mod teaset;

/// Loads a Catmull-Clark control mesh, choosing the reader by extension (`.obj`;
/// `.gltf`/`.glb` once supported).
pub fn load_control_mesh(
    path: &std::path::Path,
) -> crate::Result<crate::catmull_clark::ControlMesh> {
    obj::load_obj(path)
}
