//! OpenSubdiv as the reference surface: limit points of a [`ControlMesh`] computed by
//! OpenSubdiv's Bfr, through the helper `tests/osd/osd_eval.cpp` (Debian's `libosd-dev`).
//!
//! The helper is `$TESSERA_OSD_EVAL` when set (`cargo xtask test` builds it and sets it);
//! otherwise it is compiled here with g++ into `target/osd-eval/osd_eval`, again whenever
//! the source is newer. Without OpenSubdiv's headers every caller panics with one line
//! saying how to install them: a comparison that quietly did not run would pass.
//!
//! Protocol (the comment at the top of `osd_eval.cpp` is the reference): on stdin the
//! options (`boundary`, `creasing`, `triangles`), then `vertices`, `faces`, `holes`,
//! `creases`, `corners` and `points` sections, each a count line and one line per item;
//! on stdout one line per point, `x y z` with 17 significant digits, `outside` or `hole`
//! (and with `-far`, `not-a-vertex`).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;

use glam::DVec3;
use tessera_core::catmull_clark::{
    BoundaryRule, ControlMesh, CreaseMethod, SurfaceModel, SHARPNESS_INFINITE,
};

use crate::fuzz::Rng;

/// The helper's source.
pub fn source() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("osd/osd_eval.cpp")
}

/// A header every `libosd-dev` has: its absence means OpenSubdiv is not installed.
pub const OSD_HEADER: &str = "/usr/include/opensubdiv/version.h";

/// Why OpenSubdiv gave no limit point for a query.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoPoint {
    /// The `(u, v)` lies outside its face's domain.
    Outside,
    /// The face has no limit surface (a hole).
    Hole,
    /// [`far_limit_points`] only: the point is not a vertex of the first refinement.
    NotAVertex,
}

/// Whether the helper can run here: `TESSERA_OSD_EVAL` names it, or OpenSubdiv's headers
/// are installed to build it. The tests never ask (they must not pass without it); the
/// bench does, on a machine without OpenSubdiv (a device without network).
pub fn available() -> bool {
    match std::env::var_os("TESSERA_OSD_EVAL") {
        Some(p) => Path::new(&p).is_file(),
        None => Path::new(OSD_HEADER).exists(),
    }
}

/// The helper's path, built on first use when `TESSERA_OSD_EVAL` is unset.
pub fn helper() -> &'static Path {
    static HELPER: OnceLock<PathBuf> = OnceLock::new();
    HELPER.get_or_init(|| {
        if let Some(p) = std::env::var_os("TESSERA_OSD_EVAL") {
            let p = PathBuf::from(p);
            assert!(
                p.is_file(),
                "TESSERA_OSD_EVAL={} is not a file: `cargo xtask test` builds it",
                p.display()
            );
            return p;
        }
        build_helper()
    })
}

fn target_dir() -> PathBuf {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(d) => root.join(d),
        None => root.join("target"),
    }
}

fn build_helper() -> PathBuf {
    assert!(
        Path::new(OSD_HEADER).exists(),
        "OpenSubdiv is not installed ({OSD_HEADER} missing): run `cargo xtask test`, which installs it, or `apt-get install libosd-dev`"
    );
    let src = source();
    let out = target_dir().join("osd-eval/osd_eval");
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    if matches!((modified(&src), modified(&out)), (Some(s), Some(o)) if o >= s) {
        return out;
    }
    std::fs::create_dir_all(out.parent().unwrap()).expect("create target/osd-eval");
    // Built under a private name and renamed, so that a concurrent run never starts a
    // half-written binary.
    let tmp = out.with_file_name(format!("osd_eval.{}", std::process::id()));
    let result = Command::new("g++")
        .args(["-O2", "-std=c++14"])
        .arg(&src)
        .arg("-o")
        .arg(&tmp)
        .arg("-losdCPU")
        .output()
        .unwrap_or_else(|e| panic!("g++ (to build {}): {e}", src.display()));
    assert!(
        result.status.success(),
        "g++ could not build {}: {}",
        src.display(),
        String::from_utf8_lossy(&result.stderr)
    );
    std::fs::rename(&tmp, &out).expect("move the helper into place");
    out
}

/// The helper's input for `mesh` and the query points `(face, u, v)`.
pub fn input(mesh: &ControlMesh, points: &[(u32, f64, f64)]) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let boundary = match mesh.boundary {
        BoundaryRule::EdgeAndCorner => "edge-and-corner",
        BoundaryRule::EdgeOnly => "edge-only",
    };
    let creasing = match mesh.crease_method {
        CreaseMethod::Normal => "normal",
        CreaseMethod::Chaikin => "chaikin",
    };
    let triangles = if mesh.smooth_triangles {
        "smooth"
    } else {
        "catmark"
    };
    // Display prints the shortest decimal that reads back as the same f64 (f32 for
    // sharpness): the helper sees exactly these numbers.
    writeln!(
        s,
        "boundary {boundary}\ncreasing {creasing}\ntriangles {triangles}"
    )
    .unwrap();
    writeln!(s, "vertices {}", mesh.positions.len()).unwrap();
    for p in &mesh.positions {
        writeln!(s, "{} {} {}", p.x, p.y, p.z).unwrap();
    }
    writeln!(s, "faces {}", mesh.faces.len()).unwrap();
    for f in &mesh.faces {
        write!(s, "{}", f.len()).unwrap();
        for v in f {
            write!(s, " {v}").unwrap();
        }
        s.push('\n');
    }
    let holes: Vec<usize> = (0..mesh.faces.len())
        .filter(|&f| mesh.holes.get(f).copied().unwrap_or(false))
        .collect();
    writeln!(s, "holes {}", holes.len()).unwrap();
    for f in holes {
        writeln!(s, "{f}").unwrap();
    }
    writeln!(s, "creases {}", mesh.creases.len()).unwrap();
    for ([a, b], sharpness) in &mesh.creases {
        writeln!(s, "{a} {b} {sharpness}").unwrap();
    }
    writeln!(s, "corners {}", mesh.corners.len()).unwrap();
    for (v, sharpness) in &mesh.corners {
        writeln!(s, "{v} {sharpness}").unwrap();
    }
    writeln!(s, "points {}", points.len()).unwrap();
    for (f, u, v) in points {
        writeln!(s, "{f} {u} {v}").unwrap();
    }
    s
}

/// Runs the helper on `input` with extra arguments; its exit status, stdout and stderr.
pub fn run_helper(input: &str, args: &[&str]) -> (bool, String, String) {
    let mut child = Command::new(helper())
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("{}: {e}", helper().display()));
    // Written from a thread: the helper may answer before it has read everything.
    let mut stdin = child.stdin.take().unwrap();
    let input = input.to_owned();
    let writer = std::thread::spawn(move || {
        // A helper that stops reading (bad input) closes the pipe: its message says why.
        let _ = stdin.write_all(input.as_bytes());
    });
    let out = child.wait_with_output().expect("wait for the helper");
    writer.join().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// OpenSubdiv's Bfr uniform tessellation of `mesh` (`-tess`): every face at `rate`
/// segments per edge, `repeats` times. The median time of one tessellation in ms, as the
/// helper measured it (the topology built once beforehand, no I/O), and the last mesh
/// (each face with its own points; no normals, no face coordinates).
pub fn bfr_uniform(mesh: &ControlMesh, rate: u32, repeats: u32) -> (f64, tessera_core::Mesh) {
    let (ok, out, err) = run_helper(
        &input(mesh, &[]),
        &["-tess", &rate.to_string(), &repeats.to_string()],
    );
    assert!(ok, "osd_eval -tess: {err}");
    let mut lines = out.lines();
    let mut header = |key: &str| -> String {
        let line = lines
            .next()
            .unwrap_or_else(|| panic!("osd_eval -tess: no '{key}' line"));
        line.strip_prefix(key)
            .unwrap_or_else(|| panic!("osd_eval -tess: expected '{key} ...', got '{line}'"))
            .trim()
            .to_owned()
    };
    let ms: f64 = header("ms").parse().expect("a time");
    let count: usize = header("vertices").parse().expect("a count");
    let numbers = |line: Option<&str>| -> Vec<f64> {
        line.expect("a line")
            .split_whitespace()
            .map(|w| w.parse().expect("a number"))
            .collect()
    };
    let mut mesh = tessera_core::Mesh::default();
    for _ in 0..count {
        let p = numbers(lines.next());
        mesh.vertices.push(tessera_core::gpu_types::OutVertex {
            position: [p[0] as f32, p[1] as f32, p[2] as f32],
            normal: [0.0; 3],
            uv: [0.0; 2],
            face: 0,
        });
    }
    let triangles: usize = lines
        .next()
        .and_then(|l| l.strip_prefix("triangles"))
        .expect("a 'triangles' line")
        .trim()
        .parse()
        .expect("a count");
    for _ in 0..triangles {
        mesh.indices
            .extend(numbers(lines.next()).into_iter().map(|i| i as u32));
    }
    (ms, mesh)
}

/// OpenSubdiv's limit points of `mesh` at `points` (`(face, u, v)` in Bfr's face
/// parameterisation), with Bfr's approximation levels at their maximum.
pub fn limit_points(mesh: &ControlMesh, points: &[(u32, f64, f64)]) -> Vec<Result<DVec3, NoPoint>> {
    limit_points_with(mesh, points, &[])
}

/// [`limit_points`] with extra helper arguments (`-l LEVEL`: Bfr's approximation levels).
pub fn limit_points_with(
    mesh: &ControlMesh,
    points: &[(u32, f64, f64)],
    args: &[&str],
) -> Vec<Result<DVec3, NoPoint>> {
    let (ok, stdout, stderr) = run_helper(&input(mesh, points), args);
    assert!(
        ok,
        "{} on {}: {}",
        helper().display(),
        mesh.source.display(),
        stderr.trim()
    );
    let out: Vec<Result<DVec3, NoPoint>> = stdout
        .lines()
        .map(|line| match line {
            "outside" => Err(NoPoint::Outside),
            "hole" => Err(NoPoint::Hole),
            "not-a-vertex" => Err(NoPoint::NotAVertex),
            _ => {
                let xyz: Vec<f64> = line
                    .split_whitespace()
                    .map(|w| {
                        w.parse()
                            .unwrap_or_else(|_| panic!("helper wrote {line:?}"))
                    })
                    .collect();
                assert_eq!(xyz.len(), 3, "helper wrote {line:?}");
                Ok(DVec3::new(xyz[0], xyz[1], xyz[2]))
            }
        })
        .collect();
    assert_eq!(out.len(), points.len(), "one line per point");
    out
}

/// OpenSubdiv's limit points of `mesh` by Far instead of Bfr: the mesh refined uniformly
/// [`far_level`] times and the limit masks applied there. Only at the vertices of the
/// first refinement ([`first_level_points`]), and exact there except at darts (one
/// infinitely sharp edge), where Sdc applies the smooth limit mask: a second reference
/// where Bfr's local refinement departs from Far's.
pub fn far_limit_points(
    mesh: &ControlMesh,
    points: &[(u32, f64, f64)],
) -> Vec<Result<DVec3, NoPoint>> {
    limit_points_with(mesh, points, &["-far", &far_level(mesh).to_string()])
}

/// The uniform refinements after which every semi-sharp feature of `mesh` has decayed
/// (each level takes 1 off a sharpness, and Chaikin's average never exceeds the
/// largest), so that Far's limit masks are exact.
pub fn far_level(mesh: &ControlMesh) -> u32 {
    let finite = mesh
        .creases
        .iter()
        .map(|c| c.1)
        .chain(mesh.corners.iter().map(|c| c.1))
        .filter(|&s| s < SHARPNESS_INFINITE)
        .fold(0.0f32, f32::max);
    (finite.ceil() as u32).max(1)
}

/// Every vertex of the first refinement, by face: a quad's corners, edge midpoints and
/// centre, each sub-face's `(0, 0)`, `(½, 0)`, `(0, ½)` and `(½, ½)` otherwise.
pub fn first_level_points(mesh: &ControlMesh) -> Vec<(u32, f64, f64)> {
    let mut out = Vec::new();
    for (f, face) in mesh.faces.iter().enumerate() {
        let f = f as u32;
        if face.len() == 4 {
            for j in 0..3 {
                for i in 0..3 {
                    out.push((f, i as f64 / 2.0, j as f64 / 2.0));
                }
            }
        } else {
            let d = sub_face_tiles(face.len());
            for k in 0..face.len() {
                let (tu, tv) = ((k % d) as f64, (k / d) as f64);
                for (a, b) in [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5)] {
                    out.push((f, tu + a, tv + b));
                }
            }
        }
    }
    out
}

/// The smooth shapes the comparison covers (no crease or corner tags), under `assets/`.
pub const SMOOTH_SHAPES: &[&str] = &[
    "opensubdiv/catmark_cube.obj",
    "opensubdiv/catmark_torus.obj",
    "opensubdiv/catmark_pyramid.obj",
    "opensubdiv/catmark_nonquads.obj",
    "opensubdiv/catmark_edgecorner.obj",
    "opensubdiv/catmark_edgeonly.obj",
    "opensubdiv/catmark_pole8.obj",
    "opensubdiv/catmark_fan.obj",
    "opensubdiv/catmark_hole_test1.obj",
    "catmull_clark/spot_control_mesh.obj",
];

/// Every shipped OpenSubdiv shape with crease or corner tags
/// (`grep -l '^t \(crease\|corner\)' assets/opensubdiv/*.obj`), under `assets/`.
pub fn sharp_shapes() -> [&'static str; 38] {
    [
        "opensubdiv/catmark_bishop.obj",
        "opensubdiv/catmark_car.obj",
        "opensubdiv/catmark_chaikin0.obj",
        "opensubdiv/catmark_chaikin1.obj",
        "opensubdiv/catmark_chaikin2.obj",
        "opensubdiv/catmark_cube_corner0.obj",
        "opensubdiv/catmark_cube_corner1.obj",
        "opensubdiv/catmark_cube_corner2.obj",
        "opensubdiv/catmark_cube_corner3.obj",
        "opensubdiv/catmark_cube_corner4.obj",
        "opensubdiv/catmark_cube_creases0.obj",
        "opensubdiv/catmark_cube_creases1.obj",
        "opensubdiv/catmark_cube_creases2.obj",
        "opensubdiv/catmark_cubes_infsharp.obj",
        "opensubdiv/catmark_cubes_semisharp.obj",
        "opensubdiv/catmark_dart_edgecorner.obj",
        "opensubdiv/catmark_dart_edgeonly.obj",
        "opensubdiv/catmark_edgenone.obj",
        "opensubdiv/catmark_edgeonly.obj",
        "opensubdiv/catmark_fvar_bound2.obj",
        "opensubdiv/catmark_fvar_project0.obj",
        "opensubdiv/catmark_gregory_test3.obj",
        "opensubdiv/catmark_gregory_test7.obj",
        "opensubdiv/catmark_helmet.obj",
        "opensubdiv/catmark_hole_test2.obj",
        "opensubdiv/catmark_inf_crease0.obj",
        "opensubdiv/catmark_inf_crease1.obj",
        "opensubdiv/catmark_pawn.obj",
        "opensubdiv/catmark_pyramid_creases0.obj",
        "opensubdiv/catmark_pyramid_creases1.obj",
        "opensubdiv/catmark_pyramid_creases2.obj",
        "opensubdiv/catmark_rook.obj",
        "opensubdiv/catmark_single_crease.obj",
        "opensubdiv/catmark_tent_creases0.obj",
        "opensubdiv/catmark_tent_creases1.obj",
        "opensubdiv/catmark_torus_creases0.obj",
        "opensubdiv/catmark_torus_creases1.obj",
        "opensubdiv/catmark_val2_interior.obj",
    ]
}

/// Tiles per row of the quad sub-faces of a face of `sides ≠ 4` sides, as Bfr lays them
/// out (`Parameterization`'s constructor, opensubdiv/bfr/parameterization.cpp).
pub fn sub_face_tiles(sides: usize) -> usize {
    if sides < 10 {
        2 + usize::from(sides > 4)
    } else {
        1 + ((sides - 1) as f64).sqrt() as usize
    }
}

/// A uniform sample of `[0, 1)`.
fn unit(rng: &mut Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// `n` query points on `mesh`, each on a face drawn uniformly (holes included): a quad's
/// `(u, v)` uniform in its unit square, another face's in one sub-face's half-unit
/// square. One in four is a corner, edge midpoint or centre of the square instead, so
/// that vertices (the extraordinary ones where patches are least regular) and edges are
/// always among the points.
pub fn sample_points(mesh: &ControlMesh, n: usize, rng: &mut Rng) -> Vec<(u32, f64, f64)> {
    (0..n)
        .map(|_| {
            let f = rng.below(mesh.faces.len());
            let sides = mesh.faces[f].len();
            let (a, b) = if rng.chance(25) {
                (rng.below(3) as f64 / 2.0, rng.below(3) as f64 / 2.0)
            } else {
                (unit(rng), unit(rng))
            };
            if sides == 4 {
                (f as u32, a, b)
            } else {
                let d = sub_face_tiles(sides);
                let k = rng.below(sides);
                (f as u32, (k % d) as f64 + 0.5 * a, (k / d) as f64 + 0.5 * b)
            }
        })
        .collect()
}

/// How tessera's surface and OpenSubdiv's agree on a set of points.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// Points compared.
    pub points: usize,
    /// Points both evaluated (the others are outside their face or on a hole for both).
    pub evaluated: usize,
    /// The largest distance between the two limit points, model units.
    pub max_error: f64,
    /// The point of [`Self::max_error`], and tessera's and OpenSubdiv's positions there.
    pub worst: Option<((u32, f64, f64), DVec3, DVec3)>,
    /// Points where one of the two has a limit point and the other has none.
    pub disagreements: Vec<String>,
    /// The control mesh's bounding-box diagonal.
    pub diag: f64,
}

impl Comparison {
    /// [`Self::max_error`] as a fraction of the bounding-box diagonal.
    pub fn relative(&self) -> f64 {
        self.max_error / self.diag
    }
}

impl std::fmt::Display for Comparison {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} points ({} evaluated), max error {:.2e} of the diagonal",
            self.points,
            self.evaluated,
            self.relative()
        )?;
        if let Some(((face, u, v), ours, theirs)) = self.worst {
            write!(
                f,
                " at face {face} ({u}, {v}): tessera {ours}, OpenSubdiv {theirs}"
            )?;
        }
        if !self.disagreements.is_empty() {
            write!(
                f,
                "; {} disagreements, first: {}",
                self.disagreements.len(),
                self.disagreements[0]
            )?;
        }
        Ok(())
    }
}

/// Compares `model` (tessera's surface) with OpenSubdiv's surface of `osd_mesh` at
/// `points`. The two are normally the same mesh; the tests of this comparison give
/// them different ones.
pub fn compare(
    osd_mesh: &ControlMesh,
    model: &SurfaceModel,
    points: &[(u32, f64, f64)],
) -> Comparison {
    compare_with(
        osd_mesh,
        |f, u, v| model.eval_face(f, u, v).map(|p| p.position),
        points,
        limit_points(osd_mesh, points),
    )
}

/// [`compare`] of tessera's points `ours(face, u, v)` (`None` outside the face or on a
/// hole) with given reference points (`theirs`, one per point).
pub fn compare_with(
    osd_mesh: &ControlMesh,
    mut ours: impl FnMut(u32, f64, f64) -> Option<DVec3>,
    points: &[(u32, f64, f64)],
    theirs: Vec<Result<DVec3, NoPoint>>,
) -> Comparison {
    let mut c = Comparison {
        points: points.len(),
        evaluated: 0,
        max_error: 0.0,
        worst: None,
        disagreements: Vec::new(),
        diag: osd_mesh.bbox_diag(),
    };
    for (&(face, u, v), theirs) in points.iter().zip(theirs) {
        match (ours(face, u, v), theirs) {
            (Some(ours), Ok(theirs)) => {
                c.evaluated += 1;
                // A NaN must not pass as agreement.
                let e = match (ours - theirs).length() {
                    e if e.is_nan() => f64::INFINITY,
                    e => e,
                };
                if e > c.max_error || c.worst.is_none() {
                    c.max_error = e;
                    c.worst = Some(((face, u, v), ours, theirs));
                }
            }
            (None, Err(_)) => {}
            (ours, theirs) => c.disagreements.push(format!(
                "face {face} ({u}, {v}): tessera {ours:?}, OpenSubdiv {theirs:?}"
            )),
        }
    }
    c
}
