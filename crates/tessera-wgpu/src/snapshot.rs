//! Image snapshots with a perceptual tolerance, for tests and the CLI.
//!
//! Two images are compared pixel by pixel as CIE L\*a\*b\* colours (sRGB, D65, composited
//! over white so that alpha counts): a pixel differs when its CIE76 ΔE exceeds
//! [`Tolerance::delta_e`], and the images match when they have the same size, at most
//! [`Tolerance::max_fraction`] of their pixels differ, and at most
//! [`Tolerance::max_clustered`] differing pixels are *clustered* (their whole 3 × 3
//! neighbourhood differs). Antialiasing and rasterization differences make thin, scattered
//! differences along edges and lines; a part that is missing, moved or recoloured makes a
//! solid patch, which the second count catches even when it is small. The fraction leaves
//! out differing pixels that a one-pixel shift explains (each image's colour there is
//! found within one pixel in the other): GPUs rasterize lines differently, and a
//! one-pixel wireframe shift is not a different picture. The clustered count keeps them.
//! A failed check writes `<name>.actual.png` and `<name>.diff.png` (differing pixels in
//! red over a faded copy of the reference) into an output folder, and a reference is
//! (re)written instead of compared when [`BLESS_ENV`] is set.

use std::path::{Path, PathBuf};

use image::{Rgba, RgbaImage};

use crate::error::{Error, Result};
use crate::image_out::{load_png, save_png, srgb_to_linear};

/// Set this environment variable (to anything but `0` or empty) to write references
/// instead of comparing against them: `TESSERA_BLESS=1 cargo test ...`.
pub const BLESS_ENV: &str = "TESSERA_BLESS";

/// Whether [`BLESS_ENV`] asks for references to be (re)written.
pub fn bless_requested() -> bool {
    std::env::var_os(BLESS_ENV).is_some_and(|v| !v.is_empty() && v != "0")
}

/// When two images count as the same.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// A pixel differs when its CIE76 ΔE is above this.
    pub delta_e: f32,
    /// The images differ when more than this fraction of the pixels differ.
    pub max_fraction: f64,
    /// The images differ when more than this many differing pixels have a 3 × 3
    /// neighbourhood (inside the image) where every pixel differs.
    pub max_clustered: u64,
}

impl Tolerance {
    /// ΔE above 6 (a difference one sees side by side without looking for it: the
    /// just-noticeable difference is about 2.3, and ±1 or ±2 levels of noise on every
    /// channel stay below 1.93 and 3.85), on more than 0.5% of the pixels (96 at
    /// 160 × 120: room for antialiasing that differs along silhouettes and lines), or
    /// clustered on more than 4 pixels. A slightly moved eye changes scattered pixels
    /// along edges and none clustered, while a patch left out clusters; another GPU's
    /// rasterisation differs mostly by one-pixel shifts, which the comparison discounts.
    /// The unit tests below hold the comparison to these cases.
    pub const DEFAULT: Tolerance = Tolerance {
        delta_e: 6.0,
        max_fraction: 0.005,
        max_clustered: 4,
    };
}

impl Default for Tolerance {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// How two images compare.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    /// Width and height of the expected image.
    pub expected_size: (u32, u32),
    /// Width and height of the actual image.
    pub actual_size: (u32, u32),
    /// Pixels whose ΔE is above the tolerance's (every pixel when the sizes differ).
    pub differing: u64,
    /// Differing pixels that a one-pixel shift explains: the actual colour is within the
    /// tolerance of an expected pixel at most one pixel away, and the expected colour of
    /// an actual one (0 when the sizes differ).
    pub shifted: u64,
    /// Differing pixels whose 3 × 3 neighbourhood differs entirely (0 when the sizes
    /// differ).
    pub clustered: u64,
    /// Pixels compared (of the larger image when the sizes differ).
    pub total: u64,
    /// The largest ΔE seen (0 when the sizes differ).
    pub max_delta_e: f32,
    /// The tolerance the comparison was made with.
    pub tolerance: Tolerance,
}

impl Comparison {
    /// Whether both images have the same size.
    pub fn same_size(&self) -> bool {
        self.expected_size == self.actual_size
    }

    /// Fraction of pixels that differ beyond a one-pixel shift.
    pub fn fraction(&self) -> f64 {
        if self.total == 0 {
            0.0
        } else {
            (self.differing - self.shifted) as f64 / self.total as f64
        }
    }

    /// Same size, few enough differing pixels, and few enough of them clustered.
    pub fn passed(&self) -> bool {
        self.same_size()
            && self.fraction() <= self.tolerance.max_fraction
            && self.clustered <= self.tolerance.max_clustered
    }

    /// One line for messages.
    pub fn summary(&self) -> String {
        if !self.same_size() {
            let (ew, eh) = self.expected_size;
            let (aw, ah) = self.actual_size;
            return format!("size {aw}x{ah} differs from the reference's {ew}x{eh}");
        }
        format!(
            "{} of {} pixels ({:.3}%) differ by ΔE > {} beyond a one-pixel shift (tolerance \
             {:.3}%; {} more are shifted), {} differing pixels clustered (tolerance {}), \
             max ΔE {:.1}",
            self.differing - self.shifted,
            self.total,
            100.0 * self.fraction(),
            self.tolerance.delta_e,
            100.0 * self.tolerance.max_fraction,
            self.shifted,
            self.clustered,
            self.tolerance.max_clustered,
            self.max_delta_e
        )
    }
}

/// CIE L\*a\*b\* (D65) of an 8-bit sRGB pixel composited over white.
pub fn lab(p: Rgba<u8>) -> [f32; 3] {
    let a = p[3] as f32 / 255.0;
    let lin = |c: u8| {
        // Over white in linear light.
        srgb_to_linear(c) * a + (1.0 - a)
    };
    let (r, g, b) = (lin(p[0]), lin(p[1]), lin(p[2]));
    let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
    let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
    let f = |t: f32| {
        if t > 216.0 / 24389.0 {
            t.cbrt()
        } else {
            (24389.0 / 27.0 * t + 16.0) / 116.0
        }
    };
    let (fx, fy, fz) = (f(x), f(y), f(z));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// CIE76 colour difference of two pixels (Euclidean distance in L\*a\*b\*).
pub fn delta_e(a: Rgba<u8>, b: Rgba<u8>) -> f32 {
    if a == b {
        return 0.0;
    }
    let (p, q) = (lab(a), lab(b));
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

/// Compares `actual` with `expected`.
pub fn compare(expected: &RgbaImage, actual: &RgbaImage, tolerance: &Tolerance) -> Comparison {
    let mut c = Comparison {
        expected_size: expected.dimensions(),
        actual_size: actual.dimensions(),
        differing: 0,
        shifted: 0,
        clustered: 0,
        total: 0,
        max_delta_e: 0.0,
        tolerance: *tolerance,
    };
    if !c.same_size() {
        let w = expected.width().max(actual.width()) as u64;
        let h = expected.height().max(actual.height()) as u64;
        c.total = w * h;
        c.differing = c.total;
        return c;
    }
    let (w, h) = (expected.width() as usize, expected.height() as usize);
    let mut differs = vec![false; w * h];
    for ((e, a), flag) in expected.pixels().zip(actual.pixels()).zip(&mut differs) {
        let d = delta_e(*e, *a);
        c.total += 1;
        c.max_delta_e = c.max_delta_e.max(d);
        if d > tolerance.delta_e {
            c.differing += 1;
            *flag = true;
        }
    }
    c.clustered = clustered(&differs, w, h).filter(|&k| k).count() as u64;
    c.shifted = (0..w * h)
        .filter(|&i| differs[i] && shift_explains(expected, actual, i % w, i / w, tolerance))
        .count() as u64;
    c
}

/// Whether a one-pixel shift explains the difference at `(x, y)`: the actual colour
/// there is within the tolerance of an expected pixel at most one pixel away, and the
/// expected colour of an actual one.
fn shift_explains(
    expected: &RgbaImage,
    actual: &RgbaImage,
    x: usize,
    y: usize,
    tolerance: &Tolerance,
) -> bool {
    let near = |img: &RgbaImage, colour: Rgba<u8>| {
        (y.saturating_sub(1)..=y + 1).any(|yy| {
            (x.saturating_sub(1)..=x + 1).any(|xx| {
                img.get_pixel_checked(xx as u32, yy as u32)
                    .is_some_and(|p| delta_e(*p, colour) <= tolerance.delta_e)
            })
        })
    };
    let (e, a) = (
        *expected.get_pixel(x as u32, y as u32),
        *actual.get_pixel(x as u32, y as u32),
    );
    near(expected, a) && near(actual, e)
}

/// For each pixel, whether it and its 8 neighbours (all inside the image) differ.
fn clustered(differs: &[bool], w: usize, h: usize) -> impl Iterator<Item = bool> + '_ {
    (0..w * h).map(move |i| {
        let (x, y) = (i % w, i / w);
        x > 0
            && y > 0
            && x + 1 < w
            && y + 1 < h
            && (y - 1..=y + 1).all(|yy| (x - 1..=x + 1).all(|xx| differs[yy * w + xx]))
    })
}

/// A picture of the differences: the reference faded toward white, differing pixels in
/// red (dark red where clustered, orange where a one-pixel shift explains them), pixels
/// that differ below the tolerance in pale yellow;
/// where the sizes differ, pixels outside either image are magenta.
pub fn diff_image(expected: &RgbaImage, actual: &RgbaImage, tolerance: &Tolerance) -> RgbaImage {
    let w = expected.width().max(actual.width());
    let h = expected.height().max(actual.height());
    let mut cluster = vec![false; (w * h) as usize];
    if expected.dimensions() == actual.dimensions() {
        let differs: Vec<bool> = expected
            .pixels()
            .zip(actual.pixels())
            .map(|(e, a)| delta_e(*e, *a) > tolerance.delta_e)
            .collect();
        for (flag, k) in cluster
            .iter_mut()
            .zip(clustered(&differs, w as usize, h as usize))
        {
            *flag = k;
        }
    }
    RgbaImage::from_fn(w, h, |x, y| {
        let (Some(e), Some(a)) = (
            expected.get_pixel_checked(x, y),
            actual.get_pixel_checked(x, y),
        ) else {
            return Rgba([255, 0, 255, 255]);
        };
        let d = delta_e(*e, *a);
        if cluster[(y * w + x) as usize] {
            Rgba([140, 0, 0, 255])
        } else if d > tolerance.delta_e {
            if shift_explains(expected, actual, x as usize, y as usize, tolerance) {
                Rgba([245, 150, 0, 255])
            } else {
                Rgba([230, 0, 0, 255])
            }
        } else if d > 0.0 {
            Rgba([255, 225, 120, 255])
        } else {
            let l = lab(*e)[0] / 100.0;
            let v = (255.0 * (0.8 + 0.2 * l)).round() as u8;
            Rgba([v, v, v, 255])
        }
    })
}

/// Paths of the files a failed check of `name` writes into `out_dir`.
pub fn failure_paths(name: &str, out_dir: &Path) -> (PathBuf, PathBuf) {
    (
        out_dir.join(format!("{name}.actual.png")),
        out_dir.join(format!("{name}.diff.png")),
    )
}

/// Compares `actual` with `expected`; on a mismatch writes the actual image and the diff
/// into `out_dir` (created if needed) and fails with the comparison's summary and those
/// paths. On a match, such files left by an earlier failure are removed.
pub fn check_images(
    name: &str,
    expected: &RgbaImage,
    actual: &RgbaImage,
    out_dir: &Path,
    tolerance: &Tolerance,
) -> Result<Comparison> {
    let c = compare(expected, actual, tolerance);
    let (actual_path, diff_path) = failure_paths(name, out_dir);
    if c.passed() {
        let _ = std::fs::remove_file(&actual_path);
        let _ = std::fs::remove_file(&diff_path);
        return Ok(c);
    }
    create_dir(out_dir)?;
    save_png(actual, &actual_path)?;
    save_png(&diff_image(expected, actual, tolerance), &diff_path)?;
    Err(Error::Snapshot {
        name: name.to_string(),
        msg: format!(
            "{}; wrote {} and {}",
            c.summary(),
            actual_path.display(),
            diff_path.display()
        ),
    })
}

/// Checks `actual` against the reference PNG at `reference`, as [`check_images`] does.
/// With `bless` the reference is written instead (its folder created if needed), stale
/// failure files are removed, and the comparison with the old reference, if there was
/// one, is returned. Without it a missing
/// reference fails (after writing the actual image into `out_dir` for inspection).
pub fn check_snapshot(
    name: &str,
    actual: &RgbaImage,
    reference: &Path,
    out_dir: &Path,
    tolerance: &Tolerance,
    bless: bool,
) -> Result<Comparison> {
    let old = reference
        .exists()
        .then(|| load_png(reference))
        .transpose()?;
    if bless {
        if let Some(dir) = reference.parent() {
            create_dir(dir)?;
        }
        save_png(actual, reference)?;
        let (actual_path, diff_path) = failure_paths(name, out_dir);
        let _ = std::fs::remove_file(actual_path);
        let _ = std::fs::remove_file(diff_path);
        let old = old.unwrap_or_else(|| actual.clone());
        return Ok(compare(&old, actual, tolerance));
    }
    let Some(expected) = old else {
        create_dir(out_dir)?;
        let (actual_path, _) = failure_paths(name, out_dir);
        save_png(actual, &actual_path)?;
        return Err(Error::Snapshot {
            name: name.to_string(),
            msg: format!(
                "no reference at {} (wrote the render to {}); set {BLESS_ENV}=1 to create it",
                reference.display(),
                actual_path.display()
            ),
        });
    };
    check_images(name, &expected, actual, out_dir, tolerance)
}

fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::Image {
        path: dir.display().to_string(),
        msg: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic scene: a soft gradient background with a shaded disc, like a
    /// render, so that noise lands on dark, light and saturated pixels alike.
    fn scene(cx: f32, cy: f32, tint: [f32; 3]) -> RgbaImage {
        RgbaImage::from_fn(160, 120, |x, y| {
            let (fx, fy) = (x as f32, y as f32);
            let r2 = (fx - cx).powi(2) + (fy - cy).powi(2);
            if r2 < 40.0f32.powi(2) {
                let s = 1.0 - r2.sqrt() / 40.0;
                let c = tint.map(|t| (255.0 * t * (0.15 + 0.85 * s)) as u8);
                Rgba([c[0], c[1], c[2], 255])
            } else {
                let g = 200 + (fy / 120.0 * 50.0) as u8;
                Rgba([g, g, g.saturating_add(5), 255])
            }
        })
    }

    fn base() -> RgbaImage {
        scene(80.0, 60.0, [0.3, 0.45, 0.8])
    }

    /// xorshift noise of ±`amp` levels on every channel of every pixel.
    fn noised(img: &RgbaImage, amp: i32) -> RgbaImage {
        let mut s = 0x9e37_79b9u32;
        let mut out = img.clone();
        for p in out.pixels_mut() {
            for c in 0..3 {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                let d = (s % (2 * amp as u32 + 1)) as i32 - amp;
                p[c] = (p[c] as i32 + d).clamp(0, 255) as u8;
            }
        }
        out
    }

    fn out_dir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("tessera-snapshot-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn identical_images_match() {
        let c = compare(&base(), &base(), &Tolerance::DEFAULT);
        assert!(c.passed(), "{}", c.summary());
        assert_eq!((c.differing, c.max_delta_e), (0, 0.0));
    }

    #[test]
    fn noise_of_two_levels_matches() {
        for amp in [1, 2] {
            let c = compare(&base(), &noised(&base(), amp), &Tolerance::DEFAULT);
            assert!(c.passed(), "±{amp}: {}", c.summary());
            assert_eq!(c.differing, 0, "±{amp}: {}", c.summary());
            assert!(c.max_delta_e > 0.0);
        }
    }

    #[test]
    fn noise_of_two_levels_stays_below_the_pixel_threshold_on_any_colour() {
        // Every 8-bit colour on a coarse lattice, each channel moved by ±2.
        let mut worst = 0.0f32;
        for r in (0..=255).step_by(15) {
            for g in (0..=255).step_by(15) {
                for b in (0..=255).step_by(15) {
                    let p = Rgba([r as u8, g as u8, b as u8, 255]);
                    for d in 0..27 {
                        let m = |c: u8, k: i32| (c as i32 + 2 * k).clamp(0, 255) as u8;
                        let q = Rgba([
                            m(p[0], d % 3 - 1),
                            m(p[1], d / 3 % 3 - 1),
                            m(p[2], d / 9 - 1),
                            255,
                        ]);
                        worst = worst.max(delta_e(p, q));
                    }
                }
            }
        }
        assert!(worst < Tolerance::DEFAULT.delta_e, "worst ΔE {worst}");
    }

    #[test]
    fn different_images_fail() {
        let t = Tolerance::DEFAULT;
        // Shifted by 3 pixels, recoloured, a different shape, a different size.
        let shifted = scene(83.0, 60.0, [0.3, 0.45, 0.8]);
        let recoloured = scene(80.0, 60.0, [0.8, 0.45, 0.3]);
        let mut shape = base();
        for y in 20..100 {
            for x in 40..120 {
                shape.put_pixel(x, y, Rgba([40, 40, 40, 255]));
            }
        }
        let smaller = image::imageops::crop_imm(&base(), 0, 0, 159, 120).to_image();
        for (what, img) in [
            ("shifted", shifted),
            ("recoloured", recoloured),
            ("shape", shape),
            ("size", smaller),
        ] {
            let c = compare(&base(), &img, &t);
            assert!(!c.passed(), "{what}: {}", c.summary());
        }
    }

    #[test]
    fn a_small_solid_difference_fails_where_thin_scattered_ones_pass() {
        let t = Tolerance::DEFAULT;
        // A 5 × 5 blot: 25 pixels (0.13%), 9 of them clustered.
        let mut blot = base();
        for y in 10..15 {
            for x in 10..15 {
                blot.put_pixel(x, y, Rgba([0, 0, 0, 255]));
            }
        }
        let c = compare(&base(), &blot, &t);
        assert_eq!((c.differing, c.clustered), (25, 9));
        assert!(!c.passed(), "{}", c.summary());
        // Thin lines of more pixels, two pixels wide (antialiasing along an edge).
        let mut lines = base();
        for x in 10..30 {
            for y in [10, 11, 40, 41] {
                lines.put_pixel(x, y, Rgba([0, 0, 0, 255]));
            }
        }
        let c = compare(&base(), &lines, &t);
        assert_eq!((c.differing, c.clustered), (80, 0));
        assert!(c.passed(), "{}", c.summary());
    }

    /// `base()` with one-pixel dark lines across it at `rows`, like a wireframe.
    fn ruled(rows: &[u32]) -> RgbaImage {
        let mut img = base();
        for &y in rows {
            for x in 10..150 {
                img.put_pixel(x, y, Rgba([20, 20, 40, 255]));
            }
        }
        img
    }

    #[test]
    fn lines_one_pixel_apart_match_where_lines_gone_fail() {
        let t = Tolerance::DEFAULT;
        let lines = ruled(&[20, 40, 60, 80, 100]);
        // Every line one pixel lower, as another GPU's rasterizer may draw them: over
        // 1300 differing pixels (7%), all explained by the shift.
        let moved = ruled(&[21, 41, 61, 81, 101]);
        let c = compare(&lines, &moved, &t);
        assert!(c.differing > 1300, "{}", c.summary());
        assert_eq!((c.shifted, c.clustered), (c.differing, 0));
        assert!(c.passed(), "{}", c.summary());
        // Two lines left out: their pixels are not near any line in the actual image
        // (only where they cross the disk's dark rim).
        let c = compare(&lines, &ruled(&[20, 60, 100]), &t);
        assert!(c.differing > 250, "{}", c.summary());
        assert!(c.shifted * 10 < c.differing, "{}", c.summary());
        assert!(!c.passed(), "{}", c.summary());
        // Two pixels lower is a different picture.
        let c = compare(&lines, &ruled(&[22, 42, 62, 82, 102]), &t);
        assert!(c.shifted * 10 < c.differing, "{}", c.summary());
        assert!(!c.passed(), "{}", c.summary());
    }

    #[test]
    fn transparent_pixels_compare_as_white() {
        assert_eq!(delta_e(Rgba([0, 0, 0, 0]), Rgba([255, 255, 255, 255])), 0.0);
        assert!(delta_e(Rgba([0, 0, 0, 255]), Rgba([0, 0, 0, 0])) > 99.0);
    }

    #[test]
    fn failed_check_writes_actual_and_diff() {
        let dir = out_dir("fail");
        let actual = scene(90.0, 60.0, [0.3, 0.45, 0.8]);
        let e = check_images("moved", &base(), &actual, &dir, &Tolerance::DEFAULT).unwrap_err();
        assert!(matches!(e, Error::Snapshot { .. }), "{e}");
        let (a, d) = failure_paths("moved", &dir);
        assert_eq!(load_png(&a).unwrap(), actual);
        let diff = load_png(&d).unwrap();
        assert_eq!(diff.dimensions(), actual.dimensions());
        let c = compare(&base(), &actual, &Tolerance::DEFAULT);
        let count = |rgba: [u8; 4]| diff.pixels().filter(|p| p.0 == rgba).count() as u64;
        assert!(c.clustered > 0);
        assert_eq!(count([140, 0, 0, 255]), c.clustered);
        // Shifted pixels in orange, unless clustered.
        let orange = count([245, 150, 0, 255]);
        assert!(orange > 0 && orange <= c.shifted);
        assert_eq!(count([230, 0, 0, 255]) + orange + c.clustered, c.differing);
        // Where nothing changed (a corner of the background) the diff is a faded grey.
        let corner = diff.get_pixel(0, 0);
        assert!(corner[0] == corner[1] && corner[1] == corner[2] && corner[0] > 200);
        // A later pass removes the stale failure files.
        check_images("moved", &base(), &base(), &dir, &Tolerance::DEFAULT).unwrap();
        assert!(!a.exists() && !d.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_reference_fails_unless_blessed() {
        let dir = out_dir("bless");
        let reference = dir.join("refs/disc.png");
        let out = dir.join("out");
        let e = check_snapshot(
            "disc",
            &base(),
            &reference,
            &out,
            &Tolerance::DEFAULT,
            false,
        )
        .unwrap_err();
        assert!(e.to_string().contains(BLESS_ENV), "{e}");
        assert!(!reference.exists());
        assert!(failure_paths("disc", &out).0.exists());
        check_snapshot("disc", &base(), &reference, &out, &Tolerance::DEFAULT, true).unwrap();
        assert_eq!(load_png(&reference).unwrap(), base());
        check_snapshot(
            "disc",
            &noised(&base(), 1),
            &reference,
            &out,
            &Tolerance::DEFAULT,
            false,
        )
        .unwrap();
        let moved = scene(70.0, 60.0, [0.3, 0.45, 0.8]);
        assert!(
            check_snapshot("disc", &moved, &reference, &out, &Tolerance::DEFAULT, false).is_err()
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
