//! Frames over time: the scene's changes between frames (moved objects, materials, lights,
//! the camera), uploaded in place before the next frame, and which map stages they
//! invalidate — each stage declares what it depends on (`stage::Deps`), and a frame
//! records a map stage only when one of those changed.

use crate::error::{Error, Result};
use crate::frame::stage::{Deps, StageInit};
use crate::frame::views;
use crate::plan::Plan;
use crate::scene::update::Changes;
use crate::scene::{Camera, Scene};
use crate::vk::Context;

use super::{bindings, stage_init, Renderer};

/// `Stage::redraw`: (faces to draw, faces in all), or None for the whole stage, with
/// `Stage::redraw_note`.
type Redraw = (Option<(u32, u32)>, Option<String>);

/// A map stage the frame recorded, and why: its first frame, `map_updates=always`, or what
/// it depends on that changed.
#[derive(Clone, Debug, PartialEq)]
pub struct MapUpdate {
    pub stage: &'static str,
    pub reason: String,
}

/// What the renderer knows of the scene between frames, and what the next frame records.
pub(super) struct Updates {
    /// The scene the GPU holds (meshes, materials, lights, camera; no texels): what
    /// `update` compares a new state with.
    cpu: Scene,
    texture_count: usize,
    has_environment: bool,
    /// Changes taken by `update`, uploaded when the next frame is recorded.
    pending: Changes,
    /// Per stage, in recording order: the meshes it was planned for.
    objects: Vec<Vec<usize>>,
    /// Per stage: frames it still records after a change (inter-object cycles spread over
    /// frames by `frame_latency`).
    latency_left: Vec<u32>,
    first_frame: bool,
    /// The map stages the last recorded frame regenerated.
    recorded: Vec<MapUpdate>,
}

impl Updates {
    pub fn new(scene: &Scene) -> Updates {
        Updates {
            cpu: geometry_of(scene),
            texture_count: scene.textures.len(),
            has_environment: scene.environment.is_some(),
            pending: Changes::default(),
            objects: Vec::new(),
            latency_left: Vec::new(),
            first_frame: true,
            recorded: Vec::new(),
        }
    }

    /// The stages' objects, in recording order.
    pub fn track(&mut self, objects: Vec<Vec<usize>>) {
        self.latency_left = vec![0; objects.len()];
        self.objects = objects;
    }

    /// The scene as the GPU holds it (no texels).
    pub fn scene(&self) -> &Scene {
        &self.cpu
    }

    /// The map stages the last recorded frame regenerated, and why.
    pub fn recorded(&self) -> &[MapUpdate] {
        &self.recorded
    }

    /// Decides which map stages this frame records, after changes `c`.
    /// `redraw`: each stage's `Stage::redraw` after the changes.
    fn invalidate(&mut self, plan: &Plan, deps: &[Deps], (names, redraw): (&[&'static str], &[Redraw]), c: &Changes) {
        self.recorded.clear();
        let list = |ids: &[usize], name: &dyn Fn(usize) -> String| ids.iter().map(|&i| name(i)).collect::<Vec<_>>().join(", ");
        let moved = list(&c.moved, &|i| format!("'{}'", self.cpu.meshes[i].name));
        let materials = list(&c.materials, &|i| format!("'{}'", self.cpu.materials[i].name));
        let lights = list(&c.lights, &|i| format!("'{}'", self.cpu.lights[i].name));
        let q = &plan.quality;
        for (i, deps) in deps.iter().enumerate() {
            let mut why = Vec::new();
            if self.first_frame {
                why.push("first frame".to_string());
            } else if q.frame.map_updates_always {
                why.push("map_updates=always".to_string());
            } else {
                let geometry = !c.moved.is_empty();
                // A light effect depends on its own objects' materials only.
                let own_materials = || self.objects[i].iter().any(|&m| c.materials.contains(&self.cpu.meshes[m].material));
                let (g, m, l, cam) = match deps {
                    Deps::EveryFrame => continue,
                    Deps::Shadows => (geometry, false, !c.lights.is_empty(), false),
                    Deps::Geometry => (geometry, false, false, false),
                    Deps::LitObjects => (geometry, own_materials(), !c.lights.is_empty(), false),
                    Deps::LitView => (geometry, own_materials(), !c.lights.is_empty(), c.camera),
                    Deps::World => (geometry, !c.materials.is_empty(), !c.lights.is_empty(), false),
                    Deps::CameraMap => (geometry, false, false, c.camera),
                };
                if g {
                    why.push(format!("moved {moved}"));
                }
                if m {
                    why.push(format!("material {materials}"));
                }
                if l {
                    why.push(format!("light {lights}"));
                }
                if cam {
                    why.push("camera".to_string());
                }
                // A stage that tracks what each face saw draws only the faces that saw it.
                let (count, note) = redraw.get(i).cloned().unwrap_or_default();
                match count {
                    Some((0, _)) if !cam => why.clear(),
                    Some((k, n)) if k < n && !why.is_empty() => why.push(note.unwrap_or_else(|| format!("{k} of {n} faces"))),
                    _ => {}
                }
            }
            if *deps == Deps::EveryFrame {
                continue;
            }
            if !why.is_empty() && plan.frame_latency && *deps == Deps::World {
                // One inter-object cycle per frame: the change needs `cycles` frames.
                self.latency_left[i] = q.distance.cycles.max(1);
            }
            if why.is_empty() && self.latency_left[i] > 0 {
                why.push(format!("frame latency: {} more cycle(s)", self.latency_left[i]));
            }
            self.latency_left[i] = self.latency_left[i].saturating_sub(1);
            if !why.is_empty() {
                self.recorded.push(MapUpdate { stage: names[i], reason: why.join("; ") });
            }
        }
        self.first_frame = false;
    }
}

impl Renderer {
    /// Takes the scene's new state for the next recorded frame: moved objects, changed
    /// materials, lights and camera (the scene's own setters validate each change:
    /// `Scene::set_object_transform`, `set_material`, `set_light`). The topology must be
    /// the renderer's (same objects, triangles, textures, material and light kinds), and the
    /// plan's structure must survive (each object keeps its method and maps; reference
    /// points and proxies follow the objects). Touches no GPU memory: the next `record`
    /// uploads the change in place, so a frame may still be in flight. On error nothing
    /// changes. Returns what changed.
    pub fn update(&mut self, scene: &Scene) -> Result<Changes> {
        scene.validate()?;
        let u = &self.updates;
        if scene.textures.len() != u.texture_count || scene.environment.is_some() != u.has_environment {
            return Err(Error::invalid("scene update", "other textures or environment: make a new renderer"));
        }
        let new = geometry_of(scene);
        let c = Changes::between(&u.cpu, &new)?;
        if c.is_empty() {
            return Ok(c);
        }
        let mut plan = self.plan.clone();
        // Objects moved: the maps' reference points follow; under `auto` a camera move
        // changes what each object covers too, so its choice is predicted again (kept within
        // the hysteresis, `plan::predict::switch`).
        if !c.moved.is_empty() || (c.camera && plan.choice == crate::plan::Choice::Auto && !plan.objects.is_empty()) {
            plan.refresh_geometry(scene)?;
        }
        let camera = if c.camera { Some(scene.camera_or_default()) } else { None };
        if let Some(cam) = &camera {
            cam.validate()?;
        }
        self.plan = plan;
        self.updates.cpu = new;
        if let Some(cam) = camera {
            self.camera = cam;
        }
        self.updates.pending.merge(&c);
        Ok(c)
    }

    /// The map stages the last recorded frame regenerated, and why.
    pub fn map_updates(&self) -> &[MapUpdate] {
        self.updates.recorded()
    }

    /// Replaces the camera (the output size's aspect ratio still wins).
    pub fn set_camera(&mut self, camera: Camera) -> Result<()> {
        camera.validate()?;
        if camera != self.camera {
            self.updates.pending.camera = true;
        }
        self.camera = camera;
        self.updates.cpu.camera = Some(camera);
        Ok(())
    }

    /// Uploads the pending changes in place and decides which map stages this frame
    /// records. Called by `record`: every earlier frame has completed (the one-frame-in-
    /// flight rule), so the host-visible buffers are free to write.
    pub(super) fn apply_updates(&mut self, ctx: &Context) -> Result<()> {
        // The changes stay pending until they are all in: a frame that fails half-way (a
        // structure rebuild out of memory) leaves them for the next one, which redoes them.
        let c = self.updates.pending.clone();
        self.apply(ctx, &c)?;
        self.updates.pending = Changes::default();
        Ok(())
    }

    fn apply(&mut self, ctx: &Context, c: &Changes) -> Result<()> {
        let cpu = &self.updates.cpu;
        if !c.moved.is_empty() {
            for &i in &c.moved {
                let d = self.scene.draws[i];
                let v: Vec<crate::gpu_scene::Vertex> = crate::gpu_scene::vertices_of(&cpu.meshes[i]).collect();
                let at = d.vertex_offset as usize * std::mem::size_of::<crate::gpu_scene::Vertex>();
                self.scene.vertices.write_at(at, bytemuck::cast_slice(&v))?;
                let mesh = &cpu.meshes[i];
                let b = mesh.bounds();
                let draw = &mut self.scene.draws[i];
                (draw.lo, draw.hi) = (b.min, b.max);
                // A hidden object draws no triangle anywhere.
                draw.index_count = if mesh.hidden { 0 } else { mesh.indices.len() as u32 };
            }
            self.bindings.objects.write(bytemuck::cast_slice(&bindings::object_table(cpu, &self.plan)))?;
        }
        if !c.materials.is_empty() {
            let m: Vec<_> = cpu.materials.iter().map(crate::gpu_scene::gpu_material).collect();
            self.scene.materials.write(bytemuck::cast_slice(&m))?;
        }
        if !c.moved.is_empty() || !c.lights.is_empty() {
            // A directional light's shadow projection covers the scene's bounds.
            self.light_table = views::light_table(cpu, &self.plan);
            if let Some(l) = &mut self.bindings.lights {
                l.write(bytemuck::cast_slice(&self.light_table))?;
            }
        }
        if !c.is_empty() {
            let init: StageInit =
                stage_init(ctx, cpu, &self.scene, &self.plan, &self.bindings, &self.targets, (self.width, self.height), &self.shared);
            let puts = self.maps.changes();
            self.shared.scene_changed(&init, c)?;
            for s in &mut self.stages {
                s.update(&init, c, &mut self.maps)?;
            }
            // A stage may have reallocated its maps (the layered maps' layer count).
            if self.maps.changes() != puts {
                self.bindings.write(ctx, &self.scene, &self.maps);
            }
        }
        let names: Vec<&'static str> = self.stages.iter().map(|s| s.name()).collect();
        let redraw: Vec<Redraw> = self.stages.iter().map(|s| (s.redraw(), s.redraw_note())).collect();
        self.updates.invalidate(&self.plan, &self.deps, (&names, &redraw), c);
        Ok(())
    }
}

/// The scene without its texels and environment: what the renderer keeps to compare
/// updates with and to hand its stages.
fn geometry_of(scene: &Scene) -> Scene {
    Scene {
        meshes: scene.meshes.clone(),
        materials: scene.materials.clone(),
        lights: scene.lights.clone(),
        camera: scene.camera,
        textures: Vec::new(),
        environment: None,
        skipped: Vec::new(),
        animation: None,
    }
}
