//! Pipelines kept per context and shared by its renderers: a pipeline asked again with the
//! same shaders, state and layout *definition* is the one made before. A renderer made
//! again for the same scene (a re-plan when objects move, a re-configure through the C ABI,
//! a method switched back in the viewer) then skips the driver's shader compilation, which
//! on lavapipe is most of a renderer's creation (SPIR-V to NIR and its optimisation; its
//! `VkPipelineCache` keeps none of it). Each pipeline counts its users; one without users is
//! kept, the [`IDLE`] most recently released, and destroyed when pushed out or with the
//! context.
//!
//! Layouts are kept the same way, one per definition for the context's life
//! (`pipeline::descriptor_set_layout`, `pipeline::pipeline_layout`; the library's are a
//! few constant binding tables): a kept pipeline is used only with the layout it was made
//! with. (Vulkan allows a pipeline with any compatible layout, and its layout destroyed
//! first; lavapipe then kept about 1 KiB per context that `tests/c_abi_leaks.rs` counted.)

use std::collections::{HashMap, VecDeque};
use std::hash::{Hash, Hasher};
use std::sync::Mutex;

use ash::vk;
use ash::vk::Handle;

/// Pipelines without users kept for a later renderer (lavapipe: 1–500 ms each to make).
pub const IDLE: usize = 128;

/// A 128-bit key of what a pipeline or layout is made from.
pub type Key = (u64, u64);

/// Two independent 64-bit hashes of `value`.
pub fn key_of<T: Hash + ?Sized>(value: &T) -> Key {
    let mut a = std::hash::DefaultHasher::new();
    let mut b = std::hash::DefaultHasher::new();
    0xa5a5_u16.hash(&mut b);
    value.hash(&mut a);
    value.hash(&mut b);
    (a.finish(), b.finish())
}

struct Entry {
    pipeline: vk::Pipeline,
    users: u32,
}

#[derive(Default)]
struct Inner {
    /// Set layout and pipeline layout handles (raw) → their definitions' keys.
    layouts: HashMap<u64, Key>,
    /// Definition key → (the layout kept for it, whether a pipeline layout (else a set
    /// layout)): one layout per definition for the context's life.
    kept: HashMap<Key, (u64, bool)>,
    pipelines: HashMap<Key, Entry>,
    by_handle: HashMap<u64, Key>,
    /// Keys of pipelines without users, the most recently released last.
    idle: VecDeque<Key>,
}

impl Inner {
    /// The pipeline made from `key`, one user more (out of the idle ones if it had none).
    fn take_user(&mut self, key: Key) -> Option<vk::Pipeline> {
        let e = self.pipelines.get_mut(&key)?;
        e.users += 1;
        let p = e.pipeline;
        if e.users == 1 {
            self.idle.retain(|k| *k != key);
        }
        Some(p)
    }
}

/// A context's shared pipelines.
#[derive(Default)]
pub struct PipelineMemo {
    inner: Mutex<Inner>,
}

impl PipelineMemo {
    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The definition key of a layout kept here ([`keep_layout`]); `None` for one made
    /// elsewhere (its pipelines are then not shared).
    pub fn layout_key<H: Handle>(&self, handle: H) -> Option<Key> {
        self.lock().layouts.get(&handle.as_raw()).copied()
    }

    /// The layout kept for definition `key`, if one was made.
    pub fn kept_layout<H: Handle>(&self, key: Key) -> Option<H> {
        self.lock().kept.get(&key).map(|&(raw, _)| H::from_raw(raw))
    }

    /// Keeps `handle` (just made, of definition `key`) for the context's life; the handle
    /// to use: another thread's, where it kept one of the same definition meanwhile (and
    /// `handle` is then returned as the second value, to be destroyed).
    pub fn keep_layout<H: Handle + Copy>(&self, handle: H, key: Key, pipeline_layout: bool) -> (H, Option<H>) {
        let mut g = self.lock();
        if let Some(&(raw, _)) = g.kept.get(&key) {
            return (H::from_raw(raw), Some(handle));
        }
        g.kept.insert(key, (handle.as_raw(), pipeline_layout));
        g.layouts.insert(handle.as_raw(), key);
        (handle, None)
    }

    /// Whether `handle` is a layout kept for the context's life (not destroyed by its user).
    pub fn is_kept<H: Handle>(&self, handle: H) -> bool {
        let raw = handle.as_raw();
        let g = self.lock();
        g.layouts.get(&raw).and_then(|k| g.kept.get(k)).is_some_and(|&(kept, _)| kept == raw)
    }

    /// Every layout kept, for the context's end: (pipeline layouts, set layouts), raw.
    pub fn take_layouts(&self) -> (Vec<u64>, Vec<u64>) {
        let mut g = self.lock();
        g.layouts.clear();
        let (pl, sl): (Vec<_>, Vec<_>) = g.kept.drain().map(|(_, v)| v).partition(|&(_, p)| p);
        (pl.into_iter().map(|(r, _)| r).collect(), sl.into_iter().map(|(r, _)| r).collect())
    }

    /// The pipeline made from `key`, one user more; else `make`'s, recorded with one user.
    /// The second value is a pipeline for the caller to destroy: `make`'s, where another
    /// thread recorded the same one meanwhile.
    pub fn get_or_make(
        &self,
        key: Key,
        make: impl FnOnce() -> crate::error::Result<vk::Pipeline>,
    ) -> crate::error::Result<(vk::Pipeline, Option<vk::Pipeline>)> {
        if let Some(p) = self.lock().take_user(key) {
            return Ok((p, None));
        }
        // Made outside the lock: another thread's pipelines are not held up by this one.
        let p = make()?;
        let mut g = self.lock();
        if let Some(kept) = g.take_user(key) {
            // Another thread made the same one meanwhile: keep one.
            return Ok((kept, Some(p)));
        }
        g.pipelines.insert(key, Entry { pipeline: p, users: 1 });
        g.by_handle.insert(p.as_raw(), key);
        Ok((p, None))
    }

    /// One user fewer of `pipeline`; the pipelines pushed out of the idle ones (or
    /// `pipeline` itself, if it was not made here) are returned to be destroyed.
    pub fn release(&self, pipeline: vk::Pipeline) -> Vec<vk::Pipeline> {
        let mut g = self.lock();
        let Some(&key) = g.by_handle.get(&pipeline.as_raw()) else { return vec![pipeline] };
        let e = g.pipelines.get_mut(&key).expect("a recorded pipeline");
        e.users = e.users.saturating_sub(1);
        if e.users > 0 {
            return Vec::new();
        }
        g.idle.push_back(key);
        let mut out = Vec::new();
        while g.idle.len() > IDLE {
            let k = g.idle.pop_front().expect("idle is not empty");
            if let Some(e) = g.pipelines.remove(&k) {
                g.by_handle.remove(&e.pipeline.as_raw());
                out.push(e.pipeline);
            }
        }
        out
    }

    /// Every pipeline kept, for the context's end.
    pub fn take_all(&self) -> Vec<vk::Pipeline> {
        let mut g = self.lock();
        g.idle.clear();
        g.by_handle.clear();
        g.pipelines.drain().map(|(_, e)| e.pipeline).collect()
    }

    /// (pipelines kept, of them without users).
    pub fn counts(&self) -> (usize, usize) {
        let g = self.lock();
        (g.pipelines.len(), g.idle.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(raw: u64) -> vk::Pipeline {
        vk::Pipeline::from_raw(raw)
    }

    #[test]
    fn a_pipeline_is_made_once_counted_by_users_and_kept_idle_up_to_the_limit() {
        let m = PipelineMemo::default();
        let made = std::cell::Cell::new(0);
        let make = |raw| {
            made.set(made.get() + 1);
            Ok(p(raw))
        };
        let (a, _) = m.get_or_make(key_of("a"), || make(1)).unwrap();
        let (a2, _) = m.get_or_make(key_of("a"), || make(2)).unwrap();
        assert_eq!((a, a2, made.get()), (p(1), p(1), 1));
        assert!(m.release(a).is_empty());
        assert_eq!(m.counts(), (1, 0));
        assert!(m.release(a).is_empty());
        assert_eq!(m.counts(), (1, 1), "kept without users");
        // Asked again: the idle one, no new pipeline.
        let (a3, _) = m.get_or_make(key_of("a"), || make(3)).unwrap();
        assert_eq!((a3, made.get(), m.counts()), (p(1), 1, (1, 0)));
        assert!(m.release(a3).is_empty());
        // A pipeline the memo did not make is returned to be destroyed.
        assert_eq!(m.release(p(99)), vec![p(99)]);
        // Past IDLE idle pipelines, the least recently released go first.
        for i in 0..IDLE as u64 {
            let (q, _) = m.get_or_make(key_of(&i), || make(100 + i)).unwrap();
            let out = m.release(q);
            assert_eq!(out, if i == IDLE as u64 - 1 { vec![p(1)] } else { vec![] }, "{i}");
        }
        assert_eq!(m.counts(), (IDLE, IDLE));
        assert_eq!(m.take_all().len(), IDLE);
        assert_eq!(m.counts(), (0, 0));
    }

    #[test]
    fn layouts_are_matched_by_definition() {
        let m = PipelineMemo::default();
        let a = vk::PipelineLayout::from_raw(7);
        assert_ne!(key_of("same"), key_of("other"));
        // Kept layouts: one per definition, the second made of it handed back to destroy.
        let (c, d) = (vk::PipelineLayout::from_raw(9), vk::PipelineLayout::from_raw(10));
        assert_eq!(m.keep_layout(c, key_of("def"), true), (c, None));
        assert_eq!(m.layout_key(c), Some(key_of("def")));
        assert_eq!(m.keep_layout(d, key_of("def"), true), (c, Some(d)));
        assert_eq!(m.kept_layout::<vk::PipelineLayout>(key_of("def")), Some(c));
        assert!(m.is_kept(c) && !m.is_kept(d) && !m.is_kept(a));
        assert_eq!(m.take_layouts(), (vec![9], vec![]));
        assert!(!m.is_kept(c));
    }
}
