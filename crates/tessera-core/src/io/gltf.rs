//! glTF 2.0 (`.gltf`, `.glb`) triangle meshes as Catmull-Clark control meshes.
//!
//! Every triangle primitive of the default scene (or of every mesh when there is no
//! scene) is read with its node transforms applied. glTF splits a vertex wherever its
//! attributes differ (normals, texture seams); a control mesh needs one vertex per
//! point, so vertices are welded back by exact position. Buffers come from the GLB
//! binary chunk, `data:` URIs (base64) or files next to the input.
//!
//! The `gltf` crate parses the JSON and validates it; everything it would follow
//! without a check (the GLB container, the accessors a primitive names, accessor and
//! buffer-view ranges) is checked here first, and accessors are read here with checked
//! arithmetic, so that no file can make a dependency panic. Counts are trusted only as
//! far as the bytes behind them go: nothing is allocated for more elements than the
//! file (with its buffers) could hold.

use std::collections::HashMap;
use std::path::Path;

use glam::{DMat4, DVec3, DVec4};
use gltf::json;
use gltf::json::accessor::{ComponentType, GenericComponentType, IndexComponentType, Type};
use gltf::json::validation::Checked;

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
    let invalid = |m: String| Error::input(path, format!("not a valid glTF file: {m}"));
    let (json_bytes, blob) = if bytes.starts_with(b"glTF") {
        split_glb(bytes).map_err(|m| Error::input(path, format!("not a valid GLB file: {m}")))?
    } else {
        (bytes, None)
    };
    let root: json::Root =
        json::deserialize::from_slice(json_bytes).map_err(|e| invalid(e.to_string()))?;
    check_indices(&root).map_err(invalid)?;
    // The crate's own validation (enumerations, required extensions, every other index)
    // follows one index unchecked, a primitive's POSITION accessor: checked above.
    let root = gltf::Document::from_json(root)
        .map_err(|e| invalid(e.to_string()))?
        .into_json();
    let sources = read_sources(path, &root)?;
    let buffers = buffer_bytes(path, &root, blob, &sources)?;
    // What the file and the files it names could describe: the bound on every count below.
    let budget = bytes.len() + sources.iter().map(Vec::len).sum::<usize>();
    let mut reader = Reader {
        path,
        root: &root,
        buffers: &buffers,
        budget,
        read: 0,
        mesh: ControlMesh {
            source: path.to_path_buf(),
            ..ControlMesh::default()
        },
        weld: HashMap::new(),
        skipped: 0,
    };
    let scene = match root.scene {
        Some(s) => Some(s.value()),
        None => (!root.scenes.is_empty()).then_some(0),
    };
    match scene.and_then(|s| root.scenes.get(s).map(|scene| (s, scene))) {
        Some((s, scene)) => {
            // glTF nodes form trees: a node reached twice (a cycle, or a child that is
            // also a root) is an error, not an endless or exponential walk. Nodes are
            // marked when pushed, so the stack holds each at most once.
            let mut seen = vec![false; root.nodes.len()];
            let mut enter =
                |n: usize, world: DMat4, stack: &mut Vec<(usize, DMat4)>| match seen.get_mut(n) {
                    Some(seen) if !*seen => {
                        *seen = true;
                        stack.push((n, world));
                        Ok(())
                    }
                    Some(_) => Err(invalid(format!(
                        "node {n} is reached twice from scene {s}: nodes must form trees"
                    ))),
                    None => Err(invalid(format!(
                        "scene {s} reaches node {n}, which does not exist"
                    ))),
                };
            let mut stack = Vec::new();
            for n in &scene.nodes {
                enter(n.value(), DMat4::IDENTITY, &mut stack)?;
            }
            while let Some((n, parent)) = stack.pop() {
                let Some(node) = root.nodes.get(n) else {
                    continue;
                };
                let world = parent * node_matrix(node);
                if let Some(m) = node.mesh {
                    reader.add_mesh(m.value(), world)?;
                }
                for c in node.children.iter().flatten() {
                    enter(c.value(), world, &mut stack)?;
                }
            }
        }
        None => {
            for m in 0..root.meshes.len() {
                reader.add_mesh(m, DMat4::IDENTITY)?;
            }
        }
    }
    let Reader {
        mut mesh, skipped, ..
    } = reader;
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

/// The JSON chunk and the optional BIN chunk of a GLB file. Read here, not by the `gltf`
/// crate, whose reader subtracts from the header's length unchecked.
fn split_glb(bytes: &[u8]) -> std::result::Result<(&[u8], Option<&[u8]>), String> {
    let u32_at = |at: usize| -> Option<usize> {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let version = u32_at(4).ok_or("the header is truncated")?;
    if version != 2 {
        return Err(format!("version {version}; only glTF 2 is read"));
    }
    let length = u32_at(8).ok_or("the header is truncated")?;
    if length < 12 || length > bytes.len() {
        return Err(format!(
            "the header gives a length of {length} bytes; the file has {}",
            bytes.len()
        ));
    }
    let data = &bytes[..length];
    let chunk = |at: usize| -> std::result::Result<(&[u8], &[u8], usize), String> {
        let len = u32_at(at).filter(|_| at + 8 <= data.len());
        let len = len.ok_or_else(|| format!("a chunk header at byte {at} is truncated"))?;
        let kind = &data[at + 4..at + 8];
        let body = data
            .get(at + 8..(at + 8).saturating_add(len))
            .ok_or_else(|| {
                format!(
                    "the chunk at byte {at} holds {len} bytes, past the end at {}",
                    data.len()
                )
            })?;
        Ok((kind, body, at + 8 + len))
    };
    let (kind, json, next) = chunk(12)?;
    if kind != b"JSON" {
        return Err("the first chunk is not JSON".into());
    }
    // Chunks of other types after the JSON are ignored, as the format asks.
    let bin = match next + 8 <= data.len() {
        true => match chunk(next)? {
            (b"BIN\0", body, _) => Some(body),
            _ => None,
        },
        false => None,
    };
    Ok((json, bin))
}

/// Every index that reading a mesh follows, and that the `gltf` crate's validation would
/// follow unchecked, refers to something that exists.
fn check_indices(root: &json::Root) -> std::result::Result<(), String> {
    let exists = |what: &str, i: usize, len: usize, from: &dyn Fn() -> String| {
        if i < len {
            Ok(())
        } else {
            Err(format!(
                "{} refers to {what} {i}, which does not exist ({len} defined)",
                from()
            ))
        }
    };
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let at = || format!("mesh {m} primitive {p}");
            for (semantic, a) in &prim.attributes {
                let from = || format!("{} attribute {}", at(), semantic.to_string());
                exists("accessor", a.value(), accessors, &from)?;
            }
            if let Some(a) = prim.indices {
                exists("accessor", a.value(), accessors, &|| {
                    format!("{} indices", at())
                })?;
            }
            for (t, target) in prim.targets.iter().flatten().enumerate() {
                for a in [target.positions, target.normals, target.tangents]
                    .into_iter()
                    .flatten()
                {
                    exists("accessor", a.value(), accessors, &|| {
                        format!("{} morph target {t}", at())
                    })?;
                }
            }
        }
    }
    let views = root.buffer_views.len();
    for (a, accessor) in root.accessors.iter().enumerate() {
        let from = || format!("accessor {a}");
        if let Some(v) = accessor.buffer_view {
            exists("buffer view", v.value(), views, &from)?;
        }
        if let Some(sparse) = &accessor.sparse {
            exists(
                "buffer view",
                sparse.indices.buffer_view.value(),
                views,
                &from,
            )?;
            exists(
                "buffer view",
                sparse.values.buffer_view.value(),
                views,
                &from,
            )?;
        }
    }
    for (v, view) in root.buffer_views.iter().enumerate() {
        exists("buffer", view.buffer.value(), root.buffers.len(), &|| {
            format!("buffer view {v}")
        })?;
    }
    if let Some(s) = root.scene {
        exists("scene", s.value(), root.scenes.len(), &|| {
            "the document".into()
        })?;
    }
    let nodes = root.nodes.len();
    for (s, scene) in root.scenes.iter().enumerate() {
        for n in &scene.nodes {
            exists("node", n.value(), nodes, &|| format!("scene {s}"))?;
        }
    }
    for (n, node) in root.nodes.iter().enumerate() {
        let from = || format!("node {n}");
        if let Some(m) = node.mesh {
            exists("mesh", m.value(), root.meshes.len(), &from)?;
        }
        for c in node.children.iter().flatten() {
            exists("node", c.value(), nodes, &from)?;
        }
    }
    Ok(())
}

/// The data behind each distinct buffer URI (decoded `data:` URIs, files), in order of
/// first use: a file that many buffers name is read once.
fn read_sources(path: &Path, root: &json::Root) -> Result<Vec<Vec<u8>>> {
    let mut seen = std::collections::HashSet::new();
    let mut sources = Vec::new();
    for (i, buffer) in root.buffers.iter().enumerate() {
        if let Some(uri) = &buffer.uri {
            if seen.insert(uri.as_str()) {
                sources.push(read_uri(path, i, uri)?);
            }
        }
    }
    Ok(sources)
}

/// Each buffer's bytes, cut to its declared length: slices of the GLB chunk or of
/// `sources` (never copies, however many buffers share them).
fn buffer_bytes<'a>(
    path: &Path,
    root: &json::Root,
    blob: Option<&'a [u8]>,
    sources: &'a [Vec<u8>],
) -> Result<Vec<&'a [u8]>> {
    let mut source_of = HashMap::new();
    for buffer in &root.buffers {
        if let Some(uri) = &buffer.uri {
            let next = source_of.len();
            source_of.entry(uri.as_str()).or_insert(next);
        }
    }
    let mut buffers = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let data: &[u8] = match &buffer.uri {
            None => blob.ok_or_else(|| {
                Error::input(path, "buffer refers to a GLB binary chunk the file lacks")
            })?,
            Some(uri) => source_of
                .get(uri.as_str())
                .and_then(|&k| sources.get(k))
                .map_or(&[], Vec::as_slice),
        };
        let declared = usize::try_from(buffer.byte_length.0).unwrap_or(usize::MAX);
        let data = data.get(..declared).ok_or_else(|| {
            Error::input(
                path,
                format!(
                    "buffer {i} holds {} bytes, {} declared",
                    data.len(),
                    buffer.byte_length.0
                ),
            )
        })?;
        buffers.push(data);
    }
    Ok(buffers)
}

/// A node's local transform: its matrix, or translation · rotation · scale.
fn node_matrix(node: &json::Node) -> DMat4 {
    if let Some(m) = node.matrix {
        return DMat4::from_cols_array(&m.map(f64::from));
    }
    let t = DVec3::from_array(node.translation.unwrap_or([0.0; 3]).map(f64::from));
    let s = DVec3::from_array(node.scale.unwrap_or([1.0; 3]).map(f64::from));
    let [x, y, z, w] = node
        .rotation
        .map_or([0.0, 0.0, 0.0, 1.0], |r| r.0.map(f64::from));
    // The rotation matrix of the quaternion written out: glam's constructors assert a
    // unit quaternion in debug builds, and a file's need not be one.
    let rotation = [
        DVec3::new(
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y + w * z),
            2.0 * (x * z - w * y),
        ),
        DVec3::new(
            2.0 * (x * y - w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z + w * x),
        ),
        DVec3::new(
            2.0 * (x * z + w * y),
            2.0 * (y * z - w * x),
            1.0 - 2.0 * (x * x + y * y),
        ),
    ];
    DMat4::from_cols(
        (rotation[0] * s.x).extend(0.0),
        (rotation[1] * s.y).extend(0.0),
        (rotation[2] * s.z).extend(0.0),
        DVec4::new(t.x, t.y, t.z, 1.0),
    )
}

/// How many times over the file's data may be read (see [`Reader::read`]): a mesh of
/// many materials shares one `POSITION` accessor among that many primitives.
const REREAD: usize = 16;

/// Reads meshes into one welded control mesh.
struct Reader<'a> {
    path: &'a Path,
    root: &'a json::Root,
    buffers: &'a [&'a [u8]],
    /// At most this many elements in any accessor read without data behind it, and
    /// this many triangles and points in all (instances included).
    budget: usize,
    /// Positions and indices decoded so far, over every primitive and instance: at most
    /// [`REREAD`] times the budget, so that instancing or primitives sharing one
    /// accessor cannot multiply the work without end.
    read: usize,
    mesh: ControlMesh,
    weld: HashMap<[u64; 3], u32>,
    skipped: usize,
}

impl Reader<'_> {
    fn err(&self, msg: String) -> Error {
        Error::input(self.path, msg)
    }

    fn add_mesh(&mut self, m: usize, transform: DMat4) -> Result<()> {
        let root = self.root;
        let mesh = root
            .meshes
            .get(m)
            .ok_or_else(|| self.err(format!("mesh {m} does not exist")))?;
        for prim in &mesh.primitives {
            if prim.mode != Checked::Valid(json::mesh::Mode::Triangles) {
                self.skipped += 1;
                continue;
            }
            let position = prim
                .attributes
                .get(&Checked::Valid(json::mesh::Semantic::Positions))
                .ok_or_else(|| self.err(format!("mesh {m} has a primitive without positions")))?;
            if self.mesh.positions.len() > self.budget {
                return Err(self.too_many(m, "points"));
            }
            let positions = self.positions(position.value())?;
            let indices = match prim.indices {
                Some(a) => self.indices(a.value())?,
                None => (0..positions.len() as u32).collect(),
            };
            self.read += positions.len() + indices.len();
            if self.read > REREAD * self.budget {
                return Err(self.err(format!(
                    "mesh {m}: the primitives and nodes read the file's data more than {REREAD} times over"
                )));
            }
            if !indices.len().is_multiple_of(3) {
                return Err(self.err(format!(
                    "mesh {m}: {} indices is not a multiple of 3",
                    indices.len()
                )));
            }
            if self.mesh.faces.len() + indices.len() / 3 > self.budget {
                return Err(self.too_many(m, "triangles"));
            }
            let mut ids = Vec::with_capacity(positions.len());
            for p in &positions {
                let p = transform.transform_point3(DVec3::from_array(p.map(f64::from)));
                if !p.is_finite() || p.abs().max_element() > super::MAX_COORDINATE {
                    return Err(self.err(format!(
                        "mesh {m}: position {p} is not finite or beyond ±{:e}",
                        super::MAX_COORDINATE
                    )));
                }
                let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
                let next = self.mesh.positions.len() as u32;
                let id = *self.weld.entry(key).or_insert(next);
                if id == next {
                    self.mesh.positions.push(p);
                }
                ids.push(id);
            }
            for t in indices.chunks_exact(3) {
                let mut face = Vec::with_capacity(3);
                for &i in t {
                    face.push(ids.get(i as usize).copied().ok_or_else(|| {
                        self.err(format!(
                            "mesh {m}: index {i} out of range ({} vertices)",
                            ids.len()
                        ))
                    })?);
                }
                self.mesh.faces.push(face);
            }
        }
        Ok(())
    }

    fn too_many(&self, m: usize, what: &str) -> Error {
        self.err(format!(
            "mesh {m}: the nodes instance more {what} than the file's {} bytes could hold",
            self.budget
        ))
    }

    /// A `POSITION` accessor: `VEC3` of floats.
    fn positions(&self, a: usize) -> Result<Vec<[f32; 3]>> {
        let accessor = self.accessor(a)?;
        let floats = matches!(
            accessor.component_type,
            Checked::Valid(GenericComponentType(ComponentType::F32))
        );
        if accessor.type_ != Checked::Valid(Type::Vec3) || !floats {
            return Err(self.err(format!(
                "accessor {a}: positions must be VEC3 of floats (componentType 5126)"
            )));
        }
        self.elements(a, 12, |b| {
            let f = |k: usize| f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
            [f(0), f(4), f(8)]
        })
    }

    /// An index accessor: `SCALAR` of unsigned bytes, shorts or ints.
    fn indices(&self, a: usize) -> Result<Vec<u32>> {
        let accessor = self.accessor(a)?;
        let size = match (accessor.type_, accessor.component_type) {
            (Checked::Valid(Type::Scalar), Checked::Valid(GenericComponentType(c))) => uint_size(c),
            _ => None,
        };
        let size = size.ok_or_else(|| {
            self.err(format!(
                "accessor {a}: indices must be SCALAR of unsigned bytes, shorts or ints"
            ))
        })?;
        self.elements(a, size, uint)
    }

    fn accessor(&self, a: usize) -> Result<&json::Accessor> {
        self.root
            .accessors
            .get(a)
            .ok_or_else(|| self.err(format!("accessor {a} does not exist")))
    }

    /// Accessor `a`'s elements of `size` bytes each, decoded, with its sparse values
    /// substituted.
    fn elements<T: Copy + Default>(
        &self,
        a: usize,
        size: usize,
        decode: impl Fn(&[u8]) -> T,
    ) -> Result<Vec<T>> {
        let accessor = self.accessor(a)?;
        let what = format!("accessor {a}");
        let count = usize::try_from(accessor.count.0).unwrap_or(usize::MAX);
        let offset = accessor.byte_offset.map_or(0, |o| o.0);
        let mut out: Vec<T> = match accessor.buffer_view {
            Some(v) => self
                .strided(&what, v.value(), offset, count, size)?
                .map(&decode)
                .collect(),
            // Zeros, with sparse values on top: nothing in the file bounds the count.
            None if count > self.budget => {
                return Err(self.err(format!(
                    "{what}: {count} elements without a buffer view, more than the file's {} bytes could describe",
                    self.budget
                )))
            }
            None => vec![T::default(); count],
        };
        if let Some(sparse) = &accessor.sparse {
            let n = usize::try_from(sparse.count.0).unwrap_or(usize::MAX);
            if n > count {
                return Err(self.err(format!("{what}: {n} sparse values for {count} elements")));
            }
            let index_size = match sparse.indices.component_type {
                Checked::Valid(IndexComponentType(c)) => uint_size(c),
                Checked::Invalid => None,
            }
            .ok_or_else(|| self.err(format!("{what}: sparse indices must be unsigned")))?;
            let indices = self.strided(
                &format!("{what} sparse indices"),
                sparse.indices.buffer_view.value(),
                sparse.indices.byte_offset.0,
                n,
                index_size,
            )?;
            let values = self.strided(
                &format!("{what} sparse values"),
                sparse.values.buffer_view.value(),
                sparse.values.byte_offset.0,
                n,
                size,
            )?;
            for (i, value) in indices.zip(values) {
                let i = uint(i);
                let slot = out.get_mut(i as usize).ok_or_else(|| {
                    self.err(format!(
                        "{what}: sparse index {i} out of range ({count} elements)"
                    ))
                })?;
                *slot = decode(value);
            }
        }
        Ok(out)
    }

    /// `count` elements of `size` bytes from byte `offset` of buffer view `v`, each a
    /// `byteStride` apart: all checked to lie in the view, and the view in its buffer.
    fn strided(
        &self,
        what: &str,
        v: usize,
        offset: u64,
        count: usize,
        size: usize,
    ) -> Result<impl Iterator<Item = &[u8]>> {
        let view = self
            .root
            .buffer_views
            .get(v)
            .ok_or_else(|| self.err(format!("{what}: buffer view {v} does not exist")))?;
        let b = view.buffer.value();
        let buffer = self
            .buffers
            .get(b)
            .ok_or_else(|| self.err(format!("buffer view {v}: buffer {b} does not exist")))?;
        let start = view.byte_offset.map_or(0, |o| o.0);
        let range = usize::try_from(start)
            .ok()
            .zip(usize::try_from(view.byte_length.0).ok())
            .and_then(|(s, len)| Some(s..s.checked_add(len)?));
        let bytes = range.and_then(|r| buffer.get(r)).ok_or_else(|| {
            self.err(format!(
                "buffer view {v}: {} bytes from byte {start} run past the end of buffer {b} ({} bytes)",
                view.byte_length.0,
                buffer.len()
            ))
        })?;
        let stride = view.byte_stride.map_or(size, |s| s.0);
        if stride < size {
            return Err(self.err(format!(
                "{what}: byteStride {stride} of buffer view {v} is less than its {size}-byte elements"
            )));
        }
        // The last element ends at offset + stride · (count - 1) + size.
        let data = usize::try_from(offset).ok().and_then(|o| {
            let end = match count {
                0 => o,
                _ => (count - 1)
                    .checked_mul(stride)?
                    .checked_add(o)?
                    .checked_add(size)?,
            };
            bytes.get(o..end)
        });
        let data = data.ok_or_else(|| {
            self.err(format!(
                "{what}: {count} elements of {size} bytes from byte {offset} (stride {stride}) run past the end of buffer view {v} ({} bytes)",
                bytes.len()
            ))
        })?;
        Ok(data.chunks(stride).map(move |c| &c[..size]))
    }
}

fn uint_size(c: ComponentType) -> Option<usize> {
    match c {
        ComponentType::U8 => Some(1),
        ComponentType::U16 => Some(2),
        ComponentType::U32 => Some(4),
        _ => None,
    }
}

/// A little-endian unsigned integer of 1, 2 or 4 bytes.
fn uint(b: &[u8]) -> u32 {
    b.iter().rev().fold(0, |n, &byte| n << 8 | u32::from(byte))
}

/// Buffer `i`'s data from its URI: base64 in a `data:` URI, or a file next to `path`.
/// Errors name the glTF file.
fn read_uri(path: &Path, i: usize, uri: &str) -> Result<Vec<u8>> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, data) = rest
            .split_once(";base64,")
            .ok_or_else(|| Error::input(path, format!("buffer {i}: data URI is not base64")))?;
        return base64_decode(data)
            .ok_or_else(|| Error::input(path, format!("buffer {i}: data URI: invalid base64")));
    }
    let file = path.parent().unwrap_or(Path::new(".")).join(uri);
    let cannot = |e: String| {
        Error::input(
            path,
            format!("buffer {i}: cannot read {}: {e}", file.display()),
        )
    };
    // A regular file only: a device or a pipe (`/dev/zero`) could be read forever.
    let meta = std::fs::metadata(&file).map_err(|e| cannot(e.to_string()))?;
    if !meta.is_file() {
        return Err(cannot("not a regular file".into()));
    }
    std::fs::read(&file).map_err(|e| cannot(e.to_string()))
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

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{json, Value};

    /// One triangle in a GLB: three float positions, then three `u8` indices.
    fn triangle() -> (Value, Vec<u8>) {
        let mut bin = Vec::new();
        for c in [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            bin.extend_from_slice(&c.to_le_bytes());
        }
        bin.extend_from_slice(&[0, 1, 2, 0]);
        let json = json!({
            "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "buffers": [{"byteLength": bin.len()}],
            "bufferViews": [{"buffer": 0, "byteLength": 36},
                            {"buffer": 0, "byteOffset": 36, "byteLength": 3}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5121, "count": 3, "type": "SCALAR"}],
        });
        (json, bin)
    }

    fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
        let mut j = json.to_string().into_bytes();
        j.resize(j.len().next_multiple_of(4), b' ');
        let mut out = b"glTF".to_vec();
        for n in [2, 12 + 8 + j.len() + 8 + bin.len(), j.len()] {
            out.extend_from_slice(&(n as u32).to_le_bytes());
        }
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&j);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
        out
    }

    /// The triangle with `edit` applied to its JSON: the error, checked to be one line
    /// naming the file.
    fn err_with(edit: impl FnOnce(&mut Value)) -> String {
        let (mut json, bin) = triangle();
        edit(&mut json);
        let e = parse_gltf(Path::new("t.glb"), &glb(&json, &bin))
            .expect_err("refused")
            .to_string();
        assert!(e.starts_with("t.glb: ") && !e.contains('\n'), "{e}");
        e
    }

    #[test]
    fn the_triangle_loads() {
        let (json, bin) = triangle();
        let mesh = parse_gltf(Path::new("t.glb"), &glb(&json, &bin)).unwrap();
        assert_eq!((mesh.positions.len(), mesh.faces), (3, vec![vec![0, 1, 2]]));
    }

    #[test]
    fn indices_are_checked_before_the_gltf_crate_follows_them() {
        // The crate's validation indexes the POSITION accessor unchecked.
        let e = err_with(|j| j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(2));
        assert!(
            e.ends_with("mesh 0 primitive 0 attribute POSITION refers to accessor 2, which does not exist (2 defined)"),
            "{e}"
        );
        let e = err_with(|j| j["accessors"][1]["bufferView"] = json!(9));
        assert!(e.contains("accessor 1 refers to buffer view 9"), "{e}");
        let e = err_with(|j| j["bufferViews"][0]["buffer"] = json!(1));
        assert!(e.contains("buffer view 0 refers to buffer 1"), "{e}");
        let e = err_with(|j| j["nodes"][0]["children"] = json!([4]));
        assert!(e.contains("node 0 refers to node 4"), "{e}");
        let e = err_with(|j| j["scenes"][0]["nodes"] = json!([1]));
        assert!(e.contains("scene 0 refers to node 1"), "{e}");
        let e = err_with(|j| j["nodes"][0]["mesh"] = json!(1));
        assert!(e.contains("node 0 refers to mesh 1"), "{e}");
    }

    #[test]
    fn accessor_ranges_are_checked_with_overflow_in_mind() {
        let e = err_with(|j| j["accessors"][0]["count"] = json!(1u64 << 40));
        assert!(
            e.contains("accessor 0: 1099511627776 elements of 12 bytes"),
            "{e}"
        );
        let e = err_with(|j| j["accessors"][0]["byteOffset"] = json!(u64::MAX));
        assert!(e.contains("run past the end of buffer view 0"), "{e}");
        let e = err_with(|j| j["bufferViews"][0]["byteOffset"] = json!(u64::MAX - 1));
        assert!(e.contains("buffer view 0: 36 bytes from byte"), "{e}");
        // A stride the crate accepts but its element reader would slice past.
        let e = err_with(|j| j["bufferViews"][0]["byteStride"] = json!(4));
        assert!(
            e.contains("byteStride 4 of buffer view 0 is less than its 12-byte"),
            "{e}"
        );
        let e = err_with(|j| j["accessors"][0]["componentType"] = json!(5121));
        assert!(e.contains("positions must be VEC3 of floats"), "{e}");
        // No elements: nothing to index (the crate's reader computes `count - 1`).
        let e = err_with(|j| j["accessors"][0]["count"] = json!(0));
        assert!(e.contains("index 0 out of range (0 vertices)"), "{e}");
    }

    #[test]
    fn sparse_accessors_are_read_and_bounded() {
        // Sparse values on zeros: vertex 2 moved to (0, 2, 0) through a sparse accessor
        // without a buffer view behind its base.
        let (mut json, mut bin) = triangle();
        let at = bin.len();
        bin.extend_from_slice(&[2, 0, 0, 0]);
        for c in [0f32, 2.0, 0.0] {
            bin.extend_from_slice(&c.to_le_bytes());
        }
        json["buffers"][0]["byteLength"] = json!(bin.len());
        json["bufferViews"] = json!([json["bufferViews"][0], json["bufferViews"][1],
            {"buffer": 0, "byteOffset": at, "byteLength": 1},
            {"buffer": 0, "byteOffset": at + 4, "byteLength": 12}]);
        json["accessors"][0]["sparse"] = json!({"count": 1,
            "indices": {"bufferView": 2, "componentType": 5121}, "values": {"bufferView": 3}});
        let load = |json: &Value| parse_gltf(Path::new("s.glb"), &glb(json, &bin));
        let mesh = load(&json).unwrap();
        assert_eq!(mesh.positions[2], DVec3::new(0.0, 2.0, 0.0));
        let mut zeros = json.clone();
        zeros["accessors"][0]
            .as_object_mut()
            .unwrap()
            .remove("bufferView");
        assert_eq!(load(&zeros).unwrap().positions.len(), 2, "zeros welded");
        // Nothing in the file backs a view-less accessor's count: it is capped.
        zeros["accessors"][0]["count"] = json!(1u64 << 40);
        let e = load(&zeros).unwrap_err().to_string();
        assert!(
            e.contains("1099511627776 elements without a buffer view"),
            "{e}"
        );
        let mut out_of_range = json.clone();
        out_of_range["accessors"][0]["count"] = json!(2);
        let e = load(&out_of_range).unwrap_err().to_string();
        assert!(
            e.contains("sparse index 2 out of range (2 elements)"),
            "{e}"
        );
    }

    #[test]
    fn node_graphs_must_be_trees() {
        let e = err_with(|j| j["nodes"][0]["children"] = json!([0]));
        assert!(e.contains("node 0 is reached twice from scene 0"), "{e}");
        // Instancing by siblings is fine, sharing a child is not.
        let (mut json, bin) = triangle();
        json["nodes"] = json!([{"children": [1, 2]}, {"mesh": 0},
            {"mesh": 0, "translation": [5, 0, 0]}]);
        let mesh = parse_gltf(Path::new("t.glb"), &glb(&json, &bin)).unwrap();
        assert_eq!(mesh.faces.len(), 2);
        let e = err_with(|j| {
            j["nodes"] = json!([{"children": [1, 2]}, {"children": [2]}, {"mesh": 0}])
        });
        assert!(e.contains("node 2 is reached twice"), "{e}");
    }

    #[test]
    fn instancing_is_capped_by_the_file_size() {
        let (mut json, bin) = triangle();
        let n = 2000;
        json["nodes"] = json!([{"children": (1..=n).collect::<Vec<_>>()}]);
        for _ in 1..=n {
            json["nodes"]
                .as_array_mut()
                .unwrap()
                .push(json!({"mesh": 0}));
        }
        // A few thousand nodes of one triangle each fit the file...
        assert!(parse_gltf(Path::new("t.glb"), &glb(&json, &bin)).is_ok());
        // ...a mesh of many triangles instanced by each of them does not.
        let mut big = bin.clone();
        big.truncate(36);
        let indices: Vec<u8> = (0..30_000).map(|k| [0, 1, 2][k % 3]).collect();
        big.extend_from_slice(&indices);
        json["buffers"][0]["byteLength"] = json!(big.len());
        json["bufferViews"][1]["byteLength"] = json!(indices.len());
        json["accessors"][1]["count"] = json!(indices.len());
        let e = parse_gltf(Path::new("t.glb"), &glb(&json, &big))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("the nodes instance more triangles than the file's"),
            "{e}"
        );
    }

    #[test]
    fn rereading_shared_accessors_is_bounded() {
        // Primitives sharing one large POSITION accessor, one triangle each.
        let (mut json, _) = triangle();
        let points = 10_000;
        let mut bin: Vec<u8> = (0..points)
            .flat_map(|k| [k as f32, (k % 7) as f32, 0.0])
            .flat_map(f32::to_le_bytes)
            .collect();
        let at = bin.len();
        bin.extend_from_slice(&[0, 1, 2, 0]);
        json["buffers"][0]["byteLength"] = json!(bin.len());
        json["bufferViews"][0]["byteLength"] = json!(at);
        json["bufferViews"][1]["byteOffset"] = json!(at);
        json["accessors"][0]["count"] = json!(points);
        let with = |json: &mut Value, primitives: usize| {
            let prim = json["meshes"][0]["primitives"][0].clone();
            json["meshes"][0]["primitives"] = Value::Array(vec![prim; primitives]);
            parse_gltf(Path::new("t.glb"), &glb(json, &bin)).map_err(|e| e.to_string())
        };
        assert_eq!(with(&mut json, 100).unwrap().faces.len(), 100);
        let e = with(&mut json, 400).unwrap_err();
        assert!(
            e.ends_with("the primitives and nodes read the file's data more than 16 times over"),
            "{e}"
        );
    }

    #[test]
    fn glb_containers_are_checked() {
        let (json, bin) = triangle();
        let good = glb(&json, &bin);
        let err = |bytes: &[u8]| {
            parse_gltf(Path::new("t.glb"), bytes)
                .unwrap_err()
                .to_string()
        };
        // A length below the header's own 12 bytes (the crate subtracts unchecked).
        let mut short = good.clone();
        short[8..12].copy_from_slice(&8u32.to_le_bytes());
        assert_eq!(
            err(&short),
            format!(
                "t.glb: not a valid GLB file: the header gives a length of 8 bytes; the file has {}",
                good.len()
            )
        );
        let mut chunk = good.clone();
        chunk[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(err(&chunk).contains("the chunk at byte 12 holds 4294967295 bytes"));
        assert!(err(&good[..10]).contains("the header is truncated"));
        let mut version = good.clone();
        version[4] = 1;
        assert!(err(&version).contains("version 1"));
    }

    #[test]
    fn quoted_control_characters_stay_on_one_line() {
        let e = err_with(|j| j["extensionsRequired"] = json!(["KHR_a\nb"]));
        assert!(e.contains("KHR_a\\nb"), "{e}");
    }

    #[test]
    fn external_buffers_are_read_once_and_named_in_errors() {
        let dir = std::env::temp_dir().join(format!("tessera-gltf-ext-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (mut json, bin) = triangle();
        std::fs::write(dir.join("t.bin"), &bin).unwrap();
        let buffer = json!({"uri": "t.bin", "byteLength": bin.len()});
        json["buffers"] = json!([buffer, buffer]);
        json["bufferViews"][1]["buffer"] = json!(1);
        let file = dir.join("t.gltf");
        std::fs::write(&file, json.to_string()).unwrap();
        assert_eq!(load_gltf(&file).unwrap().faces.len(), 1);
        json["buffers"][1]["uri"] = json!("missing.bin");
        std::fs::write(&file, json.to_string()).unwrap();
        let e = load_gltf(&file).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "{}: buffer 1: cannot read {}: ",
                file.display(),
                dir.join("missing.bin").display()
            )),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[cfg(unix)]
    #[test]
    fn external_buffers_must_be_regular_files() {
        let (mut json, _) = triangle();
        json["buffers"][0]["uri"] = json!("/dev/zero");
        let e = parse_gltf(Path::new("t.gltf"), json.to_string().as_bytes())
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "t.gltf: buffer 0: cannot read /dev/zero: not a regular file"
        );
    }
}
