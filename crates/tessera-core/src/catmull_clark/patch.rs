//! Exact evaluation of each patch (OpenSubdiv's "Bfr" layer).
//!
//! A patch whose corners are all regular is one bicubic B-spline, stored in Bézier form.
//! Otherwise its one-ring is subdivided: of its four children, those without an
//! extraordinary corner are bicubic, the others are subdivided again, down to
//! `depth` levels. The result is a small quadtree of Bézier pieces (three per level
//! around each extraordinary vertex) ending in a [`CornerNode`] that holds the limit
//! point and normal of the vertex and its one-ring, so that any parameter, however close
//! to the vertex, can still be evaluated exactly by subdividing further on demand.
//! Below `depth` only the squares at an extraordinary vertex are split further, down
//! to [`CORNER_DEPTH`](super::CORNER_DEPTH), so that the innermost square, which the
//! flatness bound treats as a ball around the limit point, is negligibly small.
//! Every dyadic parameter of depth ≤ `depth` lies in a Bézier piece or is the vertex
//! itself, so the tessellator evaluates bicubics only.

use glam::DVec3;
use std::sync::OnceLock;

use super::bicubic::{self, Net};
use super::control_mesh::CreaseMethod;
use super::local::{bspline_to_bezier, LocalMesh};
use super::refine::Scheme;
use super::topology::PatchMesh;

/// A node of a patch's quadtree.
#[derive(Clone, Debug)]
pub enum Node {
    /// The surface over the node is this bicubic Bézier patch.
    Bezier(Box<Net>),
    /// Children in quadrant order `[0,½]², [½,1]×[0,½], [½,1]², [0,½]×[½,1]`.
    Split([u32; 4]),
    /// The deepest node at an extraordinary vertex.
    Corner(Box<CornerNode>),
}

/// The node at an extraordinary vertex where the stored quadtree stops.
#[derive(Clone, Debug)]
pub struct CornerNode {
    /// Which node corner (0..4, at `(0,0), (1,0), (1,1), (0,1)`) is the vertex.
    pub corner: usize,
    /// Limit point of the vertex.
    pub limit: DVec3,
    /// Unit limit normal at the vertex.
    pub normal: DVec3,
    /// `|S(x) - limit| ≤ hull_radius` over the node (convex hull of the one-ring).
    pub hull_radius: f64,
    /// The node's one-ring, subdivided further when a point inside is evaluated.
    pub ring: LocalMesh,
}

/// A ball around an extraordinary vertex that holds the surface over a split node with
/// that vertex at one corner (the convex hull of the node's one-ring): the flatness bound
/// stops walking down the chain at a node small enough for the ball to be negligible.
#[derive(Clone, Copy, Debug)]
pub struct Ball {
    /// Limit point of the vertex: the ball's centre.
    pub limit: DVec3,
    /// Radius, model units.
    pub radius: f64,
}

/// The exact surface of one patch.
#[derive(Clone, Debug)]
pub struct PatchSurface {
    /// Node 0 covers the whole patch.
    pub nodes: Vec<Node>,
    /// Per node: for split nodes with one extraordinary corner, its ball.
    pub balls: Vec<Option<Ball>>,
    /// The rules the one-rings are subdivided with.
    pub scheme: Scheme,
    /// Whether a sharp edge or vertex shapes the patch (one at its corners).
    pub creased: bool,
}

/// A point of the limit surface with its unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The limit point, model units.
    pub position: DVec3,
    /// Unit normal (zero where it is not defined).
    pub normal: DVec3,
}

impl PatchSurface {
    /// Builds the quadtree of patch `p`, subdividing at most `depth ≥ 1` times.
    pub fn build(mesh: &PatchMesh, p: usize, depth: u32) -> Self {
        let ring = LocalMesh::gather(
            &mesh.points,
            &mesh.quads,
            &mesh.point_quads,
            &mesh.sharpness,
            p,
        );
        Self::from_ring(ring, mesh.scheme, depth, &mut |_, _| {})
    }

    /// The quadtree over the target of `ring`, subdividing at most `depth ≥ 1` times;
    /// `observe` sees each node's one-ring as the node is made (the stencil tables read
    /// the rings their balls are taken from).
    pub fn from_ring(
        ring: LocalMesh,
        scheme: Scheme,
        depth: u32,
        observe: &mut dyn FnMut(u32, &LocalMesh),
    ) -> Self {
        let creased = !ring.sharp.is_empty();
        let mut s = PatchSurface {
            nodes: Vec::new(),
            balls: Vec::new(),
            scheme,
            creased,
        };
        s.add(ring, 0, depth.max(1), None, observe);
        s
    }

    /// `chain_normal`: the vertex normal, computed where the chain below `depth` starts
    /// (deeper one-rings are too small for double precision to give it accurately).
    fn add(
        &mut self,
        ring: LocalMesh,
        level: u32,
        depth: u32,
        chain_normal: Option<DVec3>,
        observe: &mut dyn FnMut(u32, &LocalMesh),
    ) -> u32 {
        let id = self.nodes.len() as u32;
        observe(id, &ring);
        let (scheme, rule) = (self.scheme, self.scheme.boundary);
        self.balls.push(None);
        if let Some(net) = ring.regular_net(rule) {
            self.nodes
                .push(Node::Bezier(Box::new(bspline_to_bezier(&net))));
            return id;
        }
        // Below `depth`, only the chain of squares shrinking onto an extraordinary
        // vertex goes on (three Bézier pieces per level), down to `CORNER_DEPTH`: the
        // flatness bound then reads stored pieces only, on the CPU as on the GPU.
        // Semi-sharp sharpness is subdivided away first (at most 10 levels), so that
        // every piece that is not a chain is a B-spline.
        let semi_sharp = ring.has_semi_sharp(rule);
        let chain_ends = level >= super::CORNER_DEPTH || {
            level >= depth
                && !semi_sharp
                && ring
                    .children(&scheme)
                    .iter()
                    .filter(|c| c.regular_net(rule).is_none())
                    .count()
                    != 1
        };
        if chain_ends {
            // The extraordinary corner (0 if a regular-looking one-ring failed to give a
            // net, which the validated topologies do not produce: the node stays sound,
            // its bound is the convex hull around that corner's limit).
            let corner = ring.irregular_corner(rule).unwrap_or(0);
            let limit = ring.limit_point(corner, &scheme);
            self.nodes.push(Node::Corner(Box::new(CornerNode {
                corner,
                limit,
                normal: chain_normal.unwrap_or_else(|| ring.corner_normal(corner, &scheme)),
                hull_radius: ring.hull_radius(limit),
                ring,
            })));
            return id;
        }
        self.nodes.push(Node::Split([0; 4]));
        let irregular: Vec<usize> = (0..4)
            .filter(|&c| !ring.corner_is_regular(c, rule))
            .collect();
        // The ball is the one-ring's convex hull, which holds the surface only where
        // every weight is non-negative: not while Chaikin's rule may still extrapolate.
        let hull_holds = !(semi_sharp && scheme.creasing == CreaseMethod::Chaikin);
        if let ([corner], true) = (&irregular[..], hull_holds) {
            let limit = ring.limit_point(*corner, &scheme);
            self.balls[id as usize] = Some(Ball {
                limit,
                radius: ring.hull_radius(limit),
            });
        }
        // Below `depth` only the chain goes on: its normal is the one computed here.
        let normal = (level >= depth && !semi_sharp).then(|| {
            chain_normal.unwrap_or_else(|| {
                let corner = ring.irregular_corner(rule).unwrap_or(0);
                ring.corner_normal(corner, &scheme)
            })
        });
        let children = ring.children(&scheme);
        let mut ids = [0u32; 4];
        for (c, child) in children.into_iter().enumerate() {
            ids[c] = self.add(child, level + 1, depth, normal, observe);
        }
        self.nodes[id as usize] = Node::Split(ids);
        id
    }

    /// Bézier pieces plus corner nodes: what the quadtree stores.
    pub fn piece_count(&self) -> usize {
        self.nodes
            .iter()
            .filter(|n| !matches!(n, Node::Split(_)))
            .count()
    }

    /// Whether the patch is one bicubic.
    pub fn is_regular(&self) -> bool {
        matches!(self.nodes[0], Node::Bezier(_))
    }

    /// Exact position and normal at `(u, v) ∈ [0,1]²`.
    pub fn eval(&self, u: f64, v: f64) -> SurfacePoint {
        let (mut node, mut u, mut v) = (0usize, u.clamp(0.0, 1.0), v.clamp(0.0, 1.0));
        loop {
            match &self.nodes[node] {
                Node::Bezier(net) => return eval_net(net, u, v),
                Node::Split(children) => {
                    let (c, cu, cv) = quadrant(u, v);
                    node = children[c] as usize;
                    (u, v) = (cu, cv);
                }
                Node::Corner(corner) => return eval_corner(corner, &self.scheme, u, v),
            }
        }
    }
}

/// The quadrant of `(u, v)` and the coordinates inside it.
pub fn quadrant(u: f64, v: f64) -> (usize, f64, f64) {
    let (right, top) = (u >= 0.5, v >= 0.5);
    let c = match (right, top) {
        (false, false) => 0,
        (true, false) => 1,
        (true, true) => 2,
        (false, true) => 3,
    };
    let f = |t: f64, hi: bool| if hi { 2.0 * t - 1.0 } else { 2.0 * t };
    (c, f(u, right), f(v, top))
}

/// Position and unit normal of a Bézier net. Where the derivatives are parallel (a
/// collapsed edge) the normal is taken a little inside.
pub fn eval_net(net: &Net, u: f64, v: f64) -> SurfacePoint {
    let (p, pu, pv) = bicubic::eval(net, u, v);
    let mut n = pu.cross(pv);
    if n.length_squared()
        <= 1e-24 * (pu.length_squared() * pv.length_squared()).max(f64::MIN_POSITIVE)
    {
        let (_, qu, qv) = bicubic::eval(net, u + (0.5 - u) * 1e-4, v + (0.5 - v) * 1e-4);
        n = qu.cross(qv);
    }
    SurfacePoint {
        position: p,
        normal: n.normalize_or_zero(),
    }
}

/// Evaluation inside a corner node: the vertex itself, or further subdivision of its
/// one-ring until `(u, v)` falls in a regular child.
fn eval_corner(node: &CornerNode, scheme: &Scheme, u: f64, v: f64) -> SurfacePoint {
    let at_vertex = |u: f64, v: f64, c: usize| {
        let (cu, cv) = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)][c];
        u == cu && v == cv
    };
    if at_vertex(u, v, node.corner) {
        return SurfacePoint {
            position: node.limit,
            normal: node.normal,
        };
    }
    let (mut ring, mut u, mut v) = (node.ring.children(scheme), u, v);
    // Each step halves the distance to the vertex; f64 runs out after ~1000 halvings,
    // long before which the point is in a regular child.
    for _ in 0..1100 {
        let (c, cu, cv) = quadrant(u, v);
        let child = &ring[c];
        if let Some(net) = child.regular_net(scheme.boundary) {
            return eval_net(&bspline_to_bezier(&net), cu, cv);
        }
        (u, v) = (cu, cv);
        if at_vertex(u, v, node.corner) {
            break;
        }
        ring = child.children(scheme);
    }
    SurfacePoint {
        position: node.limit,
        normal: node.normal,
    }
}

/// All patches of a mesh, built once (the part a GPU stage would upload).
#[derive(Clone, Debug)]
pub struct SurfaceModel {
    /// The patches' connectivity and level-1 points.
    pub mesh: PatchMesh,
    /// One per patch; holes get an empty surface.
    pub patches: Vec<PatchSurface>,
    /// Levels each quadtree was built to (`1..=TREE_DEPTH`).
    pub depth: u32,
    /// Each patch's flatness bound over its whole square ([`root_bound`](Self::root_bound)),
    /// once asked for.
    root_bounds: Vec<OnceLock<f64>>,
    /// Each control face's bound taken whole ([`face_bound`](Self::face_bound)), once
    /// asked for.
    face_bounds: Vec<OnceLock<f64>>,
}

impl SurfaceModel {
    /// Builds every patch's quadtree to `depth` levels (`1..=TREE_DEPTH`).
    pub fn new(mesh: PatchMesh, depth: u32) -> Self {
        let depth = depth.clamp(1, super::TREE_DEPTH);
        let patches: Vec<PatchSurface> = (0..mesh.patch_count())
            .map(|p| PatchSurface::build(&mesh, p, depth))
            .collect();
        SurfaceModel {
            root_bounds: patches.iter().map(|_| OnceLock::new()).collect(),
            face_bounds: mesh.control_faces.iter().map(|_| OnceLock::new()).collect(),
            mesh,
            patches,
            depth,
        }
    }

    /// The flatness bound ([`box_bound`](super::bound::box_bound)) of patch `p`'s whole
    /// square, with its own corners. It depends on the surface alone, not on the
    /// tolerance or the view, and every adaptive run takes it for every patch (the first
    /// trial's root, and a view's culling): it is computed the first time and kept, so a
    /// run in a new view pays only for the cells below.
    pub fn root_bound(&self, p: usize) -> f64 {
        *self.root_bounds[p].get_or_init(|| {
            let surface = &self.patches[p];
            let corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
                .map(|(u, v)| surface.eval(u, v).position);
            let walk = super::bound::WALK_ONE;
            super::bound::box_bound(surface, [0, walk, 0, walk], corners)
        })
    }

    /// The flatness bound of control face `f` taken whole, as one cell through the limit
    /// points of its vertices ([`face_bound`](super::bound::face_bound)): infinite for a
    /// face that is not a quad or has a hole. Computed once, as the root bounds are.
    pub fn face_bound(&self, f: usize) -> f64 {
        *self.face_bounds[f].get_or_init(|| {
            let first = self.mesh.first_patch[f] as usize;
            if self.mesh.control_faces[f].len() != 4
                || (first..first + 4).any(|p| self.mesh.hole[p])
            {
                return f64::INFINITY;
            }
            let surfaces: [&PatchSurface; 4] = std::array::from_fn(|k| &self.patches[first + k]);
            let corners = surfaces.map(|s| s.eval(0.0, 0.0).position);
            super::bound::face_bound(surfaces, corners).unwrap_or(f64::INFINITY)
        })
    }

    /// The same surface with the control points moved to `positions` (same topology):
    /// every patch is built again, to the same depth.
    pub fn with_control_points(&self, positions: &[DVec3]) -> crate::Result<Self> {
        Ok(SurfaceModel::new(
            self.mesh.with_control_points(positions)?,
            self.depth,
        ))
    }

    /// Exact point of control face `face` at `(u, v)` in the face's own
    /// parameterisation ([`PatchMesh::face_point`], OpenSubdiv Bfr's); `None` outside
    /// its domain, or on a hole.
    pub fn eval_face(&self, face: u32, u: f64, v: f64) -> Option<SurfacePoint> {
        let (p, pu, pv) = self.mesh.patch_at(face, u, v)?;
        (!self.mesh.hole[p]).then(|| self.eval(p, pu, pv))
    }

    /// Exact point of patch `p` at `(u, v)`.
    pub fn eval(&self, p: usize, u: f64, v: f64) -> SurfacePoint {
        self.patches[p].eval(u, v)
    }
}
