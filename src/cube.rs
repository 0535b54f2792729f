//! Cube-map conventions, exactly as the Vulkan specification's cube-map face selection
//! table (§16.5.4 "Cube Map Face Selection") defines them. Face order +X, −X, +Y, −Y,
//! +Z, −Z is the array-layer order. For a direction r with major axis value m_a on face f,
//! s = (s_c/|m_a| + 1)/2 and t = (t_c/|m_a| + 1)/2; s grows with the image column and t
//! with the row. Twin of `glsl/common/cube.glsl`.

use glam::{Mat4, Vec3, Vec4};

/// (s_c axis, t_c axis, major axis) per face, as rows that dot the direction.
pub const FACE_AXES: [[Vec3; 3]; 6] = [
    [Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.0, -1.0, 0.0), Vec3::new(1.0, 0.0, 0.0)], // +X: sc = −rz, tc = −ry
    [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, -1.0, 0.0), Vec3::new(-1.0, 0.0, 0.0)], // −X: sc = +rz, tc = −ry
    [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 0.0)],   // +Y: sc = +rx, tc = +rz
    [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.0, -1.0, 0.0)], // −Y: sc = +rx, tc = −rz
    [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 0.0, 1.0)],  // +Z: sc = +rx, tc = −ry
    [Vec3::new(-1.0, 0.0, 0.0), Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 0.0, -1.0)], // −Z: sc = −rx, tc = −ry
];

/// World → clip matrix that rasterises face `face` of a cube map centred at `center`:
/// clip = (s_c, t_c, near, m_a), i.e. a 90° frustum with reversed, infinite depth
/// (z_ndc = near / m_a), in Vulkan's y-down framebuffer convention.
pub fn face_view_proj(face: usize, center: Vec3, near: f32) -> Mat4 {
    let [a, b, c] = FACE_AXES[face];
    // Rows of the matrix; glam is column-major, so build the transpose.
    let rows = [a.extend(-a.dot(center)), b.extend(-b.dot(center)), Vec4::new(0.0, 0.0, 0.0, near), c.extend(-c.dot(center))];
    Mat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose()
}

/// The face, s and t in [0,1] that a direction selects (the Vulkan table).
pub fn direction_to_face_st(d: Vec3) -> (usize, f32, f32) {
    let a = d.abs();
    let face = if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 {
            0
        } else {
            1
        }
    } else if a.y >= a.z {
        if d.y >= 0.0 {
            2
        } else {
            3
        }
    } else if d.z >= 0.0 {
        4
    } else {
        5
    };
    let [sa, ta, ma] = FACE_AXES[face];
    let m = ma.dot(d).abs();
    (face, 0.5 * (sa.dot(d) / m + 1.0), 0.5 * (ta.dot(d) / m + 1.0))
}

/// Inverse of `direction_to_face_st`: the (unnormalised) direction of face coordinates.
pub fn face_st_to_direction(face: usize, s: f32, t: f32) -> Vec3 {
    let [sa, ta, ma] = FACE_AXES[face];
    ma + sa * (2.0 * s - 1.0) + ta * (2.0 * t - 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_st_round_trip() {
        for face in 0..6 {
            for (s, t) in [(0.1, 0.2), (0.5, 0.5), (0.9, 0.7)] {
                let d = face_st_to_direction(face, s, t);
                let (f2, s2, t2) = direction_to_face_st(d);
                assert_eq!(f2, face);
                assert!((s - s2).abs() < 1e-6 && (t - t2).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn projection_matches_table() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        for face in 0..6 {
            let m = face_view_proj(face, c, 0.01);
            let d = face_st_to_direction(face, 0.25, 0.8);
            let clip = m * (c + d * 2.0).extend(1.0);
            let ndc = clip.truncate() / clip.w;
            // Vulkan: x_ndc = −1 is column 0 (s = 0), y_ndc = −1 is row 0 (t = 0).
            assert!((ndc.x - (2.0 * 0.25 - 1.0)).abs() < 1e-5, "face {face}: {ndc}");
            assert!((ndc.y - (2.0 * 0.8 - 1.0)).abs() < 1e-5, "face {face}: {ndc}");
            assert!(ndc.z > 0.0 && ndc.z < 1.0);
        }
    }
}
