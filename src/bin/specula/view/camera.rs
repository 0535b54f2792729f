//! The viewer's camera: fly (WASD + mouse look) and orbit (drag around a pivot, wheel to
//! zoom). The camera it hands the renderer is built exactly as `specula render
//! --camera-pos E --camera-target T --fov F` builds one from the numbers [`Controller::args`]
//! prints, so a screenshot can be rendered again from the command line bit for bit.

use glam::Vec3;
use specula::scene::{Camera, Scene};

/// Radians of turn per pixel of mouse motion.
const TURN_PER_PIXEL: f32 = 0.004;
/// Pitch stays off the poles, where the look-at basis degenerates.
const MAX_PITCH: f32 = 1.55;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Fly,
    Orbit,
}

/// A movement key held down.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Move {
    Forward,
    Back,
    Left,
    Right,
    Up,
    Down,
    Fast,
}

const MOVES: [Move; 7] = [Move::Forward, Move::Back, Move::Left, Move::Right, Move::Up, Move::Down, Move::Fast];

pub struct Controller {
    pub eye: Vec3,
    /// Heading in radians: 0 looks down −Z, positive turns towards −X.
    pub yaw: f32,
    pub pitch: f32,
    pub fov_deg: f32,
    znear: f32,
    /// The orbit mode's centre.
    pub pivot: Vec3,
    /// Fly speed in scene units per second (the wheel scales it in fly mode).
    pub speed: f32,
    pub mode: Mode,
    held: [bool; 7],
    /// The scene's size, for the orbit pivot's distance.
    centre: Vec3,
    /// False until the user moves: the scene's own camera is rendered unchanged until then.
    pub moved: bool,
}

impl Controller {
    /// Starts at the scene's camera, flying at a quarter of the scene's diagonal a second.
    pub fn new(scene: &Scene) -> Controller {
        let cam = scene.camera_or_default();
        let forward = cam.world_from_camera.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
        let b = scene.bounds();
        let (centre, diagonal) = (0.5 * (b.min + b.max), (b.max - b.min).length());
        let diagonal = if diagonal.is_finite() && diagonal > 0.0 { diagonal } else { 1.0 };
        let mut c = Controller {
            eye: cam.position,
            yaw: (-forward.x).atan2(-forward.z),
            pitch: forward.y.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH),
            fov_deg: cam.yfov.to_degrees(),
            znear: scene.camera.map_or(0.01, |c| c.znear),
            pivot: centre,
            speed: 0.25 * diagonal,
            mode: Mode::Fly,
            held: [false; 7],
            centre,
            moved: false,
        };
        c.pivot = c.eye + c.forward() * (centre - c.eye).length().max(1e-3 * diagonal);
        c
    }

    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(-sy * cp, sp, -cy * cp)
    }

    fn right(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        Vec3::new(cy, 0.0, -sy)
    }

    pub fn hold(&mut self, m: Move, down: bool) {
        self.held[MOVES.iter().position(|&x| x == m).unwrap_or(0)] = down;
    }

    fn held(&self, m: Move) -> bool {
        self.held[MOVES.iter().position(|&x| x == m).unwrap_or(0)]
    }

    /// Switches between fly and orbit; the orbit pivot is where the view points, at the
    /// scene centre's distance, so the view does not jump.
    pub fn toggle_mode(&mut self) {
        self.mode = match self.mode {
            Mode::Fly => {
                self.pivot = self.eye + self.forward() * (self.centre - self.eye).length().max(1e-3 * self.speed);
                Mode::Orbit
            }
            Mode::Orbit => Mode::Fly,
        };
    }

    /// Moves by the held keys over `dt` seconds (fly mode; in orbit mode W/S zoom).
    pub fn step(&mut self, dt: f32) {
        let axis = |a: Move, b: Move| self.held(a) as i32 as f32 - self.held(b) as i32 as f32;
        let (f, r, u) = (axis(Move::Forward, Move::Back), axis(Move::Right, Move::Left), axis(Move::Up, Move::Down));
        if f == 0.0 && r == 0.0 && u == 0.0 {
            return;
        }
        let fast = if self.held(Move::Fast) { 4.0 } else { 1.0 };
        match self.mode {
            Mode::Fly => {
                let d = self.forward() * f + self.right() * r + Vec3::Y * u;
                self.eye += d.normalize_or_zero() * self.speed * fast * dt;
            }
            Mode::Orbit => self.zoom(-f * fast * dt * 4.0),
        }
        self.moved = true;
    }

    /// Mouse motion by `dx`, `dy` pixels with the look (fly) or drag (orbit) button held.
    pub fn turn(&mut self, dx: f32, dy: f32) {
        if dx == 0.0 && dy == 0.0 {
            return;
        }
        self.yaw -= dx * TURN_PER_PIXEL;
        self.pitch = (self.pitch - dy * TURN_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
        if self.mode == Mode::Orbit {
            let r = (self.eye - self.pivot).length();
            self.eye = self.pivot - self.forward() * r;
        }
        self.moved = true;
    }

    /// The wheel: in orbit mode zooms towards the pivot, in fly mode scales the speed.
    pub fn wheel(&mut self, steps: f32) {
        match self.mode {
            Mode::Orbit => self.zoom(steps),
            Mode::Fly => self.speed *= 1.25f32.powf(steps),
        }
    }

    fn zoom(&mut self, steps: f32) {
        let r = (self.eye - self.pivot).length() * 0.85f32.powf(steps);
        self.eye = self.pivot - self.forward() * r.max(1e-4);
        self.moved = true;
    }

    /// The point the camera looks at, as `--camera-target` takes it.
    pub fn target(&self) -> Vec3 {
        self.eye + self.forward()
    }

    /// The camera `specula render` builds from [`Controller::args`].
    pub fn camera(&self) -> specula::Result<Camera> {
        Camera::checked(self.eye, self.target(), self.fov_deg.to_radians(), self.znear)
    }

    /// `--camera-pos=… --camera-target=… --fov=…` for this camera (with `=`, as values may
    /// start with a minus sign); Rust prints each f32 with the fewest digits that read back
    /// to the same number.
    pub fn args(&self) -> String {
        let v = |p: Vec3| format!("{},{},{}", p.x, p.y, p.z);
        format!("--camera-pos={} --camera-target={} --fov={}", v(self.eye), v(self.target()), self.fov_deg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        specula::scenes::builtin("corner-mirror").unwrap().unwrap()
    }

    #[test]
    fn starts_at_the_scene_camera_and_flies_forward() {
        let s = scene();
        let mut c = Controller::new(&s);
        let cam = s.camera_or_default();
        let fwd = cam.world_from_camera.transform_vector3(Vec3::NEG_Z).normalize();
        assert!((c.forward() - fwd).length() < 1e-5, "{} vs {fwd}", c.forward());
        c.hold(Move::Forward, true);
        let before = c.eye;
        c.step(0.5);
        assert!(((c.eye - before) - fwd * c.speed * 0.5).length() < 1e-4);
        assert!(c.moved);
    }

    #[test]
    fn orbit_keeps_the_distance_to_the_pivot_and_looks_at_it() {
        let mut c = Controller::new(&scene());
        c.toggle_mode();
        let r = (c.eye - c.pivot).length();
        c.turn(120.0, -30.0);
        assert!(((c.eye - c.pivot).length() - r).abs() < 1e-3 * r);
        assert!((c.forward() - (c.pivot - c.eye).normalize()).length() < 1e-4);
        c.wheel(2.0);
        assert!((c.eye - c.pivot).length() < r);
    }

    #[test]
    fn printed_arguments_read_back_to_the_same_camera() {
        let mut c = Controller::new(&scene());
        c.turn(37.0, 11.0);
        c.hold(Move::Right, true);
        c.step(0.1);
        let a = c.args();
        let parts: Vec<&str> = a.split_whitespace().flat_map(|w| w.split('=')).collect();
        let p = |s: &str| {
            let v: Vec<f32> = s.split(',').map(|x| x.parse().unwrap()).collect();
            Vec3::new(v[0], v[1], v[2])
        };
        let (eye, target, fov) = (p(parts[1]), p(parts[3]), parts[5].parse::<f32>().unwrap());
        assert_eq!(Camera::checked(eye, target, fov.to_radians(), c.znear).unwrap(), c.camera().unwrap());
    }
}
