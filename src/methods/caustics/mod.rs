//! Caustics (survey §6): light focused by specular objects onto diffuse surfaces. They are
//! an effect added to whatever method renders the camera view: the plan gets one caustics
//! stage over every *generator* (a specular object that a punctual light sees) and its
//! lights, and every pass that shades diffuse surfaces projects the result
//! (glsl/caustics/project.glsl, called by `shade_diffuse`), so caustics appear in the
//! camera, in mirrors and through glass.
//!
//! Per generator, around its reference point:
//! - `caustics.receivers`: the receiver distance map, everything but the generator;
//! - `caustics.photons`: per light a photon hit location image (the generator seen from the
//!   light through its bounding cone, a cube of six views when the light is inside that
//!   cone's sphere, an orthographic view for a directional light), each texel a photon
//!   traced through the generator in the sampled geometry to its terminal hit;
//! - `caustics.splat` (photon splatting, §6.3.1) or `caustics.triangles` (§6.3.2): the
//!   photons into the light cube map, radiant intensity seen from the reference point;
//! - `caustics.filter`: a box filter over the light cube map (`caustic_filter` > 0);
//! - or, `caustics=photon-map` (§6.1.1, PDC03), `caustics.photon_map`: instead of light cube
//!   maps, every photon sorted into a hashed uniform grid on the GPU (count, scan, scatter:
//!   glsl/caustics/grid*.comp), from which the camera's diffuse surfaces and the ray
//!   tracers' diffuse hits gather their `photon_k` nearest (glsl/caustics/photon_map.glsl,
//!   in the `CAUSTICS_PHOTON_MAP` variants of caustics/project.frag and raytrace/shade.comp
//!   only: its lists in every diffuse shader slowed every method on lavapipe);
//! - or, `caustic_space=screen` (§6.2, LC04/WD06b), `caustics.screen`: the splats drawn
//!   straight into a camera-sized irradiance image, depth-tested against the camera's depth
//!   of everything; only the camera's own diffuse surfaces read it (no light cube maps).

pub mod atlas;
pub mod knobs;
pub mod project;
pub mod reach;
pub mod slots;
pub mod stage;

use glam::{Mat4, Vec3};

use crate::cube::face_view_proj;
use crate::frame::stage::{order, Deps, EffectInfo, FramePart, Maps, StageInit, ViewFrame};
use crate::frame::views::view;
use crate::quality::{CubeKnobs, DistanceKnobs, FrameKnobs, SearchKnobs};
use crate::vk::Context;
use crate::Result;

use crate::gpu_scene::{GpuLight, GpuView};
use crate::methods::registry::Family;
use crate::plan::types::{CausticCube, CausticsPlan, Generator, LightViews, ObjectPlan, Plan, PlanStages};
use crate::quality::{CausticPaths, CausticSpace, Caustics, Quality};
use crate::scene::{LightKind, Scene};

impl CausticsPlan {
    /// Where cube `c` is this frame: its light's position, or its generator's reference point.
    pub fn centre(&self, c: usize, lights: &[GpuLight]) -> Vec3 {
        let cube = &self.cubes[c];
        match cube.light {
            Some(l) => Vec3::from_slice(&lights[l].position_range[..3]),
            None => self.generators[cube.generator].reference_point,
        }
    }

    /// Where cube `c` is in `scene`: its light's position, or its generator's reference point
    /// (`centre`, from the scene's lights rather than the frame's table).
    pub fn scene_centre(&self, c: usize, scene: &Scene) -> Vec3 {
        let cube = &self.cubes[c];
        cube.light.map_or(self.generators[cube.generator].reference_point, |l| scene.lights[l].position)
    }

    /// The profiled passes it records, in order.
    pub fn passes(&self, q: &Quality) -> Vec<&'static str> {
        let mut v = vec!["caustics.receivers", "caustics.photons"];
        if self.tracks_reach(q) {
            v.push("caustics.reach");
        }
        v.push(match self.filter {
            _ if self.space == CausticSpace::Screen => "caustics.screen",
            _ if self.space == CausticSpace::Texture => "caustics.light_map",
            Caustics::Splat => "caustics.splat",
            Caustics::PhotonMap => "caustics.photon_map",
            _ => "caustics.triangles",
        });
        if self.light_cubes() && q.caustics.caustic_filter > 0 {
            v.push("caustics.filter");
        }
        v
    }

    /// Whether it records where the photons went (`caustics.reach`, issue 33 item 4): not for
    /// exact photons, which bounce off every specular surface (any move may reach them), nor
    /// under a search of fewer than 3 linear steps, whose probes near a hit are not bounded
    /// (caustics/reach.comp), nor without the projection's distance test (the light then falls
    /// on whatever lies in its directions, near or far); nor under `map_updates=always`, which
    /// redoes every generator every frame anyway.
    pub fn tracks_reach(&self, q: &Quality) -> bool {
        !q.frame.map_updates_always
            && q.caustics.caustic_paths != CausticPaths::Exact
            && q.search.linear_steps >= 3
            && q.caustics.caustic_distance_test
    }

    /// Whether the maps around objects show these caustics (light cube maps and the texture
    /// space's light map; the photon map's gather and the screen's splats are the camera's
    /// alone).
    pub fn shown_in_maps(&self) -> bool {
        self.light_cubes() || self.space == CausticSpace::Texture
    }

    /// Whether it keeps light cube maps (splats and caustic triangles go there; the photon
    /// map's gather reads the photons themselves, screen space splats into the camera's view,
    /// texture space into the receivers' light map).
    pub fn light_cubes(&self) -> bool {
        self.filter != Caustics::PhotonMap && !matches!(self.space, CausticSpace::Screen | CausticSpace::Texture)
    }

    /// Every photon of every layer (photons² a layer): what `caustics.photons` traces, and
    /// with caustics=photon-map what the grid sorts.
    pub fn photon_count(&self, q: &Quality) -> u64 {
        self.photon_layers as u64 * (q.caustics.photons as u64).pow(2)
    }

    /// What it does as the cost model counts it ([`photon_work`]): photons traced, and
    /// texels of its caustic cubes (six faces of `cube_size`² each).
    pub fn work(&self, q: &Quality) -> (f64, f64) {
        (self.photon_count(q) as f64, self.cubes.len() as f64 * 6.0 * (q.cube.cube_size as f64).powi(2))
    }

    /// caustics=photon-map: the photon grid's buckets, the power of two at or above the
    /// photons' count (a load factor of at most 1).
    pub fn grid_cells(&self, q: &Quality) -> u32 {
        (self.photon_count(q).max(256).next_power_of_two()).min(1 << 30) as u32
    }
}

/// Caustics are an effect over whatever methods render the objects: planned for the whole
/// frame, with two effect stages, and views of their own.
pub const FAMILY: Family = Family {
    name: "caustics",
    slots: slots::SLOTS,
    methods: &[],
    effects: &[STAGE, PROJECT],
    plan_frame: Some(|scene, p| p.caustics = plan(scene, &p.objects, &p.quality)),
    plan_stages: Some(plan_stages),
    views: Some(|p| {
        p.caustics.as_ref().map_or_else(Vec::new, |c| vec![(CUBE_VIEWS, 6 * c.cubes.len() as u32), (PHOTON_VIEWS, c.photon_layers)])
    }),
    refresh: Some(refresh),
    describe: Some(|p, scene| p.caustics.as_ref().map(|c| describe(c, &p.quality, scene))),
    frame_part: Some(create_frame_part),
    ..Family::NONE
};

/// The view blocks of the caustic cubes (six faces each, in `CausticsPlan::cubes` order) and
/// of the photon images (one view per layer).
pub const CUBE_VIEWS: &str = "caustics.cube_views";
pub const PHOTON_VIEWS: &str = "caustics.photon_views";

/// The pass of the refractor maps (§4.4) that solid generators' photons exit through.
const REFRACTOR_MAP: &str = "refractor.generate";

/// Caustics' stages: generators that a light sees; a solid dielectric among them needs its
/// refractor map for the photons' paths inside it, whatever its own method (but with
/// caustic_paths=surface, where they do not leave it).
fn plan_stages(scene: &Scene, p: &mut Plan, st: &mut PlanStages) {
    let Some(c) = p.caustics.clone() else { return };
    let refractor = crate::methods::registry::map_named(REFRACTOR_MAP).expect("a registered method makes refractor maps");
    let q = p.quality.clone();
    for g in &c.generators {
        let solid =
            matches!(scene.materials[scene.meshes[g.mesh].material].kind, crate::scene::SurfaceKind::Dielectric { thin: false, .. });
        let o = p.objects.iter_mut().find(|o| o.mesh == g.mesh).expect("generator is a planned object");
        // Surface paths (§6.4) never leave the generator: no refractor map.
        if solid && q.caustics.caustic_paths != CausticPaths::Surface {
            st.add_map(o, refractor.kind(), (refractor.describe)(&q, (0, 0)) + " for its caustics");
        }
    }
    let generators: Vec<usize> = c.generators.iter().map(|g| g.mesh).collect();
    // Screen space splats into the camera's view: the camera's moves redo it.
    let stage = if c.space == CausticSpace::Screen { EffectInfo { deps: Deps::LitView, ..STAGE } } else { STAGE };
    st.stages.push(stage.stage(p, generators.clone()));
    // A whole-scene ray tracer shades every pixel itself (its kernel projects them).
    if !st.shades_scene {
        st.stages.push(PROJECT.stage(p, generators));
    }
    for o in &mut p.objects {
        if c.generators.iter().any(|g| g.mesh == o.mesh) {
            o.passes.extend(c.passes(&q));
            if !st.shades_scene {
                o.passes.push(PROJECT.name);
            }
        }
    }
}

/// The caustics stage (§6): receiver maps, photons, light cube maps, their filter.
pub const STAGE: EffectInfo = EffectInfo {
    name: "caustics",
    order: order::CAUSTICS,
    deps: Deps::LitObjects,
    create: stage::CausticsStage::create,
    passes: |p| p.caustics.as_ref().map_or_else(Vec::new, |c| c.passes(&p.quality)),
};

/// `caustics.project` (§6.3.3): the caustics on the camera's diffuse surfaces, a pass of its
/// own so that its cost is profiled.
pub const PROJECT: EffectInfo = EffectInfo {
    name: "caustics.project",
    order: order::CAUSTICS_PROJECT,
    deps: Deps::EveryFrame,
    create: |init, _| project::CausticsProject::create(init),
    passes: |_| vec!["caustics.project"],
};

/// The caustics' part of a frame: the views of their cubes (around each generator's
/// reference point, or its light) and of their photon images, written every frame.
struct CausticViews;

/// `registry::Family::frame_part` of the caustics.
pub fn create_frame_part(init: &StageInit, _maps: &mut Maps) -> Result<Option<Box<dyn FramePart>>> {
    Ok(init.plan.caustics.as_ref().map(|_| Box::new(CausticViews) as Box<dyn FramePart>))
}

impl FramePart for CausticViews {
    fn write_views(&mut self, fr: &ViewFrame, table: &mut [GpuView]) {
        let Some(c) = &fr.plan.caustics else { return };
        let near = fr.plan.cube_near;
        let (Some(cubes), Some(photons)) = (fr.layout.first(CUBE_VIEWS), fr.layout.first(PHOTON_VIEWS)) else { return };
        for k in 0..c.cubes.len() {
            let base = cubes + 6 * k as u32;
            let centre = c.centre(k, fr.lights);
            for f in 0..6 {
                table[(base + f) as usize] = view(face_view_proj(f as usize, centre, near), centre.extend(0.0), glam::Vec4::ZERO);
            }
        }
        for (i, v) in photon_views(c, fr.scene, fr.lights, &fr.plan.quality, near).into_iter().enumerate() {
            if let Some(slot) = table.get_mut(photons as usize + i) {
                *slot = v;
            }
        }
    }

    fn destroy(&mut self, _ctx: &Context) {}
}

/// Whether the light can send photons into the sphere (centre, radius): a spot light's cone
/// must reach it; point and directional lights reach everything (occluders between the
/// light and the generator are the shadow maps' business, per photon).
fn light_sees(kind: LightKind, position: Vec3, direction: Vec3, centre: Vec3, radius: f32) -> bool {
    match kind {
        LightKind::Spot { outer_cone, .. } => {
            let to = centre - position;
            let d = to.length();
            if d <= radius {
                return true;
            }
            let angle = direction.normalize().dot(to / d).clamp(-1.0, 1.0).acos();
            angle <= outer_cone + (radius / d).asin()
        }
        _ => true,
    }
}

/// The map knobs the caustics stage reads whatever the frame's methods (its light and
/// receiver cubes at `cube_size`, the refractor maps the photons exit through and their
/// search, the shadow maps that occlude them, the Fresnel weights along a path): with
/// caustics, every method's image depends on them.
pub const MAP_KNOBS: &[&str] = &[
    CubeKnobs::cube_size,
    CubeKnobs::cube_precision,
    FrameKnobs::fresnel,
    FrameKnobs::shadow_size,
    SearchKnobs::linear_steps,
    SearchKnobs::secant_steps,
    SearchKnobs::binary_steps,
    SearchKnobs::search_tolerance,
    DistanceKnobs::internal_bounces,
];

/// A mesh's bounding sphere: its box's centre, and the farthest vertex from it (tighter
/// than the half diagonal: a sphere's photon cone then holds the sphere, not its box).
pub fn bounding_sphere(scene: &Scene, mesh: usize) -> (Vec3, f32) {
    let m = &scene.meshes[mesh];
    let c = m.bounds().center();
    let r = m.positions.iter().map(|p| (*p - c).length()).fold(0.0f32, f32::max);
    (c, (r * 1.0001).max(1e-6))
}

/// Whether a light at `position` lies inside (or at the rim of) the sphere, so that no cone
/// from it bounds the sphere: it then sees the generator through a cube of six views.
fn light_inside(position: Vec3, centre: Vec3, radius: f32) -> bool {
    (position - centre).length() <= radius * 1.05
}

/// The caustics stage the scene needs under `q`, or none: caustics are off, no diffuse
/// surface receives them, no punctual light, or no specular object a light sees. Every
/// method's diffuse shading projects them, the ray tracers' (§2) shading kernels too.
pub fn plan(scene: &Scene, objects: &[ObjectPlan], q: &Quality) -> Option<CausticsPlan> {
    plan_of(scene, objects.iter().map(|o| (o.mesh, o.name.clone(), o.own_reference_point)), q)
}

/// What the caustics stage of a frame whose specular objects are `meshes` does under `q`,
/// as the cost model counts it (`plan::predict::features::Workload`): photons traced (every
/// photon image's texels) and caustic cube texels (receiver distance cubes and light cubes,
/// six faces of `cube_size`² each). Zero where the frame has no caustics.
pub fn photon_work(scene: &Scene, meshes: &[usize], q: &Quality) -> (f64, f64) {
    plan_of(scene, meshes.iter().map(|&m| (m, String::new(), Vec3::ZERO)), q).map_or((0.0, 0.0), |c| c.work(q))
}

/// [`plan`] over (mesh, name, reference point) of each specular object.
fn plan_of(scene: &Scene, objects: impl Iterator<Item = (usize, String, Vec3)>, q: &Quality) -> Option<CausticsPlan> {
    if q.caustics.caustics == Caustics::Off || scene.lights.is_empty() {
        return None;
    }
    if !scene.meshes.iter().any(|m| !scene.materials[m.material].kind.is_specular()) {
        return None;
    }
    let mut generators = Vec::new();
    let mut cubes: Vec<CausticCube> = Vec::new();
    let mut layers = 0;
    for (mesh, name, reference_point) in objects {
        let (centre, radius) = bounding_sphere(scene, mesh);
        let dielectric = matches!(scene.materials[scene.meshes[mesh].material].kind, crate::scene::SurfaceKind::Dielectric { .. });
        let thin = matches!(scene.materials[scene.meshes[mesh].material].kind, crate::scene::SurfaceKind::Dielectric { thin: true, .. });
        let branches = match q.caustics.caustic_paths {
            _ if !dielectric => 1,
            CausticPaths::Refracted | CausticPaths::Surface => 1,
            CausticPaths::Both => 2,
            CausticPaths::Exact if thin => 2,
            // T·T, R, then T·Rᵏ·T for k = 1 … internal_bounces.
            CausticPaths::Exact => 2 + q.distance.internal_bounces.min(knobs::EXACT_MAX_INTERNAL),
        };
        let mut lights = Vec::new();
        let g = generators.len();
        let first_cube = cubes.len();
        for (i, l) in scene.lights.iter().enumerate() {
            if !light_sees(l.kind, l.position, l.direction, centre, radius) {
                continue;
            }
            let faces = if l.kind != LightKind::Directional && light_inside(l.position, centre, radius) { 6 } else { 1 };
            // Light space centres a cube at each point or spot light; everything else shares
            // the generator's cube around its reference point.
            let light = (q.caustics.caustic_space == CausticSpace::Light && l.kind != LightKind::Directional).then_some(i);
            let cube = match cubes[first_cube..].iter().position(|c| c.light == light) {
                Some(k) => first_cube + k,
                None => {
                    cubes.push(CausticCube { generator: g, light });
                    cubes.len() - 1
                }
            };
            lights.push(LightViews { light: i, first_layer: layers, faces, branches, cube: cube as u32 });
            layers += faces * branches;
        }
        if !lights.is_empty() {
            generators.push(Generator { mesh, name, reference_point, lights });
        }
    }
    if generators.is_empty() {
        return None;
    }
    let mut p =
        CausticsPlan { filter: q.caustics.caustics, generators, cubes, space: q.caustics.caustic_space, photon_layers: layers, bytes: 0 };
    p.bytes = bytes(&p, q);
    Some(p)
}

/// Device memory: per caustic cube a receiver distance cube (R32F) and a light cube map
/// (RGBA32F, two with filtering; none for the photon map), the photon images (two RGBA32F
/// layers per view and a depth buffer), the receivers' depth buffer, for caustic triangles
/// their set-up buffers (64 bytes and six face flags per triangle), for the photon map its
/// sorted photons and grid.
pub fn bytes(p: &CausticsPlan, q: &Quality) -> u64 {
    let s = q.cube.cube_size as u64;
    let n = q.caustics.photons as u64;
    let g = p.cubes.len() as u64;
    let light_cubes = match (p.light_cubes(), q.caustics.caustic_filter > 0) {
        (false, _) => 0,
        (true, true) => 2,
        (true, false) => 1,
    };
    // The photon map: two vec4 and a coarse place a photon, and four words a bucket.
    let photon_map = if p.filter == Caustics::PhotonMap { p.photon_count(q) * 36 + p.grid_cells(q) as u64 * 16 } else { 0 };
    // The stage renders its cubes in six passes (src/methods/caustics/stage.rs): one depth layer.
    let triangles = if p.filter == Caustics::Triangles { p.photon_layers as u64 * 2 * (n - 1) * (n - 1) * (64 + 24) } else { 0 };
    // Texture space: the light map (RGBA32F) and a receiver-triangle cube beside each receiver
    // distance cube (R32F); the atlas's table is counted by the stage that builds it.
    let texture = if p.space == CausticSpace::Texture { (q.caustics.light_map_size as u64).pow(2) * 16 + g * 6 * s * s * 4 } else { 0 };
    g * 6 * s * s * (4 + 16 * light_cubes) + p.photon_layers as u64 * n * n * 32 + n * n * 4 + s * s * 4 + triangles + photon_map + texture
}

/// What `specula plan` says of it.
pub fn describe(p: &CausticsPlan, q: &Quality, scene: &Scene) -> String {
    let store = if p.space == CausticSpace::Texture {
        // The atlas the stage builds: its texel is how far a splat's leak reaches.
        match atlas::Atlas::build(scene, q.caustics.light_map_size, atlas::gutter()) {
            Ok(a) => format!(
                "a {}² RGBA32F light map of the receivers' {} chart(s), a texel {:.3e} object units",
                q.caustics.light_map_size, a.charts, a.texel
            ),
            Err(e) => format!("a {}² RGBA32F light map: {e}", q.caustics.light_map_size),
        }
    } else if p.space == CausticSpace::Screen {
        "a camera-sized RGBA32F irradiance image".to_string()
    } else if p.light_cubes() {
        format!(
            "{} light cube(s) 6×{}² RGBA32F{}",
            p.cubes.len(),
            q.cube.cube_size,
            if q.caustics.caustic_filter > 0 { format!(", box filter radius {}", q.caustics.caustic_filter) } else { String::new() }
        )
    } else {
        format!(
            "{} photons in a grid of {} buckets, gathered by their {} nearest within {} of the diagonal",
            p.photon_count(q),
            p.grid_cells(q),
            q.caustics.photon_k,
            q.caustics.photon_radius
        )
    };
    let mut s = format!(
        "caustics ({}, {} space): {} photons² per light view, {store}, {:.2} MiB",
        match p.filter {
            Caustics::Splat => format!("splat, splat_size {}", q.caustics.splat_size),
            Caustics::PhotonMap => "photon map".into(),
            _ => "triangles".into(),
        },
        match p.space {
            CausticSpace::Light => "light",
            CausticSpace::Screen => "screen",
            CausticSpace::Texture => "texture",
            CausticSpace::Cube => "cube-map",
        },
        q.caustics.photons,
        p.bytes as f64 / (1 << 20) as f64
    );
    for g in &p.generators {
        let lights: Vec<String> = g
            .lights
            .iter()
            .map(|l| {
                let name = &scene.lights[l.light].name;
                if l.faces == 6 {
                    format!("'{name}' (inside its bounding sphere: 6 views)")
                } else {
                    format!("'{name}'")
                }
            })
            .collect();
        s += &format!("\n  generator  {} lit by {}", g.name, lights.join(", "));
    }
    // Chains (light → mirror → glass → floor): the sampled paths end at the first surface of
    // the receivers' distance map, specular or not.
    let specular = scene.meshes.iter().filter(|m| !m.hidden && scene.materials[m.material].kind.is_specular()).count();
    if specular > 1 && q.caustics.caustic_paths != CausticPaths::Exact {
        s += "\n  chains     a photon that meets another specular object after its generator stops there (sampled paths); \
              caustic_paths=exact follows it through every specular surface up to the depth knob";
    }
    s
}

/// The photon views of this frame, one per photon image layer: where each light sees its
/// generator from. `eye` is the light (w 0) or, for a directional light, the view's origin
/// (w 1); `dir` is the view's axis and, in w, one texel's solid angle on the axis
/// ((2 tan θ / N)², θ the half angle) or, orthographic, one texel's area (m²).
pub fn photon_views(p: &CausticsPlan, scene: &Scene, lights: &[GpuLight], q: &Quality, near_scale: f32) -> Vec<GpuView> {
    let n = q.caustics.photons as f32;
    let mut views = Vec::with_capacity(p.photon_layers as usize);
    for g in &p.generators {
        let (centre, radius) = bounding_sphere(scene, g.mesh);
        let positions = &scene.meshes[g.mesh].positions;
        for lv in &g.lights {
            let v = light_views(lv, scene.lights[lv.light].kind, &lights[lv.light], n, near_scale, (centre, radius), positions);
            // The reflected branch looks from the same place.
            for _ in 0..lv.branches {
                views.extend_from_slice(&v);
            }
        }
    }
    views
}

/// The views from which light `lv` sees the generator (its bounding sphere (centre, radius),
/// its corners `positions`): one per face.
fn light_views(
    lv: &LightViews,
    kind: LightKind,
    l: &GpuLight,
    n: f32,
    near_scale: f32,
    (centre, radius): (Vec3, f32),
    positions: &[Vec3],
) -> Vec<GpuView> {
    let pos = Vec3::from_slice(&l.position_range[..3]);
    if kind == LightKind::Directional {
        let dir = Vec3::from_slice(&l.direction_kind[..3]).normalize();
        let vp = crate::frame::views::directional_view_proj(dir, centre, radius);
        let texel = 2.0 * radius / n;
        return vec![view(vp, (centre - dir * radius).extend(1.0), dir.extend(texel * texel))];
    }
    if lv.faces == 6 {
        return (0..6)
            .map(|f| {
                let axis = crate::cube::FACE_AXES[f][2];
                view(crate::cube::face_view_proj(f, pos, near_scale), pos.extend(0.0), axis.extend((2.0 / n).powi(2)))
            })
            .collect();
    }
    let to = centre - pos;
    let d = to.length();
    let axis = to / d;
    let up = if axis.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let near = ((d - radius) * 0.5).max(near_scale);
    let look = Mat4::look_to_rh(pos, axis, up);
    // The image fitted to the generator's corners as the light sees them (an off-centre
    // frustum: every photon on the generator, where the bounding sphere's cone spends most
    // of a flat or long generator's photons beside it), two texels wider on each side so
    // that the silhouette's texels are whole; the cone where a corner lies near or behind
    // the light's plane.
    let (r_x, r_y) = fitted_extent(&look, positions, 1e-3 * d).unwrap_or_else(|| {
        let t = (((radius / d).min(1.0).asin() * 1.02).min(1.5)).tan();
        ((-t, t), (-t, t))
    });
    let ((l0, r0), (b0, t0)) = (r_x, r_y);
    let (mx, my) = (2.0 * (r0 - l0) / n, 2.0 * (t0 - b0) / n);
    let ((l0, r0), (b0, t0)) = ((l0 - mx, r0 + mx), (b0 - my, t0 + my));
    // Reversed-Z, infinite far plane, as glam's perspective_infinite_reverse_rh but
    // off-centre; y flipped for Vulkan.
    let proj = Mat4::from_cols(
        glam::Vec4::new(2.0 / (r0 - l0), 0.0, 0.0, 0.0),
        glam::Vec4::new(0.0, -2.0 / (t0 - b0), 0.0, 0.0),
        glam::Vec4::new((r0 + l0) / (r0 - l0), -(t0 + b0) / (t0 - b0), 0.0, -1.0),
        glam::Vec4::new(0.0, 0.0, near, 0.0),
    );
    // The texel's area on the image plane at unit distance (photons.frag: its solid angle
    // times cos³ of its angle to the axis).
    let texel_area = (r0 - l0) / n * ((t0 - b0) / n);
    vec![view(proj * look, pos.extend(0.0), axis.extend(texel_area))]
}

/// The extent (x: left, right; y: bottom, top) on the image plane at unit distance of
/// `points` seen through `look` (a right-handed view looking down −z), or `None` when one
/// lies closer to the light's plane than `min_z` (behind it, or beside the light) or the
/// extent is degenerate or wider than the bounding cone may be (tan 86°).
fn fitted_extent(look: &Mat4, points: &[Vec3], min_z: f32) -> Option<((f32, f32), (f32, f32))> {
    let (mut lx, mut hx, mut ly, mut hy) = (f32::INFINITY, f32::NEG_INFINITY, f32::INFINITY, f32::NEG_INFINITY);
    for p in points {
        let v = look.transform_point3(*p);
        let z = -v.z;
        if z.is_nan() || z < min_z {
            return None;
        }
        let (x, y) = (v.x / z, v.y / z);
        (lx, hx, ly, hy) = (lx.min(x), hx.max(x), ly.min(y), hy.max(y));
    }
    let wide = 14.3; // tan 86°
    let ok = hx > lx && hy > ly && [lx, hx, ly, hy].iter().all(|v| v.abs() < wide);
    ok.then_some(((lx, hx), (ly, hy)))
}

/// After objects moved: the generators' reference points follow their objects'.
pub fn refresh(p: &mut Plan) {
    let refs: Vec<(usize, Vec3)> = p.objects.iter().map(|o| (o.mesh, o.own_reference_point)).collect();
    if let Some(c) = p.caustics.as_mut() {
        for g in &mut c.generators {
            if let Some((_, r)) = refs.iter().find(|(m, _)| *m == g.mesh) {
                g.reference_point = *r;
            }
        }
    }
}
