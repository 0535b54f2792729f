//! A create/render/destroy loop of contexts leaks nothing. Valgrind and LeakSanitizer
//! are impractical with lavapipe (its LLVM JIT makes a valgrind run of this loop take hours
//! and drowns LSan in the driver's deliberate process-lifetime caches), so the test counts
//! instead, with the Khronos validation layer on:
//! - Vulkan objects: at vkDestroyDevice the layer reports every child object still alive
//!   as an error; the process-wide validation error count must stay 0.
//! - Device memory: each context's allocation registry is empty before its device goes.
//! - Host memory of the library: every Rust allocation of this process goes through counting
//!   callbacks registered with `specula_set_host_allocator` (the C ABI's host allocator);
//!   after 6 warm-up cycles the live Rust heap must not grow over the next 24 (measured: 0 B
//!   in every run; the bound, under a byte per cycle, shows any allocation leaked every cycle).
//! - Host memory of the whole process's C heap (the loader, the layer, lavapipe and the
//!   library): glibc's `mallinfo2` live bytes, after `malloc_trim`, after each cycle. The
//!   driver keeps 464 B a cycle (the median step of every run; the same with the validation
//!   layer off, while the library's own heap stays flat; heaptrack finds about 110 B a cycle
//!   never freed, 60 B of it allocated under vkSetDebugUtilsObjectNameEXT, the rest freed at
//!   exit), and its transient allocations move single samples by up to 1.5 KiB. Measured
//!   over ten runs: the least-squares slope 460–507 B per cycle (standard deviation 15 B),
//!   the median step 464 B every time (Mesa 22.3.6). The bounds: the slope at most 560 B
//!   (the largest measured plus 3.5 standard deviations) and the median step at most 528 B
//!   (measured plus one 64-byte block), so that a leak of about 100 B every cycle shows on
//!   that driver. On Mesa 25.0.7 (scripts/setup.sh) the driver keeps less: slope 28–95 B,
//!   median step 0 B in three runs. Since each context keeps its pipelines and layouts for
//!   its renderers (`vk::pipeline_memo`), lavapipe keeps more per context: over 13 runs the
//!   slope 53–1298 B (537–1298 but for one), the median step 0–1424 B, with the validation
//!   layer; 460–530 B without it, against 28–130 B with the pipelines made per renderer
//!   (296–534 B with the layer, the same day). Not found in the library (its heap stays
//!   flat, every Vulkan object is destroyed before its device, an empty submission after the
//!   pipelines' destruction changes nothing, and neither does keeping one layout per
//!   definition). The bounds, 1800 B for both, let a leak of about 500 B a cycle through. (Those runs
//!   counted 40 cycles after 10; the suite counts 24 after 6, 20 s less of CI: the slope's
//!   spread grows by (40/24)^1.5, about 2.2, which on Mesa 25 leaves it far under the bound.) The
//!   33 KiB per cycle the hardening issue measured is the layer's synchronization
//!   validation (Vulkan-ValidationLayers 1.3.239 keeps about 31 KiB per device it
//!   tracks): this test turns it off (`SPECULA_SYNC_VALIDATION=0`) so that it measures the
//!   library; tests/sync_validation.rs keeps the hazard checks.
//! - Handles: no live context remains.
//!
//! Not counted: the resident size. Without the layer it still grows by 20–40 KiB per cycle
//! while the C heap grows by under 0.5 KiB: the growth is in lavapipe's process-wide LLVM code memory
//! (its rwx mappings grow by one every two cycles), which destroying the device does not
//! release; a create/destroy loop of bare contexts (no pipelines) shows none.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::ffi::c_void;
use std::sync::atomic::{AtomicIsize, Ordering};

use specula::ffi::*;

static LIVE_BYTES: AtomicIsize = AtomicIsize::new(0);
static HOST_ALLOCATIONS: AtomicIsize = AtomicIsize::new(0);

unsafe extern "C" fn count_allocate(_user: *mut c_void, size: usize, alignment: usize) -> *mut c_void {
    LIVE_BYTES.fetch_add(size as isize, Ordering::Relaxed);
    HOST_ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
    System.alloc(Layout::from_size_align(size, alignment).unwrap()) as *mut c_void
}

unsafe extern "C" fn count_free(_user: *mut c_void, p: *mut c_void, size: usize, alignment: usize) {
    LIVE_BYTES.fetch_sub(size as isize, Ordering::Relaxed);
    System.dealloc(p as *mut u8, Layout::from_size_align(size, alignment).unwrap())
}

/// Every Rust allocation of this process through the counting callbacks from now on (the
/// library's global allocator routes them, the test harness's own included).
fn count_the_heap() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let a = SpeculaHostAllocator {
            r#type: SPECULA_STRUCT_HOST_ALLOCATOR,
            size: std::mem::size_of::<SpeculaHostAllocator>() as u32,
            user: std::ptr::null_mut(),
            allocate: Some(count_allocate),
            free: Some(count_free),
        };
        assert_eq!(unsafe { specula_set_host_allocator(&a) }, SPECULA_SUCCESS);
    });
}

fn ok(r: SpeculaResult, ctx: *mut SpeculaContext) {
    if r != SPECULA_SUCCESS {
        let msg = unsafe { std::ffi::CStr::from_ptr(specula_context_last_error(ctx)) };
        panic!("{r}: {msg:?}");
    }
}

/// One context: a mirror, a glass triangle pair and a floor from arrays, one light.
unsafe fn cycle() {
    let ctx = common::c_context();
    build_scene(ctx);
    let rd = render_desc(specula::methods::ENVMAP.abi);
    ok(specula_context_configure(ctx, &rd), ctx);
    let mut px = [0u8; 16 * 16 * 4];
    ok(specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, px.as_mut_ptr().cast(), px.len()), ctx);
    let mut bytes = 0;
    ok(specula_context_memory_bytes(ctx, &mut bytes), ctx);
    assert!(bytes > 0);
    // Re-configuring frees the old renderer's memory before the new one allocates.
    ok(specula_context_configure(ctx, &rd), ctx);
    ok(specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, px.as_mut_ptr().cast(), px.len()), ctx);
    let mut again = 0;
    ok(specula_context_memory_bytes(ctx, &mut again), ctx);
    assert_eq!(bytes, again, "re-configure leaked device memory");
    assert_eq!(specula_context_destroy(ctx), SPECULA_SUCCESS);
}

fn render_desc(method: u32) -> SpeculaRenderDesc {
    SpeculaRenderDesc {
        r#type: SPECULA_STRUCT_RENDER_DESC,
        size: std::mem::size_of::<SpeculaRenderDesc>() as u32,
        method,
        width: 16,
        height: 16,
        max_ms: 0.0,
        min_psnr_db: 0.0,
        models_path: std::ptr::null(),
        cache_dir: std::ptr::null(),
    }
}

/// A mirror, a glass triangle pair and a floor from arrays, one light, a camera; small maps.
unsafe fn build_scene(ctx: *mut SpeculaContext) {
    let mat = |surface, ior| {
        let m = SpeculaMaterialDesc {
            r#type: SPECULA_STRUCT_MATERIAL_DESC,
            size: std::mem::size_of::<SpeculaMaterialDesc>() as u32,
            surface,
            base_color: [0.5; 3],
            emission: [0.1; 3],
            nu: [0.2; 3],
            kappa: [3.0; 3],
            ior,
            thin: 0,
            attenuation_color: [0.0; 3],
            attenuation_distance: 0.0,
            dispersion: 0.0,
            graded: 0,
            index_origin: [0.0; 3],
            index_gradient: [0.0; 3],
            index_hessian: [0.0; 6],
        };
        let mut i = 0;
        ok(specula_context_add_material(ctx, &m, &mut i), ctx);
        i
    };
    let (diffuse, mirror, glass) =
        (mat(SPECULA_SURFACE_DIFFUSE, 1.0), mat(SPECULA_SURFACE_MIRROR, 1.0), mat(SPECULA_SURFACE_DIELECTRIC, 1.5));
    let pos: [f32; 12] = [-1.0, 0.0, -1.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0, -1.0, 0.0, 1.0];
    let idx: [u32; 6] = [0, 1, 2, 0, 2, 3];
    for (m, y) in [(diffuse, 0.0f32), (mirror, 0.5), (glass, 1.0)] {
        let t: [f32; 16] = [0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, y, 0.0, 1.0];
        let mesh = SpeculaMeshDesc {
            r#type: SPECULA_STRUCT_MESH_DESC,
            size: std::mem::size_of::<SpeculaMeshDesc>() as u32,
            positions: pos.as_ptr(),
            normals: std::ptr::null(),
            vertex_count: 4,
            indices: idx.as_ptr(),
            index_count: 6,
            transform: t.as_ptr(),
            material: m,
        };
        ok(specula_context_add_mesh(ctx, &mesh, std::ptr::null_mut()), ctx);
    }
    let light = SpeculaLightDesc {
        r#type: SPECULA_STRUCT_LIGHT_DESC,
        size: std::mem::size_of::<SpeculaLightDesc>() as u32,
        kind: SPECULA_LIGHT_POINT,
        position: [0.0, 2.0, 0.0],
        direction: [0.0, -1.0, 0.0],
        intensity: [5.0; 3],
        inner_cone: 0.0,
        outer_cone: 0.0,
        range: 0.0,
    };
    ok(specula_context_add_light(ctx, &light), ctx);
    let cam = SpeculaCameraDesc {
        r#type: SPECULA_STRUCT_CAMERA_DESC,
        size: std::mem::size_of::<SpeculaCameraDesc>() as u32,
        position: [0.0, 2.0, 2.0],
        target: [0.0; 3],
        yfov: 1.0,
        znear: 0.01,
    };
    ok(specula_context_set_camera(ctx, &cam), ctx);
    ok(specula_context_set_knob(ctx, c"cube_size".as_ptr(), c"16".as_ptr()), ctx);
    ok(specula_context_set_knob(ctx, c"shadow_size".as_ptr(), c"16".as_ptr()), ctx);
}

extern "C" {
    fn mallinfo2() -> MallInfo2;
    fn malloc_trim(pad: usize) -> i32;
}

/// glibc's `struct mallinfo2` (Debian 12: glibc 2.36).
#[repr(C)]
struct MallInfo2 {
    arena: usize,
    ordblks: usize,
    smblks: usize,
    hblks: usize,
    hblkhd: usize,
    usmblks: usize,
    fsmblks: usize,
    uordblks: usize,
    fordblks: usize,
    keepcost: usize,
}

/// Live bytes of the process's C heap: in-use ordinary blocks plus mmapped blocks.
fn c_heap_live() -> isize {
    unsafe {
        malloc_trim(0);
        let m = mallinfo2();
        (m.uordblks + m.hblkhd) as isize
    }
}

/// The tests of this binary count the process's allocations: one at a time.
static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn resident_kib() -> u64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap();
    s.lines().find_map(|l| l.strip_prefix("VmRSS:")).and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok()).unwrap_or(0)
}

/// 60 reconfigures with unchanged settings (issue 37: an engine reconfigures on every
/// resolution change or settings toggle), 30 each with a fixed method and with `auto` (which
/// also looks up the device's unit costs and the objects' facts), a frame after every 10.
/// Measured with 100 (lavapipe, validation on): the library's heap grows by about 2 KiB (fixed
/// method) and 11–17 KiB (auto) once — the same after 30 or 90 reconfigures, i.e. none of it per
/// reconfigure, 0 B over every later run of 10 — and the resident size by 10.4–11.1 MiB over the
/// 100 (about 110 KiB a reconfigure: lavapipe's LLVM code memory for the pipelines each
/// configure compiles again, as in the create/destroy cycles above; the library heap and the C
/// heap stay flat). The bounds: the library heap's growth over the second or the third run of
/// 10 at most 64 B a reconfigure, and the resident size at most 12 MiB over the 60 (about 6.6 MiB
/// at the measured rate; the 1.5 MiB a reconfigure the issue measured would be 90 MiB).
#[test]
fn reconfigures_leak_nothing() {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    count_the_heap();
    std::env::set_var("SPECULA_SYNC_VALIDATION", "0");
    unsafe {
        let ctx = common::c_context();
        build_scene(ctx);
        let mut px = [0u8; 16 * 16 * 4];
        let methods = [("envmap", specula::methods::ENVMAP.abi), ("auto", specula::methods::registry::ABI_AUTO)];
        // Warm-up: the first configure of each kind loads the driver's compiler, the stored
        // models and this device's unit costs, once per process.
        for (_, method) in methods {
            for _ in 0..3 {
                ok(specula_context_configure(ctx, &render_desc(method)), ctx);
                ok(specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, px.as_mut_ptr().cast(), px.len()), ctx);
            }
        }
        let rss0 = resident_kib() as i64;
        for (label, method) in methods {
            let rd = render_desc(method);
            const HALF: isize = 10;
            let mut heap = Vec::new();
            for _ in 0..3 {
                heap.push(LIVE_BYTES.load(Ordering::Relaxed));
                for _ in 0..HALF {
                    ok(specula_context_configure(ctx, &rd), ctx);
                }
                ok(specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, px.as_mut_ptr().cast(), px.len()), ctx);
            }
            heap.push(LIVE_BYTES.load(Ordering::Relaxed));
            let grew: Vec<isize> = heap.windows(2).map(|w| w[1] - w[0]).collect();
            eprintln!("{label}: library heap {:+} B over the first {HALF} reconfigures, then {:+} B and {:+} B", grew[0], grew[1], grew[2]);
            // A leak grows the heap in every run of reconfigures. Under the whole suite's load
            // one run grew once by +5696 B where it measures 0 B alone (the counted heap is
            // the process's: the test harness's threads and the planner's parallel prediction
            // on rayon's pool, whose queues' blocks are freed through an epoch collector as
            // the threads are scheduled, count too). So the smaller of the two later runs'
            // growths is bounded.
            let second = grew[1].min(grew[2]);
            assert!(
                second <= 64 * HALF,
                "{label}: the library's heap grew by {grew:?} B over runs of {HALF} reconfigures with unchanged settings"
            );
        }
        let rss = resident_kib() as i64 - rss0;
        eprintln!("resident size {rss:+} KiB over 60 reconfigures");
        assert!(rss < 12 * 1024, "the resident size grew by {rss} KiB over 60 reconfigures with unchanged settings");
        assert_eq!(specula_context_destroy(ctx), SPECULA_SUCCESS);
    }
}

#[test]
fn contexts_leak_nothing() {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    count_the_heap();
    const WARM_UP: usize = 6;
    const CYCLES: isize = 24;
    // Synchronization validation keeps state per device in the layer (see the top).
    std::env::set_var("SPECULA_SYNC_VALIDATION", "0");
    unsafe {
        for _ in 0..WARM_UP {
            cycle();
        }
        // The C heap after each cycle (allocated before the count starts).
        let mut c = Vec::with_capacity(CYCLES as usize);
        let (heap0, c0) = (LIVE_BYTES.load(Ordering::Relaxed), c_heap_live());
        for _ in 0..CYCLES {
            cycle();
            c.push((c_heap_live() - c0) as f64);
        }
        let growth = LIVE_BYTES.load(Ordering::Relaxed) - heap0;
        // The C heap's growth per cycle: the least-squares slope over the samples (the
        // driver's transient allocations move single samples by up to 1.5 KiB), and the
        // residuals' spread about that line.
        let n = CYCLES as f64;
        let mean_k = (n + 1.0) / 2.0;
        let mean_c = c.iter().sum::<f64>() / n;
        let sxx = c.iter().enumerate().map(|(k, _)| (k as f64 + 1.0 - mean_k).powi(2)).sum::<f64>();
        let slope = c.iter().enumerate().map(|(k, v)| (k as f64 + 1.0 - mean_k) * (v - mean_c)).sum::<f64>() / sxx;
        let residual =
            (c.iter().enumerate().map(|(k, v)| (v - mean_c - slope * (k as f64 + 1.0 - mean_k)).powi(2)).sum::<f64>() / n).sqrt();
        let mut steps: Vec<f64> = c.windows(2).map(|w| w[1] - w[0]).collect();
        steps.sort_by(f64::total_cmp);
        let median = steps[steps.len() / 2];
        eprintln!(
            "over {CYCLES} cycles: library heap {growth:+} B; C heap {:+} B, {slope:.1} B per cycle (least squares; residual {residual:.0} B, median step {median} B)",
            c[c.len() - 1]
        );
        assert_eq!(specula_live_context_count(), 0);
        assert_eq!(
            specula::vk::process_validation_errors(),
            0,
            "the validation layer reported errors (e.g. objects alive at vkDestroyDevice)"
        );
        // Measured 0 B (see the top).
        assert!(growth.abs() < CYCLES, "library heap grew by {growth} bytes over {CYCLES} create/render/destroy cycles");
        // Measured 460–507 B and 464 B on Mesa 22, 28–95 B and 0 B on Mesa 25 (see the top);
        // with the context's kept pipelines, 53–1298 B and 0–1424 B (see the top).
        assert!(slope <= 1800.0, "the process's C heap grew by {slope:.1} bytes per create/render/destroy cycle");
        assert!(median <= 1800.0, "the process's C heap grew by a median {median} bytes per create/render/destroy cycle");
    }
}

/// Blocks the host's Vulkan allocation callbacks handed out and not yet taken back, by address
/// (size, alignment), and how many it handed out.
static VK_LIVE: std::sync::Mutex<Vec<(usize, usize, usize)>> = std::sync::Mutex::new(Vec::new());
static VK_ALLOCATIONS: AtomicIsize = AtomicIsize::new(0);
static VK_UNKNOWN_FREES: AtomicIsize = AtomicIsize::new(0);

unsafe extern "system" fn vk_allocate(_: *mut c_void, size: usize, align: usize, _: ash::vk::SystemAllocationScope) -> *mut c_void {
    let p = System.alloc(Layout::from_size_align(size.max(1), align.max(1)).unwrap());
    VK_ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
    VK_LIVE.lock().unwrap().push((p as usize, size.max(1), align.max(1)));
    p as *mut c_void
}

unsafe extern "system" fn vk_free(_: *mut c_void, p: *mut c_void) {
    if p.is_null() {
        return;
    }
    let mut live = VK_LIVE.lock().unwrap();
    match live.iter().position(|b| b.0 == p as usize) {
        Some(i) => {
            let (_, size, align) = live.swap_remove(i);
            System.dealloc(p as *mut u8, Layout::from_size_align(size, align).unwrap());
        }
        None => {
            VK_UNKNOWN_FREES.fetch_add(1, Ordering::Relaxed);
        }
    }
}

unsafe extern "system" fn vk_reallocate(
    user: *mut c_void,
    p: *mut c_void,
    size: usize,
    align: usize,
    scope: ash::vk::SystemAllocationScope,
) -> *mut c_void {
    if p.is_null() {
        return vk_allocate(user, size, align, scope);
    }
    if size == 0 {
        vk_free(user, p);
        return std::ptr::null_mut();
    }
    let old = VK_LIVE.lock().unwrap().iter().find(|b| b.0 == p as usize).map_or(0, |b| b.1);
    let q = vk_allocate(user, size, align, scope);
    std::ptr::copy_nonoverlapping(p as *const u8, q as *mut u8, old.min(size));
    vk_free(user, p);
    q
}

/// Issue 37: a host's VkAllocationCallbacks reach every Vulkan object the library makes (the
/// instance, the device, the renderer's images, buffers and pipelines) and every block comes
/// back by the context's end; the library's CPU memory goes through the host allocator; a
/// NULL callback is refused by name; a caller of the first SpeculaContextDesc (without the
/// field) still creates.
#[test]
fn vulkan_objects_use_the_hosts_allocation_callbacks_and_give_every_block_back() {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    count_the_heap();
    let callbacks = ash::vk::AllocationCallbacks::default()
        .pfn_allocation(Some(vk_allocate))
        .pfn_reallocation(Some(vk_reallocate))
        .pfn_free(Some(vk_free));
    let mut desc = SpeculaContextDesc {
        r#type: SPECULA_STRUCT_CONTEXT_DESC,
        size: std::mem::size_of::<SpeculaContextDesc>() as u32,
        device_name: std::ptr::null(),
        enable_validation: 1,
        vulkan_allocator: &callbacks as *const _ as *const c_void,
    };
    unsafe {
        let mut ctx = std::ptr::null_mut();
        assert_eq!(specula_context_create(&desc, &mut ctx), SPECULA_SUCCESS, "{:?}", std::ffi::CStr::from_ptr(specula_creation_error()));
        let after_create = VK_ALLOCATIONS.load(Ordering::Relaxed);
        build_scene(ctx);
        let heap_before = HOST_ALLOCATIONS.load(Ordering::Relaxed);
        ok(specula_context_configure(ctx, &render_desc(specula::methods::ENVMAP.abi)), ctx);
        let mut px = [0u8; 16 * 16 * 4];
        ok(specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, px.as_mut_ptr().cast(), px.len()), ctx);
        let (created, made) = (VK_ALLOCATIONS.load(Ordering::Relaxed), HOST_ALLOCATIONS.load(Ordering::Relaxed) - heap_before);
        assert!(after_create > 0, "creating the instance and device made no block through the callbacks");
        assert!(created > after_create, "configuring and rendering made no Vulkan block through the callbacks");
        assert!(made > 100, "configure and render made {made} allocations through the host allocator");
        assert_eq!(specula_context_destroy(ctx), SPECULA_SUCCESS);
        let live = VK_LIVE.lock().unwrap().len();
        eprintln!("Vulkan host blocks: {created} made through the host's callbacks, {live} left; {made} CPU allocations for a configure and a frame");
        assert_eq!(live, 0, "{live} blocks the host's callbacks made were not given back");
        assert_eq!(VK_UNKNOWN_FREES.load(Ordering::Relaxed), 0, "blocks freed that the callbacks did not make");

        let no_free = callbacks.pfn_free(None);
        desc.vulkan_allocator = &no_free as *const _ as *const c_void;
        assert_eq!(specula_context_create(&desc, &mut ctx), SPECULA_ERROR_NULL_POINTER);
        assert!(ctx.is_null());
        let why = std::ffi::CStr::from_ptr(specula_creation_error()).to_string_lossy().into_owned();
        assert!(why.contains("vulkan_allocator->pfnFree is NULL"), "{why}");

        let no_allocate = SpeculaHostAllocator {
            r#type: SPECULA_STRUCT_HOST_ALLOCATOR,
            size: std::mem::size_of::<SpeculaHostAllocator>() as u32,
            user: std::ptr::null_mut(),
            allocate: None,
            free: Some(count_free),
        };
        assert_eq!(specula_set_host_allocator(&no_allocate), SPECULA_ERROR_NULL_POINTER);

        desc.size = SPECULA_CONTEXT_DESC_SIZE_V1;
        desc.vulkan_allocator = std::ptr::dangling(); // beyond the caller's struct: never read
        let before = VK_ALLOCATIONS.load(Ordering::Relaxed);
        assert_eq!(specula_context_create(&desc, &mut ctx), SPECULA_SUCCESS);
        assert_eq!(specula_context_destroy(ctx), SPECULA_SUCCESS);
        assert_eq!(VK_ALLOCATIONS.load(Ordering::Relaxed), before, "a first-version desc used callbacks it did not pass");
    }
}
