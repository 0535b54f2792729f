//! The context handle and the machinery every call goes through: the live-handle set,
//! the panic boundary (`with_ctx`, `boundary`), error codes and last-error messages, the
//! log callback, the struct-header and C-string checks; and the calls that create,
//! destroy and inspect a context.

use std::cell::RefCell;
use std::collections::HashSet;
use std::ffi::{c_char, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Mutex;

use ash::vk::{self, Handle};
use glam::Vec3;

use super::types::*;
use crate::error::Error;
use crate::methods::{Choice, Method};
use crate::quality::Quality;
use crate::renderer::Renderer;
use crate::scene::Scene;
use crate::vk::{Context, DeviceOptions, HostHandles, VulkanAllocator};

// ------------------------------------------------------------------ the context

const MAGIC: u64 = 0x5350_4543_554c_4131; // "SPECULA1"

/// Opaque context: a device (own or the host's), a scene, knobs and a configured renderer.
pub struct SpeculaContext {
    magic: u64,
    pub(super) scene: Scene,
    pub(super) quality: Quality,
    /// The last configured whole-scene choice.
    pub(super) choice: Choice,
    /// Per-object methods (object name, method), set by specula_context_set_object_method.
    pub(super) object_methods: Vec<(String, Method)>,
    pub(super) renderer: Option<Renderer>,
    /// The budgeted planner's choices and knobs of the last configure with a budget, reused
    /// when an update replans, and its prediction.
    pub(super) budget: Option<(crate::plan::Choices, Quality, crate::plan::budget::Prediction)>,
    /// Bumped on every scene change; a renderer built for an older scene is stale.
    pub(super) scene_version: u64,
    pub(super) renderer_version: u64,
    /// A standalone context's update changed the plan: the next render reconfigures.
    pub(super) replan: bool,
    /// Where `auto`'s unit costs are cached (`SpeculaRenderDesc::cache_dir`); `None`: the
    /// default (`plan::predict::cost_model::cache_dir`).
    pub(super) cache_dir: Option<std::path::PathBuf>,
    /// NUL-terminated message of the last failed call, overwritten in place so that a
    /// pointer the caller holds stays valid for the context's lifetime.
    last_error: [u8; MESSAGE_BYTES],
    pub(super) log: SpeculaLogCallback,
    pub(super) log_user: *mut c_void,
    /// Dropped last: everything above that holds device objects is freed before it.
    pub(super) vk: Context,
}

/// Live context pointers: a destroyed or foreign handle is detected, not dereferenced.
static LIVE: Mutex<Option<HashSet<usize>>> = Mutex::new(None);

const MESSAGE_BYTES: usize = 1024;

thread_local! {
    /// Like `last_error`, per thread, for the create calls (which have no context yet).
    static CREATION_ERROR: RefCell<Box<[u8; MESSAGE_BYTES]>> = RefCell::new(Box::new([0; MESSAGE_BYTES]));
}

/// Copies `msg` into `buf` NUL-terminated, truncated at a character boundary.
fn store_message(buf: &mut [u8; MESSAGE_BYTES], msg: &str) {
    let mut end = msg.len().min(MESSAGE_BYTES - 1);
    while !msg.is_char_boundary(end) {
        end -= 1;
    }
    buf[..end].copy_from_slice(&msg.as_bytes()[..end]);
    buf[end] = 0;
    for b in &mut buf[..end] {
        if *b == 0 {
            *b = b' ';
        }
    }
}

fn live_insert(p: *mut SpeculaContext) {
    let mut l = LIVE.lock().unwrap_or_else(|e| e.into_inner());
    l.get_or_insert_with(HashSet::new).insert(p as usize);
}

fn live_remove(p: *mut SpeculaContext) -> bool {
    let mut l = LIVE.lock().unwrap_or_else(|e| e.into_inner());
    l.as_mut().is_some_and(|s| s.remove(&(p as usize)))
}

fn is_live(p: *const SpeculaContext) -> bool {
    let l = LIVE.lock().unwrap_or_else(|e| e.into_inner());
    l.as_ref().is_some_and(|s| s.contains(&(p as usize)))
}

/// Number of live contexts (tests use it to prove destroy frees them).
#[no_mangle]
pub extern "C" fn specula_live_context_count() -> u32 {
    let l = LIVE.lock().unwrap_or_else(|e| e.into_inner());
    l.as_ref().map_or(0, |s| s.len() as u32)
}

fn code(e: &Error) -> SpeculaResult {
    match e {
        Error::Io { .. } => SPECULA_ERROR_IO,
        Error::Scene { .. } => SPECULA_ERROR_SCENE,
        Error::InvalidInput { .. } | Error::Image(_) => SPECULA_ERROR_INVALID_ARGUMENT,
        Error::Unsupported(_) => SPECULA_ERROR_UNSUPPORTED,
        Error::OutOfMemory(_) => SPECULA_ERROR_OUT_OF_MEMORY,
        Error::Vulkan { .. } => SPECULA_ERROR_VULKAN,
        Error::Validation(_) => SPECULA_ERROR_VALIDATION,
        Error::PlanChanged(_) => SPECULA_ERROR_WRONG_ORDER,
    }
}

/// A failure with its code and message.
pub(super) struct Fail(SpeculaResult, String);

impl From<Error> for Fail {
    fn from(e: Error) -> Fail {
        Fail(code(&e), e.to_string())
    }
}

pub(super) type FfiResult<T = ()> = Result<T, Fail>;

pub(super) fn fail<T>(code: SpeculaResult, msg: impl Into<String>) -> FfiResult<T> {
    Err(Fail(code, msg.into()))
}

/// Runs `f` with the panic boundary: a panic becomes SPECULA_ERROR_PANIC.
fn boundary(f: impl FnOnce() -> FfiResult<SpeculaResult>) -> Result<SpeculaResult, Fail> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(p) => {
            let msg = p.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| p.downcast_ref::<String>().cloned()).unwrap_or_default();
            Err(Fail(SPECULA_ERROR_PANIC, format!("internal panic: {msg}")))
        }
    }
}

impl SpeculaContext {
    fn set_error(&mut self, f: &Fail) {
        store_message(&mut self.last_error, &f.1);
        self.log(SPECULA_LOG_ERROR, &f.1);
    }

    pub(super) fn log(&self, level: SpeculaLogLevel, msg: &str) {
        if let Some(cb) = self.log {
            if let Ok(m) = CString::new(msg.replace('\0', " ")) {
                // A panicking callback must not unwind into us: C callbacks cannot unwind.
                unsafe { cb(self.log_user, level, m.as_ptr()) };
            }
        }
    }

    pub(super) fn forward_validation_messages(&self) {
        for m in self.vk.validation.error_messages() {
            let level = if m.starts_with("warning: ") { SPECULA_LOG_WARNING } else { SPECULA_LOG_ERROR };
            self.log(level, &m);
        }
    }

    pub(super) fn destroy_renderer(&mut self) {
        if let Some(mut r) = self.renderer.take() {
            let _ = self.vk.wait_idle_if_owned();
            r.destroy(&self.vk);
        }
    }

    pub(super) fn renderer(&mut self) -> FfiResult<&mut Renderer> {
        if self.renderer.is_none() {
            return fail(SPECULA_ERROR_WRONG_ORDER, "no renderer: call specula_context_configure first");
        }
        if self.renderer_version != self.scene_version {
            return fail(
                SPECULA_ERROR_WRONG_ORDER,
                "the scene changed since specula_context_configure (or an update changed its plan): configure again",
            );
        }
        Ok(self.renderer.as_mut().unwrap())
    }
}

impl Drop for SpeculaContext {
    fn drop(&mut self) {
        self.destroy_renderer();
        self.magic = 0;
    }
}

/// Looks a handle up and runs `f` on it inside the panic boundary, recording any error as
/// the context's last error.
pub(super) unsafe fn with_ctx(ctx: *mut SpeculaContext, f: impl FnOnce(&mut SpeculaContext) -> FfiResult<SpeculaResult>) -> SpeculaResult {
    if ctx.is_null() {
        return SPECULA_ERROR_INVALID_HANDLE;
    }
    if !is_live(ctx) || (*ctx).magic != MAGIC {
        return SPECULA_ERROR_INVALID_HANDLE;
    }
    let c = &mut *ctx;
    match boundary(|| f(c)) {
        Ok(r) => r,
        Err(e) => {
            c.set_error(&e);
            e.0
        }
    }
}

/// Checks a struct's tag and size and returns a reference to it.
pub(super) unsafe fn header<'a, T>(p: *const T, tag: SpeculaStructType, what: &str) -> FfiResult<&'a T> {
    if p.is_null() {
        return fail(SPECULA_ERROR_NULL_POINTER, format!("{what} is NULL"));
    }
    // Every struct starts with (type, size): read those two first, then the rest.
    let head = p as *const u32;
    let (t, size) = (*head, *head.add(1));
    if t != tag {
        return fail(SPECULA_ERROR_STRUCT_MISMATCH, format!("{what}: type tag {t}, expected {tag}"));
    }
    if (size as usize) < std::mem::size_of::<T>() {
        return fail(SPECULA_ERROR_STRUCT_MISMATCH, format!("{what}: size {size}, expected at least {}", std::mem::size_of::<T>()));
    }
    Ok(&*p)
}

/// A struct that grew: checks its tag and that its size covers at least the first
/// `min_size` bytes (the struct as first released), and returns a copy whose fields beyond
/// the caller's size are zero (each such field documents that zero is its default), with
/// the size the caller gave.
pub(super) unsafe fn header_grown<T: Copy>(p: *const T, tag: SpeculaStructType, what: &str, min_size: usize) -> FfiResult<(T, usize)> {
    if p.is_null() {
        return fail(SPECULA_ERROR_NULL_POINTER, format!("{what} is NULL"));
    }
    let head = p as *const u32;
    let (t, size) = (*head, *head.add(1) as usize);
    if t != tag {
        return fail(SPECULA_ERROR_STRUCT_MISMATCH, format!("{what}: type tag {t}, expected {tag}"));
    }
    if size < min_size {
        return fail(SPECULA_ERROR_STRUCT_MISMATCH, format!("{what}: size {size}, expected at least {min_size}"));
    }
    let mut out = std::mem::MaybeUninit::<T>::zeroed();
    let n = size.min(std::mem::size_of::<T>());
    std::ptr::copy_nonoverlapping(p as *const u8, out.as_mut_ptr() as *mut u8, n);
    // SAFETY: every T this is used with is plain data (integers and floats) for which
    // all-zero bytes are a valid value.
    Ok((out.assume_init(), size))
}

pub(super) unsafe fn cstr<'a>(p: *const c_char, what: &str) -> FfiResult<&'a str> {
    if p.is_null() {
        return fail(SPECULA_ERROR_NULL_POINTER, format!("{what} is NULL"));
    }
    CStr::from_ptr(p).to_str().or_else(|_| fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("{what} is not UTF-8")))
}

/// Checks a list getter's output arguments: `count` non-NULL, `out` non-NULL when it has room.
pub(super) unsafe fn list_args<T>(out: *mut T, capacity: u32, count: *mut u32) -> FfiResult<()> {
    if count.is_null() {
        return fail(SPECULA_ERROR_NULL_POINTER, "count is NULL");
    }
    if out.is_null() && capacity > 0 {
        return fail(SPECULA_ERROR_NULL_POINTER, "out is NULL with capacity > 0");
    }
    Ok(())
}

/// Writes `items`' count into `*count` and as many as fit into `out` (checked by
/// `list_args`); SPECULA_WARNING_TRUNCATED when some did not fit.
pub(super) unsafe fn write_list<T: Copy>(items: &[T], out: *mut T, capacity: u32, count: *mut u32) -> SpeculaResult {
    *count = items.len() as u32;
    for (i, e) in items.iter().take(capacity as usize).enumerate() {
        *out.add(i) = *e;
    }
    if (capacity as usize) < items.len() {
        SPECULA_WARNING_TRUNCATED
    } else {
        SPECULA_SUCCESS
    }
}

/// `s` NUL-terminated in N bytes, cut at a character boundary.
pub(super) fn fixed_str<const N: usize>(s: &str) -> [c_char; N] {
    let mut out = [0 as c_char; N];
    let mut end = s.len().min(N - 1);
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    for (d, b) in out.iter_mut().zip(s[..end].bytes()) {
        *d = b as c_char;
    }
    out
}

pub(super) fn vec3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

fn set_creation_error(f: &Fail) {
    CREATION_ERROR.with(|e| store_message(&mut e.borrow_mut(), &f.1));
}

fn create(out: *mut *mut SpeculaContext, make: impl FnOnce() -> FfiResult<Context>) -> SpeculaResult {
    let r = boundary(|| {
        if out.is_null() {
            return fail(SPECULA_ERROR_NULL_POINTER, "out is NULL");
        }
        unsafe { *out = std::ptr::null_mut() };
        let vk = make()?;
        let ctx = Box::new(SpeculaContext {
            magic: MAGIC,
            scene: Scene::new(),
            quality: Quality::default(),
            choice: Choice::Auto,
            object_methods: Vec::new(),
            renderer: None,
            budget: None,
            scene_version: 0,
            renderer_version: 0,
            replan: false,
            cache_dir: None,
            last_error: [0; MESSAGE_BYTES],
            log: None,
            log_user: std::ptr::null_mut(),
            vk,
        });
        let p = Box::into_raw(ctx);
        live_insert(p);
        unsafe { *out = p };
        Ok(SPECULA_SUCCESS)
    });
    match r {
        Ok(c) => c,
        Err(f) => {
            set_creation_error(&f);
            f.0
        }
    }
}

impl Context {
    fn wait_idle_if_owned(&self) -> crate::Result<()> {
        if self.owns_device() {
            self.wait_idle()
        } else {
            Ok(())
        }
    }
}

// ------------------------------------------------------------------ entry points

/// The library version as VK_MAKE_API_VERSION(0, major, minor, patch). Thread-safe.
#[no_mangle]
pub extern "C" fn specula_version() -> u32 {
    let v = |s: &str| s.parse::<u32>().unwrap_or(0);
    vk::make_api_version(0, v(env!("CARGO_PKG_VERSION_MAJOR")), v(env!("CARGO_PKG_VERSION_MINOR")), v(env!("CARGO_PKG_VERSION_PATCH")))
}

/// The message of the last failed specula_context_create*, specula_get_requirements or
/// specula_set_host_allocator on this thread ("" if none). The pointer stays valid for the
/// thread's lifetime; its text changes with the next failure. Thread-safe.
#[no_mangle]
pub extern "C" fn specula_creation_error() -> *const c_char {
    CREATION_ERROR.with(|e| e.borrow().as_ptr() as *const c_char)
}

/// Fills `out` with what a host must enable (host-device mode). Thread-safe.
#[no_mangle]
pub unsafe extern "C" fn specula_get_requirements(out: *mut SpeculaRequirements) -> SpeculaResult {
    let r = boundary(|| {
        header(out as *const SpeculaRequirements, SPECULA_STRUCT_REQUIREMENTS, "requirements")?;
        let _: &[&CStr; 1] = &[ash::ext::robustness2::NAME]; // the one extension PTRS spells out
                                                             // Static C strings of REQUIRED_DEVICE_EXTENSIONS (a test checks they agree).
        struct Ptrs([*const c_char; 1]);
        unsafe impl Sync for Ptrs {}
        static PTRS: Ptrs = Ptrs([c"VK_EXT_robustness2".as_ptr()]);
        // Static C strings of RAY_QUERY_DEVICE_EXTENSIONS (a test checks they agree).
        struct Optional([*const c_char; 3]);
        unsafe impl Sync for Optional {}
        static OPTIONAL: Optional = Optional([
            c"VK_KHR_acceleration_structure".as_ptr(),
            c"VK_KHR_ray_query".as_ptr(),
            c"VK_KHR_deferred_host_operations".as_ptr(),
        ]);
        let o = &mut *out;
        o.api_version = vk::API_VERSION_1_3;
        o.device_extensions = PTRS.0.as_ptr();
        o.device_extension_count = PTRS.0.len() as u32;
        o.instance_extension_count = 0;
        o.image_cube_array = 1;
        o.multiview = 1;
        o.dynamic_rendering = 1;
        o.synchronization2 = 1;
        o.maintenance4 = 1;
        o.null_descriptor = 1;
        o.optional_device_extensions = OPTIONAL.0.as_ptr();
        o.optional_device_extension_count = OPTIONAL.0.len() as u32;
        o.acceleration_structure = 1;
        o.ray_query = 1;
        o.buffer_device_address = 1;
        Ok(SPECULA_SUCCESS)
    });
    r.unwrap_or_else(|f| {
        set_creation_error(&f);
        f.0
    })
}

/// Standalone mode: creates a context with its own headless device. On failure `*out` is
/// NULL and specula_creation_error() says why. Thread-safe.
#[no_mangle]
pub unsafe extern "C" fn specula_context_create(desc: *const SpeculaContextDesc, out: *mut *mut SpeculaContext) -> SpeculaResult {
    create(out, || {
        let (d, _) = header_grown(desc, SPECULA_STRUCT_CONTEXT_DESC, "desc", SPECULA_CONTEXT_DESC_SIZE_V1 as usize)?;
        let filter = if d.device_name.is_null() { None } else { Some(cstr(d.device_name, "desc.device_name")?.to_string()) };
        Ok(Context::new(&DeviceOptions {
            validation: d.enable_validation != 0,
            device_filter: filter,
            allocation_callbacks: vulkan_allocator(d.vulkan_allocator)?,
            ..Default::default()
        })?)
    })
}

/// Host-device mode: creates a context on the host's instance and device (see
/// SpeculaHostDesc). The library never submits and never destroys the host's objects.
/// Thread-safe.
#[no_mangle]
pub unsafe extern "C" fn specula_context_create_host(desc: *const SpeculaHostDesc, out: *mut *mut SpeculaContext) -> SpeculaResult {
    create(out, || {
        let (d, _) = header_grown(desc, SPECULA_STRUCT_HOST_DESC, "desc", SPECULA_HOST_DESC_SIZE_V1 as usize)?;
        let Some(gipa) = d.get_instance_proc_addr else { return fail(SPECULA_ERROR_NULL_POINTER, "desc.get_instance_proc_addr is NULL") };
        if d.instance.is_null() || d.physical_device.is_null() || d.device.is_null() {
            return fail(SPECULA_ERROR_NULL_POINTER, "desc.instance, physical_device and device must not be NULL");
        }
        let host = HostHandles {
            // Same C ABI on every platform Vulkan runs on here ("system" = "C" on x86-64 Linux).
            get_instance_proc_addr: std::mem::transmute::<
                unsafe extern "C" fn(*mut c_void, *const c_char) -> SpeculaVoidFunction,
                vk::PFN_vkGetInstanceProcAddr,
            >(gipa),
            instance: vk::Instance::from_raw(d.instance as u64),
            physical_device: vk::PhysicalDevice::from_raw(d.physical_device as u64),
            device: vk::Device::from_raw(d.device as u64),
            queue_family: d.queue_family,
            debug_utils: d.debug_utils_enabled != 0,
            ray_query: d.ray_query_enabled != 0,
            allocation_callbacks: vulkan_allocator(d.vulkan_allocator)?,
        };
        Ok(Context::from_host(&host)?)
    })
}

/// A host's `VkAllocationCallbacks`, copied; NULL is none. Vulkan requires the allocation,
/// reallocation and free functions.
unsafe fn vulkan_allocator(p: *const c_void) -> FfiResult<Option<VulkanAllocator>> {
    if p.is_null() {
        return Ok(None);
    }
    let c = *(p as *const vk::AllocationCallbacks<'static>);
    for (missing, name) in [
        (c.pfn_allocation.is_none(), "pfnAllocation"),
        (c.pfn_reallocation.is_none(), "pfnReallocation"),
        (c.pfn_free.is_none(), "pfnFree"),
    ] {
        if missing {
            return fail(SPECULA_ERROR_NULL_POINTER, format!("desc.vulkan_allocator->{name} is NULL"));
        }
    }
    Ok(Some(VulkanAllocator(c)))
}

/// Routes the library's CPU allocations (every context's, and the calls' own) through the
/// host's allocator from now on; NULL returns to the system allocator. Process-wide: Rust
/// allocates through one allocator per program. Blocks already made are freed by the
/// allocator that made them, so this may be called at any time; the callbacks must stay
/// callable until the process ends. SPECULA_ERROR_UNSUPPORTED where the library was built
/// without its `host-allocator` feature. Thread-safe.
#[no_mangle]
pub unsafe extern "C" fn specula_set_host_allocator(allocator: *const SpeculaHostAllocator) -> SpeculaResult {
    let r = boundary(|| {
        let hooks = if allocator.is_null() {
            None
        } else {
            let (a, _) = header_grown(allocator, SPECULA_STRUCT_HOST_ALLOCATOR, "allocator", std::mem::size_of::<SpeculaHostAllocator>())?;
            let (Some(allocate), Some(free)) = (a.allocate, a.free) else {
                return fail(SPECULA_ERROR_NULL_POINTER, "allocator.allocate and allocator.free must not be NULL");
            };
            Some(super::allocator::Hooks { user: a.user, allocate, free })
        };
        if !super::allocator::set(hooks) {
            return fail(SPECULA_ERROR_UNSUPPORTED, "the library was built without its host-allocator feature");
        }
        Ok(SPECULA_SUCCESS)
    });
    r.unwrap_or_else(|f| {
        set_creation_error(&f);
        f.0
    })
}

/// Destroys a context and everything it created. Needs an idle GPU in host-device mode
/// (no submitted frame of this context may still run). Passing NULL does nothing; a
/// destroyed handle returns SPECULA_ERROR_INVALID_HANDLE. Not thread-safe per context.
#[no_mangle]
pub unsafe extern "C" fn specula_context_destroy(ctx: *mut SpeculaContext) -> SpeculaResult {
    if ctx.is_null() {
        return SPECULA_SUCCESS;
    }
    if !live_remove(ctx) {
        return SPECULA_ERROR_INVALID_HANDLE;
    }
    match catch_unwind(AssertUnwindSafe(|| drop(Box::from_raw(ctx)))) {
        Ok(()) => SPECULA_SUCCESS,
        Err(_) => SPECULA_ERROR_PANIC,
    }
}

/// The message of the last failed call on `ctx` ("" if none). The pointer stays valid until
/// the context is destroyed; its text changes with the next failure. Returns a static
/// message for an invalid handle.
#[no_mangle]
pub unsafe extern "C" fn specula_context_last_error(ctx: *const SpeculaContext) -> *const c_char {
    if ctx.is_null() || !is_live(ctx) || (*ctx).magic != MAGIC {
        return c"invalid context handle (NULL, destroyed, or not a specula context)".as_ptr();
    }
    (*ctx).last_error.as_ptr() as *const c_char
}

/// Installs (or, with NULL, removes) a log callback for `ctx`.
#[no_mangle]
pub unsafe extern "C" fn specula_context_set_log_callback(
    ctx: *mut SpeculaContext,
    callback: SpeculaLogCallback,
    user: *mut c_void,
) -> SpeculaResult {
    with_ctx(ctx, |c| {
        c.log = callback;
        c.log_user = user;
        Ok(SPECULA_SUCCESS)
    })
}
