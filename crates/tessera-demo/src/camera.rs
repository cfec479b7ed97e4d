//! The orbit camera: `tessera render`'s framing of the model's box as the home view, and
//! orbit, pan and zoom relative to it.

use tessera_wgpu::glam::{DQuat, DVec3, Vec3};
use tessera_wgpu::{Pose, View};

/// The model's up axis (the Newell teapot is z-up; the teacup and teaspoon y-up).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Axis {
    X,
    Y,
    #[default]
    Z,
}

impl Axis {
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    pub fn parse(s: &str) -> Option<Axis> {
        match s {
            "x" => Some(Axis::X),
            "y" => Some(Axis::Y),
            "z" => Some(Axis::Z),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
        }
    }

    pub fn vector(self) -> DVec3 {
        match self {
            Axis::X => DVec3::X,
            Axis::Y => DVec3::Y,
            Axis::Z => DVec3::Z,
        }
    }

    /// `tessera render`'s view direction (front-right, above) for this up axis.
    pub fn framing_direction(self) -> DVec3 {
        let d = View::FRAMING_DIRECTION;
        match self {
            Axis::Z => d,
            Axis::Y => DVec3::new(d.x, d.z, -d.y),
            Axis::X => DVec3::new(d.z, d.x, d.y),
        }
    }
}

/// Elevation limit of the orbit, so that the view never looks straight along the up axis.
const MAX_ELEVATION: f64 = 89.0 * std::f64::consts::PI / 180.0;

/// The user's view relative to the home view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub up: Axis,
    /// Radians about the up axis.
    yaw: f64,
    /// Radians of elevation added to the home view's.
    pitch: f64,
    /// The home distance is divided by this.
    zoom: f64,
    /// Where the target moved from the box's centre, model units.
    pan: DVec3,
}

impl Orbit {
    pub fn new(up: Axis) -> Orbit {
        Orbit {
            up,
            yaw: 0.0,
            pitch: 0.0,
            zoom: 1.0,
            pan: DVec3::ZERO,
        }
    }

    /// Back to the home view (`F`).
    pub fn home(&mut self) {
        *self = Orbit::new(self.up);
    }

    pub fn set_up(&mut self, up: Axis) {
        *self = Orbit::new(up);
    }

    pub fn is_home(&self) -> bool {
        *self == Orbit::new(self.up)
    }

    pub fn orbit(&mut self, yaw: f32, pitch: f32) {
        let (yaw, pitch) = (yaw as f64, pitch as f64);
        self.yaw = (self.yaw + yaw) % std::f64::consts::TAU;
        self.pitch = (self.pitch + pitch).clamp(-2.0 * MAX_ELEVATION, 2.0 * MAX_ELEVATION);
    }

    /// Moves closer by `factor` (below 1: farther).
    pub fn zoom(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            self.zoom = (self.zoom * factor as f64).clamp(0.05, 50.0);
        }
    }

    /// Moves the target by `right` and `up` view heights, as seen from `pose`.
    pub fn pan(&mut self, pose: &Pose, right: f32, up: f32) {
        let (right, up) = (right as f64, up as f64);
        let back = (pose.eye - pose.target).normalize_or(DVec3::Z);
        let screen_right = pose.up.cross(back).normalize_or(DVec3::X);
        let screen_up = back.cross(screen_right);
        let height = 2.0 * (pose.eye - pose.target).length() * (0.5 * pose.fovy).tan();
        self.pan += (screen_right * right + screen_up * up) * height;
    }

    /// Where the camera stands for the box `bounds` seen in `viewport` pixels: at home
    /// exactly [`Pose::framing`] (what `tessera render` draws), else that pose turned,
    /// moved and zoomed, with near and far planes around the box.
    pub fn pose(&self, bounds: (Vec3, Vec3), viewport: (u32, u32)) -> Pose {
        let (lo, hi) = (bounds.0.as_dvec3(), bounds.1.as_dvec3());
        let up = self.up.vector();
        let home = Pose::framing(lo, hi, viewport, self.up.framing_direction(), up);
        if self.is_home() {
            return home;
        }
        let offset = home.eye - home.target;
        let distance = offset.length() / self.zoom;
        let dir = offset.normalize_or(DVec3::Z);
        let elevation =
            (dir.dot(up).clamp(-1.0, 1.0).asin() + self.pitch).clamp(-MAX_ELEVATION, MAX_ELEVATION);
        let level = (dir - up * dir.dot(up)).normalize_or(up.any_orthonormal_vector());
        let level = DQuat::from_axis_angle(up, self.yaw) * level;
        let dir = level * elevation.cos() + up * elevation.sin();
        let target = home.target + self.pan;
        Pose {
            eye: target + dir * distance,
            target,
            up,
            ..home
        }
        .around(lo, hi)
    }

    /// The view of [`pose`](Self::pose) in `viewport` pixels: what the demo draws and
    /// tessellates for.
    pub fn view(&self, bounds: (Vec3, Vec3), viewport: (u32, u32)) -> View {
        let pose = self.pose(bounds, viewport);
        // The pitch stops short of the pole and the zoom is clamped, so the pose is a
        // camera; the home framing is the fallback all the same.
        pose.view(viewport)
            .unwrap_or_else(|_| View::framing(bounds.0.as_dvec3(), bounds.1.as_dvec3(), viewport))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEAPOT: (Vec3, Vec3) = (Vec3::new(-3.0, -2.0, 0.0), Vec3::new(3.4, 2.0, 3.15));
    const VIEWPORT: (u32, u32) = (300, 200);
    const SQUARE: (u32, u32) = (200, 200);

    fn teapot() -> (DVec3, DVec3) {
        (TEAPOT.0.as_dvec3(), TEAPOT.1.as_dvec3())
    }

    #[test]
    fn home_is_the_clis_framing() {
        let (lo, hi) = teapot();
        for up in Axis::ALL {
            let o = Orbit::new(up);
            let d = View::FRAMING_DIRECTION;
            let want = match up {
                Axis::Z => View::framing(lo, hi, VIEWPORT),
                Axis::Y => {
                    View::framing_along(lo, hi, VIEWPORT, DVec3::new(d.x, d.z, -d.y), DVec3::Y)
                }
                Axis::X => {
                    View::framing_along(lo, hi, VIEWPORT, DVec3::new(d.z, d.x, d.y), DVec3::X)
                }
            };
            assert_eq!(o.view(TEAPOT, VIEWPORT), want, "{up:?}");
        }
    }

    #[test]
    fn orbit_turns_about_the_up_axis_and_home_comes_back() {
        let mut o = Orbit::new(Axis::Z);
        let home = o.pose(TEAPOT, SQUARE);
        o.orbit(std::f32::consts::FRAC_PI_2, 0.0);
        let turned = o.pose(TEAPOT, SQUARE);
        let (a, b) = (home.eye - home.target, turned.eye - turned.target);
        // Same height and distance, a quarter turn round Z.
        assert!((a.z - b.z).abs() < 1e-4 && (a.length() - b.length()).abs() < 1e-3);
        assert!(a.truncate().dot(b.truncate()).abs() < 1e-3);
        assert!(o.view(TEAPOT, SQUARE).clip_matrix().is_finite());
        o.home();
        assert_eq!(o.pose(TEAPOT, SQUARE), home);
    }

    #[test]
    fn pitch_stops_short_of_the_pole_and_zoom_moves_closer() {
        let mut o = Orbit::new(Axis::Y);
        o.orbit(0.0, 10.0);
        let c = o.pose(TEAPOT, SQUARE);
        let dir = (c.eye - c.target).normalize();
        assert!(dir.dot(DVec3::Y) < 1.0 && dir.dot(DVec3::Y) > 0.99);
        assert!(c.view(SQUARE).is_ok());
        let mut z = Orbit::new(Axis::Z);
        let far = z.pose(TEAPOT, SQUARE);
        z.zoom(2.0);
        let near = z.pose(TEAPOT, SQUARE);
        let (d0, d1) = (
            (far.eye - far.target).length(),
            (near.eye - near.target).length(),
        );
        assert!((d0 / d1 - 2.0).abs() < 1e-3);
        assert!(near.near > 0.0 && near.far > near.near);
    }

    #[test]
    fn pan_moves_the_target_across_the_view() {
        let mut o = Orbit::new(Axis::Z);
        let home = o.pose(TEAPOT, SQUARE);
        o.pan(&home, 0.5, 0.0);
        let c = o.pose(TEAPOT, SQUARE);
        let moved = c.target - home.target;
        let back = (home.eye - home.target).normalize();
        assert!(moved.dot(back).abs() < 1e-4, "in the view plane");
        // Half a view height to the right projects half a view height to the right.
        let p = home
            .view(SQUARE)
            .unwrap()
            .clip_matrix()
            .project_point3(c.target);
        assert!((p.x - 1.0).abs() < 1e-3 && p.y.abs() < 1e-3, "{p}");
    }
}
