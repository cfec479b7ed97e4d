//! Loader for the Newell teaset text format:
//!
//! ```text
//! <P>                    number of patches
//! i1,i2,...,i16          P lines: 16 one-based vertex indices, row-major 4×4 net
//! <M>                    number of vertices
//! x,y,z                  M lines
//! ```
//!
//! Every check happens before anything large is allocated: counts are compared with the
//! number of lines actually present, so an absurd count is an error, not an allocation.

use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};

/// The raw content of a teaset file: patches as 0-based indices into `vertices`.
#[derive(Clone, Debug)]
pub struct TeasetFile {
    /// The control points, in file order.
    pub vertices: Vec<Vec3>,
    /// Each patch's 4×4 net, row-major, as 0-based indices into `vertices`.
    pub patches: Vec<[u32; 16]>,
}

/// Reads and validates a teaset file from disk.
pub fn load_teaset(path: &Path) -> Result<TeasetFile> {
    let bytes = super::read_file(path)?;
    parse_teaset(path, &bytes)
}

/// Parses teaset text; `path` only names the file in errors.
pub fn parse_teaset(path: &Path, bytes: &[u8]) -> Result<TeasetFile> {
    let text = super::utf8_text(path, bytes)?;
    // Non-blank lines with their 1-based line numbers.
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty())
        .collect();
    let last_line = text.lines().count().max(1);
    let mut cursor = lines.iter().copied();
    let mut next = |what: &str| {
        cursor.next().ok_or_else(|| {
            Error::parse(
                path,
                last_line,
                format!("unexpected end of file: expected {what}"),
            )
        })
    };

    let (line, s) = next("the patch count")?;
    let patch_count = parse_count(path, line, s, "patch count")?;
    if patch_count == 0 {
        return Err(Error::parse(path, line, "patch count is 0"));
    }
    // The patch lines, the vertex-count line and at least one vertex line must exist.
    // (saturating: a count near usize::MAX must not wrap around to a small number)
    if patch_count.saturating_add(2) > lines.len() - 1 {
        return Err(Error::parse(
            path,
            line,
            format!(
                "patch count {patch_count} exceeds what the file holds ({} more non-blank lines)",
                lines.len() - 1
            ),
        ));
    }
    let mut raw_patches = Vec::with_capacity(patch_count);
    for _ in 0..patch_count {
        let (line, s) = next("a patch line of 16 indices")?;
        let mut idx = [0u64; 16];
        let mut n = 0;
        for field in s.split(',') {
            if n == 16 {
                return Err(Error::parse(
                    path,
                    line,
                    "more than 16 indices on a patch line",
                ));
            }
            let field = field.trim();
            idx[n] = field.parse::<u64>().map_err(|_| {
                Error::parse(
                    path,
                    line,
                    format!("index {} is not a positive integer: {field:?}", n + 1),
                )
            })?;
            if idx[n] == 0 {
                return Err(Error::parse(
                    path,
                    line,
                    format!("index {} is 0; indices are 1-based", n + 1),
                ));
            }
            n += 1;
        }
        if n != 16 {
            return Err(Error::parse(
                path,
                line,
                format!("expected 16 indices on a patch line, found {n}"),
            ));
        }
        raw_patches.push((line, idx));
    }

    let (line, s) = next("the vertex count")?;
    let vertex_count = parse_count(path, line, s, "vertex count")?;
    let remaining = lines.len() - patch_count - 2;
    if vertex_count == 0 || vertex_count > remaining {
        return Err(Error::parse(
            path,
            line,
            format!("vertex count {vertex_count} does not match the {remaining} vertex lines that follow"),
        ));
    }
    let mut vertices = Vec::with_capacity(vertex_count);
    for _ in 0..vertex_count {
        let (line, s) = next("a vertex line x,y,z")?;
        let mut xyz = [0f32; 3];
        let mut n = 0;
        for field in s.split(',') {
            if n == 3 {
                return Err(Error::parse(
                    path,
                    line,
                    "more than 3 coordinates on a vertex line",
                ));
            }
            let field = field.trim();
            let v: f32 = field.parse().map_err(|_| {
                Error::parse(
                    path,
                    line,
                    format!("coordinate {} is not a number: {field:?}", n + 1),
                )
            })?;
            if !v.is_finite() {
                return Err(Error::parse(
                    path,
                    line,
                    format!("coordinate {} is not finite: {field}", n + 1),
                ));
            }
            if f64::from(v.abs()) > super::MAX_COORDINATE {
                return Err(Error::parse(
                    path,
                    line,
                    format!(
                        "coordinate {} is {field}: beyond ±{:e}, where single-precision distances overflow",
                        n + 1,
                        super::MAX_COORDINATE
                    ),
                ));
            }
            xyz[n] = v;
            n += 1;
        }
        if n != 3 {
            return Err(Error::parse(
                path,
                line,
                format!("expected 3 coordinates x,y,z, found {n}"),
            ));
        }
        vertices.push(Vec3::from_array(xyz));
    }
    if let Some((line, _)) = cursor.next() {
        return Err(Error::parse(
            path,
            line,
            "unexpected content after the last vertex",
        ));
    }

    let tolerance = model_tolerance(path, &vertices, &raw_patches)?;
    let mut patches = Vec::with_capacity(patch_count);
    for (line, idx) in raw_patches {
        let mut p = [0u32; 16];
        for (k, &i) in idx.iter().enumerate() {
            if i as usize > vertex_count {
                return Err(Error::parse(
                    path,
                    line,
                    format!(
                        "index {} is {i}, beyond the vertex count {vertex_count}",
                        k + 1
                    ),
                ));
            }
            p[k] = (i - 1) as u32;
        }
        check_patch_shape(path, line, &p.map(|i| vertices[i as usize]), tolerance)?;
        patches.push(p);
    }
    Ok(TeasetFile { vertices, patches })
}

/// The distance under which control points count as one (what the model welds by):
/// 1e-6 of the bounding-box diagonal of the referenced points. A model too small for
/// single precision to resolve that is refused. Indices out of range are skipped here
/// (the caller reports them).
fn model_tolerance(path: &Path, vertices: &[Vec3], patches: &[(usize, [u64; 16])]) -> Result<f64> {
    let (mut lo, mut hi) = (glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY);
    for (_, idx) in patches {
        for &i in idx {
            if let Some(v) = vertices.get(i as usize - 1) {
                lo = lo.min(v.as_dvec3());
                hi = hi.max(v.as_dvec3());
            }
        }
    }
    let diag = (hi - lo).length();
    if diag.is_nan() || diag < MIN_DIAGONAL {
        return Err(Error::input(
            path,
            format!("the control points span {diag:e} units: below {MIN_DIAGONAL:e}, too small for single precision"),
        ));
    }
    Ok(diag * WELD_RELATIVE)
}

/// Control points closer than this fraction of the bounding-box diagonal are one point:
/// the shape checks here and the model's weld ([`BezierModel::from_teaset`](crate::bezier::BezierModel::from_teaset)) agree.
pub const WELD_RELATIVE: f64 = 1e-6;

/// The smallest model (bounding-box diagonal) accepted: its weld tolerance, 1e-6 of it,
/// squared, must still be a normal `f32`.
pub const MIN_DIAGONAL: f64 = 1e-12;

/// Rejects the patches the tessellators cannot mesh without zero-area triangles: a patch
/// whose control points lie on one line (or at one point), and one with two adjacent
/// sides collapsed to points (the corner between them is singular). One collapsed side,
/// or two opposite ones, are fine: the teapot's lid and bottom have them.
fn check_patch_shape(path: &Path, line: usize, net: &[Vec3; 16], tolerance: f64) -> Result<()> {
    let net = net.map(|p| p.as_dvec3());
    let near = |a: glam::DVec3, b: glam::DVec3| a.distance(b) <= tolerance;
    let same = |ids: [usize; 4]| ids.iter().all(|&i| near(net[i], net[ids[0]]));
    // The farthest point from the first, then every point's distance to that line.
    let far = net
        .iter()
        .copied()
        .max_by(|a, b| a.distance(net[0]).total_cmp(&b.distance(net[0])))
        .unwrap_or(net[0]);
    let axis = (far - net[0]).normalize_or_zero();
    let off_line = |p: glam::DVec3| {
        let d = p - net[0];
        (d - axis * d.dot(axis)).length()
    };
    if net.iter().all(|&p| off_line(p) <= tolerance) {
        return Err(Error::parse(
            path,
            line,
            "the 16 control points lie on one line: the patch has no area",
        ));
    }
    // Sides in order around the patch: v = 0, u = 1, v = 1, u = 0.
    let collapsed = [
        same([0, 1, 2, 3]),
        same([3, 7, 11, 15]),
        same([12, 13, 14, 15]),
        same([0, 4, 8, 12]),
    ];
    for k in 0..4 {
        if collapsed[k] && collapsed[(k + 1) % 4] {
            return Err(Error::parse(
                path,
                line,
                "two adjacent sides of the patch collapse to points: the corner between them is singular (unsupported)",
            ));
        }
    }
    Ok(())
}

fn parse_count(path: &Path, line: usize, s: &str, what: &str) -> Result<usize> {
    s.parse::<u64>()
        .ok()
        .and_then(|n| usize::try_from(n).ok())
        .ok_or_else(|| {
            Error::parse(
                path,
                line,
                format!("{what} is not a non-negative integer: {s:?}"),
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_patch() -> String {
        let mut s = String::from("1\n");
        s += &(1..=16)
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(",");
        s += "\n16\n";
        for r in 0..4 {
            for c in 0..4 {
                s += &format!("{c},{r},0\n");
            }
        }
        s
    }

    fn err(text: &str) -> String {
        parse_teaset(Path::new("t.txt"), text.as_bytes())
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn parses_a_valid_file() {
        let f = parse_teaset(Path::new("t"), one_patch().as_bytes()).unwrap();
        assert_eq!(f.patches.len(), 1);
        assert_eq!(f.vertices.len(), 16);
        assert_eq!(f.patches[0][15], 15);
        assert_eq!(f.vertices[5], Vec3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn errors_name_file_line_and_problem() {
        assert_eq!(
            err(""),
            "t.txt:1: unexpected end of file: expected the patch count"
        );
        assert!(err("abc\n").starts_with("t.txt:1: patch count is not"));
        assert!(err("99999999999\n1\n").contains("exceeds what the file holds"));
        let bad_idx = one_patch().replacen("16\n16", "17\n16", 1);
        assert_eq!(
            err(&bad_idx),
            "t.txt:2: index 16 is 17, beyond the vertex count 16"
        );
        let nan = one_patch().replacen("3,3,0", "3,nan,0", 1);
        assert_eq!(err(&nan), "t.txt:19: coordinate 2 is not finite: nan");
        let inf = one_patch().replacen("3,3,0", "inf,3,0", 1);
        assert!(err(&inf).starts_with("t.txt:19: coordinate 1 is not finite"));
        let short = one_patch().replacen("1,2,3,", "1,2,", 1);
        assert_eq!(
            err(&short),
            "t.txt:2: expected 16 indices on a patch line, found 15"
        );
        let zero = one_patch().replacen("1,2,3,", "0,2,3,", 1);
        assert!(err(&zero).contains("index 1 is 0"));
        let truncated: String = one_patch()
            .lines()
            .take(10)
            .map(|l| format!("{l}\n"))
            .collect();
        assert!(
            err(&truncated).starts_with("t.txt:3: vertex count 16 does not match"),
            "{}",
            err(&truncated)
        );
        assert!(err("1\n1,2\n").contains("exceeds"));
        // A count that would wrap `count + 2` around to a small number.
        assert!(err(&format!("{}\n1,2\n3\n4\n", u64::MAX)).contains("exceeds"));
        let huge = one_patch().replacen("3,3,0", "3,2e19,0", 1);
        assert!(
            err(&huge).starts_with("t.txt:19: coordinate 2 is 2e19: beyond"),
            "{}",
            err(&huge)
        );
        let mut point = String::from("1\n");
        point += &["1"; 16].join(",");
        point += "\n1\n0.5,0.5,0\n";
        assert_eq!(
            err(&point),
            "t.txt: the control points span 0e0 units: below 1e-12, too small for single precision"
        );
        // Control points on a line: every row the same four points.
        let mut line = String::from("1\n1,2,3,4,1,2,3,4,1,2,3,4,1,2,3,4\n4\n");
        line += "0,0,0\n1,0,0\n2,0,0\n3,0,0\n";
        assert_eq!(
            err(&line),
            "t.txt:2: the 16 control points lie on one line: the patch has no area"
        );
        // Rows v = 0 and column u = 0 both at the origin: two adjacent collapsed sides.
        let mut corner = String::from("1\n1,1,1,1,1,2,3,4,1,5,6,7,1,8,9,10\n10\n0,0,0\n");
        for (x, y) in [
            (1, 1),
            (2, 1),
            (3, 1),
            (1, 2),
            (2, 2),
            (3, 2),
            (1, 3),
            (2, 3),
            (3, 3),
        ] {
            corner += &format!("{x},{y},0\n");
        }
        assert!(err(&corner).contains("two adjacent sides of the patch collapse"));
        // Two opposite collapsed sides (a spindle) are a valid patch.
        let spindle = "1\n1,1,1,1,2,3,4,5,6,7,8,9,10,10,10,10\n10\n0,0,0\n1,1,0\n1,2,0\n1,3,0\n1,4,0\n2,1,0\n2,2,0\n2,3,0\n2,4,0\n3,0,0\n";
        assert!(parse_teaset(Path::new("s"), spindle.as_bytes()).is_ok());
        let binary = parse_teaset(Path::new("b"), &[0xff, 0xfe, 0x00])
            .unwrap_err()
            .to_string();
        assert!(binary.starts_with("b: not a text file"));
    }
}
