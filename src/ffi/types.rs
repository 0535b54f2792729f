//! The ABI's data: result codes, the enums (as integer constants), the versioned
//! `#[repr(C)]` input structs and the pass-timing output struct.

use std::ffi::{c_char, c_void};

// ------------------------------------------------------------------ results

/// Result of every call: 0 success, negative errors, positive warnings.
pub type SpeculaResult = i32;
pub const SPECULA_SUCCESS: SpeculaResult = 0;
/// Warning: the output array was too small; `count` holds the number needed.
pub const SPECULA_WARNING_TRUNCATED: SpeculaResult = 1;
/// Warning: no frame has completed on the GPU yet (host-device mode), `count` is 0.
pub const SPECULA_WARNING_NOT_READY: SpeculaResult = 2;
/// specula_context_configure with a budget: no models cover the scene's specular objects;
/// the registry's rules chose (specula_get_predictions reports none).
pub const SPECULA_WARNING_NO_MODELS: SpeculaResult = 3;
/// specula_context_configure with a budget: no choice is predicted to meet it; the nearest
/// was configured (specula_get_predictions says what it is predicted to reach), and the log
/// callback says why.
pub const SPECULA_WARNING_BUDGET_UNREACHABLE: SpeculaResult = 4;
/// specula_context_configure: some objects' methods cannot run on this device (`ray-query`
/// on a device without VK_KHR_ray_query, or a host device that did not enable it:
/// SpeculaHostDesc::ray_query_enabled); each got its method's fallback, and the log
/// callback names the object, the method and why.
pub const SPECULA_WARNING_DEVICE_FALLBACK: SpeculaResult = 5;
pub const SPECULA_ERROR_INVALID_ARGUMENT: SpeculaResult = -1;
pub const SPECULA_ERROR_NULL_POINTER: SpeculaResult = -2;
/// A struct's `type` tag or `size` does not match what the call expects.
pub const SPECULA_ERROR_STRUCT_MISMATCH: SpeculaResult = -3;
/// The handle is null, was destroyed, or is not a handle of this library.
pub const SPECULA_ERROR_INVALID_HANDLE: SpeculaResult = -4;
/// The call is not valid in the context's current state (e.g. render before configure).
pub const SPECULA_ERROR_WRONG_ORDER: SpeculaResult = -5;
pub const SPECULA_ERROR_UNSUPPORTED: SpeculaResult = -6;
pub const SPECULA_ERROR_OUT_OF_MEMORY: SpeculaResult = -7;
pub const SPECULA_ERROR_IO: SpeculaResult = -8;
pub const SPECULA_ERROR_SCENE: SpeculaResult = -9;
pub const SPECULA_ERROR_VULKAN: SpeculaResult = -10;
pub const SPECULA_ERROR_VALIDATION: SpeculaResult = -11;
/// A caller buffer is too small for the image.
pub const SPECULA_ERROR_BUFFER_TOO_SMALL: SpeculaResult = -12;
/// The library caught an internal panic; the context should be destroyed.
pub const SPECULA_ERROR_PANIC: SpeculaResult = -13;

// ------------------------------------------------------------------ enums (as integers)

/// Type tags of the input structs.
pub type SpeculaStructType = u32;
pub const SPECULA_STRUCT_CONTEXT_DESC: SpeculaStructType = 1;
pub const SPECULA_STRUCT_HOST_DESC: SpeculaStructType = 2;
pub const SPECULA_STRUCT_MATERIAL_DESC: SpeculaStructType = 3;
pub const SPECULA_STRUCT_MESH_DESC: SpeculaStructType = 4;
pub const SPECULA_STRUCT_LIGHT_DESC: SpeculaStructType = 5;
pub const SPECULA_STRUCT_CAMERA_DESC: SpeculaStructType = 6;
pub const SPECULA_STRUCT_RENDER_DESC: SpeculaStructType = 7;
pub const SPECULA_STRUCT_HOST_IMAGE: SpeculaStructType = 8;
pub const SPECULA_STRUCT_REQUIREMENTS: SpeculaStructType = 9;
pub const SPECULA_STRUCT_HOST_ALLOCATOR: SpeculaStructType = 10;

/// Rendering methods: SPECULA_METHOD_* (defined near the top of this header, generated from
/// the method registry), the same names as the CLI's `--method`; SPECULA_METHOD_AUTO lets
/// the planner choose per object.
pub type SpeculaMethod = u32;

pub type SpeculaSurface = u32;
/// Emission + Lambertian direct light.
pub const SPECULA_SURFACE_DIFFUSE: SpeculaSurface = 0;
/// Ideal mirror with per-channel index of refraction ν and extinction κ.
pub const SPECULA_SURFACE_MIRROR: SpeculaSurface = 1;
/// Ideal dielectric of index of refraction `ior` (> 0); `thin` != 0: thin-walled.
pub const SPECULA_SURFACE_DIELECTRIC: SpeculaSurface = 2;

pub type SpeculaLightKind = u32;
pub const SPECULA_LIGHT_POINT: SpeculaLightKind = 0;
pub const SPECULA_LIGHT_SPOT: SpeculaLightKind = 1;
pub const SPECULA_LIGHT_DIRECTIONAL: SpeculaLightKind = 2;

pub type SpeculaPixelFormat = u32;
/// 4 bytes per pixel, sRGB-encoded and clamped (like the CLI's PNG).
pub const SPECULA_PIXEL_RGBA8_SRGB: SpeculaPixelFormat = 0;
/// 16 bytes per pixel, linear radiance (like the CLI's EXR).
pub const SPECULA_PIXEL_RGBA32F: SpeculaPixelFormat = 1;

pub type SpeculaLogLevel = u32;
pub const SPECULA_LOG_ERROR: SpeculaLogLevel = 0;
pub const SPECULA_LOG_WARNING: SpeculaLogLevel = 1;
pub const SPECULA_LOG_INFO: SpeculaLogLevel = 2;

/// Called with every error a call returns and every validation message; `message` is
/// valid during the call only. Called on the thread that made the failing call.
pub type SpeculaLogCallback = Option<unsafe extern "C" fn(user: *mut c_void, level: SpeculaLogLevel, message: *const c_char)>;

/// `PFN_vkVoidFunction`.
pub type SpeculaVoidFunction = Option<unsafe extern "C" fn()>;
/// `PFN_vkGetInstanceProcAddr`.
pub type SpeculaGetInstanceProcAddr = Option<unsafe extern "C" fn(instance: *mut c_void, name: *const c_char) -> SpeculaVoidFunction>;

// ------------------------------------------------------------------ structs

/// Standalone mode: the library creates its own headless instance and device.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct SpeculaContextDesc {
    /// SPECULA_STRUCT_CONTEXT_DESC
    pub r#type: SpeculaStructType,
    /// sizeof(SpeculaContextDesc)
    pub size: u32,
    /// Case-insensitive substring of the device name ("llvmpipe", "NVIDIA"), or NULL: the
    /// SPECULA_DEVICE environment variable, else the first GPU, else lavapipe.
    pub device_name: *const c_char,
    /// Non-zero: enable the Khronos validation layer; validation errors fail the frame.
    pub enable_validation: u32,
    /// A `const VkAllocationCallbacks*`, or NULL (zero where the caller's struct ends
    /// before this field): copied at the call, and passed to every Vulkan object the context
    /// creates and destroys, its instance and device included. Device memory blocks come
    /// from gpu-allocator, whose vkAllocateMemory calls pass none.
    pub vulkan_allocator: *const c_void,
}

/// sizeof(SpeculaContextDesc) before `vulkan_allocator`: still accepted.
pub const SPECULA_CONTEXT_DESC_SIZE_V1: u32 = 24;

/// Host-device mode (the FSR2/XeSS model): the host's Vulkan objects, created with
/// everything `specula_get_requirements` lists. The library loads Vulkan through
/// `get_instance_proc_addr`, never submits, and never destroys these objects.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct SpeculaHostDesc {
    /// SPECULA_STRUCT_HOST_DESC
    pub r#type: SpeculaStructType,
    /// sizeof(SpeculaHostDesc)
    pub size: u32,
    /// vkGetInstanceProcAddr of the host's loader.
    pub get_instance_proc_addr: SpeculaGetInstanceProcAddr,
    /// VkInstance
    pub instance: *mut c_void,
    /// VkPhysicalDevice
    pub physical_device: *mut c_void,
    /// VkDevice
    pub device: *mut c_void,
    /// Queue family of the command buffers the host will hand to `specula_context_record`
    /// (graphics, with timestamps).
    pub queue_family: u32,
    /// Non-zero if the host enabled VK_EXT_debug_utils on the instance: the library then
    /// names its objects and labels every pass (RenderDoc shows the survey's vocabulary).
    pub debug_utils_enabled: u32,
    /// Non-zero if the host enabled the optional ray-query extensions and features that
    /// SpeculaRequirements lists (`optional_device_extensions`, `acceleration_structure`,
    /// `ray_query`, `buffer_device_address`): the `ray-query` method then traces through
    /// them; else its objects get `bvh`, and the plan's reason says why.
    pub ray_query_enabled: u32,
    /// A `const VkAllocationCallbacks*`, or NULL (zero where the caller's struct ends
    /// before this field): copied at the call, and passed to every Vulkan object the library
    /// creates and destroys on the host's device (device memory blocks excepted, as in
    /// SpeculaContextDesc).
    pub vulkan_allocator: *const c_void,
}

/// sizeof(SpeculaHostDesc) before `vulkan_allocator`: still accepted.
pub const SPECULA_HOST_DESC_SIZE_V1: u32 = 56;

/// The host's allocator for the library's CPU memory (specula_set_host_allocator). The
/// callbacks may be called from any thread, at any time until the process ends (blocks made
/// through them are freed through them, even after another allocator was set).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct SpeculaHostAllocator {
    /// SPECULA_STRUCT_HOST_ALLOCATOR
    pub r#type: SpeculaStructType,
    /// sizeof(SpeculaHostAllocator)
    pub size: u32,
    /// Handed to both callbacks.
    pub user: *mut c_void,
    /// Returns `size` bytes aligned to `alignment` (a power of two, at least 16), or NULL
    /// when out of memory.
    pub allocate: Option<unsafe extern "C" fn(user: *mut c_void, size: usize, alignment: usize) -> *mut c_void>,
    /// Frees a block `allocate` returned, given the size and alignment it was asked for.
    pub free: Option<unsafe extern "C" fn(user: *mut c_void, memory: *mut c_void, size: usize, alignment: usize)>,
}

/// What a host must enable before it creates its device (host-device mode).
#[repr(C)]
pub struct SpeculaRequirements {
    /// SPECULA_STRUCT_REQUIREMENTS
    pub r#type: SpeculaStructType,
    /// sizeof(SpeculaRequirements)
    pub size: u32,
    /// Minimum Vulkan API version, as VK_MAKE_API_VERSION (1.3).
    pub api_version: u32,
    /// Device extensions to enable (static strings).
    pub device_extensions: *const *const c_char,
    pub device_extension_count: u32,
    /// Instance extensions to enable (none required; VK_EXT_debug_utils is optional).
    pub instance_extension_count: u32,
    /// Features to enable, each 1: VkPhysicalDeviceFeatures::imageCubeArray,
    /// VkPhysicalDeviceVulkan11Features::multiview,
    /// VkPhysicalDeviceVulkan13Features::dynamicRendering, ::synchronization2, ::maintenance4,
    /// VkPhysicalDeviceRobustness2FeaturesEXT::nullDescriptor.
    pub image_cube_array: u32,
    pub multiview: u32,
    pub dynamic_rendering: u32,
    pub synchronization2: u32,
    pub maintenance4: u32,
    pub null_descriptor: u32,
    /// Optional device extensions (static strings): with them and the three features below
    /// enabled (and SpeculaHostDesc::ray_query_enabled set), `ray-query` traces rays
    /// through Vulkan's acceleration structures: VK_KHR_acceleration_structure,
    /// VK_KHR_ray_query, VK_KHR_deferred_host_operations.
    pub optional_device_extensions: *const *const c_char,
    pub optional_device_extension_count: u32,
    /// Optional features, each 1 (with the optional extensions):
    /// VkPhysicalDeviceAccelerationStructureFeaturesKHR::accelerationStructure,
    /// VkPhysicalDeviceRayQueryFeaturesKHR::rayQuery,
    /// VkPhysicalDeviceVulkan12Features::bufferDeviceAddress.
    pub acceleration_structure: u32,
    pub ray_query: u32,
    pub buffer_device_address: u32,
}

#[repr(C)]
#[derive(Clone, Copy)]
pub struct SpeculaMaterialDesc {
    /// SPECULA_STRUCT_MATERIAL_DESC
    pub r#type: SpeculaStructType,
    /// sizeof(SpeculaMaterialDesc)
    pub size: u32,
    /// SPECULA_SURFACE_*
    pub surface: SpeculaSurface,
    /// Linear albedo of diffuse surfaces.
    pub base_color: [f32; 3],
    /// Emitted radiance [W/(m²·sr)], linear.
    pub emission: [f32; 3],
    /// Mirror: index of refraction ν per RGB channel (> 0).
    pub nu: [f32; 3],
    /// Mirror: extinction coefficient κ per RGB channel (≥ 0).
    pub kappa: [f32; 3],
    /// Dielectric: index of refraction relative to the outside (> 0).
    pub ior: f32,
    /// Dielectric: non-zero for a thin-walled surface (no bending).
    pub thin: u32,
    /// Solid dielectric (KHR_materials_volume): the colour white light turns into after
    /// `attenuation_distance` inside (each channel in 0..=1). Added after the first release:
    /// a caller whose `size` ends before it gets no absorption.
    pub attenuation_color: [f32; 3],
    /// Solid dielectric: that distance [m] (> 0); 0: no absorption (glTF's infinity).
    pub attenuation_distance: f32,
    /// Solid dielectric (KHR_materials_dispersion): 20 / Abbe number (≥ 0); 0: none. Also
    /// added after the first release (zero for a caller whose `size` ends before it).
    pub dispersion: f32,
    /// Solid dielectric (survey §6.5): non-zero for an index that varies in space, the field
    /// n(x) = ior + g·(x − o) + ½ (x − o)ᵀ H (x − o) in world space (`ior` its value at the
    /// origin o); rays inside it curve, traced by the ray tracers. Added after the volume
    /// fields (a caller whose `size` ends before it gets a uniform index).
    pub graded: u32,
    /// The field's origin o [m].
    pub index_origin: [f32; 3],
    /// Its gradient g at the origin [1/m].
    pub index_gradient: [f32; 3],
    /// Its symmetric Hessian H [1/m²]: xx, yy, zz, xy, xz, yz.
    pub index_hessian: [f32; 6],
}

/// `sizeof(SpeculaMaterialDesc)` as first released (up to `thin`): still accepted.
pub const MATERIAL_DESC_SIZE_V1: usize = std::mem::offset_of!(SpeculaMaterialDesc, attenuation_color);
/// Its size with the volume fields (up to `dispersion`): still accepted.
pub const MATERIAL_DESC_SIZE_V2: usize = std::mem::offset_of!(SpeculaMaterialDesc, graded);

/// A triangle mesh. Arrays are read during the call only (the library copies them).
#[repr(C)]
pub struct SpeculaMeshDesc {
    /// SPECULA_STRUCT_MESH_DESC
    pub r#type: SpeculaStructType,
    /// sizeof(SpeculaMeshDesc)
    pub size: u32,
    /// 3 floats per vertex, metres.
    pub positions: *const f32,
    /// 3 floats per vertex, or NULL: computed (area-weighted).
    pub normals: *const f32,
    pub vertex_count: u32,
    /// 3 indices per triangle, each < vertex_count.
    pub indices: *const u32,
    pub index_count: u32,
    /// Column-major 4×4 object-to-world matrix, or NULL for identity.
    pub transform: *const f32,
    /// Index returned by specula_context_add_material.
    pub material: u32,
}

#[repr(C)]
pub struct SpeculaLightDesc {
    /// SPECULA_STRUCT_LIGHT_DESC
    pub r#type: SpeculaStructType,
    /// sizeof(SpeculaLightDesc)
    pub size: u32,
    /// SPECULA_LIGHT_*
    pub kind: SpeculaLightKind,
    pub position: [f32; 3],
    /// Direction the light travels (spot, directional).
    pub direction: [f32; 3],
    /// Radiant intensity [W/sr] (point, spot) or irradiance [W/m²] (directional), per RGB.
    pub intensity: [f32; 3],
    /// Spot cone angles from the axis, radians, 0 ≤ inner ≤ outer ≤ π/2.
    pub inner_cone: f32,
    pub outer_cone: f32,
    /// Range in metres, or 0 for unbounded.
    pub range: f32,
}

/// A pinhole camera; the configured output size's aspect ratio is used.
#[repr(C)]
pub struct SpeculaCameraDesc {
    /// SPECULA_STRUCT_CAMERA_DESC
    pub r#type: SpeculaStructType,
    /// sizeof(SpeculaCameraDesc)
    pub size: u32,
    pub position: [f32; 3],
    pub target: [f32; 3],
    /// Vertical field of view, radians, in (0, π).
    pub yfov: f32,
    /// Near plane distance, metres (> 0); the far plane is at infinity.
    pub znear: f32,
}

#[repr(C)]
pub struct SpeculaRenderDesc {
    /// SPECULA_STRUCT_RENDER_DESC
    pub r#type: SpeculaStructType,
    /// sizeof(SpeculaRenderDesc)
    pub size: u32,
    /// SPECULA_METHOD_*
    pub method: SpeculaMethod,
    /// Output size in pixels, 1..=16384 each.
    pub width: u32,
    pub height: u32,
    /// The budgeted planner (with SPECULA_METHOD_AUTO; 0: unset, at most one of the two):
    /// per specular object a method and for the frame the knob values, from per-object error
    /// and cost models, so that a frame takes at most `max_ms` GPU milliseconds at the least
    /// predicted error, or every specular object reaches `min_psnr_db` on its pixels at the
    /// least predicted time. Without either, SPECULA_METHOD_AUTO spends at most the exact
    /// tracer's predicted frame and takes the fastest choice within 0.5 dB of the most
    /// accurate. specula_get_predictions reports the prediction.
    pub max_ms: f64,
    pub min_psnr_db: f64,
    /// A scene's own calibration (JSON from `specula tradeoff --calibrate`), or NULL:
    /// predictions from the objects' facts and the device's unit costs.
    pub models_path: *const c_char,
    /// Where the device's unit costs are cached (the directory; created), or NULL: the
    /// SPECULA_CACHE_DIR environment variable, else the user's cache directory. A device
    /// seen for the first time is calibrated there (a few seconds on a GPU, about three
    /// minutes on lavapipe).
    pub cache_dir: *const c_char,
}

/// The size of SpeculaRenderDesc before the budget fields (type, size, method, width,
/// height): still accepted, as no budget.
pub const SPECULA_RENDER_DESC_SIZE_V1: u32 = 20;

/// The size of SpeculaRenderDesc before `cache_dir` (through `models_path`): still
/// accepted, as the default cache.
pub const SPECULA_RENDER_DESC_SIZE_V2: u32 = 48;

/// SpeculaRenderDesc through `models_path`, all a caller of the second version passes.
#[repr(C)]
pub(super) struct RenderDescV2 {
    pub r#type: SpeculaStructType,
    pub size: u32,
    pub method: SpeculaMethod,
    pub width: u32,
    pub height: u32,
    pub max_ms: f64,
    pub min_psnr_db: f64,
    pub models_path: *const c_char,
}

const _: () = assert!(std::mem::size_of::<RenderDescV2>() == SPECULA_RENDER_DESC_SIZE_V2 as usize);

/// The first fields of SpeculaRenderDesc, all a caller of the first version passes.
#[repr(C)]
pub(super) struct RenderDescV1 {
    pub r#type: SpeculaStructType,
    pub size: u32,
    pub method: SpeculaMethod,
    pub width: u32,
    pub height: u32,
}

/// What the budgeted planner predicted for one specular object (specula_get_predictions);
/// the last entry, named "frame", is the whole frame (method SPECULA_METHOD_AUTO, the
/// predicted frame time and the PSNR of all specular pixels).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct SpeculaPrediction {
    /// NUL-terminated object name, or "frame".
    pub name: [c_char; 48],
    /// SPECULA_METHOD_* chosen.
    pub method: SpeculaMethod,
    /// Its pixels in the models' frame, scaled to the configured size.
    pub pixels: u32,
    /// Predicted GPU milliseconds of its passes (its share of shared ones).
    pub predicted_ms: f64,
    /// Predicted PSNR on its pixels, dB (capped at 200).
    pub predicted_psnr_db: f64,
}

/// A host image to render into (host-device mode). Usage must include TRANSFER_DST; its
/// extent must equal the configured size. R32G32B32A32_SFLOAT receives a bit-exact copy of
/// the linear radiance; other formats (that support BLIT_DST) a converting blit.
#[repr(C)]
pub struct SpeculaHostImage {
    /// SPECULA_STRUCT_HOST_IMAGE
    pub r#type: SpeculaStructType,
    /// sizeof(SpeculaHostImage)
    pub size: u32,
    /// VkImage
    pub image: u64,
    /// VkImageView (informational: the library copies into `image`).
    pub view: u64,
    /// VkFormat
    pub format: u32,
    pub width: u32,
    pub height: u32,
    /// VkImageLayout the image is in when the recorded commands start.
    pub current_layout: u32,
    /// VkImageLayout to leave it in.
    pub final_layout: u32,
    /// Name for debug tools, or NULL.
    pub debug_name: *const c_char,
}

/// One pass of a frame: its stable name (as in the CLI profile), GPU and CPU time.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct SpeculaPassTiming {
    /// NUL-terminated, e.g. "envmap.generate".
    pub name: [c_char; 48],
    pub gpu_ms: f64,
    pub cpu_ms: f64,
}

/// A map a frame regenerated, and why (specula_get_map_updates).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct SpeculaMapUpdate {
    /// NUL-terminated stage name, e.g. "distance.generate".
    pub stage: [c_char; 48],
    /// NUL-terminated, e.g. "first frame", "moved 'mesh2'", "light 'light0'".
    pub reason: [c_char; 208],
}
