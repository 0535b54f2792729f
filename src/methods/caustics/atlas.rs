//! `caustic_space=texture` (survey §6.2, SKALP05): the receivers' light-map atlas. A photon
//! hit is identified by the texture coordinates of the surface point it lands on, so every
//! receiver needs coordinates that name each of its points once. The meshes' own `uvs` are
//! the materials' (tiled floors repeat them), so the atlas makes its own: each diffuse mesh
//! cut into charts (triangles joined across shared edges while their normals stay within
//! 45° of the chart's first), each chart projected orthographically along that normal in the
//! mesh's object space (so that the map moves with the object), and every chart packed on
//! shelves into one square light map at one texel size for the whole scene, `gutter` texels
//! apart so that a splat at a chart's edge never reaches its neighbour.
//!
//! The GPU reads it as `vec4`s (`CausticAtlas` in set 0): per mesh four — the world-to-object
//! transform's rows (3), then (first triangle's index as bits, the texel's area in world
//! units, 1 for a receiver, 0) — then per triangle of the scene's list four: the rows taking
//! an object-space point to light-map coordinates (u, v), the chart's rectangle in them
//! (min u, min v, max u, max v), and (the chart's normal in object space, the mesh's index as
//! bits).

use glam::{DVec3, Mat4, Vec3};

use crate::scene::{Scene, SurfaceKind};
use crate::{Error, Result};

/// Normals within this cosine of a chart's first triangle join it (45°).
const CHART_COS: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The atlas of one scene at one light-map size.
#[derive(Clone, Debug)]
pub struct Atlas {
    /// Texels along each side of the light map.
    pub size: u32,
    /// The texel's edge in object units (the same for every mesh).
    pub texel: f64,
    /// Charts packed.
    pub charts: usize,
    /// Per mesh: its first triangle in the scene's list, whether it receives, its object
    /// space (world-to-object), and its world-space texel area.
    meshes: Vec<MeshEntry>,
    /// Per triangle of the scene's list: u row, v row, chart rectangle, (chart normal, mesh).
    triangles: Vec<[[f32; 4]; 4]>,
}

#[derive(Clone, Debug)]
struct MeshEntry {
    first: u32,
    receiver: bool,
    world: Mat4,
}

/// One chart: its triangles (indices in the mesh), normal and projected bounds.
struct Chart {
    triangles: Vec<usize>,
    normal: DVec3,
    t: DVec3,
    b: DVec3,
    min: [f64; 2],
    max: [f64; 2],
}

/// The gutter between charts, in texels: a splat reaches at most `TEXTURE_SPLAT_MAX` texels
/// past its photon, the bilinear lookup one texel more, and one more for rounding.
pub fn gutter() -> u32 {
    crate::frame::layout::TEXTURE_SPLAT_MAX as u32 + 2
}

impl Atlas {
    /// Cuts and packs every diffuse mesh of `scene` into a light map of `size`² texels whose
    /// charts lie `gutter` texels apart. Refuses, naming the `light_map_size` knob, a map too
    /// small to hold the charts at one texel each.
    pub fn build(scene: &Scene, size: u32, gutter: u32) -> Result<Atlas> {
        let mut meshes = Vec::with_capacity(scene.meshes.len());
        let mut charts_of: Vec<Vec<Chart>> = Vec::with_capacity(scene.meshes.len());
        let mut first = 0u32;
        for mesh in &scene.meshes {
            let receiver = scene.materials.get(mesh.material).is_some_and(|m| m.kind == SurfaceKind::Diffuse) && !mesh.indices.is_empty();
            let to_object = object_space(mesh.world);
            let charts = if receiver {
                let positions: Vec<DVec3> = mesh.positions.iter().map(|&p| to_object.transform_point3(p).as_dvec3()).collect();
                charts(&positions, &mesh.indices)
            } else {
                Vec::new()
            };
            meshes.push(MeshEntry { first, receiver: receiver && !charts.is_empty(), world: mesh.world });
            charts_of.push(charts);
            first += (mesh.indices.len() / 3) as u32;
        }
        let all: Vec<&Chart> = charts_of.iter().flatten().collect();
        let (texel, places) = pack(&all, size, gutter)?;
        let mut triangles = vec![[[0f32; 4]; 4]; first as usize];
        let n = size as f64;
        let mut k = 0;
        for (m, charts) in charts_of.iter().enumerate() {
            for c in charts {
                let (x0, y0) = places[k];
                k += 1;
                // Texel coordinates: (dot(p, t) − min) / texel + corner, then over the size.
                let (ou, ov) = (x0 as f64 + gutter as f64, y0 as f64 + gutter as f64);
                let row = |axis: DVec3, min: f64, origin: f64| {
                    let s = axis / (texel * n);
                    [s.x as f32, s.y as f32, s.z as f32, ((origin - min / texel) / n) as f32]
                };
                let ru = row(c.t, c.min[0], ou);
                let rv = row(c.b, c.min[1], ov);
                let w = (c.max[0] - c.min[0]) / texel;
                let h = (c.max[1] - c.min[1]) / texel;
                let rect = [(ou / n) as f32, (ov / n) as f32, ((ou + w) / n) as f32, ((ov + h) / n) as f32];
                let normal = [c.normal.x as f32, c.normal.y as f32, c.normal.z as f32, f32::from_bits(m as u32)];
                for &t in &c.triangles {
                    triangles[meshes[m].first as usize + t] = [ru, rv, rect, normal];
                }
            }
        }
        Ok(Atlas { size, texel, charts: all.len(), meshes, triangles })
    }

    /// Whether mesh `m` has charts in the map.
    pub fn receives(&self, m: usize) -> bool {
        self.meshes.get(m).is_some_and(|e| e.receiver)
    }

    /// Follows the meshes' transforms (`world` of each mesh of `scene`): a moved object's
    /// chart stays on its surface.
    pub fn follow(&mut self, scene: &Scene) {
        for (e, mesh) in self.meshes.iter_mut().zip(&scene.meshes) {
            e.world = mesh.world;
        }
    }

    /// The `vec4`s of `CausticAtlas` (the module's comment), and how many lead (4 a mesh).
    pub fn gpu_words(&self) -> (Vec<[f32; 4]>, u32) {
        let mut out = self.mesh_words();
        out.reserve(4 * self.triangles.len());
        for t in &self.triangles {
            out.extend_from_slice(t);
        }
        (out, 4 * self.meshes.len() as u32)
    }

    /// The leading `vec4`s alone (four a mesh: what a move rewrites).
    pub fn mesh_words(&self) -> Vec<[f32; 4]> {
        let mut out = Vec::with_capacity(4 * self.meshes.len());
        for e in &self.meshes {
            let inv = object_space(e.world);
            let rows = inv.transpose();
            out.push(rows.x_axis.to_array());
            out.push(rows.y_axis.to_array());
            out.push(rows.z_axis.to_array());
            // The world's texel: the object's texel times the transform's scale (its
            // determinant's cube root: exact for similarity transforms).
            let scale = (e.world.determinant().abs() as f64).cbrt();
            let scale = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
            let area = (self.texel * scale).powi(2) as f32;
            out.push([f32::from_bits(e.first), area, if e.receiver { 1.0 } else { 0.0 }, 0.0]);
        }
        out
    }

    /// Bytes the GPU copy holds.
    pub fn bytes(&self) -> u64 {
        16 * 4 * (self.meshes.len() + self.triangles.len()) as u64
    }

    /// Light-map coordinates of object-space point `p` on triangle `t` (of the scene's list),
    /// clamped to its chart; `None` where the triangle is no receiver's.
    pub fn uv(&self, t: usize, p: Vec3) -> Option<[f32; 2]> {
        let [ru, rv, rect, _] = self.triangles.get(t)?;
        if rect[2] <= rect[0] {
            return None;
        }
        let u = ru[0] * p.x + ru[1] * p.y + ru[2] * p.z + ru[3];
        let v = rv[0] * p.x + rv[1] * p.y + rv[2] * p.z + rv[3];
        Some([u.clamp(rect[0], rect[2]), v.clamp(rect[1], rect[3])])
    }
}

/// The world-to-object transform of a mesh's `world` (identity where it is singular).
fn object_space(world: Mat4) -> Mat4 {
    let det = world.determinant();
    if det.is_finite() && det.abs() > 1e-30 {
        world.inverse()
    } else {
        Mat4::IDENTITY
    }
}

/// The mesh's charts: triangles flooded across shared edges (positions welded where they are
/// equal) while within `CHART_COS` of the chart's first normal. Degenerate triangles (no area,
/// or not finite) belong to no chart.
fn charts(positions: &[DVec3], indices: &[u32]) -> Vec<Chart> {
    let tris: Vec<[usize; 3]> = indices.chunks_exact(3).map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
    // Welded vertex ids: equal positions are one vertex.
    let mut weld = std::collections::HashMap::new();
    let id: Vec<usize> = positions
        .iter()
        .map(|p| {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            let next = weld.len();
            *weld.entry(key).or_insert(next)
        })
        .collect();
    let normal = |t: &[usize; 3]| {
        let n = (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
        let len = n.length();
        (len.is_finite() && len > 1e-300).then(|| n / len)
    };
    let normals: Vec<Option<DVec3>> = tris.iter().map(normal).collect();
    let mut edges: std::collections::HashMap<(usize, usize), Vec<usize>> = std::collections::HashMap::new();
    for (i, t) in tris.iter().enumerate() {
        if normals[i].is_none() {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (id[t[k]], id[t[(k + 1) % 3]]);
            edges.entry((a.min(b), a.max(b))).or_default().push(i);
        }
    }
    let mut chart_of = vec![usize::MAX; tris.len()];
    let mut out = Vec::new();
    for seed in 0..tris.len() {
        let Some(n0) = normals[seed] else { continue };
        if chart_of[seed] != usize::MAX {
            continue;
        }
        let c = out.len();
        chart_of[seed] = c;
        let mut members = vec![seed];
        let mut stack = vec![seed];
        while let Some(i) = stack.pop() {
            let t = tris[i];
            for k in 0..3 {
                let (a, b) = (id[t[k]], id[t[(k + 1) % 3]]);
                for &j in &edges[&(a.min(b), a.max(b))] {
                    if chart_of[j] == usize::MAX && normals[j].is_some_and(|n| n.dot(n0) > CHART_COS) {
                        chart_of[j] = c;
                        members.push(j);
                        stack.push(j);
                    }
                }
            }
        }
        let (t, b) = n0.any_orthonormal_pair();
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        for &i in &members {
            for &v in &tris[i] {
                let q = [positions[v].dot(t), positions[v].dot(b)];
                for a in 0..2 {
                    min[a] = min[a].min(q[a]);
                    max[a] = max[a].max(q[a]);
                }
            }
        }
        out.push(Chart { triangles: members, normal: n0, t, b, min, max });
    }
    out
}

/// Shelf packing of the charts at the smallest texel that fits them into `size`² texels with
/// `gutter` texels around each: the texel and each chart's corner (texels).
fn pack(charts: &[&Chart], size: u32, gutter: u32) -> Result<(f64, Vec<(u32, u32)>)> {
    if charts.is_empty() {
        return Ok((1.0, Vec::new()));
    }
    let extent = |c: &Chart, texel: f64| {
        let w = ((c.max[0] - c.min[0]) / texel).ceil().max(1.0) as u64 + 2 * gutter as u64;
        let h = ((c.max[1] - c.min[1]) / texel).ceil().max(1.0) as u64 + 2 * gutter as u64;
        (w, h)
    };
    let mut order: Vec<usize> = (0..charts.len()).collect();
    order.sort_by(|&a, &b| {
        let ha = charts[a].max[1] - charts[a].min[1];
        let hb = charts[b].max[1] - charts[b].min[1];
        hb.total_cmp(&ha)
    });
    let place = |texel: f64| -> Option<Vec<(u32, u32)>> {
        let mut places = vec![(0u32, 0u32); charts.len()];
        let (mut x, mut y, mut shelf) = (0u64, 0u64, 0u64);
        for &i in &order {
            let (w, h) = extent(charts[i], texel);
            if w > size as u64 {
                return None;
            }
            if x + w > size as u64 {
                x = 0;
                y += shelf;
                shelf = 0;
            }
            if y + h > size as u64 {
                return None;
            }
            places[i] = (x as u32, y as u32);
            x += w;
            shelf = shelf.max(h);
        }
        Some(places)
    };
    // Every chart at one texel plus its gutter must fit, or no texel does.
    let side = 1 + 2 * gutter as u64;
    if (charts.len() as u64) * side * side > size as u64 * size as u64 || place(f64::INFINITY).is_none() {
        return Err(Error::invalid(
            "knob light_map_size",
            format!(
                "{size}: the receivers' {} charts with their {gutter}-texel gutters do not fit in a {size}² light map (a larger light_map_size, or caustic_space=cube)",
                charts.len()
            ),
        ));
    }
    // Bisect the texel between one that fits and one that does not (the area's bound).
    let area: f64 = charts.iter().map(|c| (c.max[0] - c.min[0]) * (c.max[1] - c.min[1])).sum();
    let longest = charts.iter().map(|c| (c.max[0] - c.min[0]).max(c.max[1] - c.min[1])).fold(0.0, f64::max);
    let mut lo = (area.max(1e-300) / (size as f64 * size as f64)).sqrt().max(longest / size as f64) * 0.999;
    let mut hi = lo.max(1e-300) * 2.0;
    while place(hi).is_none() {
        lo = hi;
        hi *= 2.0;
        if !hi.is_finite() {
            return Err(Error::invalid("knob light_map_size", format!("{size}: the receivers' charts could not be packed")));
        }
    }
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        if place(mid).is_some() {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let places = place(hi).expect("the upper texel fits");
    Ok((hi, places))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{shapes, Material};

    fn scene() -> Scene {
        let mut s = Scene::default();
        let floor = s.add_material(Material { name: "floor".into(), ..Default::default() }).unwrap();
        s.add_mesh(shapes::quad("floor", Vec3::new(-2.0, 0.0, -2.0), Vec3::new(0.0, 0.0, 4.0), Vec3::new(4.0, 0.0, 0.0), 4, floor))
            .unwrap();
        s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.0, 1.0, 0.0), 0.5, 24, 12, floor)).unwrap();
        s
    }

    /// Rasterises every receiver triangle's chart coordinates on a grid of the map's texels:
    /// no texel is covered by two charts, and each chart keeps its gutter.
    #[test]
    fn charts_do_not_overlap_and_keep_their_texel() {
        let s = scene();
        let atlas = Atlas::build(&s, 256, 3).unwrap();
        assert!(atlas.receives(0) && atlas.receives(1));
        // A flat floor is one chart; the sphere's are cut where normals turn 45°.
        let (words, lead) = atlas.gpu_words();
        assert_eq!(lead, 8);
        let rect = |t: usize| words[lead as usize + 4 * t + 2];
        let floor_rects: std::collections::HashSet<[u32; 4]> = (0..32).map(|t| rect(t).map(f32::to_bits)).collect();
        assert_eq!(floor_rects.len(), 1, "the floor is one chart");
        let mut rects: Vec<[f32; 4]> = (0..s.triangle_count()).map(rect).collect();
        rects.sort_by(|a, b| a.partial_cmp(b).unwrap());
        rects.dedup();
        assert_eq!(rects.len(), atlas.charts);
        let g = 3.0 / 256.0;
        for (i, a) in rects.iter().enumerate() {
            assert!(a.iter().all(|&x| (0.0..=1.0).contains(&x)), "{a:?} inside the map");
            for b in &rects[i + 1..] {
                let apart = a[2] + g <= b[0] || b[2] + g <= a[0] || a[3] + g <= b[1] || b[3] + g <= a[1];
                assert!(apart, "charts {a:?} and {b:?} closer than their gutter");
            }
        }
        // Every vertex maps into its own chart, and a texel is one size everywhere: the
        // floor's 4 m edge spans 4 / texel texels.
        for (t, tri) in s.meshes[1].indices.chunks_exact(3).enumerate() {
            for &v in tri {
                let [u, w] = atlas.uv(32 + t, s.meshes[1].positions[v as usize]).unwrap();
                let r = rect(32 + t);
                assert!(u >= r[0] - 1e-6 && u <= r[2] + 1e-6 && w >= r[1] - 1e-6 && w <= r[3] + 1e-6);
            }
        }
        let r = rect(0);
        assert!(((r[2] - r[0]) as f64 * 256.0 - 4.0 / atlas.texel).abs() < 1e-3);
    }

    /// Degenerate triangles get no chart; a map too small for the charts is refused by name.
    #[test]
    fn degenerate_triangles_and_small_maps() {
        let mut s = scene();
        let m = s.meshes[0].material;
        let mut flat = shapes::quad("sliver", Vec3::ZERO, Vec3::X, Vec3::X * 2.0, 1, m);
        flat.normals = vec![Vec3::Y; flat.positions.len()];
        s.add_mesh(flat).unwrap();
        let atlas = Atlas::build(&s, 256, 3).unwrap();
        assert!(!atlas.receives(2), "a mesh of degenerate triangles has no chart");
        assert!(atlas.uv(s.triangle_count() - 1, Vec3::ZERO).is_none());
        let e = Atlas::build(&s, 16, 3).unwrap_err().to_string();
        assert!(e.contains("light_map_size") && e.contains("16"), "{e}");
    }
}
