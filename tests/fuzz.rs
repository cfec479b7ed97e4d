//! Mutation fuzzing of input files: a small deterministic PRNG, the seed inputs (shipped
//! Newell and OBJ files, a glTF with its buffer as a data URI, a GLB from the project's
//! own exporter) and the mutations applied to them. Used by the `loader_fuzz` test (in
//! process) and the CLI's fuzz test (through the binary).

use std::path::PathBuf;

use crate::asset;

/// splitmix64: tiny, fast and good enough to pick mutations; the same seed gives the
/// same mutants on every machine.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (0 when `n` is 0).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next_u64() % n as u64) as usize
        }
    }

    /// True with probability `percent`/100.
    pub fn chance(&mut self, percent: u64) -> bool {
        self.next_u64() % 100 < percent
    }

    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// The seed of mutant `index` of input `input`: each mutant can be rebuilt alone.
pub fn mutant_seed(seed: u64, input: u64, index: u64) -> u64 {
    let mut r = Rng::new(seed ^ input.wrapping_mul(0xd6e8_feb8_6659_fd93));
    r.0 ^= index.wrapping_mul(0xa076_1d64_78bd_642f);
    r.next_u64()
}

/// The default seed of the fuzz tests.
pub const DEFAULT_SEED: u64 = 0x7e55_e7a0_f022_2024;

/// What a seed input is, which decides how it is mutated.
#[derive(Clone, Debug)]
pub enum Seed {
    /// A text format (Newell teaset, OBJ): line and number mutations.
    Text(Vec<u8>),
    /// glTF JSON whose only buffer is `data:...;base64,` + `bin` at [`BIN_MARK`]: the
    /// JSON, the binary data behind the URI, or both, are mutated.
    Gltf { json: String, bin: Vec<u8> },
    /// A GLB's JSON and BIN chunks: either chunk, and the packed file's bytes.
    Glb { json: Vec<u8>, bin: Vec<u8> },
}

/// Where the glTF seed's buffer data goes, base64-encoded.
pub const BIN_MARK: &str = "@BIN@";

impl Seed {
    /// The unmutated file.
    pub fn bytes(&self) -> Vec<u8> {
        match self {
            Seed::Text(t) => t.clone(),
            Seed::Gltf { json, bin } => json.replace(BIN_MARK, &base64(bin)).into_bytes(),
            Seed::Glb { json, bin } => glb(json, bin),
        }
    }
}

/// One fuzz input: a name, the extension its mutants are written with (it picks the
/// loader) and the seed.
#[derive(Clone, Debug)]
pub struct Input {
    pub name: &'static str,
    pub ext: &'static str,
    pub seed: Seed,
}

fn shipped(name: &'static str, rel: &str, ext: &'static str) -> Input {
    let path: PathBuf = asset(rel);
    let text = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Input {
        name,
        ext,
        seed: Seed::Text(text),
    }
}

/// The Newell teapot (32 patches).
pub fn teapot() -> Input {
    shipped("teapot", "teaset/teapot", "teaset")
}

/// Two OpenSubdiv OBJ files: a cube with crease and boundary tags, and a plane with a
/// hole tag and `v/vt/vn` references.
pub fn obj_files() -> [Input; 2] {
    [
        shipped(
            "cube_creases",
            "opensubdiv/catmark_cube_creases0.obj",
            "obj",
        ),
        shipped("hole", "opensubdiv/catmark_hole_test1.obj", "obj"),
    ]
}

/// A cube as glTF writes it: 24 vertices (4 per face, split by normal), 12 triangles.
fn split_cube() -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u16>) {
    let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for f in 0..6u16 {
        let (axis, sign) = ((f / 2) as usize, if f % 2 == 0 { 1.0 } else { -1.0 });
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let mut p = [0f32; 3];
            p[axis] = sign;
            p[a] = s;
            p[b] = t * sign;
            positions.push(p);
            let mut n = [0f32; 3];
            n[axis] = sign;
            normals.push(n);
        }
        indices.extend([0, 1, 2, 0, 2, 3].map(|i| 4 * f + i));
    }
    (positions, normals, indices)
}

/// A glTF exercising what the reader handles: a node with a matrix above one with a
/// translation, a rotation and a scale, interleaved positions and
/// normals (`byteStride`), `u16` indices at an offset, and a sparse accessor that
/// rewrites one position with the value it has.
pub fn gltf() -> Input {
    let (positions, normals, indices) = split_cube();
    let mut bin = Vec::new();
    for (p, n) in positions.iter().zip(&normals) {
        for c in p.iter().chain(n) {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let vertex_bytes = bin.len();
    for i in &indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let index_bytes = bin.len() - vertex_bytes;
    // Sparse: index 5 (u8, padded to 4), then its position.
    let sparse_at = bin.len();
    bin.extend_from_slice(&[5, 0, 0, 0]);
    for c in positions[5] {
        bin.extend_from_slice(&c.to_le_bytes());
    }
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"children": [1], "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 10, 0, 0, 1]},
            {"mesh": 0, "translation": [0.5, 0, 0], "rotation": [0, 0.6, 0, 0.8], "scale": [1, 2, 1]},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "mode": 4}]}],
        "buffers": [{"uri": format!("data:application/octet-stream;base64,{BIN_MARK}"), "byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": vertex_bytes, "byteStride": 24},
            {"buffer": 0, "byteOffset": vertex_bytes - 4, "byteLength": index_bytes + 4},
            {"buffer": 0, "byteOffset": sparse_at, "byteLength": 4},
            {"buffer": 0, "byteOffset": sparse_at + 4, "byteLength": 12},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 24, "type": "VEC3",
             "min": [-1, -1, -1], "max": [1, 1, 1],
             "sparse": {"count": 1, "indices": {"bufferView": 2, "componentType": 5121},
                        "values": {"bufferView": 3}}},
            {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 24, "type": "VEC3"},
            {"bufferView": 1, "byteOffset": 4, "componentType": 5123, "count": 36, "type": "SCALAR"},
        ],
    });
    // One value per line, so that line mutations cut and repeat array elements.
    let json = serde_json::to_string_pretty(&json).expect("serializes");
    Input {
        name: "cube_gltf",
        ext: "gltf",
        seed: Seed::Gltf { json, bin },
    }
}

/// A GLB written by the project's exporter (the CLI's `-o OUT.glb`): a cube with
/// interleaved position, normal, uv and face id, and `u32` indices.
pub fn glb_input() -> Input {
    let (positions, normals, indices) = split_cube();
    let mesh = tessera_core::Mesh {
        vertices: positions
            .iter()
            .zip(&normals)
            .enumerate()
            .map(
                |(k, (&position, &normal))| tessera_core::gpu_types::OutVertex {
                    position,
                    normal,
                    uv: [(k % 2) as f32, (k / 2 % 2) as f32],
                    face: (k / 4) as u32,
                },
            )
            .collect(),
        indices: indices.iter().map(|&i| u32::from(i)).collect(),
    };
    let mut bytes = Vec::new();
    tessera_core::io::export::write_glb(&mut bytes, &mesh).expect("writes");
    let (json, bin) = split_glb(&bytes).expect("the exporter writes a JSON and a BIN chunk");
    Input {
        name: "cube_glb",
        ext: "glb",
        seed: Seed::Glb { json, bin },
    }
}

/// Every fuzz input, one entry per loader: Newell, OBJ (two files), glTF, GLB.
pub fn inputs() -> Vec<(&'static str, Vec<Input>)> {
    vec![
        ("newell", vec![teapot()]),
        ("obj", obj_files().to_vec()),
        ("gltf", vec![gltf()]),
        ("glb", vec![glb_input()]),
    ]
}

/// A GLB file: header, JSON chunk padded with spaces, BIN chunk padded with zeros.
pub fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |b: &[u8], with: u8| {
        let mut v = b.to_vec();
        v.resize(v.len().next_multiple_of(4), with);
        v
    };
    let (json, bin) = (pad(json, b' '), pad(bin, 0));
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

fn split_glb(bytes: &[u8]) -> Option<(Vec<u8>, Vec<u8>)> {
    let u32_at = |at: usize| Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?));
    let json_len = u32_at(12)? as usize;
    let json = bytes.get(20..20 + json_len)?.to_vec();
    let bin_len = u32_at(20 + json_len)? as usize;
    let bin = bytes.get(28 + json_len..28 + json_len + bin_len)?.to_vec();
    Some((json, bin))
}

pub fn base64(bytes: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A mutated file and what was done to it (for failure reports).
#[derive(Clone, Debug)]
pub struct Mutant {
    pub bytes: Vec<u8>,
    pub ops: Vec<String>,
}

/// Mutates `seed`: one to three mutations, most of them small, so that mutants get
/// past the first checks and into the deeper ones.
pub fn mutate(rng: &mut Rng, seed: &Seed) -> Mutant {
    let mut ops = Vec::new();
    let bytes = match seed {
        Seed::Text(text) => {
            let mut b = text.clone();
            for _ in 0..count(rng) {
                mutate_text(rng, &mut b, false, &mut ops);
            }
            b
        }
        Seed::Gltf { json, bin } => {
            let mut bin = bin.clone();
            let binary = rng.chance(25);
            if binary {
                mutate_binary(rng, &mut bin, &mut ops);
            }
            let mut b = json.replace(BIN_MARK, &base64(&bin)).into_bytes();
            if !binary || rng.chance(40) {
                for _ in 0..count(rng) {
                    mutate_text(rng, &mut b, true, &mut ops);
                }
            }
            b
        }
        Seed::Glb { json, bin } => {
            let (mut json, mut bin) = (json.clone(), bin.clone());
            let mut raw = false;
            match rng.below(10) {
                0..=2 => mutate_binary(rng, &mut bin, &mut ops),
                3..=6 => {
                    for _ in 0..count(rng) {
                        mutate_text(rng, &mut json, true, &mut ops);
                    }
                }
                _ => raw = true,
            }
            let mut b = glb(&json, &bin);
            if raw || rng.chance(10) {
                mutate_glb_bytes(rng, &mut b, &mut ops);
            }
            b
        }
    };
    Mutant { bytes, ops }
}

fn count(rng: &mut Rng) -> usize {
    match rng.below(10) {
        0..=5 => 1,
        6..=8 => 2,
        _ => 3,
    }
}

/// Huge, negative, non-finite and malformed numbers.
const NUMBERS: &[&str] = &[
    "0",
    "1",
    "2",
    "3",
    "16",
    "17",
    "65535",
    "65536",
    "2147483648",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999999",
    "1e9",
    "1e19",
    "3.5e38",
    "1e39",
    "1e308",
    "1e309",
    "-1",
    "-2",
    "-0",
    "-2147483649",
    "-1e30",
    "-9223372036854775808",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "infinity",
    "1.2.3",
    "1e",
    "--1",
    "0x1F",
    "",
    "1,2",
    ".",
    "+",
    "1e99999",
    "0.5",
    "1e-45",
];

/// Out-of-range and wrongly typed glTF indices.
const INDICES: &[&str] = &[
    "1",
    "2",
    "3",
    "4",
    "5",
    "6",
    "7",
    "8",
    "24",
    "36",
    "255",
    "65535",
    "4294967295",
    "4294967296",
    "-1",
    "1.5",
    "1e9",
    "null",
    "\"0\"",
    "[]",
    "{}",
];

/// glTF keys whose values are indices or sizes.
const KEYS: &[&str] = &[
    "\"POSITION\":",
    "\"NORMAL\":",
    "\"TEXCOORD_0\":",
    "\"_FACE\":",
    "\"indices\":",
    "\"bufferView\":",
    "\"buffer\":",
    "\"mesh\":",
    "\"scene\":",
    "\"nodes\":",
    "\"children\":",
    "\"count\":",
    "\"byteOffset\":",
    "\"byteLength\":",
    "\"byteStride\":",
    "\"componentType\":",
    "\"mode\":",
];

fn mutate_text(rng: &mut Rng, b: &mut Vec<u8>, json: bool, ops: &mut Vec<String>) {
    if b.is_empty() {
        b.push(b'1');
        ops.push("empty: wrote 1".into());
        return;
    }
    let kinds = if json { 13 } else { 10 };
    match rng.below(kinds) {
        0 => {
            let (i, bit) = (rng.below(b.len()), rng.below(8));
            b[i] ^= 1 << bit;
            ops.push(format!("flip bit {bit} of byte {i}"));
        }
        1 => {
            let i = rng.below(b.len());
            let v = *rng.pick(b"\n\r,-.0 9e/{}[]\":\x00\xff\t#");
            b[i] = v;
            ops.push(format!("byte {i} = {v:#04x}"));
        }
        2 => {
            let at = rng.below(b.len());
            b.truncate(at);
            ops.push(format!("truncate at {at}"));
        }
        3 => {
            let lines = line_spans(b);
            let (s, e) = *rng.pick(&lines);
            b.drain(s..e);
            ops.push(format!("delete line at {s}"));
        }
        4 => {
            let lines = line_spans(b);
            let (s, e) = *rng.pick(&lines);
            let line = b[s..e].to_vec();
            let (at, _) = *rng.pick(&lines);
            let at = if rng.chance(50) { e } else { at };
            b.splice(at..at, line);
            ops.push(format!("duplicate line at {s} to {at}"));
        }
        5 => {
            let lines = line_spans(b);
            let (a, b2) = (*rng.pick(&lines), *rng.pick(&lines));
            if a.0 != b2.0 {
                let (first, second) = if a.0 < b2.0 { (a, b2) } else { (b2, a) };
                let mut out = b[..first.0].to_vec();
                out.extend_from_slice(&b[second.0..second.1]);
                out.extend_from_slice(&b[first.1..second.0]);
                out.extend_from_slice(&b[first.0..first.1]);
                out.extend_from_slice(&b[second.1..]);
                *b = out;
            }
            ops.push(format!("swap lines at {} and {}", a.0, b2.0));
        }
        6..=8 => {
            let numbers = number_spans(b);
            if numbers.is_empty() {
                return mutate_text(rng, b, json, ops);
            }
            let (s, e) = *rng.pick(&numbers);
            let with = *rng.pick(NUMBERS);
            ops.push(format!(
                "number {:?} at {s} = {with:?}",
                String::from_utf8_lossy(&b[s..e])
            ));
            b.splice(s..e, with.bytes());
        }
        9 => {
            let at = rng.below(b.len());
            let len = 1 + rng.below(8.min(b.len() - at));
            if rng.chance(50) {
                b.drain(at..at + len);
                ops.push(format!("delete {len} bytes at {at}"));
            } else {
                let junk: Vec<u8> = (0..len).map(|_| rng.next_u64() as u8).collect();
                b.splice(at..at, junk);
                ops.push(format!("insert {len} random bytes at {at}"));
            }
        }
        _ => {
            // A glTF index or size replaced: out of range, negative, of the wrong type.
            let text = b.clone();
            let hits: Vec<usize> = KEYS
                .iter()
                .flat_map(|k| find_all(&text, k.as_bytes()).map(move |at| at + k.len()))
                .collect();
            if hits.is_empty() {
                return mutate_text(rng, b, json, ops);
            }
            let after = *rng.pick(&hits);
            let Some(&(s, e)) = number_spans(&text).iter().find(|(s, _)| *s >= after) else {
                return;
            };
            let with = *rng.pick(INDICES);
            ops.push(format!(
                "index {:?} at {s} = {with}",
                String::from_utf8_lossy(&text[s..e])
            ));
            b.splice(s..e, with.bytes());
        }
    }
}

fn find_all<'a>(hay: &'a [u8], needle: &'a [u8]) -> impl Iterator<Item = usize> + 'a {
    (0..hay.len().saturating_sub(needle.len() - 1)).filter(move |&i| hay[i..].starts_with(needle))
}

/// Byte ranges of lines, each with its newline.
fn line_spans(b: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut start = 0;
    for (i, &c) in b.iter().enumerate() {
        if c == b'\n' {
            spans.push((start, i + 1));
            start = i + 1;
        }
    }
    if start < b.len() || spans.is_empty() {
        spans.push((start, b.len()));
    }
    spans
}

/// Byte ranges of numbers: a digit (or `-` and a digit) not inside a word, and what
/// follows of `0-9 . e E + -`.
fn number_spans(b: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts =
            b[i].is_ascii_digit() || (b[i] == b'-' && b.get(i + 1).is_some_and(u8::is_ascii_digit));
        let in_word = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b"_.".contains(&b[i - 1]));
        if starts && !in_word {
            let s = i;
            i += 1;
            while i < b.len() && (b[i].is_ascii_digit() || b".eE+-".contains(&b[i])) {
                i += 1;
            }
            spans.push((s, i));
        } else {
            i += 1;
        }
    }
    spans
}

/// Mutates binary buffer data: bits, non-finite and huge floats, out-of-range indices,
/// truncation.
fn mutate_binary(rng: &mut Rng, b: &mut Vec<u8>, ops: &mut Vec<String>) {
    if b.is_empty() {
        return;
    }
    match rng.below(6) {
        0 => {
            let (i, bit) = (rng.below(b.len()), rng.below(8));
            b[i] ^= 1 << bit;
            ops.push(format!("bin: flip bit {bit} of byte {i}"));
        }
        1 | 2 => {
            let v = *rng.pick(&[
                f32::NAN,
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::MAX,
                -1e30,
                1e19,
                -0.0,
                1e-40,
            ]);
            let at = rng.below(b.len() / 4) * 4;
            if at + 4 <= b.len() {
                b[at..at + 4].copy_from_slice(&v.to_le_bytes());
            }
            ops.push(format!("bin: f32 {v} at {at}"));
        }
        3 | 4 => {
            let v = *rng.pick(&[0xffff_ffffu32, 0xffff, 24, 23, 8, 0x8000_0000, 0xff]);
            let at = rng.below(b.len() / 2) * 2;
            let n = if rng.chance(50) { 2 } else { 4 };
            if at + n <= b.len() {
                b[at..at + n].copy_from_slice(&v.to_le_bytes()[..n]);
            }
            ops.push(format!("bin: u{} {v:#x} at {at}", n * 8));
        }
        _ => {
            let at = rng.below(b.len());
            b.truncate(at);
            ops.push(format!("bin: truncate at {at}"));
        }
    }
}

/// Mutates a packed GLB: header and chunk fields, bits, truncation.
fn mutate_glb_bytes(rng: &mut Rng, b: &mut Vec<u8>, ops: &mut Vec<String>) {
    let json_len = u32::from_le_bytes(b[12..16].try_into().expect("4 bytes")) as usize;
    match rng.below(4) {
        0 | 1 => {
            let at = *rng.pick(&[4, 8, 12, 16, 20 + json_len, 24 + json_len]);
            let len = b.len() as u32;
            let v = *rng.pick(&[
                0,
                1,
                3,
                8,
                11,
                12,
                13,
                20,
                len.wrapping_sub(1),
                len,
                len + 1,
                len + 4,
                json_len as u32 + 1,
                json_len as u32 - 4,
                0x7fff_ffff,
                0x8000_0000,
                0xffff_fff4,
                0xffff_ffff,
            ]);
            if at + 4 <= b.len() {
                b[at..at + 4].copy_from_slice(&v.to_le_bytes());
            }
            ops.push(format!("glb: u32 {v:#x} at {at}"));
        }
        2 => {
            let (i, bit) = (rng.below(b.len()), rng.below(8));
            b[i] ^= 1 << bit;
            ops.push(format!("glb: flip bit {bit} of byte {i}"));
        }
        _ => {
            let at = rng.below(b.len());
            b.truncate(at);
            ops.push(format!("glb: truncate at {at}"));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutants_are_deterministic_and_differ() {
        let input = gltf();
        let m = |i| mutate(&mut Rng::new(mutant_seed(DEFAULT_SEED, 3, i)), &input.seed);
        assert_eq!(m(7).bytes, m(7).bytes);
        let distinct: std::collections::HashSet<Vec<u8>> = (0..50).map(|i| m(i).bytes).collect();
        assert!(distinct.len() > 45, "{} distinct of 50", distinct.len());
        // A mutation can undo itself (a byte set to its own value, a line swapped with
        // itself), rarely.
        let unchanged = (0..50)
            .filter(|&i| m(i).bytes == input.seed.bytes())
            .count();
        assert!(unchanged <= 2, "{unchanged} of 50 unchanged");
    }

    #[test]
    fn number_and_line_spans() {
        let t = b"v 1.5 -2e3 x3\nf 1 2/3 TEXCOORD_0\n";
        let spans: Vec<&[u8]> = number_spans(t).iter().map(|&(s, e)| &t[s..e]).collect();
        assert_eq!(spans, [&b"1.5"[..], b"-2e3", b"1", b"2", b"3"]);
        assert_eq!(line_spans(t), [(0, 14), (14, 33)]);
        assert_eq!(base64(b"ab"), "YWI=");
        assert_eq!(base64(b"abc"), "YWJj");
    }
}
