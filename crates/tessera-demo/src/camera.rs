//! The orbit camera: `tessera render`'s framing of the model's box as the home view, and
//! orbit, pan and zoom relative to it.

use tessera_wgpu::glam::{Quat, Vec3};
use tessera_wgpu::Camera;

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

    pub fn vector(self) -> Vec3 {
        match self {
            Axis::X => Vec3::X,
            Axis::Y => Vec3::Y,
            Axis::Z => Vec3::Z,
        }
    }

    /// `tessera render`'s view direction (front-right, above) for this up axis.
    pub fn framing_direction(self) -> Vec3 {
        let d = Camera::FRAMING_DIRECTION;
        match self {
            Axis::Z => d,
            Axis::Y => Vec3::new(d.x, d.z, -d.y),
            Axis::X => Vec3::new(d.z, d.x, d.y),
        }
    }
}

/// Elevation limit of the orbit, so that the view never looks straight along the up axis.
const MAX_ELEVATION: f32 = 89.0 * std::f32::consts::PI / 180.0;

/// The user's view relative to the home view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub up: Axis,
    /// Radians about the up axis.
    yaw: f32,
    /// Radians of elevation added to the home view's.
    pitch: f32,
    /// The home distance is divided by this.
    zoom: f32,
    /// Where the target moved from the box's centre, model units.
    pan: Vec3,
}

impl Orbit {
    pub fn new(up: Axis) -> Orbit {
        Orbit {
            up,
            yaw: 0.0,
            pitch: 0.0,
            zoom: 1.0,
            pan: Vec3::ZERO,
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
        self.yaw = (self.yaw + yaw) % std::f32::consts::TAU;
        self.pitch = (self.pitch + pitch).clamp(-2.0 * MAX_ELEVATION, 2.0 * MAX_ELEVATION);
    }

    /// Moves closer by `factor` (below 1: farther).
    pub fn zoom(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            self.zoom = (self.zoom * factor).clamp(0.05, 50.0);
        }
    }

    /// Moves the target by `right` and `up` view heights, as seen by `camera`.
    pub fn pan(&mut self, camera: &Camera, right: f32, up: f32) {
        let back = (camera.eye - camera.target).normalize_or(Vec3::Z);
        let screen_right = camera.up.cross(back).normalize_or(Vec3::X);
        let screen_up = back.cross(screen_right);
        let height = 2.0 * (camera.eye - camera.target).length() * (0.5 * camera.fovy).tan();
        self.pan += (screen_right * right + screen_up * up) * height;
    }

    /// The camera for the box `bounds` seen with `aspect`: at home exactly
    /// [`Camera::framing_along`] (what `tessera render` draws), else that view turned,
    /// moved and zoomed, with near and far planes around the box.
    pub fn camera(&self, bounds: (Vec3, Vec3), aspect: f32) -> Camera {
        let up = self.up.vector();
        let home =
            Camera::framing_along(bounds.0, bounds.1, aspect, self.up.framing_direction(), up);
        if self.is_home() {
            return home;
        }
        let offset = home.eye - home.target;
        let distance = offset.length() / self.zoom;
        let dir = offset.normalize_or(Vec3::Z);
        let elevation =
            (dir.dot(up).clamp(-1.0, 1.0).asin() + self.pitch).clamp(-MAX_ELEVATION, MAX_ELEVATION);
        let level = (dir - up * dir.dot(up)).normalize_or(up.any_orthonormal_vector());
        let level = Quat::from_axis_angle(up, self.yaw) * level;
        let dir = level * elevation.cos() + up * elevation.sin();
        let target = home.target + self.pan;
        let eye = target + dir * distance;
        // The box's bounding sphere, as `framing_along` encloses it.
        let (center, radius) = sphere(bounds);
        let d = (eye - center).length();
        Camera {
            eye,
            target,
            up,
            near: (d - radius * 1.05).max(radius * 0.01),
            far: d + radius * 1.05,
            ..home
        }
    }
}

fn sphere((lo, hi): (Vec3, Vec3)) -> (Vec3, f32) {
    if !(lo.is_finite() && hi.is_finite() && lo.cmple(hi).all()) {
        return (Vec3::ZERO, 1.0);
    }
    let r = 0.5 * (hi - lo).length();
    (0.5 * (lo + hi), if r > 0.0 { r } else { 1.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEAPOT: (Vec3, Vec3) = (Vec3::new(-3.0, -2.0, 0.0), Vec3::new(3.4, 2.0, 3.15));

    #[test]
    fn home_is_the_clis_framing() {
        for up in Axis::ALL {
            let o = Orbit::new(up);
            let d = Camera::FRAMING_DIRECTION;
            let want = match up {
                Axis::Z => Camera::framing(TEAPOT.0, TEAPOT.1, 1.5),
                Axis::Y => Camera::framing_along(
                    TEAPOT.0,
                    TEAPOT.1,
                    1.5,
                    Vec3::new(d.x, d.z, -d.y),
                    Vec3::Y,
                ),
                Axis::X => Camera::framing_along(
                    TEAPOT.0,
                    TEAPOT.1,
                    1.5,
                    Vec3::new(d.z, d.x, d.y),
                    Vec3::X,
                ),
            };
            assert_eq!(o.camera(TEAPOT, 1.5), want, "{up:?}");
        }
    }

    #[test]
    fn orbit_turns_about_the_up_axis_and_home_comes_back() {
        let mut o = Orbit::new(Axis::Z);
        let home = o.camera(TEAPOT, 1.0);
        o.orbit(std::f32::consts::FRAC_PI_2, 0.0);
        let turned = o.camera(TEAPOT, 1.0);
        let (a, b) = (home.eye - home.target, turned.eye - turned.target);
        // Same height and distance, a quarter turn round Z.
        assert!((a.z - b.z).abs() < 1e-4 && (a.length() - b.length()).abs() < 1e-3);
        assert!(a.truncate().dot(b.truncate()).abs() < 1e-3);
        assert!(turned.view_proj().is_finite());
        o.home();
        assert_eq!(o.camera(TEAPOT, 1.0), home);
    }

    #[test]
    fn pitch_stops_short_of_the_pole_and_zoom_moves_closer() {
        let mut o = Orbit::new(Axis::Y);
        o.orbit(0.0, 10.0);
        let c = o.camera(TEAPOT, 1.0);
        let dir = (c.eye - c.target).normalize();
        assert!(dir.dot(Vec3::Y) < 1.0 && dir.dot(Vec3::Y) > 0.99);
        assert!(c.view_proj().is_finite());
        let mut z = Orbit::new(Axis::Z);
        let far = z.camera(TEAPOT, 1.0);
        z.zoom(2.0);
        let near = z.camera(TEAPOT, 1.0);
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
        let home = o.camera(TEAPOT, 1.0);
        o.pan(&home, 0.5, 0.0);
        let c = o.camera(TEAPOT, 1.0);
        let moved = c.target - home.target;
        let back = (home.eye - home.target).normalize();
        assert!(moved.dot(back).abs() < 1e-4, "in the view plane");
        // Half a view height to the right projects half a view height to the right.
        let p = home.view_proj().project_point3(c.target);
        assert!((p.x - 1.0).abs() < 1e-3 && p.y.abs() < 1e-3, "{p}");
    }
}
