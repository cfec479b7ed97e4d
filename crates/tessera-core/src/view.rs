//! A view: what a camera sees, and how many pixels a distance in model space can become.
//!
//! A [`View`] is one camera for everything: the renderer draws with it and the stages
//! tessellate for it. It holds the model, view and projection matrices apart (the
//! renderer lights in view space) and their product from model space to wgpu's clip
//! space, and the viewport in pixels. The frustum is `−w ≤ x ≤ w`, `−w ≤ y ≤ w`,
//! `0 ≤ z ≤ w` in clip coordinates `c = (x, y, z, w)`, whatever the depth convention
//! (reverse-Z and an infinite far plane included), and a point `X` projects to the pixel
//! offset `s(X) = (W/2 · x/w, H/2 · y/w)` from the viewport's centre.
//!
//! # From a distance in model space to pixels
//!
//! Let `c = M·(X, 1)`, with rows `r_x`, `r_y`, `r_w` and their linear parts `a_x`, `a_y`,
//! `a_w` (three-vectors). For a displacement `d` of `X`,
//!
//! ```text
//! ds_x = W/2 · (a_x·d / w − x · a_w·d / w²),   so   |ds_x| ≤ W/2 · (|a_x| / w + |x| |a_w| / w²) · |d|,
//! ```
//!
//! and the same for `y`. On a segment from `P` to `Q` whose points all have `w ≥ w_lo > 0`
//! and `|x| ≤ x_hi`, `|y| ≤ y_hi`, the mean value theorem in integral form gives
//! `|s(P) − s(Q)| ≤ K · |P − Q|` with
//!
//! ```text
//! K² = λ_max [[K_x², G], [G, K_y²]],   K_x = W/2 · (|a_x| / w_lo + x_hi |a_w| / w_lo²)   (K_y alike),
//! ```
//!
//! with `G` the matching bound on `|ρ_x · ρ_y|` for the rows `ρ_x`, `ρ_y` of the
//! Jacobian of `s` ([`View::gain`]): the largest eigenvalue of the rows' Gram matrix is
//! the Jacobian's squared norm, and it grows with each entry. On the axis of a usual
//! perspective, the rows are orthogonal and `K` is the exact focal length over depth. Over a box, `w` is affine
//! and `|x|` convex, so `w_lo` is the least `w` of its eight corners and `x_hi` the largest
//! `|x|`: off-axis points are covered by `x_hi`, and an orthographic projection
//! (`a_w = 0`, `w = 1`) gets its constant gain. A point `P` inside the frustum has
//! `w ≥ w_near`, the least `w` of the frustum (the near plane's, [`View::near_w`]), so every
//! point within `δ` of it has `w ≥ w_near − |a_w| δ`: a box that crosses the near plane, or
//! reaches behind the eye, is bounded by the larger of the two lower bounds, and its
//! tolerance shrinks as `δ` nears `w_near / |a_w|`.
//!
//! # A cell's tolerance in model units
//!
//! Let a cell's surface lie within `b` of the convex hull of its corners, whose box is
//! `A`, and let its output triangles lie there too. A surface point `P` of the cell then
//! lies in `A ⊕ b`, its nearest point `Q` on the mesh is within `b` of it, and the segment
//! `PQ` lies in `A ⊕ 2b`. With `g(δ) = p / K(A ⊕ 2δ, δ)`, any `δ ≤ g(δ)` guarantees
//! `p` pixels for `b ≤ δ`. `K` grows with `δ`, so `g` falls, and `δ₁ = g(g(0))` is such a
//! `δ`: `δ₀ = g(0) ≥ g(δ₀) = δ₁`, so `g(δ₁) ≥ g(δ₀) = δ₁`. As `δ − g(δ)` grows, the valid
//! `δ` are an interval from 0, below `δ₀`; a bisection from `δ₁` toward `δ₀` keeps a valid
//! end and comes within 2⁻¹⁰ of the interval's end ([`View::cell_tolerance`]). `δ₁` alone
//! can be far below it: where `δ₀` is large against the distance to the eye, the box
//! grown by `2δ₀` reaches the eye and `g(δ₀)` collapses. A cell whose box `A ⊕ b` lies wholly
//! outside one plane of the frustum has no point inside it ([`View::box_outside`]).

use glam::{DMat4, DVec2, DVec3, DVec4};

use crate::error::{Error, Result};

/// A camera and its viewport: model space to clip space, and the pixels of the viewport.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// World to view space.
    view: DMat4,
    /// View to clip space.
    projection: DMat4,
    /// Model to world space.
    model: DMat4,
    /// Up on the screen, in world space (the scene's up where the camera was made with
    /// one).
    up: DVec3,
    /// Model to clip space (projection · view · model).
    clip: DMat4,
    /// The viewport's width and height in pixels.
    viewport: DVec2,
    /// The least clip `w` of a point in the frustum.
    near_w: f64,
}

impl View {
    /// A perspective camera at `eye` looking at `target`, right-handed as glam's
    /// `look_at_rh` and `perspective_rh` (`fovy` vertical, in radians), with `viewport`
    /// in pixels and the near plane at `near`; the far plane is at infinity.
    pub fn look_at(
        eye: DVec3,
        target: DVec3,
        up: DVec3,
        fovy: f64,
        viewport: (u32, u32),
        near: f64,
    ) -> Result<View> {
        check_camera(eye, target, up, fovy, near)?;
        let aspect = viewport.0.max(1) as f64 / viewport.1.max(1) as f64;
        let view = DMat4::look_at_rh(eye, target, up);
        let projection = DMat4::perspective_infinite_rh(fovy, aspect, near);
        let mut out = View::from_matrices(view, projection, viewport)?;
        out.up = up.normalize();
        Ok(out)
    }

    /// Vertical field of view of [`framing`](Self::framing), radians: a mild telephoto,
    /// so that the model is not distorted.
    pub const FRAMING_FOVY: f64 = 30.0 * std::f64::consts::PI / 180.0;

    /// The direction [`framing`](Self::framing) looks from, from the target toward the
    /// eye: front (−Y), a little from the right (+X) and from above (+Z).
    pub const FRAMING_DIRECTION: DVec3 = DVec3::new(0.5, -1.0, 0.45);

    /// A 3/4 view of the box `min..max` for models with +Z up (the Newell teaset): from
    /// the front-right and above, looking at the box's centre, at the distance where
    /// every corner of the box is inside the view with a small margin.
    pub fn framing(min: DVec3, max: DVec3, viewport: (u32, u32)) -> View {
        Self::framing_along(min, max, viewport, Self::FRAMING_DIRECTION, DVec3::Z)
    }

    /// Frames the box `min..max` from `direction` (target toward eye) with `up` up, the
    /// near and far planes around the box's bounding sphere. A box that is empty or not
    /// finite is taken as the unit cube around the origin; a point as a unit sphere.
    pub fn framing_along(
        min: DVec3,
        max: DVec3,
        viewport: (u32, u32),
        direction: DVec3,
        up: DVec3,
    ) -> View {
        Pose::framing(min, max, viewport, direction, up)
            .view(viewport)
            .expect("a framing: the eye off the target, the near plane in front")
    }

    /// A view from a renderer's own matrices (world to view, view to wgpu's clip space:
    /// perspective or orthographic, reverse-Z and an infinite far plane included).
    pub fn from_matrices(view: DMat4, projection: DMat4, viewport: (u32, u32)) -> Result<View> {
        let clip = projection * view;
        if viewport.0 == 0 || viewport.1 == 0 {
            return Err(Error::Param("view: the viewport must have pixels".into()));
        }
        if !clip.is_finite() || clip.determinant().abs() < 1e-300 {
            return Err(Error::Param(
                "view: the view and projection matrices must be finite and invertible".into(),
            ));
        }
        let near_w = frustum_least_w(clip).ok_or_else(|| {
            Error::Param("view: the frustum must lie in front of the eye (w > 0 inside)".into())
        })?;
        // Up on the screen: the view's y axis in world space.
        let up = view
            .inverse()
            .transform_vector3(DVec3::Y)
            .normalize_or(DVec3::Z);
        Ok(View {
            view,
            projection,
            model: DMat4::IDENTITY,
            up,
            clip,
            viewport: DVec2::new(viewport.0 as f64, viewport.1 as f64),
            near_w,
        })
    }

    /// The same camera seeing a model placed by `model` (model to world space): boxes and
    /// distances are then in model space.
    pub fn with_model(&self, model: DMat4) -> View {
        View {
            model,
            clip: self.projection * self.view * model,
            ..*self
        }
    }

    /// Model to clip space.
    pub fn clip_matrix(&self) -> DMat4 {
        self.clip
    }

    /// World to view space.
    pub fn view_matrix(&self) -> DMat4 {
        self.view
    }

    /// View to clip space.
    pub fn projection_matrix(&self) -> DMat4 {
        self.projection
    }

    /// Model to world space.
    pub fn model_matrix(&self) -> DMat4 {
        self.model
    }

    /// The eye in world space (for an orthographic projection, the view's origin).
    pub fn eye(&self) -> DVec3 {
        self.view.inverse().transform_point3(DVec3::ZERO)
    }

    /// Up on the screen in world space: the `up` the camera was made with, or the view
    /// matrix's.
    pub fn up(&self) -> DVec3 {
        self.up
    }

    /// The viewport in pixels.
    pub fn viewport(&self) -> DVec2 {
        self.viewport
    }

    /// The least clip `w` of any point inside the frustum.
    pub fn near_w(&self) -> f64 {
        self.near_w
    }

    /// Clip coordinates of a point in model space.
    pub fn clip_of(&self, x: DVec3) -> DVec4 {
        self.clip * x.extend(1.0)
    }

    /// Whether a point lies inside the frustum.
    pub fn contains(&self, x: DVec3) -> bool {
        let c = self.clip_of(x);
        c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w && c.z >= 0.0 && c.z <= c.w
    }

    /// The pixel offset of a point from the viewport's centre (`x` right, `y` up), where it
    /// lies in front of the eye (`w > 0`).
    pub fn pixel(&self, x: DVec3) -> Option<DVec2> {
        let c = self.clip_of(x);
        (c.w > 0.0).then(|| DVec2::new(c.x, c.y) / c.w * self.viewport * 0.5)
    }

    /// Whether the box `[lo, hi]` lies wholly outside one plane of the frustum: no point of
    /// it can be seen.
    pub fn box_outside(&self, lo: DVec3, hi: DVec3) -> bool {
        let c = box_corners(lo, hi).map(|x| self.clip_of(x));
        let outside = |f: &dyn Fn(DVec4) -> f64| c.iter().all(|&c| f(c) < 0.0);
        outside(&|c| c.w - c.x)
            || outside(&|c| c.w + c.x)
            || outside(&|c| c.w - c.y)
            || outside(&|c| c.w + c.y)
            || outside(&|c| c.z)
            || outside(&|c| c.w - c.z)
    }

    /// The facing field `f(X)`: a small piece of surface at `X` with normal `n = a × b`
    /// (tangents `a`, `b` in the triangles' winding) turns counter-clockwise on screen,
    /// front-facing as wgpu's default `FrontFace::Ccw`, where `w · f(X)·n > 0`.
    ///
    /// With `r_x`, `r_y`, `r_w` the linear parts of the clip rows and `c = (x, y, w)` the
    /// point's clip coordinates, the screen image of the tangents has determinant
    /// `det[c, A a, A b] / w³` (expand `d(x/w)` and `d(y/w)`), and
    /// `det[c, A a, A b] = c · (A a × A b) = (adj(A) c) · (a × b)`. So
    /// `f(X) = x (r_y × r_w) + y (r_w × r_x) + w (r_x × r_y)`: affine in `X`, orthographic
    /// projections (`r_w = 0`) included. For a usual perspective it is a negative multiple
    /// of `X − eye`.
    pub fn facing(&self, x: DVec3) -> DVec3 {
        let [r_x, r_y, r_w] = [0, 1, 3].map(|r| self.clip.row(r).truncate());
        let c = self.clip_of(x);
        c.x * r_y.cross(r_w) + c.y * r_w.cross(r_x) + c.w * r_x.cross(r_y)
    }

    /// Whether every surface of the box `[lo, hi]` whose normals lie in the cone spanned
    /// by `normals` faces away from the eye: `f(X)·n < 0` for every point `X` of the box
    /// and every normal `n` of the cone ([`facing`](Self::facing)). The product is linear
    /// in `n`, so the cone's generators decide it, and affine in `X`,
    /// `f(X) = f(lo) + Σ_k t_k g_k` with `g_k = f(lo + d_k e_k) − f(lo)` and `t_k ∈ [0, 1]`
    /// over the box, so its largest value is `f(lo)·n + Σ_k max(0, g_k·n)` (the largest at
    /// the eight corners, in four products). Where `w ≤ 0` nothing is drawn, so the sign of
    /// `w` does not matter. Zero generators span nothing and are passed over.
    pub fn box_back_facing(
        &self,
        lo: DVec3,
        hi: DVec3,
        normals: impl IntoIterator<Item = DVec3>,
    ) -> bool {
        let f = self.box_facing(lo, hi);
        normals.into_iter().all(|n| f.faces_away(n))
    }

    /// The facing field over the box `[lo, hi]`, to test many generators against
    /// ([`box_back_facing`](Self::box_back_facing)).
    pub fn box_facing(&self, lo: DVec3, hi: DVec3) -> BoxFacing {
        let f0 = self.facing(lo);
        let d = hi - lo;
        BoxFacing {
            f0,
            g: [DVec3::X, DVec3::Y, DVec3::Z].map(|e| self.facing(lo + d * e) - f0),
        }
    }

    /// `K`, the pixels that a model-space distance can become on a segment inside the box
    /// `[lo, hi]` one of whose ends lies in the frustum and which is at most `reach` long
    /// (see the module docs); infinite where no positive `w` bounds it.
    pub fn gain(&self, lo: DVec3, hi: DVec3, reach: f64) -> f64 {
        let [a_x, a_y, a_w] = [0, 1, 3].map(|r| self.clip.row(r).truncate());
        let c = box_corners(lo, hi).map(|x| self.clip_of(x));
        let w_box = c.iter().map(|c| c.w).fold(f64::INFINITY, f64::min);
        let w_lo = w_box.max(self.near_w - a_w.length() * reach);
        if w_lo.is_nan() || w_lo <= 0.0 {
            return f64::INFINITY;
        }
        let x_hi = c.iter().map(|c| c.x.abs()).fold(0.0, f64::max);
        let y_hi = c.iter().map(|c| c.y.abs()).fold(0.0, f64::max);
        // ds = (ρ_x·d, ρ_y·d), ρ_x = α_x a_x − β_x a_w with |α_x| ≤ W/2 / w_lo and
        // |β_x| ≤ W/2 · x_hi / w_lo² (ρ_y alike).
        let (half_w, half_h) = (0.5 * self.viewport.x, 0.5 * self.viewport.y);
        let (alpha_x, beta_x) = (half_w / w_lo, half_w * x_hi / (w_lo * w_lo));
        let (alpha_y, beta_y) = (half_h / w_lo, half_h * y_hi / (w_lo * w_lo));
        let kx = alpha_x * a_x.length() + beta_x * a_w.length();
        let ky = alpha_y * a_y.length() + beta_y * a_w.length();
        let g12 = alpha_x * alpha_y * a_x.dot(a_y).abs()
            + alpha_x * beta_y * a_x.dot(a_w).abs()
            + beta_x * alpha_y * a_y.dot(a_w).abs()
            + beta_x * beta_y * a_w.length_squared();
        // The largest eigenvalue of the Gram matrix of (ρ_x, ρ_y), which grows with each
        // entry's bound: the squared norm of the Jacobian.
        let (mean, half_gap) = (0.5 * (kx * kx + ky * ky), 0.5 * (kx * kx - ky * ky));
        (mean + half_gap.hypot(g12)).sqrt()
    }

    /// The largest bound in model units a cell may keep for `pixels` pixels, where the
    /// box of its corners is `[lo, hi]` (see the module docs): the largest `δ ≤ g(δ)`,
    /// found by bisection between `g(g(0))` and `g(0)` (every `δ ≤ g(δ)` lies below
    /// `g(0)`, and the set of them is an interval from 0 as `δ − g(δ)` grows), always
    /// returning one that satisfies it.
    pub fn cell_tolerance(&self, lo: DVec3, hi: DVec3, pixels: f64) -> f64 {
        self.tolerance_search(lo, hi, pixels).value()
    }

    /// The bisection of [`View::cell_tolerance`], not yet run: it runs only as far as
    /// each question asked of it needs.
    pub fn tolerance_search(&self, lo: DVec3, hi: DVec3, pixels: f64) -> ToleranceSearch<'_> {
        let mut search = ToleranceSearch {
            view: self,
            lo,
            hi,
            pixels,
            valid: 0.0,
            invalid: 0.0,
            steps_left: CELL_TOLERANCE_STEPS,
        };
        let upper = search.g(0.0);
        search.valid = search.g(upper);
        search.invalid = upper;
        if search.valid >= upper {
            search.steps_left = 0;
        }
        search
    }
}

/// [`View::cell_tolerance`]'s bisection, run step by step. Its valid end only rises and
/// its invalid end only falls, so a question whose answer is the same at both ends
/// (a bound at most the valid end, or above the invalid one) is answered without the
/// steps left, and the answer is the whole search's: the steps taken never depend on the
/// questions asked.
#[derive(Clone, Copy, Debug)]
pub struct ToleranceSearch<'a> {
    view: &'a View,
    lo: DVec3,
    hi: DVec3,
    pixels: f64,
    valid: f64,
    invalid: f64,
    steps_left: usize,
}

impl ToleranceSearch<'_> {
    /// `g(δ) = p / K(A ⊕ 2δ, δ)`.
    fn g(&self, delta: f64) -> f64 {
        let grow = DVec3::splat(2.0 * delta);
        self.pixels / self.view.gain(self.lo - grow, self.hi + grow, delta)
    }

    fn step(&mut self) {
        let mid = 0.5 * (self.valid + self.invalid);
        if mid <= self.g(mid) {
            self.valid = mid;
        } else {
            self.invalid = mid;
        }
        self.steps_left -= 1;
    }

    /// Whether `bound ≤` the tolerance ([`View::cell_tolerance`]).
    pub fn admits(&mut self, bound: f64) -> bool {
        while self.steps_left > 0 && !(bound <= self.valid || bound > self.invalid) {
            self.step();
        }
        bound <= self.valid
    }

    /// The tolerance: the search run to its end.
    pub fn value(&mut self) -> f64 {
        while self.steps_left > 0 {
            self.step();
        }
        self.valid
    }
}

/// Where a perspective camera stands and what it looks at, with finite near and far
/// planes: what [`View::framing_along`] builds, and what an orbit moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Where the camera is.
    pub eye: DVec3,
    /// The point it looks at.
    pub target: DVec3,
    /// Up on the screen.
    pub up: DVec3,
    /// Vertical field of view, radians.
    pub fovy: f64,
    /// Distance of the near clipping plane.
    pub near: f64,
    /// Distance of the far clipping plane.
    pub far: f64,
}

impl Pose {
    /// See [`View::framing_along`].
    pub fn framing(
        min: DVec3,
        max: DVec3,
        viewport: (u32, u32),
        direction: DVec3,
        up: DVec3,
    ) -> Pose {
        let (min, max) = if min.is_finite() && max.is_finite() && min.cmple(max).all() {
            (min, max)
        } else {
            (DVec3::splat(-0.5), DVec3::splat(0.5))
        };
        let aspect = viewport.0.max(1) as f64 / viewport.1.max(1) as f64;
        let (center, radius) = bounding_sphere(min, max);
        let back = direction
            .try_normalize()
            .unwrap_or(View::FRAMING_DIRECTION.normalize());
        let up = if up.cross(back).length_squared() > 1e-6 {
            up.normalize()
        } else {
            back.any_orthonormal_vector()
        };
        // Camera basis: `back` toward the eye, `right`, `cam_up`.
        let right = up.cross(back).normalize();
        let cam_up = back.cross(right);
        const MARGIN: f64 = 0.95;
        let tan_y = (0.5 * View::FRAMING_FOVY).tan() * MARGIN;
        let tan_x = tan_y * aspect;
        // A corner at (x, y, z) in the camera basis relative to the centre is at depth
        // d − z from an eye at distance d; it fits when |x| ≤ (d − z)·tan_x and likewise y.
        let mut distance: f64 = 0.0;
        for corner in box_corners(min, max) {
            let c = corner - center;
            let (x, y, z) = (c.dot(right), c.dot(cam_up), c.dot(back));
            distance = distance.max(z + x.abs() / tan_x).max(z + y.abs() / tan_y);
        }
        let distance = distance.max(radius * 1.05);
        Pose {
            eye: center + back * distance,
            target: center,
            up,
            fovy: View::FRAMING_FOVY,
            near: (distance - radius * 1.05).max(radius * 0.01),
            far: distance + radius * 1.05,
        }
    }

    /// The near and far planes moved to enclose the box's bounding sphere from the eye.
    pub fn around(self, min: DVec3, max: DVec3) -> Pose {
        let (center, radius) = bounding_sphere(min, max);
        let d = (self.eye - center).length();
        Pose {
            near: (d - radius * 1.05).max(radius * 0.01),
            far: d + radius * 1.05,
            ..self
        }
    }

    /// The view of this pose with `viewport` (right-handed, depth 0 at `near` to 1 at
    /// `far`, as glam's `perspective_rh`); an error for a pose that is not a camera (the
    /// eye on the target, up along the line of sight, planes not in front).
    pub fn view(&self, viewport: (u32, u32)) -> Result<View> {
        let aspect = viewport.0.max(1) as f64 / viewport.1.max(1) as f64;
        check_camera(self.eye, self.target, self.up, self.fovy, self.near)?;
        if !(self.far > self.near && self.far.is_finite()) {
            return Err(Error::Param(
                "view: the far plane must lie beyond the near plane".into(),
            ));
        }
        let view = DMat4::look_at_rh(self.eye, self.target, self.up);
        let projection = DMat4::perspective_rh(self.fovy, aspect, self.near, self.far);
        let viewport = (viewport.0.max(1), viewport.1.max(1));
        let mut out = View::from_matrices(view, projection, viewport)?;
        out.up = self.up.normalize();
        Ok(out)
    }
}

/// Whether a perspective camera is one: one line naming what is wrong.
fn check_camera(eye: DVec3, target: DVec3, up: DVec3, fovy: f64, near: f64) -> Result<()> {
    let bad = |what: &str| Err(Error::Param(format!("view: {what}")));
    if !(eye - target).is_finite() || (eye - target).length() == 0.0 {
        return bad("the eye and the target must be distinct points");
    }
    if (target - eye).cross(up).length() <= 1e-12 * (target - eye).length() * up.length() {
        return bad("the up direction must not be parallel to the line of sight");
    }
    if !(fovy > 0.0 && fovy < std::f64::consts::PI) {
        return bad("the vertical field of view must be between 0 and 180 degrees");
    }
    if !(near.is_finite() && near > 0.0) {
        return bad("the near plane must be a positive distance");
    }
    Ok(())
}

/// The centre and radius of the box's bounding sphere (a unit sphere for a point or a
/// box that is not one).
fn bounding_sphere(min: DVec3, max: DVec3) -> (DVec3, f64) {
    if !(min.is_finite() && max.is_finite() && min.cmple(max).all()) {
        return (DVec3::ZERO, 1.0);
    }
    let r = 0.5 * (max - min).length();
    (0.5 * (min + max), if r > 0.0 { r } else { 1.0 })
}

/// Bisection steps of [`View::cell_tolerance`]: within 2⁻¹⁰ of the largest tolerance.
const CELL_TOLERANCE_STEPS: usize = 10;

/// [`View::facing`] over a box: at its lowest corner, and its steps along the sides.
#[derive(Clone, Copy, Debug)]
pub struct BoxFacing {
    f0: DVec3,
    g: [DVec3; 3],
}

impl BoxFacing {
    /// Whether the generator `n` faces away over the whole box (a zero one spans
    /// nothing): `f(lo)·n + Σ_k max(0, g_k·n) < 0`.
    pub fn faces_away(&self, n: DVec3) -> bool {
        let g = self.g;
        n == DVec3::ZERO
            || self.f0.dot(n) + g[0].dot(n).max(0.0) + g[1].dot(n).max(0.0) + g[2].dot(n).max(0.0)
                < 0.0
    }
}

/// The eight corners of a box.
pub fn box_corners(lo: DVec3, hi: DVec3) -> [DVec3; 8] {
    std::array::from_fn(|k| {
        DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// The least clip `w` over the frustum, `None` unless positive. `w` is affine, so its
/// least value is at a corner; a corner at infinity (an infinite far plane) has `w`
/// growing without end and is passed over.
fn frustum_least_w(clip: DMat4) -> Option<f64> {
    let inverse = clip.inverse();
    let mut least = f64::INFINITY;
    for k in 0..8 {
        let ndc = DVec4::new(
            if k & 1 == 0 { -1.0 } else { 1.0 },
            if k & 2 == 0 { -1.0 } else { 1.0 },
            if k & 4 == 0 { 0.0 } else { 1.0 },
            1.0,
        );
        // The homogeneous point h with clip * h = ndc; the world point h / h.w has
        // clip w = 1 / h.w.
        let h = inverse * ndc;
        if h.w.abs() > 1e-12 * h.truncate().length().max(1.0) {
            least = least.min(1.0 / h.w);
        }
    }
    (least.is_finite() && least > 0.0).then_some(least)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn car_view() -> View {
        View::look_at(
            DVec3::new(3.0, -4.0, 1.5),
            DVec3::ZERO,
            DVec3::Z,
            40f64.to_radians(),
            (800, 600),
            0.1,
        )
        .expect("a view")
    }

    /// A tiny deterministic generator, so that failures reproduce.
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn vec(&mut self, lo: f64, hi: f64) -> DVec3 {
            DVec3::new(self.next(), self.next(), self.next()) * (hi - lo) + DVec3::splat(lo)
        }
    }

    /// The direction in which a small step from `x` moves its projection the most, and
    /// how many pixels per unit (power iteration on the Jacobian, by central differences).
    fn stretch(view: &View, x: DVec3) -> (DVec3, f64) {
        let h = 1e-6 * (1.0 + x.length());
        let column = |e: DVec3| {
            (view.pixel(x + e * h).unwrap() - view.pixel(x - e * h).unwrap()) / (2.0 * h)
        };
        let j = [DVec3::X, DVec3::Y, DVec3::Z].map(column);
        let apply = |d: DVec3| j[0] * d.x + j[1] * d.y + j[2] * d.z;
        let mut d = DVec3::ONE.normalize();
        for _ in 0..50 {
            let s = apply(d);
            d = DVec3::new(j[0].dot(s), j[1].dot(s), j[2].dot(s)).normalize();
        }
        (d, apply(d).length())
    }

    /// Over random boxes, some crossing the near plane or off screen, and pairs of points
    /// in them, half of them a point and a short step in its most stretched direction: the
    /// largest pixel distance over model distance seen, as a fraction of the gain.
    fn worst_ratio(view: &View, gain: impl Fn(DVec3, DVec3, f64) -> f64) -> f64 {
        let mut rng = Lcg(7);
        let mut worst: f64 = 0.0;
        for k in 0..8000 {
            let centre = rng.vec(-3.0, 3.0);
            let half = if k % 2 == 0 {
                rng.vec(0.0, 0.5)
            } else {
                DVec3::splat(1e-4)
            };
            let (lo, hi) = (centre - half, centre + half);
            let p = lo + (hi - lo) * DVec3::new(rng.next(), rng.next(), rng.next());
            if !view.contains(p) {
                continue;
            }
            let q = if k % 2 == 0 {
                lo + (hi - lo) * DVec3::new(rng.next(), rng.next(), rng.next())
            } else {
                p + stretch(view, p).0 * 1e-5
            };
            let (lo, hi) = (lo.min(q), hi.max(q));
            let reach = (p - q).length();
            let (Some(sp), Some(sq)) = (view.pixel(p), view.pixel(q)) else {
                continue;
            };
            let k = gain(lo, hi, reach);
            if k.is_finite() && reach > 0.0 {
                worst = worst.max((sp - sq).length() / reach / k);
            }
        }
        worst
    }

    #[test]
    fn no_pair_of_points_in_a_box_moves_more_pixels_than_the_gain_allows() {
        let view = car_view();
        let worst = worst_ratio(&view, |lo, hi, reach| view.gain(lo, hi, reach));
        assert!(worst <= 1.0, "a pair moved {worst}× the gain");
        // Not vacuous: some pairs come close to it.
        assert!(worst > 0.95, "the gain is far from tight: {worst}");
        // A gain that forgets how off-axis points stretch is caught.
        let on_axis_only = |lo: DVec3, hi: DVec3, _reach: f64| {
            let w = box_corners(lo, hi)
                .map(|x| view.clip_of(x).w)
                .into_iter()
                .fold(f64::INFINITY, f64::min);
            let [a_x, a_y] = [0, 1].map(|r| view.clip.row(r).truncate().length());
            (0.5 * view.viewport.x * a_x).max(0.5 * view.viewport.y * a_y) / w
        };
        assert!(
            worst_ratio(&view, on_axis_only) > 1.0,
            "the planted gain went unnoticed"
        );
    }

    #[test]
    fn a_cell_within_its_tolerance_stays_within_the_pixels() {
        // Surface points P in the frustum, with a mesh point Q within the tolerance of the
        // corners' box grown by it: P and Q never project farther apart than p.
        let view = car_view();
        let mut rng = Lcg(11);
        let mut seen = 0;
        for _ in 0..4000 {
            let centre = rng.vec(-2.0, 2.0);
            let half = rng.vec(0.0, 0.3);
            let (lo, hi) = (centre - half, centre + half);
            let pixels = 0.5 + 2.0 * rng.next();
            let eps = view.cell_tolerance(lo, hi, pixels);
            if eps.is_nan() || eps <= 0.0 {
                continue;
            }
            let p = lo - DVec3::splat(eps)
                + (hi - lo + DVec3::splat(2.0 * eps))
                    * DVec3::new(rng.next(), rng.next(), rng.next());
            if !view.contains(p) {
                continue;
            }
            let dir = (rng.vec(-1.0, 1.0)).normalize_or_zero();
            let q = p + dir * eps;
            let (sp, sq) = (view.pixel(p).unwrap(), view.pixel(q));
            let Some(sq) = sq else {
                panic!("a point within the tolerance went behind the eye")
            };
            assert!((sp - sq).length() <= pixels * (1.0 + 1e-9));
            seen += 1;
        }
        assert!(seen > 500, "too few cases: {seen}");
    }

    #[test]
    fn the_early_answer_is_the_full_searchs() {
        // Bounds on both sides of each box's tolerance, and on it exactly: the search
        // stopped early answers as the whole one, and both answers occur.
        let view = car_view();
        let mut rng = Lcg(5);
        let (mut within, mut beyond) = (0, 0);
        for _ in 0..3000 {
            let centre = rng.vec(-3.0, 3.0);
            let half = rng.vec(0.0, 0.5);
            let (lo, hi) = (centre - half, centre + half);
            let pixels = 0.25 + 4.0 * rng.next();
            let t = view.cell_tolerance(lo, hi, pixels);
            // One search asked every question in turn, as a cell's decision asks it.
            let mut search = view.tolerance_search(lo, hi, pixels);
            for bound in [
                t,
                2.0 * t * rng.next(),
                t * (1.0 + 1e-12),
                t * 0.999,
                t * 1.001,
            ] {
                let early = view.tolerance_search(lo, hi, pixels).admits(bound);
                assert_eq!(early, bound <= t, "bound {bound} against {t}");
                assert_eq!(search.admits(bound), early, "bound {bound}, asked in turn");
                if early {
                    within += 1;
                } else {
                    beyond += 1;
                }
            }
            assert_eq!(search.value(), t);
        }
        assert!(
            within > 1000 && beyond > 1000,
            "{within} within, {beyond} beyond"
        );
    }

    #[test]
    fn the_cell_tolerance_falls_toward_the_near_plane_and_grows_far_away() {
        let view = car_view();
        let at = |d: f64| {
            let eye = DVec3::new(3.0, -4.0, 1.5);
            let c = eye + (DVec3::ZERO - eye).normalize() * d;
            view.cell_tolerance(c - DVec3::splat(1e-3), c + DVec3::splat(1e-3), 1.0)
        };
        let (near, mid, far) = (at(0.2), at(5.0), at(50.0));
        assert!(near < mid && mid < far, "{near} {mid} {far}");
        // More pixels never give a smaller tolerance, even where the first guess, grown
        // by twice itself, would reach the eye.
        let eye = DVec3::new(3.0, -4.0, 1.5);
        let c = eye + (DVec3::ZERO - eye).normalize() * 0.5;
        let mut last = 0.0;
        for px in [1.0, 10.0, 100.0, 200.0, 1000.0] {
            let t = view.cell_tolerance(c - DVec3::splat(1e-3), c + DVec3::splat(1e-3), px);
            assert!(t >= last, "{px} px: {t} < {last}");
            last = t;
        }
        // At the axis, far from the near plane, one pixel is about depth / focal length.
        let focal = 300.0 / (20f64.to_radians()).tan();
        let ratio = mid / (5.0 / focal);
        assert!(
            ratio <= 1.0 && ratio > 0.99,
            "{mid} against {}",
            5.0 / focal
        );
    }

    #[test]
    fn boxes_behind_the_eye_or_beside_the_frustum_are_outside_and_visible_ones_are_not() {
        let view = car_view();
        let s = DVec3::splat(0.1);
        assert!(!view.box_outside(-s, s));
        let behind = DVec3::new(6.0, -8.0, 3.0);
        assert!(view.box_outside(behind - s, behind + s));
        let beside = DVec3::new(40.0, 20.0, 0.0);
        assert!(view.box_outside(beside - s, beside + s));
        // A box around the eye crosses the near plane: partly visible.
        let eye = DVec3::new(3.0, -4.0, 1.5);
        assert!(!view.box_outside(eye - s, eye + s));
        // Every point of a box called outside is outside.
        let mut rng = Lcg(3);
        for _ in 0..2000 {
            let c = rng.vec(-10.0, 10.0);
            let h = rng.vec(0.0, 1.0);
            if view.box_outside(c - h, c + h) {
                for _ in 0..8 {
                    let x = c - h + 2.0 * h * DVec3::new(rng.next(), rng.next(), rng.next());
                    assert!(!view.contains(x));
                }
            }
        }
    }

    #[test]
    fn a_renderers_own_matrices_give_the_same_view() {
        let (eye, target) = (DVec3::new(3.0, -4.0, 1.5), DVec3::ZERO);
        let view = DMat4::look_at_rh(eye, target, DVec3::Z);
        let fovy = 40f64.to_radians();
        let ours = car_view();
        let finite = View::from_matrices(
            view,
            DMat4::perspective_rh(fovy, 800.0 / 600.0, 0.1, 100.0),
            (800, 600),
        )
        .unwrap();
        // Reverse-Z with an infinite far plane: near at z = w.
        let reverse = View::from_matrices(
            view,
            DMat4::perspective_infinite_reverse_rh(fovy, 800.0 / 600.0, 0.1),
            (800, 600),
        )
        .unwrap();
        for v in [finite, reverse] {
            assert!((v.near_w() - 0.1).abs() < 1e-9, "{}", v.near_w());
            let (lo, hi) = (DVec3::splat(-0.2), DVec3::splat(0.3));
            let (a, b) = (
                ours.cell_tolerance(lo, hi, 1.0),
                v.cell_tolerance(lo, hi, 1.0),
            );
            assert!((a / b - 1.0).abs() < 1e-9, "{a} against {b}");
        }
        // Orthographic: the same tolerance everywhere, one pixel of the view's height.
        let ortho = View::from_matrices(
            view,
            DMat4::orthographic_rh(-4.0, 4.0, -3.0, 3.0, 0.1, 100.0),
            (800, 600),
        )
        .unwrap();
        let t = |c: DVec3| ortho.cell_tolerance(c, c + DVec3::splat(0.01), 1.0);
        let (a, b) = (t(DVec3::ZERO), t(DVec3::new(1.0, 2.0, -1.0)));
        assert!((a / b - 1.0).abs() < 1e-12);
        assert!(a <= 6.0 / 600.0 && a > 0.5 * 6.0 / 600.0, "{a}");
        // A bad camera is an error, not a panic.
        assert!(View::look_at(eye, eye, DVec3::Z, fovy, (800, 600), 0.1).is_err());
        assert!(View::look_at(eye, target, eye - target, fovy, (800, 600), 0.1).is_err());
        assert!(View::look_at(eye, target, DVec3::Z, fovy, (800, 600), 0.0).is_err());
    }

    #[test]
    fn framing_keeps_every_corner_in_view_and_depth_range() {
        let boxes = [
            (DVec3::new(-3.0, -2.0, 0.0), DVec3::new(3.4, 2.0, 3.15)), // teapot-like
            (DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, 10.0, 0.1)),
            (DVec3::splat(2.0), DVec3::splat(2.0)),
        ];
        for (min, max) in boxes {
            for viewport in [(50, 100), (100, 100), (400, 300), (200, 100)] {
                let v = View::framing(min, max, viewport);
                let mut widest: f64 = 0.0;
                for c in box_corners(min, max) {
                    let p = v.clip_matrix().project_point3(c);
                    assert!(
                        p.x.abs() <= 1.0 && p.y.abs() <= 1.0,
                        "{min} {max} {viewport:?}: {p}"
                    );
                    assert!((0.0..=1.0).contains(&p.z), "{min} {max} {viewport:?}: {p}");
                    widest = widest.max(p.x.abs()).max(p.y.abs());
                }
                if min != max {
                    // Framed, not lost in the middle of the image.
                    assert!(widest > 0.8, "{min} {max} {viewport:?}: {widest}");
                }
            }
        }
    }

    #[test]
    fn framing_looks_from_front_right_above_with_z_up() {
        let v = View::framing(DVec3::splat(-1.0), DVec3::splat(1.0), (100, 100));
        let d = v.eye();
        assert!(d.x > 0.0 && d.y < 0.0 && d.z > 0.0, "{d}");
        assert_eq!(v.up(), DVec3::Z);
        // +Z projects upward on screen.
        let m = v.clip_matrix();
        assert!(m.project_point3(DVec3::Z).y > m.project_point3(DVec3::ZERO).y);
    }

    #[test]
    fn framing_survives_degenerate_input() {
        for (min, max) in [
            (DVec3::splat(f64::NAN), DVec3::ONE),
            (DVec3::ONE, DVec3::ZERO),
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::INFINITY)),
        ] {
            let pose = Pose::framing(min, max, (0, 0), DVec3::ZERO, DVec3::ZERO);
            assert!(pose.near > 0.0 && pose.far > pose.near);
            let v = View::framing_along(min, max, (0, 0), DVec3::ZERO, DVec3::ZERO);
            assert!(v.clip_matrix().is_finite(), "{min} {max}");
        }
    }

    #[test]
    fn a_view_keeps_its_matrices_apart() {
        let v = car_view();
        let model = DMat4::from_translation(DVec3::new(1.0, 2.0, 3.0));
        let placed = v.with_model(model);
        assert_eq!(placed.model_matrix(), model);
        assert_eq!(placed.view_matrix(), v.view_matrix());
        let x = DVec3::new(0.3, -0.2, 0.1);
        let a = placed.clip_of(x);
        let b = v.clip_of(x + DVec3::new(1.0, 2.0, 3.0));
        assert!((a - b).length() < 1e-12, "{a} {b}");
        assert!((v.eye() - DVec3::new(3.0, -4.0, 1.5)).length() < 1e-12);
        assert_eq!(v.up(), DVec3::Z);
        // From matrices alone, up is the view's y axis.
        let m = View::from_matrices(v.view_matrix(), v.projection_matrix(), (800, 600)).unwrap();
        assert!(m.up().dot(DVec3::Z) > 0.9, "{}", m.up());
        assert!(m.up().dot(v.eye().normalize()).abs() < 1e-9, "{}", m.up());
        assert_eq!(m.clip_matrix(), v.clip_matrix());
    }

    #[test]
    fn facing_gives_the_winding_on_screen_and_back_facing_boxes_face_away_everywhere() {
        let ortho = View::from_matrices(
            DMat4::look_at_rh(DVec3::new(3.0, -4.0, 1.5), DVec3::ZERO, DVec3::Z),
            DMat4::orthographic_rh(-4.0, 4.0, -3.0, 3.0, 0.1, 100.0),
            (800, 600),
        )
        .unwrap();
        let mut rng = Lcg(7);
        for view in [car_view(), ortho] {
            // A triangle winds counter-clockwise on screen exactly where f·n > 0.
            let (mut front, mut back) = (0, 0);
            for _ in 0..2000 {
                let a = rng.vec(-2.0, 2.0);
                let (b, c) = (a + rng.vec(-0.3, 0.3), a + rng.vec(-0.3, 0.3));
                let (Some(pa), Some(pb), Some(pc)) = (view.pixel(a), view.pixel(b), view.pixel(c))
                else {
                    continue;
                };
                let area = (pb - pa).perp_dot(pc - pa);
                let f = view.facing((a + b + c) / 3.0).dot((b - a).cross(c - a));
                if area.abs() < 1e-6 {
                    continue;
                }
                assert_eq!(area > 0.0, f > 0.0, "{a} {b} {c}: area {area}, f·n {f}");
                if area > 0.0 {
                    front += 1;
                } else {
                    back += 1;
                }
            }
            assert!(front > 500 && back > 500, "{front} {back}");
            // A box called back-facing faces away at every point, for every normal of its
            // cone.
            let mut called = 0;
            for _ in 0..500 {
                let c = rng.vec(-3.0, 3.0);
                let h = rng.vec(0.0, 0.3);
                let axis = rng.vec(-1.0, 1.0);
                let normals = [axis, axis + rng.vec(-0.2, 0.2), axis + rng.vec(-0.2, 0.2)];
                if !view.box_back_facing(c - h, c + h, normals) {
                    continue;
                }
                called += 1;
                for _ in 0..8 {
                    let x = c - h + 2.0 * h * DVec3::new(rng.next(), rng.next(), rng.next());
                    let n =
                        normals[0] * rng.next() + normals[1] * rng.next() + normals[2] * rng.next();
                    assert!(view.facing(x).dot(n) < 0.0, "{x} {n}");
                }
            }
            assert!(called > 50, "{called} boxes back-facing");
            // A plane's facing flips with its normal.
            let n = view.eye() - DVec3::ZERO;
            let s = DVec3::splat(0.1);
            assert!(view.box_back_facing(-s, s, [-n]));
            assert!(!view.box_back_facing(-s, s, [n]));
            assert!(!view.box_back_facing(-s, s, [-n, n]));
        }
    }
}
