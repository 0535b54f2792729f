//! Writes the demo scene `assets/demo/demo.gltf` (+ `demo.bin` and one PNG per wall):
//! a closed 4 m × 3 m × 4 m box room with a textured diffuse material per wall, a mirror
//! sphere, a solid glass sphere, a small diffuse box, a point light and a camera.
//!
//! Every wall texture carries a checkerboard, a diagonal band and a large "F", so that a
//! mirrored or transposed reflection is obvious at a glance.
//!
//! Run: `cargo run --example make_demo_scene [-- OUTPUT_DIR]` (default `assets/demo`).
//! The output is deterministic and committed; the example reloads it through
//! `specula::scene::load` and checks the material classification.
//!
//! `cargo run --example make_demo_scene -- --mirrors [OUTPUT_DIR]` writes the planar-mirror
//! scene `assets/mirrors/mirrors.gltf` instead (survey §5's showcase): the same room with
//! two facing mirror panels on the left and right walls (the corridor of images), the
//! mirror sphere between them, the box and the light, no animation.
//!
//! `cargo run --example make_demo_scene -- --bunny BUNNY_JS [OUTPUT_DIR]` writes the glass
//! bunny scene `assets/bunny/bunny.gltf` (issue 31's first scene): the same room and light
//! with the Stanford bunny (Stanford 3D Scanning Repository; the closed 1839-vertex,
//! 3674-triangle mesh of npm's public-domain `bunny` package, whose `index.js` is BUNNY_JS)
//! in solid glass of ν 1.5, 0.7 m tall on the floor, and the box: a non-convex refractor
//! whose refracted rays meet it several times.

use std::path::PathBuf;

use glam::{Mat4, Quat, Vec2, Vec3};
use serde_json::{json, Value};
use specula::scene::SurfaceKind;

const TEXTURE_SIZE: u32 = 256;
const WALL_QUADS: usize = 8;

struct Geometry {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    indices: Vec<u32>,
}

impl Geometry {
    fn new() -> Geometry {
        Geometry { positions: Vec::new(), normals: Vec::new(), uvs: Vec::new(), indices: Vec::new() }
    }

    /// Adds triangle (a, b, c), wound counter-clockwise as seen from the side its vertex
    /// normals point to; degenerate triangles are dropped.
    fn triangle(&mut self, a: u32, b: u32, c: u32) {
        let p = |i: u32| self.positions[i as usize];
        let face = (p(b) - p(a)).cross(p(c) - p(a));
        if face.length_squared() < 1e-14 {
            return;
        }
        let n = self.normals[a as usize] + self.normals[b as usize] + self.normals[c as usize];
        if face.dot(n) >= 0.0 {
            self.indices.extend([a, b, c]);
        } else {
            self.indices.extend([a, c, b]);
        }
    }

    /// A grid of `cols × rows` quads; `vertex(i, j)` gives position, normal and uv.
    fn grid(&mut self, cols: usize, rows: usize, vertex: impl Fn(usize, usize) -> (Vec3, Vec3, Vec2)) {
        let first = self.positions.len() as u32;
        for j in 0..=rows {
            for i in 0..=cols {
                let (p, n, t) = vertex(i, j);
                self.positions.push(p);
                self.normals.push(n);
                self.uvs.push(t);
            }
        }
        let at = |i: usize, j: usize| first + (j * (cols + 1) + i) as u32;
        for j in 0..rows {
            for i in 0..cols {
                self.triangle(at(i, j), at(i + 1, j), at(i + 1, j + 1));
                self.triangle(at(i, j), at(i + 1, j + 1), at(i, j + 1));
            }
        }
    }
}

/// A rectangle centred at `center`, spanned by `right` × half_w and `up` × half_h, facing
/// `right × up`; the texture appears upright and unmirrored when seen from that side.
fn wall(center: Vec3, right: Vec3, up: Vec3, half_w: f32, half_h: f32) -> Geometry {
    let normal = right.cross(up).normalize();
    let mut g = Geometry::new();
    g.grid(WALL_QUADS, WALL_QUADS, |i, j| {
        let s = i as f32 / WALL_QUADS as f32; // 0..1 along right
        let t = j as f32 / WALL_QUADS as f32; // 0..1 downwards
        let p = center + right * (half_w * (2.0 * s - 1.0)) + up * (half_h * (1.0 - 2.0 * t));
        (p, normal, Vec2::new(s, t))
    });
    g
}

/// UV sphere centred at the origin with analytic normals.
fn sphere(radius: f32, segments: usize, rings: usize) -> Geometry {
    let mut g = Geometry::new();
    g.grid(segments, rings, |i, j| {
        let phi = std::f32::consts::TAU * i as f32 / segments as f32;
        let theta = std::f32::consts::PI * j as f32 / rings as f32;
        let n = Vec3::new(theta.sin() * phi.sin(), theta.cos(), theta.sin() * phi.cos());
        (n * radius, n, Vec2::new(i as f32 / segments as f32, j as f32 / rings as f32))
    });
    g
}

/// Axis-aligned cube of edge `size` centred at the origin, flat-shaded.
fn cube(size: f32) -> Geometry {
    let h = size * 0.5;
    let mut g = Geometry::new();
    for (n, right, up) in [
        (Vec3::X, Vec3::NEG_Z, Vec3::Y),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::X, Vec3::NEG_Z),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
    ] {
        let base = g.positions.len() as u32;
        for (s, t) in [(-1.0, 1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
            g.positions.push(n * h + right * (h * s) + up * (h * t));
            g.normals.push(n);
            g.uvs.push(Vec2::new((s + 1.0) * 0.5, (1.0 - t) * 0.5));
        }
        g.triangle(base, base + 1, base + 2);
        g.triangle(base, base + 2, base + 3);
    }
    g
}

/// Checkerboard in two shades of `hue`, a light diagonal band and a dark "F".
fn wall_texture(hue: [u8; 3]) -> image::RgbaImage {
    let shade = |k: f32| -> image::Rgba<u8> {
        let c = hue.map(|v| (v as f32 * k).round().clamp(0.0, 255.0) as u8);
        image::Rgba([c[0], c[1], c[2], 255])
    };
    let tint = |w: f32| -> image::Rgba<u8> {
        let c = hue.map(|v| (v as f32 + (255.0 - v as f32) * w).round() as u8);
        image::Rgba([c[0], c[1], c[2], 255])
    };
    image::RgbaImage::from_fn(TEXTURE_SIZE, TEXTURE_SIZE, |x, y| {
        let (xi, yi) = (x as i32, y as i32);
        let in_rect = |x0: i32, y0: i32, x1: i32, y1: i32| xi >= x0 && xi < x1 && yi >= y0 && yi < y1;
        // "F": stem, top bar, middle bar (asymmetric under every flip and transpose).
        if in_rect(56, 40, 88, 216) || in_rect(56, 40, 184, 72) || in_rect(56, 112, 152, 144) {
            return shade(0.22);
        }
        if (xi - yi).abs() < 12 {
            return tint(0.6);
        }
        if ((x / 32) + (y / 32)) % 2 == 0 {
            shade(1.0)
        } else {
            shade(0.72)
        }
    })
}

/// Binary buffer with one buffer view per accessor.
struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    /// A buffer view of `bytes`; target 0: none (animation data).
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        let mut v = json!({ "buffer": 0, "byteOffset": self.data.len(), "byteLength": bytes.len() });
        if target != 0 {
            v["target"] = json!(target);
        }
        self.views.push(v);
        self.data.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// Float keys or values of an animation sampler (SCALAR or VEC3); inputs get min/max.
    fn animation_accessor(&mut self, values: &[f32], dims: usize) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, 0);
        let mut acc = json!({
            "bufferView": view, "componentType": 5126, "count": values.len() / dims,
            "type": if dims == 1 { "SCALAR" } else { "VEC3" }
        });
        if dims == 1 {
            acc["min"] = json!([values.iter().copied().fold(f32::INFINITY, f32::min)]);
            acc["max"] = json!([values.iter().copied().fold(f32::NEG_INFINITY, f32::max)]);
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    fn vec_accessor(&mut self, values: &[f32], dims: usize, bounds: bool) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, 34962);
        let mut acc = json!({
            "bufferView": view, "componentType": 5126, "count": values.len() / dims,
            "type": if dims == 3 { "VEC3" } else { "VEC2" }
        });
        if bounds {
            let (mut lo, mut hi) = (vec![f32::INFINITY; dims], vec![f32::NEG_INFINITY; dims]);
            for c in values.chunks_exact(dims) {
                for k in 0..dims {
                    lo[k] = lo[k].min(c[k]);
                    hi[k] = hi[k].max(c[k]);
                }
            }
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    fn primitive(&mut self, g: &Geometry, material: usize) -> Value {
        let flat3 = |v: &[Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
        let pos = self.vec_accessor(&flat3(&g.positions), 3, true);
        let nrm = self.vec_accessor(&flat3(&g.normals), 3, false);
        let uv = self.vec_accessor(&g.uvs.iter().flat_map(|t| t.to_array()).collect::<Vec<f32>>(), 2, false);
        assert!(g.positions.len() <= u16::MAX as usize);
        let bytes: Vec<u8> = g.indices.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect();
        let view = self.view(&bytes, 34963);
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5123, "count": g.indices.len(), "type": "SCALAR"
        }));
        json!({
            "attributes": { "POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv },
            "indices": self.accessors.len() - 1,
            "material": material,
        })
    }
}

/// κ of a conductor with index `nu` whose normal-incidence reflectance is `f0`.
fn kappa_for(f0: f32, nu: f32) -> f32 {
    ((f0 * (nu + 1.0).powi(2) - (nu - 1.0).powi(2)) / (1.0 - f0)).max(0.0).sqrt()
}

/// Solid clear glass of ν 1.5 (KHR_materials_transmission, _ior, _volume with `thickness`).
fn glass_material(thickness: f64) -> Value {
    json!({
        "name": "glass",
        "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.0 },
        "extensions": {
            "KHR_materials_transmission": { "transmissionFactor": 1.0 },
            "KHR_materials_ior": { "ior": 1.5 },
            "KHR_materials_volume": { "thicknessFactor": thickness }
        }
    })
}

/// The bunny of npm's `bunny` package (`exports.positions=[[x,y,z],…];exports.cells=[[a,b,c],…]`)
/// scaled to `height` (m), standing at `base` (the centre of its foot print), with
/// area-weighted vertex normals.
fn bunny(source: &str, height: f32, base: Vec3) -> Geometry {
    let array = |key: &str| -> Value {
        let start = source.find(key).unwrap_or_else(|| panic!("{key} not in the bunny source")) + key.len();
        let end = start + source[start..].find("]]").expect("a closed array") + 2;
        serde_json::from_str(&source[start..end]).expect("the bunny's arrays are JSON")
    };
    let positions: Vec<Vec3> = array("exports.positions=")
        .as_array()
        .unwrap()
        .iter()
        .map(|p| Vec3::new(p[0].as_f64().unwrap() as f32, p[1].as_f64().unwrap() as f32, p[2].as_f64().unwrap() as f32))
        .collect();
    let (min, max) = positions.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(a, b), &p| (a.min(p), b.max(p)));
    let scale = height / (max.y - min.y);
    let foot = Vec3::new(0.5 * (min.x + max.x), min.y, 0.5 * (min.z + max.z));
    let mut g = Geometry::new();
    g.positions = positions.iter().map(|&p| base + (p - foot) * scale).collect();
    g.uvs = vec![Vec2::ZERO; g.positions.len()];
    let mut normals = vec![Vec3::ZERO; g.positions.len()];
    for t in array("exports.cells=").as_array().unwrap() {
        let [a, b, c] = [0, 1, 2].map(|k| t[k].as_u64().unwrap() as u32);
        let [pa, pb, pc] = [a, b, c].map(|i| g.positions[i as usize]);
        let n = (pb - pa).cross(pc - pa);
        [a, b, c].iter().for_each(|&i| normals[i as usize] += n);
        g.indices.extend([a, b, c]);
    }
    g.normals = normals.iter().map(|n| n.normalize_or_zero()).collect();
    g
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mirrors_scene = args.first().is_some_and(|a| a == "--mirrors");
    if mirrors_scene {
        args.remove(0);
    }
    let bunny_source = if args.first().is_some_and(|a| a == "--bunny") {
        args.remove(0);
        let path = args.remove(0);
        Some(std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("reading the bunny source {path}: {e}")))
    } else {
        None
    };
    let bunny_scene = bunny_source.is_some();
    let (default_dir, stem) = match (mirrors_scene, bunny_scene) {
        (true, _) => ("assets/mirrors", "mirrors"),
        (_, true) => ("assets/bunny", "bunny"),
        _ => ("assets/demo", "demo"),
    };
    let out = args.first().map(PathBuf::from).unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(default_dir));
    std::fs::create_dir_all(&out).expect("create output directory");

    let mut bin = Bin { data: Vec::new(), views: Vec::new(), accessors: Vec::new() };
    let mut materials = Vec::new();
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    let mut images = Vec::new();

    // The room: x ∈ [−2, 2], y ∈ [0, 3], z ∈ [−2, 2], every wall facing inwards.
    let walls = [
        ("floor", [196, 148, 96], Vec3::new(0.0, 0.0, 0.0), Vec3::X, Vec3::NEG_Z, 2.0, 2.0),
        ("ceiling", [226, 222, 196], Vec3::new(0.0, 3.0, 0.0), Vec3::X, Vec3::Z, 2.0, 2.0),
        ("back", [72, 112, 204], Vec3::new(0.0, 1.5, -2.0), Vec3::X, Vec3::Y, 2.0, 1.5),
        ("front", [92, 172, 92], Vec3::new(0.0, 1.5, 2.0), Vec3::NEG_X, Vec3::Y, 2.0, 1.5),
        ("left", [204, 72, 60], Vec3::new(-2.0, 1.5, 0.0), Vec3::NEG_Z, Vec3::Y, 2.0, 1.5),
        ("right", [152, 92, 196], Vec3::new(2.0, 1.5, 0.0), Vec3::Z, Vec3::Y, 2.0, 1.5),
    ];
    let mut wall_nodes = Vec::new();
    for (name, hue, center, right, up, hw, hh) in walls {
        let file = format!("wall_{name}.png");
        wall_texture(hue).save(out.join(&file)).expect("write wall texture");
        images.push(json!({ "uri": file, "name": format!("wall_{name}") }));
        let texture = images.len() - 1;
        materials.push(json!({
            "name": format!("wall_{name}"),
            "pbrMetallicRoughness": {
                "baseColorTexture": { "index": texture },
                "metallicFactor": 0.0, "roughnessFactor": 1.0
            }
        }));
        let g = wall(center, right, up, hw, hh);
        let prim = bin.primitive(&g, materials.len() - 1);
        meshes.push(json!({ "name": format!("wall_{name}"), "primitives": [prim] }));
        nodes.push(json!({ "name": format!("wall_{name}"), "mesh": meshes.len() - 1 }));
        wall_nodes.push(nodes.len() - 1);
    }
    nodes.push(json!({ "name": "room", "children": wall_nodes }));
    let room = nodes.len() - 1;

    // Mirror sphere (not in the bunny scene): silver-like ν with κ chosen so that F0 equals
    // the base colour.
    let mirror = (!bunny_scene).then(|| {
        let f0 = [0.95f32, 0.93, 0.88];
        let nu = [0.155f32, 0.117, 0.138];
        let kappa: Vec<f32> = (0..3).map(|c| kappa_for(f0[c], nu[c])).collect();
        materials.push(json!({
            "name": "mirror",
            "pbrMetallicRoughness": {
                "baseColorFactor": [f0[0], f0[1], f0[2], 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0
            },
            "extras": { "specula": { "nu": nu, "kappa": kappa } }
        }));
        let prim = bin.primitive(&sphere(0.5, 64, 32), materials.len() - 1);
        meshes.push(json!({ "name": "mirror_sphere", "primitives": [prim] }));
        let sphere_at = if mirrors_scene { [-0.3, 0.5, -0.9] } else { [-1.2, 0.5, -1.1] };
        nodes.push(json!({ "name": "mirror_sphere", "mesh": meshes.len() - 1, "translation": sphere_at }));
        nodes.len() - 1
    });

    // The glass bunny scene: the bunny alone in the room.
    let mut bunny_node = Vec::new();
    if let Some(source) = &bunny_source {
        materials.push(glass_material(0.3));
        let prim = bin.primitive(&bunny(source, 0.7, Vec3::new(0.0, 0.0, -0.3)), materials.len() - 1);
        meshes.push(json!({ "name": "bunny", "primitives": [prim] }));
        nodes.push(json!({ "name": "bunny", "mesh": meshes.len() - 1 }));
        bunny_node.push(nodes.len() - 1);
    }

    // The planar-mirror scene: two facing panels 2 cm off the left and right walls, a plain
    // (κ = 0) mirror of F0 0.9.
    let mut panels = Vec::new();
    if mirrors_scene {
        materials.push(json!({
            "name": "panel",
            "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0 }
        }));
        let panel_material = materials.len() - 1;
        for (name, x, right) in [("panel_left", -1.98f32, Vec3::NEG_Z), ("panel_right", 1.98, Vec3::Z)] {
            let g = wall(Vec3::new(x, 1.5, 0.0), right, Vec3::Y, 1.6, 1.2);
            let prim = bin.primitive(&g, panel_material);
            meshes.push(json!({ "name": name, "primitives": [prim] }));
            nodes.push(json!({ "name": name, "mesh": meshes.len() - 1 }));
            panels.push(nodes.len() - 1);
        }
    }

    // Solid glass sphere (the demo only: the mirror scene shows planar mirrors, spheres
    // and the box).
    let mut glass = Vec::new();
    if !mirrors_scene && !bunny_scene {
        materials.push(glass_material(0.6));
        let prim = bin.primitive(&sphere(0.45, 64, 32), materials.len() - 1);
        meshes.push(json!({ "name": "glass_sphere", "primitives": [prim] }));
        nodes.push(json!({ "name": "glass_sphere", "mesh": meshes.len() - 1, "translation": [0.9, 0.45, -0.3] }));
        glass.push(nodes.len() - 1);
    }

    // Occluder: a light grey 0.5 m box standing on the floor, turned 20° about +Y.
    materials.push(json!({
        "name": "box",
        "pbrMetallicRoughness": { "baseColorFactor": [0.7, 0.7, 0.7, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8 }
    }));
    let prim = bin.primitive(&cube(0.5), materials.len() - 1);
    meshes.push(json!({ "name": "box", "primitives": [prim] }));
    let q = Quat::from_rotation_y(20f32.to_radians());
    nodes.push(json!({ "name": "box", "mesh": meshes.len() - 1, "translation": [0.2, 0.25, 0.8], "rotation": q.to_array() }));
    let occluder = nodes.len() - 1;

    nodes.push(json!({
        "name": "light", "translation": [0.0, 1.6, 0.0],
        "extensions": { "KHR_lights_punctual": { "light": 0 } }
    }));
    let light = nodes.len() - 1;

    let (eye, target) = if mirrors_scene {
        (Vec3::new(1.2, 1.7, 1.9), Vec3::new(-1.98, 1.2, -0.4))
    } else if bunny_scene {
        (Vec3::new(0.55, 0.62, 0.5), Vec3::new(0.0, 0.3, -0.3))
    } else {
        (Vec3::new(1.6, 1.6, 1.9), Vec3::new(-0.3, 0.8, -0.6))
    };
    let world_from_camera = Mat4::look_at_rh(eye, target, Vec3::Y).inverse();
    let (_, rotation, _) = world_from_camera.to_scale_rotation_translation();
    nodes.push(json!({ "name": "camera", "camera": 0, "translation": eye.to_array(), "rotation": rotation.normalize().to_array() }));
    let camera = nodes.len() - 1;

    // The mirror sphere's path (LINEAR, 4 s, a closed loop through its static place): it
    // moves past the glass sphere, so that `specula animate` shows maps following it.
    let times = [0.0f32, 1.5, 3.0, 4.0];
    let path = [Vec3::new(-1.2, 0.5, -1.1), Vec3::new(-1.2, 0.5, -0.2), Vec3::new(-0.5, 0.5, -0.6), Vec3::new(-1.2, 0.5, -1.1)];
    let input = bin.animation_accessor(&times, 1);
    let output = bin.animation_accessor(&path.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>(), 3);
    let animations = json!([{
        "name": "mirror_path",
        "channels": [{ "sampler": 0, "target": { "node": mirror.unwrap_or(0), "path": "translation" } }],
        "samplers": [{ "input": input, "output": output, "interpolation": "LINEAR" }],
    }]);

    let bin_name = format!("{stem}.bin");
    let mut scene_nodes = vec![room];
    scene_nodes.extend(mirror);
    scene_nodes.extend(bunny_node);
    scene_nodes.extend(glass);
    scene_nodes.extend(panels);
    scene_nodes.extend([occluder, light, camera]);
    // 6.5 candela at 1.6 m, the room's middle: no diffuse texel can exceed radiance 1 in any
    // view (I · albedo / (π d²) ≤ 0.95: the ceiling's brightest texel 1.4 m above the light
    // bounds it, the box's top 1.1 m below next), so a PNG clips nothing but a caustic's
    // focus (issue 15; 25 cd at 2.6 m clipped the box, the near walls and, reflected in the
    // mirror, the ceiling above the light at radiance 11). tests/showcase.rs checks it.
    let doc = json!({
        "asset": { "version": "2.0", "generator": "specula examples/make_demo_scene.rs" },
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"],
        "extensions": {
            "KHR_lights_punctual": { "lights": [{ "name": "light", "type": "point", "color": [1.0, 1.0, 1.0], "intensity": 6.5 }] }
        },
        "scene": 0,
        "scenes": [{ "name": stem, "nodes": scene_nodes }],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "samplers": [{ "magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497 }],
        "textures": (0..images.len()).map(|i| json!({ "sampler": 0, "source": i })).collect::<Vec<_>>(),
        "images": images,
        "cameras": [{
            "name": "camera", "type": "perspective",
            "perspective": { "yfov": 60f32.to_radians(), "znear": 0.05, "zfar": 100.0, "aspectRatio": 1.5 }
        }],
        "buffers": [{ "uri": bin_name, "byteLength": bin.data.len() }],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    let mut doc = doc;
    if !mirrors_scene && !bunny_scene {
        doc["animations"] = animations;
    }
    std::fs::write(out.join(&bin_name), &bin.data).expect("write the .bin");
    let gltf_path = out.join(format!("{stem}.gltf"));
    std::fs::write(&gltf_path, serde_json::to_string_pretty(&doc).unwrap() + "\n").expect("write demo.gltf");

    // Read it back through the importer.
    let scene = specula::scene::load(&gltf_path).unwrap_or_else(|e| panic!("reloading the demo scene: {e}"));
    let count = |f: &dyn Fn(&SurfaceKind) -> bool| scene.materials.iter().filter(|m| f(&m.kind)).count();
    let diffuse = count(&|k| *k == SurfaceKind::Diffuse);
    let mirrors = count(&|k| matches!(k, SurfaceKind::Mirror { .. }));
    let solids = count(&|k| matches!(k, SurfaceKind::Dielectric { thin: false, .. }));
    if mirrors_scene {
        assert_eq!((diffuse, mirrors, solids), (7, 2, 0), "mirror scene classification");
        assert!(scene.animation.is_none());
    } else if bunny_scene {
        let specular: Vec<String> = scene.specular_meshes().map(|(_, m)| m.name.clone()).collect();
        assert_eq!((diffuse, solids, specular), (7, 1, vec!["bunny/0".to_string()]), "bunny scene classification");
        assert!(scene.animation.is_none());
    } else {
        assert_eq!((diffuse, mirrors, solids, scene.materials.len()), (7, 1, 1, 9), "demo classification");
        assert_eq!(scene.animation.as_ref().map(|a| a.duration), Some(4.0), "the mirror sphere's path");
    }
    assert!(scene.camera.is_some() && scene.lights.len() == 1 && scene.textures.len() == 6);
    println!(
        "wrote {} ({} meshes, {} triangles, {} materials: {diffuse} diffuse, {mirrors} mirror, {solids} solid dielectric; {} textures, {} light)",
        gltf_path.display(),
        scene.meshes.len(),
        scene.triangle_count(),
        scene.materials.len(),
        scene.textures.len(),
        scene.lights.len()
    );
}
