//! A 128-bit fingerprint of everything in a scene that a render reads, so that work which
//! depends only on the scene (the planner's probe) can be kept and found again.

use std::hash::Hasher;

use super::{EnvironmentMap, Mesh, Scene, Texture};

/// Two SipHash streams over the same bytes, the second salted: a 128-bit key.
pub struct Fingerprint([std::collections::hash_map::DefaultHasher; 2]);

impl Default for Fingerprint {
    fn default() -> Self {
        Self::new()
    }
}

impl Fingerprint {
    pub fn new() -> Fingerprint {
        let mut salted = std::collections::hash_map::DefaultHasher::new();
        salted.write(b"specula fingerprint");
        Fingerprint([std::collections::hash_map::DefaultHasher::new(), salted])
    }

    /// The bytes, with their length (so that adjacent fields cannot trade bytes).
    pub fn bytes(&mut self, b: &[u8]) {
        for h in &mut self.0 {
            h.write_usize(b.len());
            h.write(b);
        }
    }

    /// Small values, as their `Debug` text (every field, floats to the bit: Rust prints the
    /// shortest text that reads back to the same float).
    pub fn text(&mut self, t: &str) {
        self.bytes(t.as_bytes());
    }

    pub fn finish(&self) -> u128 {
        ((self.0[0].finish() as u128) << 64) | self.0[1].finish() as u128
    }
}

/// The last `N` values computed, by key (most recently used kept): for work that is a pure
/// function of a fingerprint's inputs.
pub struct Kept<V, const N: usize>(std::sync::Mutex<Vec<(u128, std::sync::Arc<V>)>>);

impl<V, const N: usize> Default for Kept<V, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<V, const N: usize> Kept<V, N> {
    pub const fn new() -> Self {
        Kept(std::sync::Mutex::new(Vec::new()))
    }

    /// The value kept under `key`, else `compute`'s (kept).
    pub fn get(&self, key: u128, compute: impl FnOnce() -> V) -> std::sync::Arc<V> {
        let lock = || self.0.lock().unwrap_or_else(|e| e.into_inner());
        let hit = {
            let mut kept = lock();
            kept.iter().position(|(k, _)| *k == key).map(|i| kept.remove(i).1)
        };
        let value = hit.unwrap_or_else(|| std::sync::Arc::new(compute()));
        let mut kept = lock();
        kept.push((key, value.clone()));
        if kept.len() > N {
            kept.remove(0);
        }
        value
    }
}

impl Scene {
    /// Feeds every field a render reads into `h`. The structs are taken apart field by field
    /// without `..`, so that a field added to them must be added here (or named as unread).
    pub fn fingerprint(&self, h: &mut Fingerprint) {
        let Scene { meshes, materials, textures, lights, camera, environment, skipped: _, animation: _ } = self;
        h.text(&format!("{} meshes", meshes.len()));
        for mesh in meshes {
            let Mesh { name, positions, normals, uvs, indices, material, reference_point, aliases, method, world, rest: _, hidden } = mesh;
            h.text(&format!("{name:?} {material} {reference_point:?} {aliases:?} {method:?} {world:?} {hidden}"));
            h.bytes(bytemuck::cast_slice(positions));
            h.bytes(bytemuck::cast_slice(normals));
            h.bytes(bytemuck::cast_slice(uvs));
            h.bytes(bytemuck::cast_slice(indices));
        }
        h.text(&format!("{materials:?} {lights:?} {camera:?}"));
        for t in textures {
            let Texture { name, width, height, rgba8 } = t;
            h.text(&format!("{name:?} {width}x{height}"));
            h.bytes(rgba8);
        }
        match environment {
            Some(EnvironmentMap { width, height, rgba32f }) => {
                h.text(&format!("environment {width}x{height}"));
                h.bytes(bytemuck::cast_slice(rgba32f));
            }
            None => h.text("no environment"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn print(scene: &Scene) -> u128 {
        let mut h = Fingerprint::new();
        scene.fingerprint(&mut h);
        h.finish()
    }

    #[test]
    fn any_change_a_render_reads_changes_the_fingerprint() {
        let scene = crate::scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap();
        let base = print(&scene);
        assert_eq!(base, print(&scene.clone()));
        let mut moved = scene.clone();
        moved.meshes[0].positions[0].x += 1e-6;
        let mut material = scene.clone();
        material.materials[0].base_color.x *= 0.5;
        let mut light = scene.clone();
        light.lights[0].intensity *= 2.0;
        let mut hidden = scene.clone();
        hidden.meshes[0].hidden = true;
        let mut sky = scene.clone();
        sky.environment = Some(EnvironmentMap::constant(glam::Vec3::ONE));
        for (what, s) in [("position", moved), ("material", material), ("light", light), ("hidden", hidden), ("environment", sky)] {
            assert_ne!(print(&s), base, "{what}");
        }
    }
}
