//! Resources several stages of one frame share: made by the first stage that asks for one,
//! held by every stage that uses it, told once of each scene change (before the stages) and
//! when a frame begins, and destroyed by the renderer after its stages. The frame names none of them: each is declared where it is made (the
//! scene's acceleration structures for ray queries, `methods::raytrace::ray_query::shared`).

use std::any::Any;
use std::cell::RefCell;
use std::rc::Rc;

use crate::frame::stage::StageInit;
use crate::scene::update::Changes;
use crate::vk::Context;
use crate::{Error, Result};

/// What a shared resource does beyond being used.
pub trait SharedResource: Any {
    /// The scene changed (`init` holds it as it is now): called once per change, before the
    /// stages' own updates.
    fn scene_changed(&mut self, _init: &StageInit, _changes: &Changes) -> Result<()> {
        Ok(())
    }
    /// A frame begins (before any stage records).
    fn begin_frame(&mut self) {}
    fn destroy(&mut self, ctx: &Context);
}

struct Entry {
    key: &'static str,
    /// For handing out as its own type.
    any: Rc<dyn Any>,
    /// For the frame's calls.
    resource: Rc<RefCell<dyn SharedResource>>,
}

/// The frame's shared resources, by key.
#[derive(Default)]
pub struct Shared {
    entries: RefCell<Vec<Entry>>,
}

impl Shared {
    /// The resource under `key`, made by `create` if no stage asked for it before.
    pub fn get_or_create<T: SharedResource>(&self, key: &'static str, create: impl FnOnce() -> Result<T>) -> Result<Rc<RefCell<T>>> {
        if let Some(e) = self.entries.borrow().iter().find(|e| e.key == key) {
            return e
                .any
                .clone()
                .downcast::<RefCell<T>>()
                .map_err(|_| Error::invalid("shared resource", format!("'{key}' holds another type")));
        }
        let made = Rc::new(RefCell::new(create()?));
        self.entries.borrow_mut().push(Entry { key, any: made.clone(), resource: made.clone() });
        Ok(made)
    }

    /// Keys of the resources made, in order.
    pub fn keys(&self) -> Vec<&'static str> {
        self.entries.borrow().iter().map(|e| e.key).collect()
    }

    pub fn scene_changed(&self, init: &StageInit, changes: &Changes) -> Result<()> {
        for e in self.entries.borrow().iter() {
            e.resource.borrow_mut().scene_changed(init, changes)?;
        }
        Ok(())
    }

    pub fn begin_frame(&self) {
        for e in self.entries.borrow().iter() {
            e.resource.borrow_mut().begin_frame();
        }
    }

    /// Destroys every resource (after the stages that held them).
    pub fn destroy(&self, ctx: &Context) {
        for e in self.entries.borrow_mut().drain(..) {
            e.resource.borrow_mut().destroy(ctx);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Counter(u32);
    impl SharedResource for Counter {
        fn begin_frame(&mut self) {
            self.0 = 0;
        }
        fn destroy(&mut self, _: &Context) {}
    }

    /// The first asker makes it, later askers get the same one; another type under the same
    /// key is an error, not a panic.
    #[test]
    fn one_resource_per_key() {
        let shared = Shared::default();
        let a = shared.get_or_create("counter", || Ok(Counter(1))).unwrap();
        let b = shared.get_or_create::<Counter>("counter", || panic!("made twice")).unwrap();
        assert!(Rc::ptr_eq(&a, &b));
        a.borrow_mut().0 = 5;
        shared.begin_frame();
        assert_eq!(b.borrow().0, 0);
        struct Other;
        impl SharedResource for Other {
            fn destroy(&mut self, _: &Context) {}
        }
        assert!(shared.get_or_create("counter", || Ok(Other)).is_err());
        assert_eq!(shared.keys(), vec!["counter"]);
    }
}
