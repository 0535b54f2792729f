//! The Vulkan context: instance, physical device, device, queue family, allocator and the
//! validation messenger. Either created by the library (standalone, headless) or borrowed
//! from a host engine (the FSR2/XeSS model): passes never assume they own the queue or the
//! command buffer, they record into whatever `vk::CommandBuffer` they are given.

use std::collections::BTreeMap;
use std::ffi::{c_void, CStr, CString};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use ash::vk;
use ash::vk::Handle;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use crate::error::{Error, Result, VkCall};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Whether the validation layer provides instance extension `name`.
fn layer_has_extension(entry: &ash::Entry, name: &CStr) -> bool {
    unsafe { entry.enumerate_instance_extension_properties(Some(VALIDATION_LAYER)) }
        .map(|v| v.iter().any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == name)))
        .unwrap_or(false)
}

/// How to create a standalone context.
#[derive(Clone, Debug, Default)]
pub struct DeviceOptions {
    /// Enable the Khronos validation layer (tests always do).
    pub validation: bool,
    /// Case-insensitive substring of the device name ("llvmpipe", "NVIDIA" …). Falls back
    /// to the `SPECULA_DEVICE` environment variable; without either, the first discrete or
    /// integrated GPU is taken, then anything else (lavapipe).
    pub device_filter: Option<String>,
    /// Leave Vulkan's ray-tracing extensions off even where the device has them (as does
    /// `SPECULA_RAY_QUERY=off`): `ray-query` then falls back to `bvh`, as on a device
    /// without them.
    pub hide_ray_query: bool,
    /// Instance extensions to enable besides the library's own: a window's surface
    /// extensions (`specula view`). Each must be available, or creation fails naming it.
    pub instance_extensions: Vec<std::ffi::CString>,
    /// Device extensions to enable besides the library's own (`VK_KHR_swapchain` for a
    /// window). Each must be available on the chosen device, or creation fails naming it.
    pub device_extensions: Vec<std::ffi::CString>,
    /// The host's Vulkan allocation callbacks, passed to every Vulkan object the context
    /// creates and destroys (its instance and device included).
    pub allocation_callbacks: Option<VulkanAllocator>,
}

/// A host's `VkAllocationCallbacks`, copied: the library passes them to every
/// `vkCreate*`/`vkDestroy*` it calls. Device memory comes from gpu-allocator, whose
/// `vkAllocateMemory` calls pass none (the driver's own host allocations for those few
/// large blocks).
#[derive(Clone, Copy)]
pub struct VulkanAllocator(pub vk::AllocationCallbacks<'static>);

// SAFETY: the callbacks are the host's, which promises (Vulkan's rules for
// VkAllocationCallbacks) that they may be called from any thread the context is used on.
unsafe impl Send for VulkanAllocator {}
unsafe impl Sync for VulkanAllocator {}

impl std::fmt::Debug for VulkanAllocator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "VulkanAllocator(user data {:p})", self.0.p_user_data)
    }
}

/// What a host engine hands over in host-device mode.
#[derive(Clone, Copy)]
pub struct HostHandles {
    pub get_instance_proc_addr: vk::PFN_vkGetInstanceProcAddr,
    pub instance: vk::Instance,
    pub physical_device: vk::PhysicalDevice,
    pub device: vk::Device,
    pub queue_family: u32,
    /// The host enabled VK_EXT_debug_utils on its instance: object names and pass labels.
    pub debug_utils: bool,
    /// The host enabled [`RAY_QUERY_DEVICE_EXTENSIONS`] and the features
    /// [`ray_query_supported`] checks: `ray-query` traces through them.
    pub ray_query: bool,
    /// The host's Vulkan allocation callbacks for every object the library creates.
    pub allocation_callbacks: Option<VulkanAllocator>,
}

/// Messages the validation layer reported; tests fail on any error.
#[derive(Debug, Default)]
pub struct ValidationLog {
    pub errors: AtomicU32,
    pub warnings: AtomicU32,
    pub messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    pub fn error_count(&self) -> u32 {
        self.errors.load(Ordering::Relaxed)
    }
    pub fn warning_count(&self) -> u32 {
        self.warnings.load(Ordering::Relaxed)
    }
    /// The first 64 messages: errors as the layer wrote them, warnings prefixed `warning: `.
    pub fn error_messages(&self) -> Vec<String> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }
}

/// Every live device allocation, by resource name: what the frame's resources hold; and
/// an optional budget (bytes) that allocations may not exceed.
#[derive(Debug, Default)]
pub struct MemoryRegistry {
    next: AtomicU64,
    live: Mutex<BTreeMap<u64, (String, u64)>>,
    /// 0: no budget beyond the device's own.
    budget: AtomicU64,
}

impl MemoryRegistry {
    /// Caps the device memory this context's resources may hold (`None`: the device's
    /// heaps alone). An allocation beyond it fails as out of device memory, naming the
    /// resource and its size; what was allocated before stays usable.
    pub fn set_budget(&self, bytes: Option<u64>) {
        self.budget.store(bytes.unwrap_or(0), Ordering::Relaxed);
    }

    pub fn budget(&self) -> Option<u64> {
        Some(self.budget.load(Ordering::Relaxed)).filter(|&b| b > 0)
    }

    /// Refuses `bytes` more for `name` beyond the budget.
    pub(crate) fn check_budget(&self, name: &str, bytes: u64) -> crate::Result<()> {
        if let Some(b) = self.budget() {
            let used = self.total();
            if used + bytes > b {
                return Err(Error::OutOfMemory(format!(
                    "device memory for '{name}': {bytes} bytes ({:.2} MiB) do not fit the budget of {b} bytes, {used} in use",
                    bytes as f64 / 1048576.0
                )));
            }
        }
        Ok(())
    }

    pub(crate) fn add(&self, name: &str, bytes: u64) -> u64 {
        let id = self.next.fetch_add(1, Ordering::Relaxed);
        if let Ok(mut l) = self.live.lock() {
            l.insert(id, (name.to_string(), bytes));
        }
        id
    }
    pub(crate) fn remove(&self, id: u64) {
        if let Ok(mut l) = self.live.lock() {
            l.remove(&id);
        }
    }
    /// (resource name, bytes) of every live allocation, in creation order.
    pub fn snapshot(&self) -> Vec<(String, u64)> {
        self.live.lock().map(|l| l.values().cloned().collect()).unwrap_or_default()
    }
    pub fn total(&self) -> u64 {
        self.snapshot().iter().map(|(_, b)| b).sum()
    }
}

pub struct Context {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue_family: u32,
    /// The library's own queue; `None` when a host owns submission.
    pub queue: Option<vk::Queue>,
    pub properties: vk::PhysicalDeviceProperties,
    pub device_name: String,
    pub driver_info: String,
    pub debug_utils: Option<ash::ext::debug_utils::Device>,
    debug_instance: Option<ash::ext::debug_utils::Instance>,
    messenger: vk::DebugUtilsMessengerEXT,
    pub validation: Arc<ValidationLog>,
    pub memory: MemoryRegistry,
    allocator: Mutex<Option<Allocator>>,
    owned: bool,
    /// The device was created with `sampleRateShading` (MSAA's per-sample passes need it).
    /// Only the library's own devices: a host device's enabled features are not known.
    pub sample_rate_shading: bool,
    /// The device was created with `geometryShader`: fragment shaders may read
    /// gl_PrimitiveID (caustic_space=texture needs it). Only the library's own devices.
    pub geometry_shader: bool,
    /// The device was created with `fragmentStoresAndAtomics`: fragment shaders may write
    /// storage buffers (the planar objects' fallback counters). Only the library's own devices.
    pub fragment_stores: bool,
    /// Vulkan's ray-tracing API (acceleration structures and ray queries), where the device
    /// has it and it was enabled; else why not (the `ray-query` method's fallback reason).
    pub ray_query: std::result::Result<RayQueryDevice, String>,
    /// The host's allocation callbacks for every object the library creates and destroys.
    callbacks: Option<VulkanAllocator>,
    /// Pipelines shared by the context's renderers (`pipeline::graphics_pipeline`, …).
    pub(crate) pipelines: super::pipeline_memo::PipelineMemo,
}

/// What the `ray-query` method needs of a device that traces through Vulkan's ray-tracing
/// API: the extension's functions and its alignment rules.
pub struct RayQueryDevice {
    pub accel: ash::khr::acceleration_structure::Device,
    /// `minAccelerationStructureScratchOffsetAlignment`.
    pub scratch_alignment: u64,
}

/// Device extensions the library needs beyond Vulkan 1.3: null descriptors stand in for
/// maps a scene does not need, instead of dummy allocations.
pub const REQUIRED_DEVICE_EXTENSIONS: &[&CStr] = &[ash::ext::robustness2::NAME];

/// Optional device extensions: with them (and the features [`ray_query_supported`] checks)
/// the `ray-query` method traces rays through acceleration structures built by the driver.
pub const RAY_QUERY_DEVICE_EXTENSIONS: &[&CStr] =
    &[ash::khr::acceleration_structure::NAME, ash::khr::ray_query::NAME, ash::khr::deferred_host_operations::NAME];

/// Whether the device has what `ray-query` needs: [`RAY_QUERY_DEVICE_EXTENSIONS`] and the
/// features accelerationStructure, rayQuery and bufferDeviceAddress; else which is missing.
pub fn ray_query_supported(instance: &ash::Instance, pd: vk::PhysicalDevice) -> std::result::Result<(), String> {
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut accel = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut rq = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f12).push_next(&mut accel).push_next(&mut rq);
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    let features = [
        (accel.acceleration_structure, "accelerationStructure"),
        (rq.ray_query, "rayQuery"),
        (f12.buffer_device_address, "bufferDeviceAddress"),
    ];
    device_has(instance, pd, RAY_QUERY_DEVICE_EXTENSIONS, &features)
}

/// The first of `extensions` the device lacks, else the first of `features` it does not
/// support, as a message; `Ok` when it has them all.
fn device_has(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    extensions: &[&CStr],
    features: &[(vk::Bool32, &str)],
) -> std::result::Result<(), String> {
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }.unwrap_or_default();
    if let Some(name) = extensions.iter().find(|n| !exts.iter().any(|e| e.extension_name_as_c_str().is_ok_and(|x| x == **n))) {
        return Err(format!("the device lacks the extension {}", name.to_string_lossy()));
    }
    match features.iter().find(|(v, _)| *v == vk::FALSE) {
        Some((_, name)) => Err(format!("the device lacks the feature {name}")),
        None => Ok(()),
    }
}

/// Whether ray queries are hidden by `SPECULA_RAY_QUERY=off` (or `0`, `no`).
pub fn ray_query_hidden_by_env() -> bool {
    std::env::var("SPECULA_RAY_QUERY").is_ok_and(|v| matches!(v.trim().to_ascii_lowercase().as_str(), "off" | "0" | "no" | "false"))
}

/// Device features every pass relies on; a host device must enable them (see
/// `required_device_extensions` and `Context::from_host`).
pub fn required_features_supported(instance: &ash::Instance, pd: vk::PhysicalDevice) -> std::result::Result<(), String> {
    let mut f11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut robust = vk::PhysicalDeviceRobustness2FeaturesEXT::default();
    let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f11).push_next(&mut f13).push_next(&mut robust);
    unsafe { instance.get_physical_device_features2(pd, &mut f2) };
    let f = f2.features;
    let features = [
        (f.image_cube_array, "imageCubeArray"),
        (f11.multiview, "multiview"),
        (robust.null_descriptor, "nullDescriptor (VK_EXT_robustness2)"),
        (f13.dynamic_rendering, "dynamicRendering"),
        (f13.synchronization2, "synchronization2"),
        (f13.maintenance4, "maintenance4"),
    ];
    device_has(instance, pd, REQUIRED_DEVICE_EXTENSIONS, &features)
}

/// Validation errors reported by any context of this process, ever: a leaked Vulkan object
/// shows up here, because the layer reports every child object still alive at
/// vkDestroyDevice, after the context's own log is gone.
static PROCESS_VALIDATION_ERRORS: AtomicU32 = AtomicU32::new(0);

pub fn process_validation_errors() -> u32 {
    PROCESS_VALIDATION_ERRORS.load(Ordering::Relaxed)
}

unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // Never unwind through the driver: nothing here can panic on bad input.
    if user.is_null() || data.is_null() {
        return vk::FALSE;
    }
    let log = &*(user as *const ValidationLog);
    let msg = if (*data).p_message.is_null() { "".into() } else { CStr::from_ptr((*data).p_message).to_string_lossy() };
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        log.errors.fetch_add(1, Ordering::Relaxed);
        PROCESS_VALIDATION_ERRORS.fetch_add(1, Ordering::Relaxed);
        eprintln!("[vulkan validation error] {msg}");
        if let Ok(mut m) = log.messages.lock() {
            if m.len() < 64 {
                m.push(msg.into_owned());
            }
        }
    } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        log.warnings.fetch_add(1, Ordering::Relaxed);
        eprintln!("[vulkan validation warning] {msg}");
        if let Ok(mut m) = log.messages.lock() {
            if m.len() < 64 {
                m.push(format!("warning: {msg}"));
            }
        }
    }
    vk::FALSE
}

impl Context {
    /// Creates a headless instance and device of the library's own.
    pub fn new(opts: &DeviceOptions) -> Result<Context> {
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| Error::Unsupported(format!("cannot load the Vulkan loader (libvulkan.so.1): {e}")))?;
        let layers_avail = unsafe { entry.enumerate_instance_layer_properties() }.call("vkEnumerateInstanceLayerProperties")?;
        let has_layer = |n: &CStr| layers_avail.iter().any(|l| l.layer_name_as_c_str().is_ok_and(|x| x == n));
        if opts.validation && !has_layer(VALIDATION_LAYER) {
            return Err(Error::Unsupported(
                "validation requested but VK_LAYER_KHRONOS_validation is not installed (apt-get install vulkan-validationlayers)".into(),
            ));
        }
        let exts_avail = unsafe { entry.enumerate_instance_extension_properties(None) }.call("vkEnumerateInstanceExtensionProperties")?;
        let has_debug_utils = exts_avail.iter().any(|e| e.extension_name_as_c_str().is_ok_and(|x| x == ash::ext::debug_utils::NAME));

        let app_name = c"specula";
        let app = vk::ApplicationInfo::default().application_name(app_name).engine_name(app_name).api_version(vk::API_VERSION_1_3);
        let layers: Vec<*const i8> = if opts.validation { vec![VALIDATION_LAYER.as_ptr()] } else { vec![] };
        let mut exts: Vec<*const i8> = if has_debug_utils { vec![ash::ext::debug_utils::NAME.as_ptr()] } else { vec![] };
        // Synchronization validation (hazards between passes) with the validation layer,
        // unless SPECULA_SYNC_VALIDATION=0.
        let sync = opts.validation
            && std::env::var("SPECULA_SYNC_VALIDATION").map_or(true, |v| v != "0")
            && layer_has_extension(&entry, ash::ext::validation_features::NAME);
        if sync {
            exts.push(ash::ext::validation_features::NAME.as_ptr());
        }
        for e in &opts.instance_extensions {
            if !exts_avail.iter().any(|a| a.extension_name_as_c_str().is_ok_and(|x| x == e.as_c_str())) {
                return Err(Error::Unsupported(format!(
                    "the Vulkan instance lacks the extension {} that was asked for",
                    e.to_string_lossy()
                )));
            }
            exts.push(e.as_ptr());
        }
        let enabled_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);
        let validation = Arc::new(ValidationLog::default());
        let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING)
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                    | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(debug_callback))
            .user_data(Arc::as_ptr(&validation) as *mut c_void);
        let mut ci = vk::InstanceCreateInfo::default().application_info(&app).enabled_layer_names(&layers).enabled_extension_names(&exts);
        if has_debug_utils && opts.validation {
            ci = ci.push_next(&mut messenger_info); // also catches create/destroy-instance messages
        }
        if sync {
            ci = ci.push_next(&mut features);
        }
        let alloc = opts.allocation_callbacks;
        let callbacks = alloc.as_ref().map(|c| &c.0);
        let instance = unsafe { entry.create_instance(&ci, callbacks) }.call("vkCreateInstance")?;
        let mut ctx_guard = InstanceGuard { instance: Some(instance), debug: None, messenger: vk::DebugUtilsMessengerEXT::null(), alloc };
        let instance_ref = ctx_guard.instance.as_ref().unwrap();
        if has_debug_utils {
            let di = ash::ext::debug_utils::Instance::new(&entry, instance_ref);
            if opts.validation {
                ctx_guard.messenger =
                    unsafe { di.create_debug_utils_messenger(&messenger_info, callbacks) }.call("vkCreateDebugUtilsMessengerEXT")?;
            }
            ctx_guard.debug = Some(di);
        }

        let filter = opts.device_filter.clone().or_else(|| std::env::var("SPECULA_DEVICE").ok()).filter(|s| !s.is_empty());
        let physical = pick_physical_device(instance_ref, filter.as_deref())?;
        required_features_supported(instance_ref, physical).map_err(Error::Unsupported)?;
        let families = unsafe { instance_ref.get_physical_device_queue_family_properties(physical) };
        let queue_family = families
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE) && f.timestamp_valid_bits > 0)
            .ok_or_else(|| Error::Unsupported("no graphics+compute queue with timestamps".into()))? as u32;

        let prio = [1.0f32];
        let qci = [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&prio)];
        let supported = unsafe { instance_ref.get_physical_device_features(physical) };
        let sample_rate_shading = supported.sample_rate_shading == vk::TRUE;
        let geometry_shader = supported.geometry_shader == vk::TRUE;
        let fragment_stores = supported.fragment_stores_and_atomics == vk::TRUE;
        let features = vk::PhysicalDeviceFeatures::default()
            .image_cube_array(true)
            .sample_rate_shading(sample_rate_shading)
            .geometry_shader(geometry_shader)
            .fragment_stores_and_atomics(fragment_stores);
        let mut f11 = vk::PhysicalDeviceVulkan11Features::default().multiview(true);
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true).synchronization2(true).maintenance4(true);
        let mut robust = vk::PhysicalDeviceRobustness2FeaturesEXT::default().null_descriptor(true);
        let mut ext_names: Vec<*const i8> = REQUIRED_DEVICE_EXTENSIONS.iter().map(|e| e.as_ptr()).collect();
        let device_exts =
            unsafe { instance_ref.enumerate_device_extension_properties(physical) }.call("vkEnumerateDeviceExtensionProperties")?;
        ext_names.extend(asked_extensions(&device_exts, &opts.device_extensions, "the device")?);
        // Vulkan's ray-tracing API where the device has it, unless hidden.
        let ray_query = if opts.hide_ray_query || ray_query_hidden_by_env() {
            Err("ray queries are hidden (SPECULA_RAY_QUERY=off or DeviceOptions::hide_ray_query)".to_string())
        } else {
            ray_query_supported(instance_ref, physical)
        };
        let on = ray_query.is_ok();
        if on {
            ext_names.extend(RAY_QUERY_DEVICE_EXTENSIONS.iter().map(|e| e.as_ptr()));
        }
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default().buffer_device_address(on);
        let mut accel = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(on);
        let mut rq = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(on);
        let mut dci = vk::DeviceCreateInfo::default()
            .queue_create_infos(&qci)
            .enabled_extension_names(&ext_names)
            .enabled_features(&features)
            .push_next(&mut f11)
            .push_next(&mut f12)
            .push_next(&mut f13)
            .push_next(&mut robust);
        if on {
            dci = dci.push_next(&mut accel).push_next(&mut rq);
        }
        let device = unsafe { instance_ref.create_device(physical, &dci, callbacks) }.call("vkCreateDevice")?;
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let (instance, debug_instance, messenger) = ctx_guard.release();
        let mut ctx = Context::assemble(
            entry,
            instance,
            physical,
            device,
            queue_family,
            Some(queue),
            debug_instance,
            messenger,
            validation,
            true,
            ray_query,
        )?;
        ctx.owned = true;
        ctx.sample_rate_shading = sample_rate_shading;
        ctx.geometry_shader = geometry_shader;
        ctx.fragment_stores = fragment_stores;
        ctx.callbacks = alloc;
        Ok(ctx)
    }

    /// Host-device mode (the FSR2/XeSS model): loads Vulkan through the host's
    /// `vkGetInstanceProcAddr` and uses its instance, physical device and device. The host
    /// keeps ownership: dropping the context destroys only what the library created. The
    /// library never submits; it records into command buffers the host hands it.
    ///
    /// # Safety
    /// The handles must be valid and created with `REQUIRED_DEVICE_EXTENSIONS` and the
    /// features `required_features_supported` checks enabled; they must outlive the context.
    pub unsafe fn from_host(host: &HostHandles) -> Result<Context> {
        let entry = ash::Entry::from_static_fn(ash::StaticFn { get_instance_proc_addr: host.get_instance_proc_addr });
        let instance = ash::Instance::load(entry.static_fn(), host.instance);
        let device = ash::Device::load(instance.fp_v1_0(), host.device);
        let props = instance.get_physical_device_properties(host.physical_device);
        if vk::api_version_major(props.api_version) == 1 && vk::api_version_minor(props.api_version) < 3 {
            return Err(Error::Unsupported("the host's physical device does not support Vulkan 1.3".into()));
        }
        required_features_supported(&instance, host.physical_device).map_err(Error::Unsupported)?;
        let families = instance.get_physical_device_queue_family_properties(host.physical_device);
        match families.get(host.queue_family as usize) {
            Some(f) if f.queue_flags.contains(vk::QueueFlags::GRAPHICS) && f.timestamp_valid_bits > 0 => {}
            _ => return Err(Error::invalid("queue_family", "is not a graphics queue family with timestamps on this physical device")),
        }
        let debug_instance = host.debug_utils.then(|| ash::ext::debug_utils::Instance::new(&entry, &instance));
        // The host says whether it enabled the ray-tracing extensions; the device must have them.
        let ray_query = if !host.ray_query {
            Err("the host device did not enable the ray-query extensions and features (see specula_get_requirements)".to_string())
        } else if ray_query_hidden_by_env() {
            Err("ray queries are hidden (SPECULA_RAY_QUERY=off)".to_string())
        } else {
            ray_query_supported(&instance, host.physical_device)
        };
        let mut ctx = Context::assemble(
            entry,
            instance,
            host.physical_device,
            device,
            host.queue_family,
            None,
            debug_instance,
            vk::DebugUtilsMessengerEXT::null(),
            Arc::new(ValidationLog::default()),
            false,
            ray_query,
        )?;
        ctx.callbacks = host.allocation_callbacks;
        Ok(ctx)
    }

    /// Whether the library created (and will destroy) the instance and device.
    pub fn owns_device(&self) -> bool {
        self.owned
    }

    #[allow(clippy::too_many_arguments)]
    fn assemble(
        entry: ash::Entry,
        instance: ash::Instance,
        physical: vk::PhysicalDevice,
        device: ash::Device,
        queue_family: u32,
        queue: Option<vk::Queue>,
        debug_instance: Option<ash::ext::debug_utils::Instance>,
        messenger: vk::DebugUtilsMessengerEXT,
        validation: Arc<ValidationLog>,
        owned: bool,
        ray_query: std::result::Result<(), String>,
    ) -> Result<Context> {
        let properties = unsafe { instance.get_physical_device_properties(physical) };
        let device_name = properties.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        unsafe { instance.get_physical_device_properties2(physical, &mut p2) };
        let driver_info = format!(
            "{} {}",
            driver.driver_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
            driver.driver_info_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
        );
        let debug_utils = debug_instance.as_ref().map(|_| ash::ext::debug_utils::Device::new(&instance, &device));
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            // Acceleration structures and their inputs are found by device address.
            buffer_device_address: ray_query.is_ok(),
            allocation_sizes: Default::default(),
        })
        .map_err(|e| Error::Unsupported(format!("gpu-allocator: {e}")))?;
        let ray_query = ray_query.map(|()| {
            let mut accel_props = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
            let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut accel_props);
            unsafe { instance.get_physical_device_properties2(physical, &mut p2) };
            RayQueryDevice {
                accel: ash::khr::acceleration_structure::Device::new(&instance, &device),
                scratch_alignment: (accel_props.min_acceleration_structure_scratch_offset_alignment as u64).max(1),
            }
        });
        Ok(Context {
            entry,
            instance,
            physical,
            device,
            queue_family,
            queue,
            properties,
            device_name,
            driver_info: driver_info.trim().to_string(),
            debug_utils,
            debug_instance,
            messenger,
            validation,
            memory: MemoryRegistry::default(),
            allocator: Mutex::new(Some(allocator)),
            owned,
            sample_rate_shading: false,
            geometry_shader: false,
            fragment_stores: false,
            ray_query,
            callbacks: None,
            pipelines: Default::default(),
        })
    }

    pub(crate) fn allocator(&self) -> std::sync::MutexGuard<'_, Option<Allocator>> {
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Gives `object` a debug name (RenderDoc, validation messages).
    pub fn name<H: vk::Handle>(&self, object: H, name: &str) {
        if let Some(du) = &self.debug_utils {
            if let Ok(n) = CString::new(name) {
                let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(object).object_name(&n);
                let _ = unsafe { du.set_debug_utils_object_name(&info) };
            }
        }
    }

    pub fn begin_label(&self, cmd: vk::CommandBuffer, name: &str) {
        if let Some(du) = &self.debug_utils {
            if let Ok(n) = CString::new(name) {
                let label = vk::DebugUtilsLabelEXT::default().label_name(&n).color([0.9, 0.7, 0.2, 1.0]);
                unsafe { du.cmd_begin_debug_utils_label(cmd, &label) };
            }
        }
    }

    pub fn end_label(&self, cmd: vk::CommandBuffer) {
        if let Some(du) = &self.debug_utils {
            unsafe { du.cmd_end_debug_utils_label(cmd) };
        }
    }

    /// Timestamp tick length in nanoseconds.
    pub fn timestamp_period_ns(&self) -> f64 {
        self.properties.limits.timestamp_period as f64
    }

    /// Records `f` into a fresh command buffer on the library's queue, submits it and waits.
    /// Standalone mode only.
    pub fn one_shot<R>(&self, f: impl FnOnce(vk::CommandBuffer) -> Result<R>) -> Result<R> {
        let queue = self.queue.ok_or_else(|| Error::invalid("one_shot", "this context has no queue of its own (host-device mode)"))?;
        let d = &self.device;
        let pool =
            unsafe { d.create_command_pool(&vk::CommandPoolCreateInfo::default().queue_family_index(self.queue_family), self.alloc()) }
                .call("vkCreateCommandPool")?;
        let result = (|| {
            let cmd =
                unsafe { d.allocate_command_buffers(&vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1)) }
                    .call("vkAllocateCommandBuffers")?[0];
            unsafe {
                d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT))
            }
            .call("vkBeginCommandBuffer")?;
            let r = f(cmd)?;
            unsafe { d.end_command_buffer(cmd) }.call("vkEndCommandBuffer")?;
            let fence = unsafe { d.create_fence(&vk::FenceCreateInfo::default(), self.alloc()) }.call("vkCreateFence")?;
            let cmds = [cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            let waited = unsafe { d.queue_submit(queue, &submit, fence) }
                .call("vkQueueSubmit")
                .and_then(|_| unsafe { d.wait_for_fences(&[fence], true, u64::MAX) }.call("vkWaitForFences"));
            unsafe { d.destroy_fence(fence, self.alloc()) };
            waited.map(|_| r)
        })();
        unsafe { d.destroy_command_pool(pool, self.alloc()) };
        result
    }

    /// What every `vkCreate*` and `vkDestroy*` of this context passes as `pAllocator`.
    pub fn alloc(&self) -> Option<&vk::AllocationCallbacks<'static>> {
        self.callbacks.as_ref().map(|c| &c.0)
    }

    /// Pipelines the context keeps for its renderers: (all, of them without users).
    pub fn pipeline_counts(&self) -> (usize, usize) {
        self.pipelines.counts()
    }

    pub fn wait_idle(&self) -> Result<()> {
        unsafe { self.device.device_wait_idle() }.call("vkDeviceWaitIdle")
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            for p in self.pipelines.take_all() {
                self.device.destroy_pipeline(p, self.alloc());
            }
            let (pipeline_layouts, set_layouts) = self.pipelines.take_layouts();
            for l in pipeline_layouts {
                self.device.destroy_pipeline_layout(vk::PipelineLayout::from_raw(l), self.alloc());
            }
            for l in set_layouts {
                self.device.destroy_descriptor_set_layout(vk::DescriptorSetLayout::from_raw(l), self.alloc());
            }
            // The allocator frees its memory blocks; it must go before the device.
            if let Ok(mut a) = self.allocator.lock() {
                a.take();
            }
            if self.owned {
                let alloc = self.callbacks.as_ref().map(|c| &c.0);
                self.device.destroy_device(alloc);
                if let Some(di) = &self.debug_instance {
                    if self.messenger != vk::DebugUtilsMessengerEXT::null() {
                        di.destroy_debug_utils_messenger(self.messenger, alloc);
                    }
                }
                self.instance.destroy_instance(alloc);
            }
        }
    }
}

/// The pointers of `asked` (`DeviceOptions`' extra extensions), each among `available`, or an
/// error naming the first that `what` lacks.
fn asked_extensions(available: &[vk::ExtensionProperties], asked: &[std::ffi::CString], what: &str) -> Result<Vec<*const i8>> {
    asked
        .iter()
        .map(|e| {
            if available.iter().any(|a| a.extension_name_as_c_str().is_ok_and(|x| x == e.as_c_str())) {
                Ok(e.as_ptr())
            } else {
                Err(Error::Unsupported(format!("{what} lacks the extension {} that was asked for", e.to_string_lossy())))
            }
        })
        .collect()
}

/// Destroys a half-built instance when device creation fails part-way.
struct InstanceGuard {
    instance: Option<ash::Instance>,
    debug: Option<ash::ext::debug_utils::Instance>,
    messenger: vk::DebugUtilsMessengerEXT,
    alloc: Option<VulkanAllocator>,
}

impl InstanceGuard {
    fn release(mut self) -> (ash::Instance, Option<ash::ext::debug_utils::Instance>, vk::DebugUtilsMessengerEXT) {
        let i = self.instance.take().unwrap();
        (i, self.debug.take(), self.messenger)
    }
}

impl Drop for InstanceGuard {
    fn drop(&mut self) {
        if let Some(i) = self.instance.take() {
            let alloc = self.alloc.as_ref().map(|c| &c.0);
            unsafe {
                if let Some(d) = &self.debug {
                    if self.messenger != vk::DebugUtilsMessengerEXT::null() {
                        d.destroy_debug_utils_messenger(self.messenger, alloc);
                    }
                }
                i.destroy_instance(alloc);
            }
        }
    }
}

fn pick_physical_device(instance: &ash::Instance, filter: Option<&str>) -> Result<vk::PhysicalDevice> {
    let devices = unsafe { instance.enumerate_physical_devices() }.call("vkEnumeratePhysicalDevices")?;
    let named: Vec<(vk::PhysicalDevice, String, vk::PhysicalDeviceType)> = devices
        .into_iter()
        .map(|d| {
            let p = unsafe { instance.get_physical_device_properties(d) };
            let name = p.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            (d, name, p.device_type)
        })
        .collect();
    if let Some(f) = filter {
        let f = f.to_lowercase();
        return named.iter().find(|(_, n, _)| n.to_lowercase().contains(&f)).map(|(d, _, _)| *d).ok_or_else(|| {
            Error::Unsupported(format!(
                "no Vulkan device matches '{f}' (available: {})",
                named.iter().map(|(_, n, _)| n.as_str()).collect::<Vec<_>>().join(", ")
            ))
        });
    }
    let rank = |t: vk::PhysicalDeviceType| match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        _ => 3,
    };
    named
        .iter()
        .min_by_key(|(_, _, t)| rank(*t))
        .map(|(d, _, _)| *d)
        .ok_or_else(|| Error::Unsupported("no Vulkan device (is mesa-vulkan-drivers installed?)".into()))
}
