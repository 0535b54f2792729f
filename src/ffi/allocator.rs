//! The library's CPU allocations through the host's allocator (`specula_set_host_allocator`),
//! as engines route a plugin's memory into their own budgets and trackers.
//!
//! Rust allocates through one global allocator per program, so the host's callbacks are
//! process-wide, not per context. With the `host-allocator` feature (on by default) the
//! library installs [`Routed`] as the global allocator of whatever links it: every block
//! carries, just before the pointer it hands out, which allocator made it (the system's or
//! one the host registered), so a block made before the host switched allocators is freed
//! by the allocator that made it, whenever the switch happens. Registered callbacks are kept
//! for the life of the process for that reason (a few dozen bytes each).
//!
//! A Rust program with a global allocator of its own builds the library without the
//! feature (`default-features = false`), and then `specula_set_host_allocator` returns
//! SPECULA_ERROR_UNSUPPORTED.

use std::ffi::c_void;

/// What the host registered, kept for the process's life (blocks point at it).
#[derive(Clone, Copy)]
#[cfg_attr(not(feature = "host-allocator"), allow(dead_code))]
pub(crate) struct Hooks {
    pub user: *mut c_void,
    pub allocate: unsafe extern "C" fn(user: *mut c_void, size: usize, alignment: usize) -> *mut c_void,
    pub free: unsafe extern "C" fn(user: *mut c_void, memory: *mut c_void, size: usize, alignment: usize),
}

#[cfg(feature = "host-allocator")]
mod routed {
    use std::alloc::{GlobalAlloc, Layout, System};
    use std::sync::atomic::{AtomicPtr, Ordering};

    use super::Hooks;

    /// The host's hooks, or null: the system allocator.
    static HOOKS: AtomicPtr<Hooks> = AtomicPtr::new(std::ptr::null_mut());

    /// Routes every allocation to the system's or the host's allocator and tags each block
    /// with its owner, in a prefix of max(alignment, 16) bytes before the returned pointer
    /// (the owner's address in its last 8 bytes; 0 for the system's).
    pub struct Routed;

    #[global_allocator]
    static GLOBAL: Routed = Routed;

    fn prefix(l: Layout) -> usize {
        l.align().max(16)
    }

    /// The block the allocator made for `l`: its size and alignment.
    fn outer(l: Layout) -> Option<Layout> {
        let pre = prefix(l);
        Layout::from_size_align(l.size().checked_add(pre)?, pre).ok()
    }

    unsafe fn tag(p: *mut u8) -> *mut usize {
        p.sub(std::mem::size_of::<usize>()) as *mut usize
    }

    impl Routed {
        unsafe fn make(&self, l: Layout, zeroed: bool) -> *mut u8 {
            let Some(o) = outer(l) else { return std::ptr::null_mut() };
            let hooks = HOOKS.load(Ordering::Acquire);
            let base = if hooks.is_null() {
                if zeroed {
                    System.alloc_zeroed(o)
                } else {
                    System.alloc(o)
                }
            } else {
                let h = &*hooks;
                let b = (h.allocate)(h.user, o.size(), o.align()) as *mut u8;
                if !b.is_null() && zeroed {
                    std::ptr::write_bytes(b, 0, o.size());
                }
                b
            };
            if base.is_null() {
                return base;
            }
            let p = base.add(o.align());
            tag(p).write(hooks as usize);
            p
        }
    }

    unsafe impl GlobalAlloc for Routed {
        unsafe fn alloc(&self, l: Layout) -> *mut u8 {
            self.make(l, false)
        }

        unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
            self.make(l, true)
        }

        unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
            let Some(o) = outer(l) else { return };
            let owner = tag(p).read() as *const Hooks;
            let base = p.sub(o.align());
            if owner.is_null() {
                System.dealloc(base, o);
            } else {
                let h = &*owner;
                (h.free)(h.user, base as *mut _, o.size(), o.align());
            }
        }

        unsafe fn realloc(&self, p: *mut u8, l: Layout, new_size: usize) -> *mut u8 {
            let owner = tag(p).read() as *const Hooks;
            let (Some(o), Ok(new)) = (outer(l), Layout::from_size_align(new_size, l.align())) else { return std::ptr::null_mut() };
            // A system block while the system allocates: grown in place where it can be.
            if owner.is_null() && HOOKS.load(Ordering::Acquire).is_null() {
                let Some(n) = outer(new) else { return std::ptr::null_mut() };
                let base = System.realloc(p.sub(o.align()), o, n.size());
                return if base.is_null() { base } else { base.add(o.align()) };
            }
            let q = self.make(new, false);
            if !q.is_null() {
                std::ptr::copy_nonoverlapping(p, q, l.size().min(new_size));
                self.dealloc(p, l);
            }
            q
        }
    }

    /// Installs the host's hooks (`None`: the system allocator again). Blocks keep their
    /// owner; the hooks live for the process.
    pub fn set(hooks: Option<Hooks>) {
        let p = hooks.map_or(std::ptr::null_mut(), |h| Box::into_raw(Box::new(h)));
        HOOKS.store(p, Ordering::Release);
    }
}

/// Installs the host's hooks process-wide; `false` where the library was built without the
/// `host-allocator` feature.
pub(crate) fn set(hooks: Option<Hooks>) -> bool {
    #[cfg(feature = "host-allocator")]
    {
        routed::set(hooks);
        true
    }
    #[cfg(not(feature = "host-allocator"))]
    {
        let _ = hooks;
        false
    }
}
