//! Stencil tables: what the GPU derives every patch's quadtree from, built once per
//! topology, so that moving the control points uploads the control points and nothing
//! else. OpenSubdiv does the same with its stencil tables (`Far::StencilTable`: every
//! refined point a weighted sum of control points, applied per frame by `Osd`).
//!
//! Two steps, each the twin of an entry of `shaders/cc_stencil.wgsl`:
//! - [`level1`]: the level-1 points (the first Catmull-Clark step) as sparse weighted
//!   sums of control points, one row per point.
//! - [`pieces`]: every Bézier net, ball and corner of a patch's quadtree as dense rows
//!   over the patch's one-ring of level-1 points. A one-ring gathered in canonical order
//!   ([`LocalMesh::gather_canonical`]) gives the same local mesh for all patches alike,
//!   so that they share one table: every regular interior patch one, every patch with a
//!   vertex of valence n at the same corner another. Per patch, only its one-ring's
//!   point ids and four words are stored.
//!
//! Everything the quadtree stores is linear in the one-ring, except two things the
//! kernel computes from linear rows: a ball's or corner's radius (the longest of the
//! one-ring's offsets from the limit point) and a corner's normal (the sum of the cross
//! products of the edges around the vertex in a deep one-ring, rescaled at each step,
//! as [`LocalMesh::corner_normal`] takes it). The weights are found by building the
//! quadtree, or the first step, on unit points: with point `3g + a` at the unit vector
//! of axis `a` and the others at the origin, coordinate `a` of every output is that
//! point's weight.
//!
//! Rows are kept as offsets where the outputs are offsets (a net's points 1..16 from
//! point 0, a ring's points from the limit): their weights are differences taken in
//! double precision, and the kernel sums them over the ring's offsets from its first
//! point, so that the tiny pieces next to an extraordinary vertex keep their shape in
//! single precision.

use glam::{DVec3, Vec3};
use rustc_hash::FxHashMap as HashMap;

use super::gpu_model::CcGpuModel;
use super::local::LocalMesh;
use super::patch::{Node, PatchSurface};
use super::refine::{refine_sharp, Scheme};
use super::topology::PatchMesh;
use crate::gpu_types::{
    CcCorner, CcNode, CcPatchStencil, CcPieceRecord, CcRoot, CcStencilTable, CcWeight, GpuPatch,
    CC_NODE_BALL_SHIFT, CC_NODE_BEZIER, CC_NODE_CORNER, CC_NODE_SPLIT, CC_NO_ROOT, CC_RECORD_BALL,
    CC_RECORD_CORNER, CC_RECORD_NET, CC_ROOT_CORNER_SHIFT, CC_ROOT_CREASED, CC_ROOT_QUAD_FACE,
};

/// Steps of the rescaled one-ring a corner's normal is read from, past the corner node:
/// the normal's error shrinks as the ratio of the subdivision matrix's third and second
/// eigenvalues (at most 0.6 for the valences accepted) to this power.
const NORMAL_STEPS: usize = 48;

/// The tables of one topology: everything but the control points.
#[derive(Clone, Debug, Default)]
pub struct CcStencils {
    /// Per level-1 point, its first term in `level1_weights` (and the end, last).
    pub level1_offsets: Vec<u32>,
    /// The level-1 points' terms.
    pub level1_weights: Vec<CcWeight>,
    /// Every patch's one-ring, level-1 point ids in canonical order, patch after patch.
    pub rings: Vec<u32>,
    /// Per patch: its one-ring, table, first net and corner, and first record.
    pub patches: Vec<CcPatchStencil>,
    /// Records of all patches: the kernel's invocations.
    pub record_count: u32,
    /// The shared tables.
    pub tables: Vec<CcStencilTable>,
    /// The tables' records.
    pub records: Vec<CcPieceRecord>,
    /// The records' rows, row-major, `columns` weights each.
    pub weights: Vec<f32>,
    /// The quadtrees' shape (roots, nodes, splits), and nets and corners to be filled.
    pub structure: CcGpuModel,
}

/// A quadtree node of a table, its nets and corner records counted within the patch.
#[derive(Clone, Copy, Debug)]
enum Shape {
    Net(u32),
    Split([u32; 4], Option<u32>),
    Corner(u32),
}

/// A table before it is flattened: the quadtree's shape, and per record its kind and
/// rows (`columns` weights each).
struct Table {
    shape: Vec<Shape>,
    records: Vec<(u32, u32, Vec<Vec<f64>>)>,
    columns: usize,
}

impl CcStencils {
    /// The tables of `mesh`'s topology, quadtrees `depth` levels deep (as
    /// [`PatchSurface::build`] makes them).
    pub fn new(mesh: &PatchMesh, depth: u32) -> Self {
        let (level1_offsets, level1_weights) = level1_stencils(mesh);
        let mut out = CcStencils {
            level1_offsets,
            level1_weights,
            ..Default::default()
        };
        let mut index: HashMap<String, u32> = HashMap::default();
        let mut tables: Vec<Table> = Vec::new();
        // Each table's root among the shared nodes.
        let mut roots: Vec<u32> = Vec::new();
        let (mut nets, mut corners) = (0u32, 0u32);
        for p in 0..mesh.patch_count() {
            let records = out.record_count;
            if mesh.hole[p] {
                out.patches.push(CcPatchStencil {
                    records,
                    ..bytemuck::Zeroable::zeroed()
                });
                out.structure.roots.push(CcRoot {
                    node: CC_NO_ROOT,
                    ..bytemuck::Zeroable::zeroed()
                });
                continue;
            }
            let (ring, ids) = LocalMesh::gather_canonical(
                &mesh.points,
                &mesh.quads,
                &mesh.point_quads,
                &mesh.sharpness,
                p,
            );
            let flags = root_flags(mesh, p, !ring.sharp.is_empty());
            let key = table_key(&ring);
            let t = *index.entry(key).or_insert_with(|| {
                let table = Table::new(&ring, mesh.scheme, depth);
                roots.push(out.add_structure(&table.shape));
                tables.push(table);
                tables.len() as u32 - 1
            });
            let table = &tables[t as usize];
            out.patches.push(CcPatchStencil {
                ring: out.rings.len() as u32,
                table: t,
                nets,
                corners,
                records,
            });
            out.rings.extend(ids);
            out.record_count += table.records.len() as u32;
            out.structure.roots.push(CcRoot {
                node: roots[t as usize],
                nets,
                corners,
                flags,
            });
            for (kind, _, _) in &table.records {
                if *kind & 0xff == CC_RECORD_NET {
                    nets += 1;
                } else {
                    corners += 1;
                }
            }
        }
        for table in &tables {
            out.tables.push(CcStencilTable {
                records: out.records.len() as u32,
                record_count: table.records.len() as u32,
                columns: table.columns as u32,
                pad: 0,
            });
            for (kind, out_index, rows) in &table.records {
                // A corner's one-ring row count rides above bit 16 of its kind until here;
                // its normal pairs follow those rows.
                let rings = match *kind & 0xff {
                    CC_RECORD_CORNER => *kind >> 16,
                    _ => rows.len() as u32 - 1,
                };
                let pairs = (rows.len() as u32 - 1 - rings) / 2;
                out.records.push(CcPieceRecord {
                    kind: *kind & 0xffff,
                    weights: out.weights.len() as u32,
                    counts: rings | pairs << 16,
                    out: *out_index,
                });
                for row in rows {
                    out.weights.extend(row.iter().map(|&w| w as f32));
                }
            }
        }
        out.structure.nets = vec![GpuPatch { cp: [0.0; 48] }; nets as usize];
        out.structure.corners = vec![CcCorner::default_zeroed(); corners as usize];
        out
    }

    /// A table's nodes, shared by its patches (nets and corners numbered within the
    /// patch, which adds its bases); returns the root.
    fn add_structure(&mut self, shape: &[Shape]) -> u32 {
        let s = &mut self.structure;
        let base = s.nodes.len() as u32;
        for node in shape {
            s.nodes.push(match *node {
                Shape::Net(k) => CcNode {
                    kind: CC_NODE_BEZIER,
                    index: k,
                },
                Shape::Split(children, ball) => {
                    s.splits.push(children.map(|c| base + c));
                    let ball = ball.map_or(0, |b| b + 1);
                    CcNode {
                        kind: CC_NODE_SPLIT | ball << CC_NODE_BALL_SHIFT,
                        index: s.splits.len() as u32 - 1,
                    }
                }
                Shape::Corner(k) => CcNode {
                    kind: CC_NODE_CORNER,
                    index: k,
                },
            });
        }
        base
    }

    /// Level-1 points.
    pub fn level1_count(&self) -> usize {
        self.level1_offsets.len().saturating_sub(1)
    }

    /// Bytes uploaded once: the tables and the quadtrees' shape.
    pub fn upload_bytes(&self) -> usize {
        use std::mem::size_of_val;
        let s = &self.structure;
        size_of_val(self.level1_offsets.as_slice())
            + size_of_val(self.level1_weights.as_slice())
            + size_of_val(self.rings.as_slice())
            + size_of_val(self.patches.as_slice())
            + size_of_val(self.tables.as_slice())
            + size_of_val(self.records.as_slice())
            + size_of_val(self.weights.as_slice())
            + size_of_val(s.roots.as_slice())
            + size_of_val(s.nodes.as_slice())
            + size_of_val(s.splits.as_slice())
    }

    /// Nets the pieces step derives: every patch's Bézier pieces (device memory, not
    /// upload).
    pub fn derived_nets(&self) -> usize {
        let per_table: Vec<usize> = self
            .tables
            .iter()
            .map(|t| {
                let records = &self.records[t.records as usize..][..t.record_count as usize];
                records
                    .iter()
                    .filter(|r| r.kind & 0xff == CC_RECORD_NET)
                    .count()
            })
            .collect();
        self.patches
            .iter()
            .zip(&self.structure.roots)
            .filter(|(_, root)| root.node != CC_NO_ROOT)
            .map(|(p, _)| per_table[p.table as usize])
            .sum()
    }

    /// Bytes the tables shared between patches take (records, weights, nodes).
    pub fn shared_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.structure.nodes.as_slice())
            + size_of_val(self.structure.splits.as_slice())
            + size_of_val(self.tables.as_slice())
            + size_of_val(self.records.as_slice())
            + size_of_val(self.weights.as_slice())
    }

    /// Bytes patch `p` alone uploads: its one-ring's ids and its words (stencil, root).
    pub fn patch_bytes(&self, p: usize) -> usize {
        let words = std::mem::size_of::<CcPatchStencil>() + std::mem::size_of::<CcRoot>();
        if self.structure.roots[p].node == CC_NO_ROOT {
            return words;
        }
        let columns = self.tables[self.patches[p].table as usize].columns as usize;
        4 * columns + words
    }

    /// The quadtrees of the control points `control` (one per control vertex): the
    /// twins of both kernel steps.
    pub fn model(&self, control: &[Vec3]) -> CcGpuModel {
        let (nets, corners) = pieces(self, &level1(self, control));
        CcGpuModel {
            nets,
            corners,
            ..self.structure.clone()
        }
    }
}

impl CcCorner {
    fn default_zeroed() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

/// What decides a table: the canonical one-ring's quads and sharpness.
fn table_key(ring: &LocalMesh) -> String {
    use std::fmt::Write;
    let mut key = format!("{:?}", ring.quads);
    let sorted = |m: &HashMap<(u32, u32), f32>| {
        let mut v: Vec<_> = m.iter().map(|(k, s)| (*k, s.to_bits())).collect();
        v.sort_unstable();
        v
    };
    if !ring.sharp.is_empty() || !ring.sharp.next.is_empty() {
        let mut vertices: Vec<_> = ring
            .sharp
            .vertices
            .iter()
            .map(|(v, s)| (*v, s.to_bits()))
            .collect();
        vertices.sort_unstable();
        let _ = write!(
            key,
            "|{:?}|{:?}|{:?}",
            sorted(&ring.sharp.edges),
            sorted(&ring.sharp.next),
            vertices
        );
    }
    key
}

/// `ring` with point `3g + a` at the unit vector of axis `a`, the others at the origin.
fn unit_ring(ring: &LocalMesh, g: usize) -> LocalMesh {
    let mut unit = ring.clone();
    for (i, p) in unit.points.iter_mut().enumerate() {
        *p = if i / 3 == g {
            DVec3::AXES[i % 3]
        } else {
            DVec3::ZERO
        };
    }
    unit
}

impl Table {
    /// The table of a canonical one-ring: the quadtree built once per three points.
    fn new(ring: &LocalMesh, scheme: Scheme, depth: u32) -> Self {
        let columns = ring.points.len();
        let groups = columns.div_ceil(3);
        // Per group: per record, its rows' values for the group's three points.
        let mut shape = Vec::new();
        let mut kinds: Vec<(u32, u32)> = Vec::new();
        let mut values: Vec<Vec<Vec<DVec3>>> = Vec::with_capacity(groups);
        for g in 0..groups {
            let unit = unit_ring(ring, g);
            let mut rings: Vec<Vec<DVec3>> = Vec::new();
            let surface = PatchSurface::from_ring(unit.clone(), scheme, depth, &mut |_, r| {
                rings.push(r.points.clone())
            });
            let (s, k, v) = records_of(&surface, &rings, &unit, scheme);
            if g == 0 {
                shape = s;
                kinds = k;
            }
            values.push(v);
        }
        let records = kinds
            .iter()
            .enumerate()
            .map(|(r, &(kind, out))| {
                let rows = (0..values[0][r].len())
                    .map(|k| (0..columns).map(|i| values[i / 3][r][k][i % 3]).collect())
                    .collect();
                (kind, out, rows)
            })
            .collect();
        Table {
            shape,
            records,
            columns,
        }
    }
}

/// The shape of `surface` (built on a unit ring), and per record its kind (a corner's
/// ring row count above bit 16) and index within the patch, and its rows.
#[allow(clippy::type_complexity)]
fn records_of(
    surface: &PatchSurface,
    rings: &[Vec<DVec3>],
    root: &LocalMesh,
    scheme: Scheme,
) -> (Vec<Shape>, Vec<(u32, u32)>, Vec<Vec<DVec3>>) {
    let (mut nets, mut corners) = (0u32, 0u32);
    let mut shape = Vec::with_capacity(surface.nodes.len());
    let mut kinds = Vec::new();
    let mut values = Vec::new();
    // The path from the root to each node: the children taken.
    let mut path: Vec<Vec<usize>> = vec![Vec::new(); surface.nodes.len()];
    for (id, node) in surface.nodes.iter().enumerate() {
        if let Node::Split(children) = node {
            for (c, &child) in children.iter().enumerate() {
                let mut p = path[id].clone();
                p.push(c);
                path[child as usize] = p;
            }
        }
    }
    let offsets = |points: &[DVec3], centre: DVec3| -> Vec<DVec3> {
        points.iter().map(|p| *p - centre).collect()
    };
    for (id, node) in surface.nodes.iter().enumerate() {
        match node {
            Node::Bezier(net) => {
                shape.push(Shape::Net(nets));
                kinds.push((CC_RECORD_NET, nets));
                let mut rows = vec![net[0]];
                rows.extend((1..16).map(|k| net[k] - net[0]));
                values.push(rows);
                nets += 1;
            }
            Node::Split(children) => {
                let ball = surface.balls[id].map(|b| {
                    kinds.push((CC_RECORD_BALL, corners));
                    let mut rows = vec![b.limit];
                    rows.extend(offsets(&rings[id], b.limit));
                    values.push(rows);
                    corners += 1;
                    corners - 1
                });
                shape.push(Shape::Split(*children, ball));
            }
            Node::Corner(c) => {
                shape.push(Shape::Corner(corners));
                let ring = offsets(&rings[id], c.limit);
                let kind = CC_RECORD_CORNER | (c.corner as u32) << 8 | (ring.len() as u32) << 16;
                kinds.push((kind, corners));
                let mut rows = vec![c.limit];
                rows.extend(ring);
                rows.extend(normal_rows(root, &path[id], c.corner, c.limit, scheme));
                values.push(rows);
                corners += 1;
            }
        }
    }
    (shape, kinds, values)
}

/// The edges around corner `c`'s vertex in a deep one-ring, as pairs of rows whose cross
/// products sum to the normal: from the root's ring moved so that the vertex's limit
/// point is the origin, down `path` and [`NORMAL_STEPS`] steps more toward the vertex,
/// doubled at each step so that the offsets stay near unit size.
fn normal_rows(
    root: &LocalMesh,
    path: &[usize],
    c: usize,
    limit: DVec3,
    scheme: Scheme,
) -> Vec<DVec3> {
    let mut ring = root.clone();
    for p in &mut ring.points {
        *p -= limit;
    }
    for (step, &child) in path
        .iter()
        .chain(std::iter::repeat_n(&c, NORMAL_STEPS))
        .enumerate()
    {
        ring = ring
            .children(&scheme)
            .into_iter()
            .nth(child)
            .expect("four children");
        // Past the node the vertex is corner c: moving its limit back to the origin at
        // each step keeps the rounding of the first move from being doubled away.
        let centre = if step >= path.len() {
            ring.limit_point(c, &scheme)
        } else {
            DVec3::ZERO
        };
        for p in &mut ring.points {
            *p = 2.0 * (*p - centre);
        }
    }
    let v = ring.quads[0][c];
    let mut rows = Vec::new();
    for (q, k) in ring.around(v) {
        let quad = ring.quads[q];
        rows.push(ring.points[quad[(k + 1) % 4] as usize]);
        rows.push(ring.points[quad[(k + 3) % 4] as usize]);
    }
    rows
}

/// The level-1 points' stencils over the control points. Each level-1 point depends on
/// the control points of the faces whose sub-quads hold it; points that share such a
/// set get different colours, and one first step per three colours, on unit points,
/// gives every weight.
fn level1_stencils(mesh: &PatchMesh) -> (Vec<u32>, Vec<CcWeight>) {
    let n1 = mesh.points.len();
    let nc = mesh.control_vertices;
    let mut depends: Vec<Vec<u32>> = vec![Vec::new(); n1];
    for (f, face) in mesh.control_faces.iter().enumerate() {
        let first = mesh.first_patch[f] as usize;
        for quad in &mesh.quads[first..first + face.len()] {
            for &q in quad {
                for &v in face {
                    if !depends[q as usize].contains(&v) {
                        depends[q as usize].push(v);
                    }
                }
            }
        }
    }
    // A control point that no face uses keeps its own position.
    for (v, d) in depends.iter_mut().enumerate().take(nc) {
        if d.is_empty() {
            d.push(v as u32);
        }
    }
    let mut conflicts: Vec<Vec<u32>> = vec![Vec::new(); nc];
    for d in &depends {
        for &a in d {
            conflicts[a as usize].extend(d.iter().copied().filter(|&b| b != a));
        }
    }
    let mut colour = vec![u32::MAX; nc];
    for v in 0..nc {
        let mut used: Vec<u32> = conflicts[v]
            .iter()
            .map(|&w| colour[w as usize])
            .filter(|&c| c != u32::MAX)
            .collect();
        used.sort_unstable();
        used.dedup();
        colour[v] = (0..).find(|c| used.binary_search(c).is_err()).unwrap_or(0);
    }
    let colours = colour.iter().map(|&c| c + 1).max().unwrap_or(0) as usize;
    let mut weights: Vec<Vec<CcWeight>> = vec![Vec::new(); n1];
    for run in 0..colours.div_ceil(3) {
        let unit: Vec<DVec3> = colour
            .iter()
            .map(|&c| {
                if c as usize / 3 == run {
                    DVec3::AXES[c as usize % 3]
                } else {
                    DVec3::ZERO
                }
            })
            .collect();
        let (level1, _) = refine_sharp(
            &unit,
            &mesh.control_faces,
            &mesh.scheme,
            &mesh.control_sharpness,
        );
        for (q, d) in depends.iter().enumerate() {
            for &v in d {
                let c = colour[v as usize] as usize;
                if c / 3 == run {
                    let w = level1.points[q][c % 3];
                    if w != 0.0 {
                        weights[q].push(CcWeight {
                            point: v,
                            weight: w as f32,
                        });
                    }
                }
            }
        }
    }
    let mut offsets = Vec::with_capacity(n1 + 1);
    let mut flat = Vec::new();
    for mut w in weights {
        offsets.push(flat.len() as u32);
        w.sort_unstable_by_key(|t| t.point);
        flat.extend(w);
    }
    offsets.push(flat.len() as u32);
    (offsets, flat)
}

/// Twin of `level1` in `shaders/cc_stencil.wgsl`: each level-1 point, its terms summed
/// in order.
pub fn level1(stencils: &CcStencils, control: &[Vec3]) -> Vec<Vec3> {
    let o = &stencils.level1_offsets;
    (0..stencils.level1_count())
        .map(|q| {
            let mut acc = Vec3::ZERO;
            for t in &stencils.level1_weights[o[q] as usize..o[q + 1] as usize] {
                acc += control[t.point as usize] * t.weight;
            }
            acc
        })
        .collect()
}

/// Twin of `pieces` in `shaders/cc_stencil.wgsl`: every record of every patch, from the
/// level-1 points.
pub fn pieces(stencils: &CcStencils, level1: &[Vec3]) -> (Vec<GpuPatch>, Vec<CcCorner>) {
    let mut nets = vec![GpuPatch { cp: [0.0; 48] }; stencils.structure.nets.len()];
    let mut corners = vec![CcCorner::default_zeroed(); stencils.structure.corners.len()];
    for r in 0..stencils.record_count {
        let p = record_patch(&stencils.patches, r);
        let ps = stencils.patches[p];
        let table = stencils.tables[ps.table as usize];
        let rec = stencils.records[(table.records + r - ps.records) as usize];
        let m = table.columns as usize;
        let ring = |i: usize| level1[stencils.rings[ps.ring as usize + i] as usize];
        let origin = ring(0);
        let row = |k: usize| {
            let w = &stencils.weights[rec.weights as usize + k * m..];
            let mut acc = Vec3::ZERO;
            for (i, &w) in w.iter().take(m).enumerate() {
                acc += (ring(i) - origin) * w;
            }
            acc
        };
        if rec.kind & 0xff == CC_RECORD_NET {
            let net = &mut nets[(ps.nets + rec.out) as usize];
            net.cp[0..3].copy_from_slice(&(origin + row(0)).to_array());
            for k in 1..16 {
                net.cp[3 * k..3 * k + 3].copy_from_slice(&row(k).to_array());
            }
            continue;
        }
        let rings = (rec.counts & 0xffff) as usize;
        let pairs = (rec.counts >> 16) as usize;
        let mut radius = 0.0f32;
        for k in 1..=rings {
            radius = radius.max(row(k).length());
        }
        let mut normal = Vec3::ZERO;
        for j in 0..pairs {
            normal += row(1 + rings + 2 * j).cross(row(2 + rings + 2 * j));
        }
        let corner = rec.kind & 0xff == CC_RECORD_CORNER;
        corners[(ps.corners + rec.out) as usize] = CcCorner {
            limit: (origin + row(0)).to_array(),
            corner: if corner { (rec.kind >> 8) & 0xff } else { 0 },
            normal: normal.normalize_or_zero().to_array(),
            hull_radius: radius,
        };
    }
    (nets, corners)
}

/// The patch of record `r` (below the total): the last whose first record is at most
/// `r`, by the kernel's binary search.
pub fn record_patch(patches: &[CcPatchStencil], r: u32) -> usize {
    // patches[lo].records <= r, and r is before patch hi's records (or hi is the end).
    let (mut lo, mut hi) = (0usize, patches.len());
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if patches[mid].records <= r {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// [`CcRoot::flags`] of patch `p`: creased or not, and its place in a quad face.
pub fn root_flags(mesh: &PatchMesh, p: usize, creased: bool) -> u32 {
    let (f, corner) = mesh.face_of[p];
    let quad = if mesh.control_faces[f as usize].len() == 4 {
        CC_ROOT_QUAD_FACE | (corner as u32) << CC_ROOT_CORNER_SHIFT
    } else {
        0
    };
    quad | if creased { CC_ROOT_CREASED } else { 0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::catmull_clark::patch::SurfaceModel;
    use crate::catmull_clark::{load_surface, TREE_DEPTH};

    fn model(name: &str) -> SurfaceModel {
        let path = format!("{}/../../assets/{name}", env!("CARGO_MANIFEST_DIR"));
        load_surface(std::path::Path::new(&path)).expect("model loads")
    }

    /// The double-precision quadtrees, flattened as the GPU reads them (what the stage
    /// uploaded before it had tables): the reference the tables must reproduce.
    fn flatten(model: &SurfaceModel) -> CcGpuModel {
        let mut out = CcGpuModel::default();
        for (p, surface) in model.patches.iter().enumerate() {
            if surface.nodes.is_empty() || model.mesh.hole[p] {
                out.roots.push(CcRoot {
                    node: CC_NO_ROOT,
                    ..bytemuck::Zeroable::zeroed()
                });
                continue;
            }
            let base = out.nodes.len() as u32;
            let (nets, corners) = (out.nets.len() as u32, out.corners.len() as u32);
            out.roots.push(CcRoot {
                node: base,
                nets,
                corners,
                flags: root_flags(&model.mesh, p, surface.creased),
            });
            let f = |v: DVec3| v.as_vec3().to_array();
            for (id, node) in surface.nodes.iter().enumerate() {
                out.nodes.push(match node {
                    Node::Bezier(net) => {
                        let mut cp = [0f32; 48];
                        cp[0..3].copy_from_slice(&f(net[0]));
                        for k in 1..16 {
                            cp[3 * k..3 * k + 3].copy_from_slice(&f(net[k] - net[0]));
                        }
                        out.nets.push(GpuPatch { cp });
                        CcNode {
                            kind: CC_NODE_BEZIER,
                            index: out.nets.len() as u32 - 1 - nets,
                        }
                    }
                    Node::Split(children) => {
                        out.splits.push(children.map(|c| base + c));
                        let ball = surface.balls[id].map_or(0, |b| {
                            out.corners.push(CcCorner {
                                limit: f(b.limit),
                                corner: 0,
                                normal: [0.0; 3],
                                hull_radius: b.radius as f32,
                            });
                            out.corners.len() as u32 - corners
                        });
                        CcNode {
                            kind: CC_NODE_SPLIT | ball << CC_NODE_BALL_SHIFT,
                            index: out.splits.len() as u32 - 1,
                        }
                    }
                    Node::Corner(c) => {
                        out.corners.push(CcCorner {
                            limit: f(c.limit),
                            corner: c.corner as u32,
                            normal: f(c.normal),
                            hull_radius: c.hull_radius as f32,
                        });
                        CcNode {
                            kind: CC_NODE_CORNER,
                            index: out.corners.len() as u32 - 1 - corners,
                        }
                    }
                });
            }
        }
        out
    }

    fn v3(a: &[f32]) -> Vec3 {
        Vec3::from_slice(a)
    }

    /// Largest errors of `got` against `want`, relative to the model size `size`: net
    /// origins, net offsets (relative to the net's extent), limits, radii (relative
    /// to the radius), normals (angle).
    fn errors(got: &CcGpuModel, want: &CcGpuModel, size: f32) -> [f32; 5] {
        let mut e = [0f32; 5];
        for (a, b) in got.nets.iter().zip(&want.nets) {
            e[0] = e[0].max((v3(&a.cp[0..3]) - v3(&b.cp[0..3])).length() / size);
            let extent = (1..16)
                .map(|k| v3(&b.cp[3 * k..3 * k + 3]).length())
                .fold(0f32, f32::max);
            for k in 1..16 {
                let d = (v3(&a.cp[3 * k..3 * k + 3]) - v3(&b.cp[3 * k..3 * k + 3])).length();
                e[1] = e[1].max(d / (extent + 1e-4 * size));
            }
        }
        for (a, b) in got.corners.iter().zip(&want.corners) {
            e[2] = e[2].max((v3(&a.limit) - v3(&b.limit)).length() / size);
            e[3] = e[3].max((a.hull_radius - b.hull_radius).abs() / (b.hull_radius + 1e-4 * size));
            if b.normal != [0.0; 3] {
                e[4] = e[4].max((v3(&a.normal) - v3(&b.normal)).length());
            }
        }
        e
    }

    #[test]
    fn the_tables_reproduce_every_patchs_quadtree() {
        // Regular, valence 3 and 5, boundaries and holes, triangles, creases and corners
        // (which flag their patches' roots): the same shape, and
        // the same nets, balls and corners to single precision.
        for name in [
            "opensubdiv/catmark_cube.obj",
            "opensubdiv/catmark_pyramid.obj",
            "opensubdiv/catmark_xord_interior.obj",
            "opensubdiv/catmark_edgecorner.obj",
            "opensubdiv/catmark_hole_test1.obj",
            "opensubdiv/catmark_toroidal_tet.obj",
            "catmull_clark/spot_control_mesh.obj",
            "opensubdiv/catmark_cube_creases1.obj",
            "opensubdiv/catmark_cube_corner3.obj",
        ] {
            let m = model(name);
            let got = CcGpuModel::new(&m);
            let want = flatten(&m);
            let bases = |g: &CcGpuModel| {
                g.roots
                    .iter()
                    .map(|r| (r.nets, r.corners, r.flags))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bases(&got), bases(&want), "{name}: bases");
            for p in 0..m.mesh.patch_count() {
                assert_eq!(
                    got.roots[p].node == CC_NO_ROOT,
                    want.roots[p].node == CC_NO_ROOT,
                    "{name}: hole {p}"
                );
                if want.roots[p].node == CC_NO_ROOT {
                    continue;
                }
                // The same nodes, children counted from the root.
                let n = m.patches[p].nodes.len();
                let node = |g: &CcGpuModel, k: usize| {
                    let root = g.roots[p].node;
                    let nd = g.nodes[root as usize + k];
                    let children = (nd.kind & 0xff == CC_NODE_SPLIT)
                        .then(|| g.splits[nd.index as usize].map(|c| c - root));
                    let index = if children.is_some() { 0 } else { nd.index };
                    (nd.kind, index, children)
                };
                for k in 0..n {
                    assert_eq!(node(&got, k), node(&want, k), "{name}: patch {p} node {k}");
                }
            }
            assert_eq!(got.nets.len(), want.nets.len(), "{name}: nets");
            let stencils = CcStencils::new(&m.mesh, m.depth);
            assert_eq!(
                stencils.derived_nets(),
                want.nets.len(),
                "{name}: derived nets"
            );
            assert_eq!(got.corners.len(), want.corners.len(), "{name}: corners");
            let corners_match = got
                .corners
                .iter()
                .zip(&want.corners)
                .all(|(a, b)| a.corner == b.corner);
            assert!(corners_match, "{name}: the vertex's corner");
            let e = errors(&got, &want, m.mesh.bbox_diag() as f32);
            eprintln!("{name}: {e:?}");
            assert!(
                e[0] < 2e-6 && e[2] < 2e-6,
                "{name}: origins and limits {e:?}"
            );
            assert!(
                e[1] < 1e-5 && e[3] < 1e-5,
                "{name}: offsets and radii {e:?}"
            );
            assert!(e[4] < 1e-5, "{name}: normals {e:?}");
        }
    }

    #[test]
    fn a_planted_error_in_a_table_is_caught() {
        // The comparison above can fail: one weight changed moves a net.
        let m = model("opensubdiv/catmark_pyramid.obj");
        let mut stencils = CcStencils::new(&m.mesh, m.depth);
        stencils.weights[5] += 0.05;
        let control = m.mesh.control_points_f32();
        let e = errors(
            &stencils.model(&control),
            &flatten(&m),
            m.mesh.bbox_diag() as f32,
        );
        assert!(e.iter().any(|&x| x > 1e-4), "{e:?}");
    }

    #[test]
    fn the_level1_stencils_are_the_first_step() {
        // Moved points (not the loaded ones, whose symmetry could hide a swapped weight).
        for name in [
            "opensubdiv/catmark_edgecorner.obj",
            "catmull_clark/spot_control_mesh.obj",
        ] {
            let m = model(name);
            let moved: Vec<DVec3> = m
                .mesh
                .control_points
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    *p + 0.01 * DVec3::new((i % 7) as f64, (i % 3) as f64, (i % 5) as f64)
                })
                .collect();
            let want = m.mesh.with_control_points(&moved).expect("moved").points;
            let stencils = CcStencils::new(&m.mesh, 2);
            let control: Vec<Vec3> = moved.iter().map(|p| p.as_vec3()).collect();
            let got = level1(&stencils, &control);
            assert_eq!(got.len(), want.len());
            let size = m.mesh.bbox_diag();
            for (q, (a, b)) in got.iter().zip(&want).enumerate() {
                assert!(
                    (a.as_dvec3() - *b).length() < 1e-6 * size,
                    "{name}: point {q}: {a} against {b}"
                );
            }
        }
    }

    #[test]
    fn alike_patches_share_a_table_and_an_irregular_patch_uploads_under_2_kb() {
        let m = model("opensubdiv/catmark_car.obj");
        let stencils = CcStencils::new(&m.mesh, TREE_DEPTH);
        let patches = m.mesh.patch_count();
        assert!(
            stencils.tables.len() * 20 < patches,
            "{} tables for {patches} patches",
            stencils.tables.len()
        );
        let irregular = (0..patches).filter(|&p| !m.patches[p].is_regular() && !m.mesh.hole[p]);
        let one_vertex = irregular.filter(|&p| {
            m.patches[p]
                .nodes
                .iter()
                .filter(|n| matches!(n, Node::Corner(_)))
                .count()
                == 1
        });
        let most = one_vertex
            .map(|p| stencils.patch_bytes(p))
            .max()
            .expect("an irregular patch");
        eprintln!(
            "{} tables, {} shared bytes, most {most} bytes per patch",
            stencils.tables.len(),
            stencils.shared_bytes()
        );
        assert!(most <= 2048, "{most} bytes");
    }
}
