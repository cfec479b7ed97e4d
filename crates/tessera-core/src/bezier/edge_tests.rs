//! Edge tests (Espino et al. 2005, §2.2) and the recursive bisection they drive.
//! CPU twin of `shaders/shared/map.wgsl`.
//!
//! A segment from `(u1, v1)` to `(u2, v2)` in a patch's parameter space is split at its
//! midpoint `(u12, v12)` when its test is positive; the halves are tested again, down to
//! `max_depth` levels. Inserted points are dyadic fractions `k / 256` of the segment,
//! returned as a bit set, so that the same decisions can be replayed by any later stage.

use glam::Vec3;

use super::patch::eval_frame_f32;
use super::prepare::map_read;
use crate::gpu_types::{DisplacementMap, EDGE_BIT_WORDS, MAX_DEPTH_LIMIT};

/// Which test decides whether an edge is split.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EdgeTest {
    /// `|d1 − d12| > th or |d2 − d12| > th` on the displacement map.
    Map2p,
    /// Map2p plus `d3`, `d4` across the edge at `(u12 ∓ ve, v12 ± ue)`.
    Map4p,
    /// Map4p plus `d5..d8` at `(u12, v12) + ½(±(ue, ve) ± (−ve, ue))`.
    Map8p,
    /// The vector test: `|S(u12, v12) − (S1 + S2)/2| > th`. Evaluates the surface.
    Flat,
}

impl EdgeTest {
    /// The test's lower-case name (`map2p`, `map4p`, `map8p`, `flat`), as the CLI
    /// spells it.
    pub fn name(self) -> &'static str {
        match self {
            EdgeTest::Map2p => "map2p",
            EdgeTest::Map4p => "map4p",
            EdgeTest::Map8p => "map8p",
            EdgeTest::Flat => "flat",
        }
    }

    /// Every test, in [`index`](Self::index) order.
    pub const ALL: [EdgeTest; 4] = [
        EdgeTest::Map2p,
        EdgeTest::Map4p,
        EdgeTest::Map8p,
        EdgeTest::Flat,
    ];

    /// The test's number in the shaders (`TEST_MAP2P` .. `TEST_FLAT`, the value of the
    /// pipeline constant `EDGE_TEST`).
    pub fn index(self) -> u32 {
        self as u32
    }
}

/// Denominator of the dyadic positions of inserted points.
pub const DYADIC_SCALE: u32 = 1 << MAX_DEPTH_LIMIT;

/// Inserted points of one segment: bit `k` set means a vertex at fraction `k / 256`.
pub type EdgeBits = [u32; EDGE_BIT_WORDS];

/// Whether `k` is set.
pub fn bit_is_set(bits: &EdgeBits, k: u32) -> bool {
    bits[(k / 32) as usize] >> (k % 32) & 1 != 0
}

/// The set positions in increasing order.
pub fn bit_positions(bits: &EdgeBits) -> impl Iterator<Item = u32> + '_ {
    (1..DYADIC_SCALE).filter(move |&k| bit_is_set(bits, k))
}

/// Number of inserted points.
pub fn bit_count(bits: &EdgeBits) -> u32 {
    bits.iter().map(|w| w.count_ones()).sum()
}

/// What one patch's tests read.
#[derive(Clone, Copy)]
pub struct TestInputs<'a> {
    /// Which test.
    pub test: EdgeTest,
    /// The test's threshold `th`, model units.
    pub threshold: f32,
    /// Levels of bisection of a segment.
    pub max_depth: u32,
    /// The patch's displacement map (map tests).
    pub map: &'a DisplacementMap,
    /// The patch's control points (the flat test evaluates the surface).
    pub cp: &'a [Vec3; 16],
}

/// Point at fraction `k / 256` of the segment `a → b`.
#[inline]
pub fn lerp_uv(a: [f32; 2], b: [f32; 2], k: u32) -> [f32; 2] {
    let f = k as f32 / DYADIC_SCALE as f32;
    [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f]
}

/// The map test on the segment `uv1 → uv2` (Map2p, Map4p or Map8p), reading `map`.
pub fn map_test(
    test: EdgeTest,
    map: &DisplacementMap,
    th: f32,
    uv1: [f32; 2],
    uv2: [f32; 2],
) -> bool {
    let d = |u: f32, v: f32| Some(map_read(map, u, v));
    let ends = [d(uv1[0], uv1[1]), d(uv2[0], uv2[1])];
    map_test_with(test, th, [uv1, uv2], ends, false, d)
}

/// The map test (the paper's Eq. 1–3) on the segment `uv[0] → uv[1]`, whose ends have
/// the displacements `ends` (read once by the caller: an end is shared by several
/// segments), reading the others through `d`; a point where `d` has no value (`None`)
/// takes no part.
///
/// `one_inside`: the segment is a side of the region where `d` has values, so of two
/// points mirrored across it at most one has a value (the other lies half the side's
/// length beyond it) and only that one is asked for: the GPU reads one texel pair where
/// it would read two (it runs both sides of a branch).
pub fn map_test_with(
    test: EdgeTest,
    th: f32,
    uv: [[f32; 2]; 2],
    ends: [Option<f32>; 2],
    one_inside: bool,
    d: impl Fn(f32, f32) -> Option<f32>,
) -> bool {
    let [uv1, uv2] = uv;
    let m = [(uv1[0] + uv2[0]) * 0.5, (uv1[1] + uv2[1]) * 0.5];
    let Some(d12) = d(m[0], m[1]) else {
        return false;
    };
    let differs_from = |x: Option<f32>| x.is_some_and(|x| (x - d12).abs() > th);
    if differs_from(ends[0]) || differs_from(ends[1]) {
        return true;
    }
    if test == EdgeTest::Map2p {
        return false;
    }
    let mirrored_differ = |p: [f32; 2], q: [f32; 2]| {
        if one_inside {
            differs_from(d(p[0], p[1]).or_else(|| d(q[0], q[1])))
        } else {
            differs_from(d(p[0], p[1])) || differs_from(d(q[0], q[1]))
        }
    };
    let (ue, ve) = (uv1[0] - m[0], uv1[1] - m[1]);
    if mirrored_differ([m[0] - ve, m[1] + ue], [m[0] + ve, m[1] - ue]) {
        return true;
    }
    if test == EdgeTest::Map4p {
        return false;
    }
    // d5..d8: (a, b) = (1, ±1) and (-1, ±1), each pair mirrored across the segment.
    for a in [1.0, -1.0] {
        let p = [m[0] + 0.5 * (a * ue - ve), m[1] + 0.5 * (a * ve + ue)];
        let q = [m[0] + 0.5 * (a * ue + ve), m[1] + 0.5 * (a * ve - ue)];
        if mirrored_differ(p, q) {
            return true;
        }
    }
    false
}

/// Number of inserted points before position `k`.
pub fn bit_rank(bits: &EdgeBits, k: u32) -> u32 {
    let (w, b) = ((k / 32) as usize, k % 32);
    let below: u32 = bits[..w].iter().map(|x| x.count_ones()).sum();
    below + (bits[w] & ((1u32 << b) - 1)).count_ones()
}

/// Recursive bisection of the segment `uv0 → uv1` in one patch by its edge test alone.
/// Returns the inserted points and the number of surface evaluations made (zero for the
/// map tests).
pub fn subdivide_segment(inp: &TestInputs, uv0: [f32; 2], uv1: [f32; 2]) -> (EdgeBits, u32) {
    subdivide_segment_with(inp, uv0, uv1, u32::MAX, |_, _| (false, 0))
}

/// Recursive bisection of the segment `uv0 → uv1`: the piece `[lo, hi]` (in 1/256ths)
/// at level `level` is split when its own edge test is positive (asked only while
/// `level < own_test_levels`) or when `also(lo, hi)` asks for it, at most `max_depth`
/// levels deep. Returns the inserted points and the surface evaluations.
pub fn subdivide_segment_with(
    inp: &TestInputs,
    uv0: [f32; 2],
    uv1: [f32; 2],
    own_test_levels: u32,
    mut also: impl FnMut(u32, u32) -> (bool, u32),
) -> (EdgeBits, u32) {
    let mut bits = [0u32; EDGE_BIT_WORDS];
    let mut evals = 0;
    let depth = inp.max_depth.min(MAX_DEPTH_LIMIT);
    if depth == 0 {
        return (bits, evals);
    }
    // Depth-first over the dyadic pieces [lo, lo + width] without a stack, as the shader
    // walks them: a piece is a second child when lo / width is odd.
    let (mut lo, mut level) = (0u32, 0u32);
    loop {
        let width = DYADIC_SCALE >> level;
        let (hi, mid) = (lo + width, lo + width / 2);
        let (mut split, e) = if level >= own_test_levels {
            (false, 0)
        } else {
            segment_test(inp, lerp_uv(uv0, uv1, lo), lerp_uv(uv0, uv1, hi))
        };
        evals += e;
        if !split {
            let (yes, e) = also(lo, hi);
            evals += e;
            split = yes;
        }
        if split {
            bits[(mid / 32) as usize] |= 1 << (mid % 32);
            if level + 1 < depth {
                level += 1;
                continue;
            }
        }
        while level > 0 && (lo / (DYADIC_SCALE >> level)) % 2 == 1 {
            lo -= DYADIC_SCALE >> level;
            level -= 1;
        }
        if level == 0 {
            return (bits, evals);
        }
        lo += DYADIC_SCALE >> level;
    }
}

/// The edge test on the segment `uv1 → uv2` (paper §2.2): the map tests read the map; the
/// flat test compares the surface midpoint with the chord midpoint (3 evaluations).
pub fn segment_test(inp: &TestInputs, uv1: [f32; 2], uv2: [f32; 2]) -> (bool, u32) {
    if inp.test == EdgeTest::Flat {
        let s = |uv: [f32; 2]| eval_frame_f32(inp.cp, uv[0], uv[1]).pos;
        let m = [(uv1[0] + uv2[0]) * 0.5, (uv1[1] + uv2[1]) * 0.5];
        let chord: Vec3 = (s(uv1) + s(uv2)) * 0.5;
        return ((s(m) - chord).length() > inp.threshold, 3);
    }
    (map_test(inp.test, inp.map, inp.threshold, uv1, uv2), 0)
}
