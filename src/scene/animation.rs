//! glTF animations: translation, rotation and scale channels on the node hierarchy, with
//! STEP, LINEAR (spherical for rotations) and CUBICSPLINE (Hermite) interpolation, as the
//! glTF 2.0 specification (§3.11, Appendix C) defines them. The importer records every
//! node's rest pose and, per imported mesh, light and camera, its path through the node
//! hierarchy; [`Scene::set_time`] evaluates the channels at a time and moves each object
//! through the scene's validated setters, so that a renderer takes the frame as an update.

use glam::{Mat4, Quat, Vec3, Vec4};

use super::Scene;
use crate::error::{Error, Result};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    Translation,
    Rotation,
    Scale,
}

/// One channel: a node's translation, rotation (quaternion x, y, z, w) or scale over time.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub node: usize,
    pub target: Target,
    pub interpolation: Interpolation,
    /// Key times in seconds, strictly increasing.
    pub times: Vec<f32>,
    /// One value per key; CUBICSPLINE: three per key (in-tangent, value, out-tangent).
    pub values: Vec<Vec4>,
}

/// A node's rest pose: its TRS, or a matrix (which glTF forbids animating).
#[derive(Clone, Debug, PartialEq)]
pub struct NodePose {
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
    pub matrix: Option<Mat4>,
}

/// Every animation of a glTF file, played together.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Animation {
    /// The rest pose of every glTF node, by node index.
    pub nodes: Vec<NodePose>,
    pub channels: Vec<Channel>,
    /// (scene mesh, node path from the root): the mesh's world transform is the product of
    /// the path's local transforms (a node instanced twice has two paths).
    pub meshes: Vec<(usize, Vec<usize>)>,
    pub lights: Vec<(usize, Vec<usize>)>,
    pub camera: Option<Vec<usize>>,
    /// The latest key time of any channel (seconds).
    pub duration: f32,
}

impl Channel {
    /// The channel's value at time `t`: the first key's before it, the last key's after.
    pub fn sample(&self, t: f32) -> Vec4 {
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let value = |i: usize| if cubic { self.values[3 * i + 1] } else { self.values[i] };
        let n = self.times.len();
        if n == 0 {
            return Vec4::ZERO;
        }
        if t <= self.times[0] || t.is_nan() {
            return value(0);
        }
        if t >= self.times[n - 1] {
            return value(n - 1);
        }
        let i = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[i], self.times[i + 1]);
        let dt = t1 - t0;
        let u = (t - t0) / dt;
        let rotation = self.target == Target::Rotation;
        match self.interpolation {
            Interpolation::Step => value(i),
            Interpolation::Linear if rotation => {
                let (a, b) = (Quat::from_vec4(value(i)).normalize(), Quat::from_vec4(value(i + 1)).normalize());
                Vec4::from(a.slerp(b, u))
            }
            Interpolation::Linear => value(i).lerp(value(i + 1), u),
            Interpolation::CubicSpline => {
                let (p0, m0) = (self.values[3 * i + 1], self.values[3 * i + 2] * dt);
                let (p1, m1) = (self.values[3 * (i + 1) + 1], self.values[3 * (i + 1)] * dt);
                let (u2, u3) = (u * u, u * u * u);
                let v = p0 * (2.0 * u3 - 3.0 * u2 + 1.0) + m0 * (u3 - 2.0 * u2 + u) + p1 * (-2.0 * u3 + 3.0 * u2) + m1 * (u3 - u2);
                if rotation {
                    Vec4::from(Quat::from_vec4(v).normalize())
                } else {
                    v
                }
            }
        }
    }

    /// Checks the channel read from `field` (`animations[a].channels[c]`): increasing finite
    /// times, as many values as the interpolation needs, finite values.
    pub fn validate(&self, field: &str) -> std::result::Result<(), (String, String)> {
        let input = format!("{field}.sampler.input");
        if self.times.is_empty() {
            return Err((input, "has no key times".into()));
        }
        if let Some(i) = self.times.iter().position(|t| !t.is_finite() || *t < 0.0) {
            return Err((input, format!("key time {i} must be finite and ≥ 0, got {}", self.times[i])));
        }
        if let Some(i) = self.times.windows(2).position(|w| w[1] <= w[0]) {
            return Err((input, format!("key times must increase: {} then {} at key {}", self.times[i], self.times[i + 1], i + 1)));
        }
        let per = if self.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        if self.values.len() != per * self.times.len() {
            return Err((
                format!("{field}.sampler.output"),
                format!("{} values for {} keys ({per} per key with {:?})", self.values.len(), self.times.len(), self.interpolation),
            ));
        }
        if let Some(i) = self.values.iter().position(|v| !v.is_finite()) {
            return Err((format!("{field}.sampler.output"), format!("value {i} is not finite ({})", self.values[i])));
        }
        Ok(())
    }
}

impl Animation {
    /// Node `node`'s local transform at time `t`.
    pub fn local(&self, node: usize, t: f32) -> Mat4 {
        let rest = &self.nodes[node];
        if let Some(m) = rest.matrix {
            return m;
        }
        let (mut tr, mut r, mut s) = (rest.translation, rest.rotation, rest.scale);
        for c in self.channels.iter().filter(|c| c.node == node) {
            let v = c.sample(t);
            match c.target {
                Target::Translation => tr = v.truncate(),
                Target::Rotation => r = Quat::from_vec4(v).normalize(),
                Target::Scale => s = v.truncate(),
            }
        }
        Mat4::from_scale_rotation_translation(s, r, tr)
    }

    /// The world transform of the node path `path` (root first) at time `t`.
    pub fn world(&self, path: &[usize], t: f32) -> Mat4 {
        path.iter().fold(Mat4::IDENTITY, |w, &n| w * self.local(n, t))
    }
}

impl Scene {
    /// Poses the scene at time `t` (seconds) of its glTF animations: every animated mesh,
    /// light and camera moves to where its node path puts it. A mesh scaled to zero (glTF's
    /// way of hiding a node) is hidden until its scale returns. A scene without animations
    /// stays as it is. On error (a negative `t`, a pose the setters refuse) the scene may be
    /// partly posed: pose a copy when that matters.
    pub fn set_time(&mut self, t: f32) -> Result<()> {
        if !(t.is_finite() && t >= 0.0) {
            return Err(Error::invalid("time", format!("must be a finite number of seconds ≥ 0, got {t}")));
        }
        let Some(anim) = self.animation.take() else {
            return Ok(());
        };
        let result = self.pose(&anim, t);
        self.animation = Some(anim);
        result
    }

    fn pose(&mut self, anim: &Animation, t: f32) -> Result<()> {
        for (mesh, path) in &anim.meshes {
            let world = anim.world(path, t);
            let det = glam::Mat3::from_mat4(world).determinant();
            if det == 0.0 && world.is_finite() {
                self.set_object_visible(*mesh, false)?;
                continue;
            }
            self.set_object_transform(*mesh, world)?;
            self.set_object_visible(*mesh, true)?;
        }
        for (light, path) in &anim.lights {
            let world = anim.world(path, t);
            let mut l = self.lights[*light].clone();
            l.position = world.w_axis.truncate();
            l.direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
            if l.direction == Vec3::ZERO {
                l.direction = self.lights[*light].direction;
            }
            self.set_light(*light, l)?;
        }
        if let (Some(path), Some(cam)) = (&anim.camera, self.camera.as_mut()) {
            let (_, rotation, translation) = anim.world(path, t).to_scale_rotation_translation();
            let world_from_camera = Mat4::from_rotation_translation(rotation.normalize(), translation);
            if world_from_camera.is_finite() {
                cam.position = translation;
                cam.world_from_camera = world_from_camera;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(interpolation: Interpolation, target: Target, times: &[f32], values: &[Vec4]) -> Channel {
        Channel { node: 0, target, interpolation, times: times.to_vec(), values: values.to_vec() }
    }

    #[test]
    fn step_linear_and_cubic_against_the_closed_form() {
        let v = |x: f32| Vec4::new(x, 2.0 * x, -x, 0.0);
        let step = channel(Interpolation::Step, Target::Translation, &[1.0, 2.0, 4.0], &[v(0.0), v(1.0), v(3.0)]);
        assert_eq!(step.sample(0.5), v(0.0));
        assert_eq!(step.sample(1.99), v(0.0));
        assert_eq!(step.sample(2.0), v(1.0));
        assert_eq!(step.sample(9.0), v(3.0));
        let lin = channel(Interpolation::Linear, Target::Scale, &[1.0, 2.0, 4.0], &[v(0.0), v(1.0), v(3.0)]);
        assert!((lin.sample(1.25) - v(0.25)).length() < 1e-6);
        assert!((lin.sample(3.0) - v(2.0)).length() < 1e-6);
        // Hermite with p0 = 0, p1 = 1, both tangents 0 over [0, 2]: 3u² − 2u³.
        let z = Vec4::ZERO;
        let cubic = channel(Interpolation::CubicSpline, Target::Translation, &[0.0, 2.0], &[z, v(0.0), z, z, v(1.0), z]);
        for u in [0.0f32, 0.1, 0.5, 0.9, 1.0] {
            let want = 3.0 * u * u - 2.0 * u * u * u;
            assert!((cubic.sample(2.0 * u) - v(want)).length() < 1e-5, "u = {u}");
        }
        // Tangents scale with the key interval: out-tangent 1 at p0, p1 = p0, over dt = 2:
        // p(u) = dt (u³ − 2u² + u).
        let o = Vec4::new(1.0, 2.0, -1.0, 0.0);
        let cubic = channel(Interpolation::CubicSpline, Target::Translation, &[0.0, 2.0], &[z, z, o, z, z, z]);
        let u = 0.25f32;
        assert!((cubic.sample(2.0 * u) - o * 2.0 * (u * u * u - 2.0 * u * u + u)).length() < 1e-5);
    }

    #[test]
    fn rotations_slerp_along_the_shortest_arc() {
        let a = Vec4::from(Quat::IDENTITY);
        let b = Vec4::from(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
        let lin = channel(Interpolation::Linear, Target::Rotation, &[0.0, 1.0], &[a, b]);
        let q = Quat::from_vec4(lin.sample(0.5));
        assert!(q.angle_between(Quat::from_rotation_y(std::f32::consts::FRAC_PI_4)) < 1e-5);
        // The same rotation given as −q: still the short way.
        let lin = channel(Interpolation::Linear, Target::Rotation, &[0.0, 1.0], &[a, -b]);
        let q = Quat::from_vec4(lin.sample(0.5));
        assert!(q.angle_between(Quat::from_rotation_y(std::f32::consts::FRAC_PI_4)) < 1e-5);
    }

    #[test]
    fn bad_channels_name_the_field() {
        let c = channel(Interpolation::Linear, Target::Scale, &[0.0, 0.0], &[Vec4::ONE, Vec4::ONE]);
        let (f, m) = c.validate("animations[0].channels[1]").unwrap_err();
        assert_eq!(f, "animations[0].channels[1].sampler.input");
        assert!(m.contains("must increase"), "{m}");
        let c = channel(Interpolation::CubicSpline, Target::Scale, &[0.0, 1.0], &[Vec4::ONE; 2]);
        let (f, m) = c.validate("animations[0].channels[0]").unwrap_err();
        assert!(f.ends_with("sampler.output") && m.contains("3 per key"), "{f}: {m}");
    }
}
