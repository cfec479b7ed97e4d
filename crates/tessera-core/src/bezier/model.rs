//! A Bézier model: patches with welded control points and their topology.

use std::path::Path;

use glam::{DVec3, Vec3};

use super::patch::BezierPatch;
use super::topology::PatchTopology;
use crate::error::Result;
use crate::io::teaset::{load_teaset, TeasetFile, WELD_RELATIVE};
use crate::weld::weld_points;

/// A set of bicubic Bézier patches ready for tessellation.
#[derive(Clone, Debug)]
pub struct BezierModel {
    /// The patches' control points, taken from `points` through `nets`.
    pub patches: Vec<BezierPatch>,
    /// Welded control nets: indices into `points`.
    pub nets: Vec<[u32; 16]>,
    /// The distinct (welded) control points.
    pub points: Vec<Vec3>,
    /// Which patches share curves and corners, and their orientation.
    pub topology: PatchTopology,
}

impl BezierModel {
    /// Loads a Newell teaset file.
    pub fn load(path: &Path) -> Result<Self> {
        Ok(Self::from_teaset(&load_teaset(path)?))
    }

    /// Builds a model from parsed teaset data. Control points closer than 1e-6 of the
    /// bounding-box diagonal are welded, so patches that repeat a boundary's points
    /// (the teaspoon gives every patch its own 16) still share that boundary.
    pub fn from_teaset(file: &TeasetFile) -> Self {
        // Only referenced points count: the teapot lists points no patch uses.
        let mut used = vec![false; file.vertices.len()];
        for net in &file.patches {
            for &i in net {
                used[i as usize] = true;
            }
        }
        let referenced: Vec<Vec3> = file
            .vertices
            .iter()
            .zip(&used)
            .filter(|(_, &u)| u)
            .map(|(v, _)| *v)
            .collect();
        let diag = bbox_diag(&referenced);
        let (weld_id, points) = weld_points(&file.vertices, diag * WELD_RELATIVE as f32);
        let nets: Vec<[u32; 16]> = file
            .patches
            .iter()
            .map(|n| n.map(|i| weld_id[i as usize]))
            .collect();
        Self::from_nets(points, nets)
    }

    /// Diagonal of the control points' bounding box: what relative thresholds and
    /// errors are fractions of.
    pub fn bbox_diag(&self) -> f64 {
        let (lo, hi) = self.bounds();
        f64::from((hi - lo).length())
    }

    /// Builds a model from welded control nets.
    pub fn from_nets(points: Vec<Vec3>, nets: Vec<[u32; 16]>) -> Self {
        let patches = nets
            .iter()
            .map(|n| BezierPatch {
                cp: n.map(|i| points[i as usize]),
            })
            .collect();
        let topology = PatchTopology::build(&nets);
        let mut m = BezierModel {
            patches,
            nets,
            points,
            topology,
        };
        m.orient_outward();
        m
    }

    /// Flips whole connected components whose coarse surface has a negative signed
    /// volume about its own centroid, so that normals of closed parts point outward.
    fn orient_outward(&mut self) {
        let comp = self.topology.components();
        let mut groups: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
        for (p, &c) in comp.iter().enumerate() {
            groups.entry(c).or_default().push(p);
        }
        for patches in groups.values() {
            let samples: Vec<Vec<DVec3>> = patches
                .iter()
                .map(|&p| {
                    let cp = self.patches[p].cp_f64();
                    (0..49)
                        .map(|k| {
                            let (i, j) = (k % 7, k / 7);
                            super::patch::eval_frame_f64(&cp, i as f64 / 6.0, j as f64 / 6.0).pos
                        })
                        .collect()
                })
                .collect();
            let n: usize = samples.iter().map(Vec::len).sum();
            let centroid = samples.iter().flatten().sum::<DVec3>() / n as f64;
            let mut volume = 0.0;
            for (&p, s) in patches.iter().zip(&samples) {
                let sign = if self.topology.flip[p] { -1.0 } else { 1.0 };
                for j in 0..6 {
                    for i in 0..6 {
                        let q = |a: usize, b: usize| s[b * 7 + a] - centroid;
                        let (a, b, c, d) = (q(i, j), q(i + 1, j), q(i + 1, j + 1), q(i, j + 1));
                        volume += sign * (a.dot(b.cross(c)) + a.dot(c.cross(d)));
                    }
                }
            }
            if volume < 0.0 {
                for &p in patches {
                    self.topology.flip[p] = !self.topology.flip[p];
                }
            }
        }
    }

    /// `copies` copies of the model on a square grid in the xy-plane, `spacing` apart:
    /// the benchmarks' large inputs (32 teapots make 1024 patches).
    pub fn grid_of_copies(&self, copies: usize, spacing: f32) -> BezierModel {
        let side = (copies as f32).sqrt().ceil() as usize;
        let mut points = Vec::with_capacity(copies * self.points.len());
        let mut nets = Vec::with_capacity(copies * self.nets.len());
        for c in 0..copies {
            let offset = Vec3::new(
                (c % side) as f32 * spacing,
                (c / side) as f32 * spacing,
                0.0,
            );
            let first = points.len() as u32;
            points.extend(self.points.iter().map(|p| *p + offset));
            nets.extend(self.nets.iter().map(|n| n.map(|i| i + first)));
        }
        BezierModel::from_nets(points, nets)
    }

    /// Axis-aligned bounds of the control points.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in &self.patches {
            for c in p.cp {
                lo = lo.min(c);
                hi = hi.max(c);
            }
        }
        (lo, hi)
    }

    /// Boundary curves used by only one patch side: the surface's open boundary, as the
    /// four control points of each curve.
    pub fn open_boundary_curves(&self) -> Vec<[Vec3; 4]> {
        use super::topology::SIDE_CONTROL;
        self.topology
            .curves
            .iter()
            .filter(|c| c.users == 1 && !c.collapsed)
            .map(|c| {
                SIDE_CONTROL[c.owner_side as usize].map(|i| self.patches[c.owner as usize].cp[i])
            })
            .collect()
    }
}

fn bbox_diag(points: &[Vec3]) -> f32 {
    let lo = points
        .iter()
        .fold(Vec3::splat(f32::INFINITY), |a, &b| a.min(b));
    let hi = points
        .iter()
        .fold(Vec3::splat(f32::NEG_INFINITY), |a, &b| a.max(b));
    (hi - lo).length()
}
