//! The uniform grid scheme (survey §2.3.1): cells over the triangle list's bounds, each
//! listing the triangles whose bounding box overlaps it (a conservative list: the kernel
//! accepts a hit in a cell only up to the cell's exit, so the list may be generous), and
//! traversed by 3D-DDA (Amanatides–Woo). Cell c is the word (first, count, empty, 0):
//! references `refs[first..first + count]`, and for an empty cell the Chebyshev distance
//! in cells to the nearest non-empty one (capped at `MAX_SKIP`), which lets a ray jump
//! over the (2·empty − 1)³ block of empty cells around it (KL04).

use glam::{UVec3, Vec3};

use super::{Packed, TriangleList};
use crate::error::{Error, Result};
use crate::frame::layout::GpuAccel;

/// The most cells a grid may have (16 bytes each: 64 MiB).
pub const MAX_CELLS: usize = 1 << 22;
/// The largest empty-space distance stored; farther cells store this.
pub const MAX_SKIP: u32 = 16;

/// The resolution for about `density` × N cells of cubic shape over `extent`: each axis
/// gets extent_a · ∛(density · N / volume) cells, at least 1, the total capped at
/// `MAX_CELLS`. Flat extents count as a hundredth of the largest one.
pub fn resolution(extent: Vec3, n: usize, density: f32) -> UVec3 {
    let e = extent.max(Vec3::splat(extent.max_element() * 1e-2)).max(Vec3::splat(f32::MIN_POSITIVE));
    let target = (density as f64 * n.max(1) as f64).clamp(1.0, MAX_CELLS as f64);
    let k = (target / (e.x as f64 * e.y as f64 * e.z as f64)).cbrt();
    let mut r = (e.as_dvec3() * k - glam::DVec3::splat(1e-6)).ceil().max(glam::DVec3::ONE).min(glam::DVec3::splat(1024.0)).as_uvec3();
    while (r.x as usize) * (r.y as usize) * (r.z as usize) > MAX_CELLS {
        r = (r.as_vec3() * 0.9).ceil().max(Vec3::ONE).as_uvec3();
    }
    r
}

pub fn pack(list: &TriangleList, density: f32, skip_empty: bool) -> Result<Packed> {
    if !(density > 0.0 && density <= 64.0) {
        return Err(Error::invalid("knob grid_density", format!("must be in (0, 64], got {density}")));
    }
    let (lo, hi) = if list.is_empty() { (Vec3::ZERO, Vec3::ONE) } else { list.bounds() };
    // A little margin so that corners on the upper faces fall inside the last cell.
    let extent = (hi - lo).max(Vec3::splat(1e-30));
    let margin = extent.max(Vec3::splat(extent.max_element() * 1e-3)) * 1e-4;
    let (lo, hi) = (lo - margin, hi + margin);
    let res = resolution(hi - lo, list.len(), density);
    let inv_cell = res.as_vec3() / (hi - lo);
    let cell_of = |p: Vec3| (((p - lo) * inv_cell).floor().max(Vec3::ZERO).as_uvec3()).min(res - UVec3::ONE);
    let index = |c: UVec3| (c.x + res.x * (c.y + res.y * c.z)) as usize;
    let cells = (res.x * res.y * res.z) as usize;
    // Two passes: counts, then the references in place.
    let ranges: Vec<(UVec3, UVec3)> =
        list.triangles.iter().map(|t| (cell_of(t[0].min(t[1]).min(t[2])), cell_of(t[0].max(t[1]).max(t[2])))).collect();
    let mut count = vec![0u32; cells];
    let mut total = 0u64;
    for &(a, b) in &ranges {
        for z in a.z..=b.z {
            for y in a.y..=b.y {
                for x in a.x..=b.x {
                    count[index(UVec3::new(x, y, z))] += 1;
                }
            }
        }
        total += ((b - a + UVec3::ONE).as_u64vec3()).element_product();
    }
    if total > u32::MAX as u64 / 2 {
        return Err(Error::invalid("grid", format!("{total} cell references: lower grid_density")));
    }
    let mut first = vec![0u32; cells];
    let mut acc = 0;
    for (f, &c) in first.iter_mut().zip(&count) {
        *f = acc;
        acc += c;
    }
    let mut fill = first.clone();
    let mut refs = vec![0u32; total as usize];
    for (id, &(a, b)) in ranges.iter().enumerate() {
        for z in a.z..=b.z {
            for y in a.y..=b.y {
                for x in a.x..=b.x {
                    let i = index(UVec3::new(x, y, z));
                    refs[fill[i] as usize] = id as u32;
                    fill[i] += 1;
                }
            }
        }
    }
    let empty = if skip_empty { chebyshev_distance(&count, res) } else { vec![0; cells] };
    let nodes = (0..cells).map(|i| [first[i], count[i], empty[i], 0]).collect();
    Ok(Packed {
        nodes,
        refs,
        aux: Vec::new(),
        accel: GpuAccel {
            grid_min: lo.extend(0.0).to_array(),
            grid_inv_cell: inv_cell.extend(0.0).to_array(),
            grid_res: [res.x, res.y, res.z, skip_empty as u32],
            triangle_count: list.len() as u32,
            ..bytemuck::Zeroable::zeroed()
        },
        shader: "raytrace/intersect_grid.comp",
    })
}

/// For each cell, the Chebyshev distance (in cells) to the nearest non-empty cell: 0 for
/// non-empty cells, capped at `MAX_SKIP`. Separable: d = min over non-empty p of
/// max(|Δx|, |Δy|, |Δz|), computed one axis at a time with max in place of the sum.
fn chebyshev_distance(count: &[u32], res: UVec3) -> Vec<u32> {
    let (nx, ny, nz) = (res.x as usize, res.y as usize, res.z as usize);
    let mut d: Vec<u32> = count.iter().map(|&c| if c > 0 { 0 } else { MAX_SKIP }).collect();
    let at = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
    let r = MAX_SKIP as usize;
    for axis in 0..3 {
        let len = [nx, ny, nz][axis];
        let mut line = vec![0u32; len];
        let mut out = vec![0u32; len];
        let (na, nb) = match axis {
            0 => (ny, nz),
            1 => (nx, nz),
            _ => (nx, ny),
        };
        for a in 0..na {
            for b in 0..nb {
                let idx = |i: usize| match axis {
                    0 => at(i, a, b),
                    1 => at(a, i, b),
                    _ => at(a, b, i),
                };
                for (i, l) in line.iter_mut().enumerate() {
                    *l = d[idx(i)];
                }
                for i in 0..len {
                    let lo = i.saturating_sub(r);
                    let window = &line[lo..(i + r + 1).min(len)];
                    out[i] = window.iter().enumerate().map(|(k, &v)| v.max(i.abs_diff(lo + k) as u32)).min().unwrap_or(MAX_SKIP);
                }
                for i in 0..len {
                    d[idx(i)] = out[i];
                }
            }
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chebyshev_distance_of_one_full_cell() {
        let res = UVec3::new(7, 5, 3);
        let mut count = vec![0u32; 105];
        count[2 + 7 + 35] = 1; // cell (2, 1, 1): x + 7 (y + 5 z)
        let d = chebyshev_distance(&count, res);
        for z in 0..3u32 {
            for y in 0..5u32 {
                for x in 0..7u32 {
                    let e = x.abs_diff(2).max(y.abs_diff(1)).max(z.abs_diff(1));
                    assert_eq!(d[(x + 7 * (y + 5 * z)) as usize], e, "cell {x} {y} {z}");
                }
            }
        }
    }

    #[test]
    fn resolution_follows_density_and_stays_capped() {
        let r = resolution(Vec3::ONE, 1000, 1.0);
        assert_eq!(r, UVec3::splat(10));
        let flat = resolution(Vec3::new(10.0, 0.0, 10.0), 100, 1.0);
        assert!(flat.y >= 1 && flat.x == flat.z, "{flat}");
        let huge = resolution(Vec3::ONE, 1 << 30, 64.0);
        assert!((huge.x * huge.y * huge.z) as usize <= MAX_CELLS);
    }
}
