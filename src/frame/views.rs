//! The frame's view table (camera, shadow faces and planes, every cube-mapped object's six
//! faces around its reference point) and light table (glsl/common/scene.glsl `views`,
//! `lights`): what every pass reads to know where it looks from.

use bytemuck::Zeroable;
use glam::{Mat4, Vec3, Vec4};

use crate::cube::face_view_proj;
use crate::frame::stage::ViewLayout;
use crate::gpu_scene::{light_kind_code, GpuLight, GpuView};
use crate::plan::types::Plan;
use crate::scene::{LightKind, Scene};

impl ViewLayout {
    /// The frame's own views: camera first, then six per shadow cube, one per shadow plane,
    /// six per cube-mapped object. The families add their blocks after these (`add`).
    pub fn of(plan: &Plan) -> ViewLayout {
        let mut v = ViewLayout { camera: 0, count: 1, ..Default::default() };
        for _ in &plan.shadow_cubes {
            v.shadow_cubes.push(v.count);
            v.count += 6;
        }
        for _ in &plan.shadow_planes {
            v.shadow_planes.push(v.count);
            v.count += 1;
        }
        for _ in &plan.envmaps {
            v.envmaps.push(v.count);
            v.count += 6;
        }
        v
    }
}

/// A view-table entry for `view_proj` from `eye` (w: 0 radial, 1 planar distance) with
/// `dir`, clipping nothing.
pub fn view(view_proj: Mat4, eye: Vec4, dir: Vec4) -> GpuView {
    GpuView {
        view_proj: view_proj.to_cols_array_2d(),
        inv_view_proj: view_proj.inverse().to_cols_array_2d(),
        eye: eye.to_array(),
        dir: dir.to_array(),
        clip: [0.0, 0.0, 0.0, 1.0],
    }
}

/// The frame's part of the view table for a camera (`camera_view_proj`, eye), the plan's
/// lights and maps: the camera, the shadow maps' views and the cube-mapped objects' faces.
/// The families' own blocks (the layered map's, planar mirrors', the caustics') are written
/// by their frame parts (`stage::FramePart::write_views`).
pub fn view_table(plan: &Plan, layout: &ViewLayout, lights: &[GpuLight], (camera_view_proj, eye): (Mat4, Vec3)) -> Vec<GpuView> {
    let mut views = vec![GpuView::zeroed(); layout.count as usize];
    views[layout.camera as usize] = view(camera_view_proj, eye.extend(0.0), Vec4::ZERO);
    let near = plan.cube_near;
    for (k, &li) in plan.shadow_cubes.iter().enumerate() {
        let p = Vec3::from_slice(&lights[li].position_range[..3]);
        for f in 0..6 {
            views[(layout.shadow_cubes[k] + f) as usize] = view(face_view_proj(f as usize, p, near), p.extend(0.0), Vec4::ZERO);
        }
    }
    for (k, &li) in plan.shadow_planes.iter().enumerate() {
        let l = &lights[li];
        let m = Mat4::from_cols_array_2d(&l.shadow_view_proj);
        let origin = Vec3::from_slice(&l.position_range[..3]);
        let dir = Vec3::from_slice(&l.direction_kind[..3]);
        views[layout.shadow_planes[k] as usize] = view(m, origin.extend(1.0), dir.extend(0.0));
    }
    for (e, &base) in plan.envmaps.iter().zip(&layout.envmaps) {
        for f in 0..6 {
            views[(base + f) as usize] =
                view(face_view_proj(f as usize, e.reference_point, near), e.reference_point.extend(0.0), Vec4::ZERO);
        }
    }
    views
}

/// The light table: position and range, direction and kind, intensity, spot cone and
/// shadow-map layer, and a directional light's shadow projection.
pub fn light_table(scene: &Scene, plan: &Plan) -> Vec<GpuLight> {
    let bounds = scene.bounds();
    let (center, radius) = (bounds.center(), (bounds.diagonal() * 0.5).max(1e-6));
    let size = plan.quality.frame.shadow_size as f32;
    scene
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let mut cone = [-2.0, -1.0, -1.0, size];
            let mut view_proj = Mat4::IDENTITY;
            let mut texel = 0.0;
            if let LightKind::Spot { inner_cone, outer_cone } = l.kind {
                cone[0] = outer_cone.cos();
                cone[1] = inner_cone.cos();
            }
            if let Some(k) = plan.shadow_cubes.iter().position(|&j| j == i) {
                cone[2] = k as f32;
            }
            if let Some(k) = plan.shadow_planes.iter().position(|&j| j == i) {
                cone[2] = k as f32;
                view_proj = directional_view_proj(l.direction, center, radius);
                texel = 2.0 * radius / size;
            }
            let position = if l.kind == LightKind::Directional { center - l.direction * radius } else { l.position };
            GpuLight {
                position_range: position.extend(l.range.unwrap_or(0.0)).to_array(),
                direction_kind: l.direction.extend(light_kind_code(l.kind)).to_array(),
                intensity: l.intensity.extend(texel).to_array(),
                cone,
                shadow_view_proj: view_proj.to_cols_array_2d(),
            }
        })
        .collect()
}

/// Orthographic world → clip for a directional light's planar distance map covering the
/// sphere (center, radius); reversed depth.
pub fn directional_view_proj(dir: Vec3, center: Vec3, radius: f32) -> Mat4 {
    let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let eye = center - dir * radius;
    let view = Mat4::look_to_rh(eye, dir, up);
    // x, y in [−r, r] → [−1, 1]; depth d along dir in [0, 2r] → z_ndc = 1 − d/2r.
    let proj = Mat4::from_cols(
        Vec4::new(1.0 / radius, 0.0, 0.0, 0.0),
        Vec4::new(0.0, -1.0 / radius, 0.0, 0.0),
        Vec4::new(0.0, 0.0, 1.0 / (2.0 * radius), 0.0),
        Vec4::new(0.0, 0.0, 1.0, 1.0),
    );
    proj * view
}
