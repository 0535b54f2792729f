/* host_vulkan.c — an engine that owns Vulkan: it asks specula what its device needs,
 * creates instance and device itself, hands them over, records specula's frame into its
 * own command buffer, writing into its own image, submits and reads the image back.
 *
 *   cc -std=c11 -I include examples/c/host_vulkan.c -L target/release -lspecula -lvulkan -o host_vulkan
 *   ./host_vulkan assets/demo/demo.gltf out.f32 [METHOD]
 *
 * out.f32: the linear RGBA32F radiance, raw (equal to standalone.c's for the same scene).
 * SPECULA_DEVICE selects the physical device by name; SPECULA_VALIDATE=1 enables the
 * Khronos validation layer and fails on any error it reports. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <vulkan/vulkan.h>

#include "specula.h"

#define W 128
#define H 96
#define VK(call)                                                        \
    do {                                                                \
        VkResult r_ = (call);                                           \
        if (r_ != VK_SUCCESS) {                                         \
            fprintf(stderr, "%s:%d: %s = %d\n", __FILE__, __LINE__, #call, r_); \
            exit(1);                                                    \
        }                                                               \
    } while (0)

static unsigned validation_errors = 0;

static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT type,
                                                 const VkDebugUtilsMessengerCallbackDataEXT *data, void *user) {
    (void)type;
    (void)user;
    if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) {
        ++validation_errors;
        fprintf(stderr, "[validation] %s\n", data->pMessage);
    }
    return VK_FALSE;
}

static void specula_check(SpeculaContext *ctx, SpeculaResult r, const char *what) {
    if (r < 0) {
        fprintf(stderr, "%s failed (%d): %s\n", what, r, ctx ? specula_context_last_error(ctx) : specula_creation_error());
        exit(1);
    }
}

static uint32_t memory_type(VkPhysicalDevice pd, uint32_t bits, VkMemoryPropertyFlags want) {
    VkPhysicalDeviceMemoryProperties mp;
    vkGetPhysicalDeviceMemoryProperties(pd, &mp);
    for (uint32_t i = 0; i < mp.memoryTypeCount; ++i)
        if ((bits & (1u << i)) && (mp.memoryTypes[i].propertyFlags & want) == want) return i;
    fprintf(stderr, "no memory type\n");
    exit(1);
}

/* An optional KEY=VALUE knob from the command line (e.g. depth=4). */
static void knob(SpeculaContext *ctx, const char *pair) {
    const char *eq = strchr(pair, '=');
    char key[64];
    if (!eq || (size_t)(eq - pair) >= sizeof key) {
        fprintf(stderr, "knob '%s' is not KEY=VALUE\n", pair);
        exit(1);
    }
    memcpy(key, pair, (size_t)(eq - pair));
    key[eq - pair] = 0;
    specula_check(ctx, specula_context_set_knob(ctx, key, eq + 1), "set_knob");
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: %s SCENE.gltf OUT.f32 [METHOD [KEY=VALUE]]\n", argv[0]);
        return 2;
    }
    int validate = getenv("SPECULA_VALIDATE") != NULL;

    /* 1. What specula needs, asked before the device exists. */
    SpeculaRequirements req = {SPECULA_STRUCT_REQUIREMENTS, sizeof req};
    specula_check(NULL, specula_get_requirements(&req), "get_requirements");

    /* 2. The engine's own instance (with debug utils, so specula labels its passes). */
    const char *layers[] = {"VK_LAYER_KHRONOS_validation"};
    const char *inst_ext[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME};
    VkDebugUtilsMessengerCreateInfoEXT mci = {VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mci.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT;
    mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
    mci.pfnUserCallback = on_message;
    VkApplicationInfo app = {VK_STRUCTURE_TYPE_APPLICATION_INFO, NULL, "host_vulkan", 1, "host_vulkan", 1, req.api_version};
    VkInstanceCreateInfo ici = {VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO, validate ? &mci : NULL, 0, &app,
                                validate ? 1u : 0u, layers, 1, inst_ext};
    VkInstance instance;
    VK(vkCreateInstance(&ici, NULL, &instance));
    VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
    PFN_vkCreateDebugUtilsMessengerEXT create_messenger = (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(instance, "vkCreateDebugUtilsMessengerEXT");
    if (validate) VK(create_messenger(instance, &mci, NULL, &messenger));

    /* 3. A physical device (by SPECULA_DEVICE name, else the first) and a graphics queue. */
    uint32_t n = 8;
    VkPhysicalDevice pds[8];
    VK(vkEnumeratePhysicalDevices(instance, &n, pds));
    VkPhysicalDevice pd = pds[0];
    const char *want = getenv("SPECULA_DEVICE");
    for (uint32_t i = 0; want && i < n; ++i) {
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(pds[i], &p);
        if (strstr(p.deviceName, want)) pd = pds[i];
    }
    uint32_t qf_count = 16;
    VkQueueFamilyProperties qfs[16];
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &qf_count, qfs);
    uint32_t qf = 0;
    while (qf < qf_count && !(qfs[qf].queueFlags & VK_QUEUE_GRAPHICS_BIT)) ++qf;

    /* 4. The device, with exactly the extensions and features specula listed. */
    VkPhysicalDeviceRobustness2FeaturesEXT robust = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ROBUSTNESS_2_FEATURES_EXT};
    robust.nullDescriptor = req.null_descriptor;
    VkPhysicalDeviceVulkan13Features f13 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES, &robust};
    f13.dynamicRendering = req.dynamic_rendering;
    f13.synchronization2 = req.synchronization2;
    f13.maintenance4 = req.maintenance4;
    VkPhysicalDeviceVulkan11Features f11 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES, &f13};
    f11.multiview = req.multiview;
    VkPhysicalDeviceFeatures2 f2 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f11};
    f2.features.imageCubeArray = req.image_cube_array;
    /* The optional ray-query extensions and features, where the device has them all: the
       `ray-query` method then traces through the driver's acceleration structures (without
       them its objects get `bvh`, and configure says so). */
    const char *extensions[16];
    uint32_t extension_count = 0;
    for (uint32_t i = 0; i < req.device_extension_count && extension_count < 16; ++i) extensions[extension_count++] = req.device_extensions[i];
    uint32_t available_count = 0;
    VK(vkEnumerateDeviceExtensionProperties(pd, NULL, &available_count, NULL));
    VkExtensionProperties *available = calloc(available_count ? available_count : 1, sizeof *available);
    VK(vkEnumerateDeviceExtensionProperties(pd, NULL, &available_count, available));
    uint32_t found = 0;
    for (uint32_t i = 0; i < req.optional_device_extension_count; ++i)
        for (uint32_t j = 0; j < available_count; ++j)
            if (strcmp(req.optional_device_extensions[i], available[j].extensionName) == 0) { ++found; break; }
    free(available);
    VkPhysicalDeviceRayQueryFeaturesKHR rq = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_QUERY_FEATURES_KHR};
    VkPhysicalDeviceAccelerationStructureFeaturesKHR accel = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR, &rq};
    VkPhysicalDeviceVulkan12Features f12 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &accel};
    VkPhysicalDeviceFeatures2 probe = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
    vkGetPhysicalDeviceFeatures2(pd, &probe);
    int ray_query = found == req.optional_device_extension_count && f12.bufferDeviceAddress && accel.accelerationStructure && rq.rayQuery &&
                    getenv("SPECULA_HOST_NO_RAY_QUERY") == NULL;
    memset(&f12, 0, sizeof f12);
    f12.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES;
    if (ray_query) {
        for (uint32_t i = 0; i < req.optional_device_extension_count && extension_count < 16; ++i)
            extensions[extension_count++] = req.optional_device_extensions[i];
        f12.bufferDeviceAddress = req.buffer_device_address;
        accel = (VkPhysicalDeviceAccelerationStructureFeaturesKHR){VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ACCELERATION_STRUCTURE_FEATURES_KHR, &rq};
        accel.accelerationStructure = req.acceleration_structure;
        rq = (VkPhysicalDeviceRayQueryFeaturesKHR){VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_RAY_QUERY_FEATURES_KHR};
        rq.rayQuery = req.ray_query;
        f12.pNext = &accel;
        robust.pNext = &f12;
    }
    float prio = 1.0f;
    VkDeviceQueueCreateInfo qci = {VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO, NULL, 0, qf, 1, &prio};
    VkDeviceCreateInfo dci = {VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &f2, 0, 1, &qci, 0, NULL, extension_count, extensions, NULL};
    VkDevice device;
    VK(vkCreateDevice(pd, &dci, NULL, &device));
    VkQueue queue;
    vkGetDeviceQueue(device, qf, 0, &queue);

    /* 5. The engine's target image and a host-visible buffer to read it back. */
    VkImageCreateInfo ii = {VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO, NULL, 0, VK_IMAGE_TYPE_2D, VK_FORMAT_R32G32B32A32_SFLOAT, {W, H, 1}, 1, 1,
                            VK_SAMPLE_COUNT_1_BIT, VK_IMAGE_TILING_OPTIMAL, VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                            VK_SHARING_MODE_EXCLUSIVE, 0, NULL, VK_IMAGE_LAYOUT_UNDEFINED};
    VkImage image;
    VK(vkCreateImage(device, &ii, NULL, &image));
    VkMemoryRequirements mr;
    vkGetImageMemoryRequirements(device, image, &mr);
    VkMemoryAllocateInfo mai = {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, NULL, mr.size, memory_type(pd, mr.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)};
    VkDeviceMemory image_mem;
    VK(vkAllocateMemory(device, &mai, NULL, &image_mem));
    VK(vkBindImageMemory(device, image, image_mem, 0));
    VkBufferCreateInfo bi = {VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO, NULL, 0, (VkDeviceSize)W * H * 16, VK_BUFFER_USAGE_TRANSFER_DST_BIT, VK_SHARING_MODE_EXCLUSIVE};
    VkBuffer buffer;
    VK(vkCreateBuffer(device, &bi, NULL, &buffer));
    vkGetBufferMemoryRequirements(device, buffer, &mr);
    VkMemoryAllocateInfo bai = {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, NULL, mr.size,
                                memory_type(pd, mr.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)};
    VkDeviceMemory buffer_mem;
    VK(vkAllocateMemory(device, &bai, NULL, &buffer_mem));
    VK(vkBindBufferMemory(device, buffer, buffer_mem, 0));

    /* 6. specula on the engine's device. */
    SpeculaHostDesc hd = {SPECULA_STRUCT_HOST_DESC, sizeof hd, (SpeculaGetInstanceProcAddr)vkGetInstanceProcAddr, instance, pd, device, qf, 1,
                          (uint32_t)ray_query};
    SpeculaContext *ctx = NULL;
    specula_check(NULL, specula_context_create_host(&hd, &ctx), "create_host");
    specula_check(ctx, specula_context_load_gltf(ctx, argv[1]), "load_gltf");
    specula_check(ctx, specula_context_set_knob(ctx, "cube_size", "64"), "set_knob");
    specula_check(ctx, specula_context_set_knob(ctx, "shadow_size", "64"), "set_knob");
    if (argc > 4) knob(ctx, argv[4]);
    SpeculaMethod method = argc > 3 ? (SpeculaMethod)atoi(argv[3]) : SPECULA_METHOD_ENVMAP;
    SpeculaRenderDesc rd = {SPECULA_STRUCT_RENDER_DESC, sizeof rd, method, W, H};
    specula_check(ctx, specula_context_configure(ctx, &rd), "configure");

    /* 7. Two frames (the first also uploads textures), each recorded into the engine's
     *    command buffer, then the engine's own copy to the readback buffer. */
    VkCommandPoolCreateInfo pci = {VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO, NULL, VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT, qf};
    VkCommandPool pool;
    VK(vkCreateCommandPool(device, &pci, NULL, &pool));
    VkCommandBufferAllocateInfo cai = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO, NULL, pool, VK_COMMAND_BUFFER_LEVEL_PRIMARY, 1};
    VkCommandBuffer cmd;
    VK(vkAllocateCommandBuffers(device, &cai, &cmd));
    VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;
    for (int frame = 0; frame < 2; ++frame) {
        VkCommandBufferBeginInfo cbi = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO, NULL, VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
        VK(vkBeginCommandBuffer(cmd, &cbi));
        SpeculaHostImage target = {SPECULA_STRUCT_HOST_IMAGE, sizeof target, (uint64_t)(uintptr_t)image, 0, VK_FORMAT_R32G32B32A32_SFLOAT, W, H,
                                   layout, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, "host_vulkan.target"};
        specula_check(ctx, specula_context_record(ctx, cmd, &target), "record");
        layout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        VkBufferImageCopy region = {0, 0, 0, {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1}, {0, 0, 0}, {W, H, 1}};
        vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer, 1, &region);
        VkMemoryBarrier host_read = {VK_STRUCTURE_TYPE_MEMORY_BARRIER, NULL, VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_HOST_READ_BIT};
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &host_read, 0, NULL, 0, NULL);
        VK(vkEndCommandBuffer(cmd));
        VkSubmitInfo si = {VK_STRUCTURE_TYPE_SUBMIT_INFO, NULL, 0, NULL, NULL, 1, &cmd, 0, NULL};
        VK(vkQueueSubmit(queue, 1, &si, VK_NULL_HANDLE));
        VK(vkQueueWaitIdle(queue));
    }

    SpeculaPassTiming timings[16];
    uint32_t count = 0;
    specula_check(ctx, specula_get_pass_timings(ctx, timings, 16, &count), "timings");
    for (uint32_t i = 0; i < count && i < 16; ++i) printf("%-20s %8.3f ms GPU\n", timings[i].name, timings[i].gpu_ms);

    void *mapped;
    VK(vkMapMemory(device, buffer_mem, 0, VK_WHOLE_SIZE, 0, &mapped));
    FILE *f = fopen(argv[2], "wb");
    int ok = f && fwrite(mapped, (size_t)W * H * 16, 1, f) == 1;
    if (f) fclose(f);
    vkUnmapMemory(device, buffer_mem);

    /* 8. Tear down: specula first (the GPU is idle), then the engine's objects. */
    specula_check(NULL, specula_context_destroy(ctx), "destroy");
    vkDestroyCommandPool(device, pool, NULL);
    vkDestroyBuffer(device, buffer, NULL);
    vkFreeMemory(device, buffer_mem, NULL);
    vkDestroyImage(device, image, NULL);
    vkFreeMemory(device, image_mem, NULL);
    vkDestroyDevice(device, NULL);
    if (messenger) {
        PFN_vkDestroyDebugUtilsMessengerEXT destroy_messenger = (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT");
        destroy_messenger(instance, messenger, NULL);
    }
    vkDestroyInstance(instance, NULL);
    if (validation_errors) {
        fprintf(stderr, "%u validation error(s)\n", validation_errors);
        return 1;
    }
    return ok ? 0 : 1;
}
