//! The frame's shared maps: a table of slots, each a descriptor binding of set 0 or set 1
//! that some pass fills with an image or a buffer and others sample. Every slot is declared
//! once by its owner (the frame's shadow maps in `frame::shadow`, each family's in its own
//! folder, listed by its `registry::Family::slots`), handed to `Maps::new` by the renderer,
//! which writes the descriptors, the
//! passes' reads and the frees by walking the declarations, so it names no slot.

use std::collections::BTreeMap;

use ash::vk;

use crate::vk::{Buffer, Context, Image};

/// How a slot's images are sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampler {
    Linear,
    /// Distances, materials, silhouettes, photon records: never blended.
    Nearest,
}

/// What a slot holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A combined image sampler.
    Image(Sampler),
    /// A storage buffer.
    Buffer,
}

/// One resource slot of the frame's descriptor sets: where it binds, how it is sampled and
/// which passes see it. Set 1 holds the maps the camera passes and map generation bind per
/// pass, in several sets with roles (`MapSets`); the flags below say in which.
#[derive(Clone, Copy, Debug)]
pub struct Slot {
    /// What it holds, for messages (e.g. `caustics.light_cubes`).
    pub name: &'static str,
    /// Descriptor set (0: the frame's set; 1: the maps sets) and binding
    /// (`frame::layout::binding::*`).
    pub set: u32,
    pub binding: u32,
    pub kind: Kind,
    /// The camera passes sample it (`Maps::camera_reads`).
    pub camera: bool,
    /// Every pass that shades diffuse surfaces samples it (`Maps::shadow_reads`).
    pub shading: bool,
    /// Set 1: map generation sees it too (it is made before the maps that search it); else
    /// only the camera sets hold it.
    pub generation: bool,
    /// Set 1: the geometry set holds it (passes that search geometry maps alone: caustic
    /// photons, §6).
    pub geometry: bool,
    /// Set 1: its images alternate between map cycles (inter-object cycles read the
    /// previous cycle's): one generation and one camera set per image.
    pub ping_pong: bool,
    /// Set 1: its image alone needs a generation and a camera set (even with no
    /// ping-pong image).
    pub needs_pair: bool,
    /// Its presence needs the set-1 sets (some pass binds them when it is there).
    pub needs_sets: bool,
    /// A buffer of per-mesh counters the frame reports (`Maps::counts`): `<name>.<object>`.
    pub counts: bool,
}

impl Slot {
    /// An image slot with no role flag set, to set the flags it needs over.
    pub const fn image(name: &'static str, set: u32, binding: u32, sampler: Sampler) -> Slot {
        Slot {
            name,
            set,
            binding,
            kind: Kind::Image(sampler),
            camera: false,
            shading: false,
            generation: false,
            geometry: false,
            ping_pong: false,
            needs_pair: false,
            needs_sets: false,
            counts: false,
        }
    }

    pub const fn buffer(name: &'static str, set: u32, binding: u32) -> Slot {
        Slot { kind: Kind::Buffer, ..Slot::image(name, set, binding, Sampler::Nearest) }
    }

    /// (set, binding): what identifies a slot.
    pub fn key(&self) -> (u32, u32) {
        (self.set, self.binding)
    }
}

/// The frame's shared maps, keyed by slot. A map stage creates the images of its slots; the
/// camera passes and later map stages sample them; the renderer writes the descriptors and
/// frees them.
#[derive(Default)]
pub struct Maps {
    /// Every declared slot: the frame's, then each family's (`registry::Family::slots`).
    slots: Vec<&'static Slot>,
    images: BTreeMap<(u32, u32), Vec<Image>>,
    buffers: BTreeMap<(u32, u32), Buffer>,
    /// Which image of each ping-pong slot the last cycle wrote: the one the camera passes
    /// read, and the index of their camera set.
    pub latest: usize,
    /// How many times an image or a buffer was put into a slot (`changes`).
    puts: u64,
    /// Where the caustics this frame redoes may change the light on the maps' surfaces (the
    /// caustics stage's update sets it before the maps' updates read it).
    pub caustic_reach: crate::frame::cube_deps::CausticReach,
}

impl Maps {
    /// An empty table over the declared `slots`.
    pub fn new(slots: Vec<&'static Slot>) -> Maps {
        Maps { slots, ..Maps::default() }
    }

    fn all_slots(&self) -> impl Iterator<Item = &'static Slot> + '_ {
        self.slots.iter().copied()
    }

    /// The slot's image: for a ping-pong slot the one the last cycle wrote.
    pub fn image(&self, slot: &Slot) -> Option<&Image> {
        let v = self.images.get(&slot.key())?;
        if slot.ping_pong {
            v.get(self.latest)
        } else {
            v.first()
        }
    }

    pub fn image_mut(&mut self, slot: &Slot) -> Option<&mut Image> {
        let latest = self.latest;
        let v = self.images.get_mut(&slot.key())?;
        if slot.ping_pong {
            v.get_mut(latest)
        } else {
            v.first_mut()
        }
    }

    /// Every image of the slot (the ping-pong pair, in order).
    pub fn images(&self, slot: &Slot) -> &[Image] {
        self.images.get(&slot.key()).map_or(&[], |v| v.as_slice())
    }

    /// Puts the slot's image (replacing any, which the caller has freed or taken).
    pub fn set_image(&mut self, slot: &Slot, image: Image) {
        self.puts += 1;
        self.images.insert(slot.key(), vec![image]);
    }

    /// Puts all the slot's images (a ping-pong slot's pair); none empties the slot.
    pub fn set_images(&mut self, slot: &Slot, images: Vec<Image>) {
        self.puts += 1;
        if images.is_empty() {
            self.images.remove(&slot.key());
        } else {
            self.images.insert(slot.key(), images);
        }
    }

    /// Adds an image to a ping-pong slot.
    pub fn push_image(&mut self, slot: &Slot, image: Image) {
        self.puts += 1;
        self.images.entry(slot.key()).or_default().push(image);
    }

    /// Takes the slot's images out (to record into them, or to free them).
    pub fn take_images(&mut self, slot: &Slot) -> Vec<Image> {
        self.images.remove(&slot.key()).unwrap_or_default()
    }

    pub fn take_image(&mut self, slot: &Slot) -> Option<Image> {
        self.take_images(slot).into_iter().next()
    }

    pub fn buffer(&self, slot: &Slot) -> Option<&Buffer> {
        self.buffers.get(&slot.key())
    }

    pub fn buffer_mut(&mut self, slot: &Slot) -> Option<&mut Buffer> {
        self.buffers.get_mut(&slot.key())
    }

    pub fn set_buffer(&mut self, slot: &Slot, buffer: Buffer) {
        self.puts += 1;
        self.buffers.insert(slot.key(), buffer);
    }

    /// Counts every image or buffer put into a slot: when a stage's `update` changed it,
    /// the stage reallocated a map and the descriptors must be written again.
    pub fn changes(&self) -> u64 {
        self.puts
    }

    /// Whether the slot holds anything.
    pub fn has(&self, slot: &Slot) -> bool {
        self.images.contains_key(&slot.key()) || self.buffers.contains_key(&slot.key())
    }

    /// Every map image the camera passes sample: the current one of each slot.
    pub fn camera_reads(&self) -> Vec<&Image> {
        self.all_slots().filter(|s| s.camera).filter_map(|s| self.image(s)).collect()
    }

    /// What shading a diffuse surface samples (`Slot::shading`): the shadow maps, and
    /// light a family adds there (the caustics' receiver distances and light cube maps,
    /// §6.3.3).
    pub fn shadow_reads(&self) -> impl Iterator<Item = &Image> {
        self.all_slots().filter(|s| s.shading).filter_map(|s| self.image(s))
    }

    /// Zeroes every counter slot (`Slot::counts`) before the frame's views and camera passes
    /// count again (after the last frame's counting, whose host read the frame's fence
    /// ordered).
    pub fn clear_counts(&self, rec: &mut crate::vk::Recorder) {
        let counters: Vec<vk::Buffer> = self.all_slots().filter(|s| s.counts).filter_map(|s| self.buffer(s)).map(|b| b.raw).collect();
        if counters.is_empty() {
            return;
        }
        let transfer = vk::PipelineStageFlags2::ALL_TRANSFER;
        let fragment = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        rec.memory_barrier((fragment, vk::AccessFlags2::SHADER_STORAGE_WRITE), (transfer, vk::AccessFlags2::TRANSFER_WRITE));
        for b in counters {
            unsafe { rec.ctx.device.cmd_fill_buffer(rec.cmd, b, 0, vk::WHOLE_SIZE, 0) };
        }
        let storage = vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE;
        rec.memory_barrier((transfer, vk::AccessFlags2::TRANSFER_WRITE), (fragment, storage));
    }

    /// Takes a slot's buffer out (the descriptors must be written again: `changes`).
    pub fn take_buffer(&mut self, slot: &Slot) -> Option<Buffer> {
        let b = self.buffers.remove(&slot.key());
        self.puts += u64::from(b.is_some());
        b
    }

    /// Every counter slot's words (`Slot::counts`), as the last completed frame left them.
    pub fn counts(&self) -> Vec<(&'static str, Vec<u32>)> {
        let words =
            |b: &Buffer| b.read().map(|bytes| bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect());
        self.all_slots().filter(|s| s.counts).filter_map(|s| Some((s.name, words(self.buffer(s)?).ok()?))).collect()
    }

    /// What map generation samples through a generation set besides the ping-pong images
    /// it writes itself (the refractor maps, made first).
    pub fn generation_reads(&self) -> impl Iterator<Item = &Image> {
        self.all_slots().filter(|s| s.set == 1 && s.generation && !s.ping_pong).filter_map(|s| self.image(s))
    }

    /// What the geometry set holds (passes that bind it sample these).
    pub fn geometry_reads(&self) -> impl Iterator<Item = &Image> {
        self.all_slots().filter(|s| s.set == 1 && s.geometry).filter_map(|s| self.image(s))
    }

    /// Generation/camera set pairs of set 1: one per image of a ping-pong slot, or one
    /// (holding no ping-pong image) for a slot that needs one.
    fn set_pairs(&self) -> usize {
        self.all_slots()
            .map(|s| match (s.ping_pong, s.needs_pair) {
                (true, _) => self.images(s).len(),
                (false, true) => usize::from(self.has(s)),
                (false, false) => 0,
            })
            .max()
            .unwrap_or(0)
    }

    /// How many set-1 descriptor sets the maps need: per set pair one for map generation and
    /// one for the camera passes, an all-null one and one of the geometry maps alone. Without
    /// set-1 maps the last two still exist: a camera pass that reads a map only where its
    /// object has one (a planar mirror's fallback, geometry/mirror.frag) binds the null one.
    pub fn set_count(&self) -> usize {
        2 * self.set_pairs() + 2
    }

    /// Assigns `set_count()` allocated sets to their roles.
    pub fn sets(&self, sets: &[vk::DescriptorSet]) -> MapSets {
        let n = self.set_pairs();
        if sets.len() < 2 * n + 2 {
            return MapSets::default();
        }
        MapSets { generate: sets[..n].to_vec(), camera: sets[n..2 * n].to_vec(), empty: sets[2 * n], geometry: sets[2 * n + 1] }
    }

    /// Writes every slot's descriptors: set 0's into `frame`, and each set-1 set of `sets`
    /// as its role says (`Slot::generation`, `Slot::geometry`; camera sets hold every slot,
    /// the empty set none; a ping-pong slot gives set pair i its image i). What the scene
    /// does not need gets a null descriptor.
    pub fn write_descriptors(&self, ctx: &Context, frame: vk::DescriptorSet, sets: &MapSets, linear: vk::Sampler, nearest: vk::Sampler) {
        let slots: Vec<&Slot> = self.all_slots().collect();
        for s in slots.iter().filter(|s| s.set == 0) {
            self.write(ctx, frame, s, true, self.latest, (linear, nearest));
        }
        let mut roles: Vec<(vk::DescriptorSet, Role)> = Vec::new();
        for i in 0..self.set_pairs() {
            if i < sets.generate.len() {
                roles.push((sets.generate[i], Role::Generate(i)));
                roles.push((sets.camera[i], Role::Camera(i)));
            }
        }
        if sets.empty != vk::DescriptorSet::null() {
            roles.push((sets.empty, Role::Empty));
        }
        if sets.geometry != vk::DescriptorSet::null() {
            roles.push((sets.geometry, Role::Geometry));
        }
        for (set, role) in roles {
            for s in slots.iter().filter(|s| s.set == 1) {
                let (filled, pair) = match role {
                    Role::Generate(i) => (s.generation, i),
                    Role::Camera(i) => (true, i),
                    Role::Empty => (false, 0),
                    Role::Geometry => (s.geometry, 0),
                };
                self.write(ctx, set, s, filled, pair, (linear, nearest));
            }
        }
    }

    /// One slot's descriptor in `set`: its image (of set pair `pair`, if ping-pong) or its
    /// buffer, or null where `filled` is false or the slot is empty.
    fn write(
        &self,
        ctx: &Context,
        set: vk::DescriptorSet,
        s: &Slot,
        filled: bool,
        pair: usize,
        (linear, nearest): (vk::Sampler, vk::Sampler),
    ) {
        use crate::vk::pipeline::{write_buffer, write_image};
        match s.kind {
            Kind::Image(sampler) => {
                let image = if s.ping_pong { self.images(s).get(pair) } else { self.image(s) };
                let view = image.filter(|_| filled).map_or(vk::ImageView::null(), |i| i.view);
                let sampler = if sampler == Sampler::Linear { linear } else { nearest };
                let ro = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
                write_image(ctx, set, s.binding, 0, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, view, sampler, ro);
            }
            Kind::Buffer => {
                let raw = self.buffer(s).filter(|_| filled).map_or(vk::Buffer::null(), |b| b.raw);
                write_buffer(ctx, set, s.binding, vk::DescriptorType::STORAGE_BUFFER, raw);
            }
        }
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for i in self.images.values_mut().flatten() {
            i.destroy(ctx);
        }
        for b in self.buffers.values_mut() {
            b.destroy(ctx);
        }
        *self = Maps::new(std::mem::take(&mut self.slots));
    }
}

/// The role of one set-1 set (`MapSets`), with its set pair.
#[derive(Clone, Copy)]
enum Role {
    Generate(usize),
    Camera(usize),
    Empty,
    Geometry,
}

/// Set-1 descriptor sets over the maps: `generate[i]` for map generation reading ping-pong
/// image `i` (no camera-only map), `camera[i]` for the camera passes, `empty` all null.
#[derive(Default)]
pub struct MapSets {
    pub generate: Vec<vk::DescriptorSet>,
    pub camera: Vec<vk::DescriptorSet>,
    pub empty: vk::DescriptorSet,
    /// The geometry maps alone (caustic photons search them, §6).
    pub geometry: vk::DescriptorSet,
}
