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

/// Whether any point of the box [lo, hi] lies inside face `face`'s 90° frustum from
/// `center` (infinite far plane). Exact for a box, whose coordinates vary independently:
/// some point has m ≥ |s| and m ≥ |t| (m along the face's axis) iff the largest m over the
/// box reaches the smallest |s| and the smallest |t|; a relative margin keeps boxes that
/// touch a frustum edge within rounding. Per-face culling of cube-map passes uses it.
pub fn face_sees_box(face: usize, center: Vec3, lo: Vec3, hi: Vec3) -> bool {
    if !(lo.is_finite() && hi.is_finite()) {
        return true;
    }
    let [sa, ta, ma] = FACE_AXES[face];
    let (lo, hi) = (lo - center, hi - center);
    // Range of a signed axis over the box.
    let range = |a: Vec3| {
        let (x, y) = (a.dot(lo), a.dot(hi));
        (x.min(y), x.max(y))
    };
    let nearest = |(a, b): (f32, f32)| if a <= 0.0 && b >= 0.0 { 0.0 } else { a.abs().min(b.abs()) };
    let m = range(ma).1;
    let slack = 1e-4 * (lo.abs().max(hi.abs()).max_element()) + 1e-30;
    m + slack >= 0.0 && m + slack >= nearest(range(sa)) && m + slack >= nearest(range(ta))
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
    fn face_sees_box_agrees_with_sampled_directions() {
        // Boxes around random points: a face sees a box iff some point of it projects onto
        // that face (checked densely on the box's surface grid).
        let c = Vec3::new(0.3, -0.2, 0.1);
        let mut seed = 7u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1 << 24) as f32 * 2.0 - 1.0
        };
        for _ in 0..300 {
            let p = Vec3::new(rnd(), rnd(), rnd()) * 3.0;
            let h = Vec3::new(rnd().abs(), rnd().abs(), rnd().abs()) * 0.8;
            let (lo, hi) = (p - h, p + h);
            let mut seen = [false; 6];
            let n = 12;
            for i in 0..=n {
                for j in 0..=n {
                    for k in 0..=n {
                        let q = lo + (hi - lo) * Vec3::new(i as f32, j as f32, k as f32) / n as f32;
                        if (q - c).length() > 1e-6 {
                            seen[direction_to_face_st(q - c).0] = true;
                        }
                    }
                }
            }
            for (f, &seen) in seen.iter().enumerate() {
                // Sampling can miss a sliver the exact test finds, never the other way round.
                assert!(!seen || face_sees_box(f, c, lo, hi), "face {f} must see box {lo}..{hi}");
            }
        }
        // A box straight ahead of +X only.
        let (lo, hi) = (Vec3::new(5.0, -0.1, -0.1), Vec3::new(6.0, 0.1, 0.1));
        let seen: Vec<usize> = (0..6).filter(|&f| face_sees_box(f, Vec3::ZERO, lo, hi)).collect();
        assert_eq!(seen, vec![0]);
    }

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
