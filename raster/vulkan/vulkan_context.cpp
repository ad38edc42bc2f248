// The Vulkan backend's context: the instance (with the validation layer and its messenger when
// asked for), the device chosen among those that can run the backend, the logical device with its
// queue, command buffer and fence, and the teardown of everything the backend made.
#include "vulkan_impl.h"

#include "../gpu/gpu_common.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>

namespace cullide::raster::vk {

namespace {

const char* const kValidationLayer = "VK_LAYER_KHRONOS_validation";

std::string versionText(uint32_t v) {
    return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
        std::to_string(VK_API_VERSION_PATCH(v));
}

const char* typeText(VkPhysicalDeviceType t) {
    switch (t) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
        default: return "other";
    }
}

// Preference order: a GPU first, the CPU (lavapipe) last.
int typeRank(VkPhysicalDeviceType t) {
    switch (t) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 4;
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 3;
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return 1;
        default: return 0;
    }
}

bool hasExtension(VkPhysicalDevice d, const char* name) {
    uint32_t count = 0;
    vkEnumerateDeviceExtensionProperties(d, nullptr, &count, nullptr);
    std::vector<VkExtensionProperties> ext(count);
    vkEnumerateDeviceExtensionProperties(d, nullptr, &count, ext.data());
    return std::any_of(ext.begin(), ext.end(),
                       [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

bool depthAttachment(VkPhysicalDevice d, VkFormat f) {
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(d, f, &fp);
    const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT |
        VK_FORMAT_FEATURE_TRANSFER_SRC_BIT | VK_FORMAT_FEATURE_TRANSFER_DST_BIT;
    return (fp.optimalTilingFeatures & need) == need;
}

uint32_t graphicsQueue(VkPhysicalDevice d) {
    uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(d, &count, nullptr);
    std::vector<VkQueueFamilyProperties> q(count);
    vkGetPhysicalDeviceQueueFamilyProperties(d, &count, q.data());
    for (uint32_t i = 0; i < count; ++i)
        if (q[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) return i;
    return UINT32_MAX;
}

}  // namespace

VulkanBackendImpl::VulkanBackendImpl(const VulkanBackendOptions& options) : options_(options) {
    if (const char* e = std::getenv("CULLIDE_VULKAN_VALIDATION"); e && *e && std::strcmp(e, "0") != 0)
        options_.validation = true;
    try {
        createInstance();
        pickDevice();
        createDevice();
        createLayoutAndShader();
    } catch (...) {
        destroy();
        throw;
    }
}

VulkanBackendImpl::~VulkanBackendImpl() {
    destroy();
}

void VulkanBackendImpl::warn(const std::string& msg) const {
    gpu::warn(options_.warn, msg);
}

VKAPI_ATTR VkBool32 VKAPI_CALL VulkanBackendImpl::onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                            VkDebugUtilsMessageTypeFlagsEXT,
                                                            const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                            void* user) {
    auto* self = static_cast<VulkanBackendImpl*>(user);
    if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        ++self->messages_;
        const std::string m = std::string("vulkan validation: ") + (data && data->pMessage ? data->pMessage : "?");
        if (self->log_.size() < 100) self->log_.push_back(m);
        self->warn(m);
    }
    return VK_FALSE;
}

void VulkanBackendImpl::createInstance() {
    uint32_t loaderVersion = VK_API_VERSION_1_0;
    if (auto enumerate = reinterpret_cast<PFN_vkEnumerateInstanceVersion>(
            vkGetInstanceProcAddr(nullptr, "vkEnumerateInstanceVersion")))
        enumerate(&loaderVersion);
    if (loaderVersion < VK_API_VERSION_1_1)
        unavailable("the Vulkan loader offers only Vulkan " + versionText(loaderVersion) + "; 1.1 is needed");
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "cullide";
    app.pEngineName = "cullide";
    app.apiVersion = std::min<uint32_t>(loaderVersion, VK_API_VERSION_1_3);
    apiVersion_ = app.apiVersion;

    std::vector<const char*> layers, extensions;
    VkDebugUtilsMessengerCreateInfoEXT messenger{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    if (options_.validation) {
        requireValidationLayer();
        layers.push_back(kValidationLayer);
        extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
        messenger.messageSeverity =
            VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
        messenger.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
            VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
        messenger.pfnUserCallback = &onMessage;
        messenger.pUserData = this;
    }
    VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    ci.pApplicationInfo = &app;
    ci.enabledLayerCount = uint32_t(layers.size());
    ci.ppEnabledLayerNames = layers.data();
    ci.enabledExtensionCount = uint32_t(extensions.size());
    ci.ppEnabledExtensionNames = extensions.data();
    if (options_.validation) ci.pNext = &messenger;  // also covers instance creation itself
    const VkResult r = vkCreateInstance(&ci, nullptr, &instance_);
    if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
        unavailable("no Vulkan driver (install mesa-vulkan-drivers for lavapipe, or a GPU driver)");
    check(r, "vkCreateInstance");
    if (options_.validation) createMessenger(messenger);
}

void VulkanBackendImpl::requireValidationLayer() const {
    uint32_t count = 0;
    vkEnumerateInstanceLayerProperties(&count, nullptr);
    std::vector<VkLayerProperties> props(count);
    vkEnumerateInstanceLayerProperties(&count, props.data());
    if (std::none_of(props.begin(), props.end(),
                     [](const VkLayerProperties& p) { return std::strcmp(p.layerName, kValidationLayer) == 0; }))
        unavailable(std::string("validation asked for but ") + kValidationLayer +
                    " is not installed (Debian: vulkan-validationlayers)");
}

void VulkanBackendImpl::createMessenger(const VkDebugUtilsMessengerCreateInfoEXT& messenger) {
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
    if (!create) unavailable("validation asked for but vkCreateDebugUtilsMessengerEXT is missing");
    check(create(instance_, &messenger, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
}

void VulkanBackendImpl::pickDevice() {
    uint32_t count = 0;
    check(vkEnumeratePhysicalDevices(instance_, &count, nullptr), "vkEnumeratePhysicalDevices");
    std::vector<VkPhysicalDevice> devices(count);
    check(vkEnumeratePhysicalDevices(instance_, &count, devices.data()), "vkEnumeratePhysicalDevices");
    if (devices.empty()) unavailable("no Vulkan device (install mesa-vulkan-drivers for lavapipe, or a GPU driver)");
    std::string reasons;
    int bestRank = -1;
    for (VkPhysicalDevice d : devices) {
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(d, &p);
        const std::string why = unsuitable(d, p);
        if (!why.empty()) {
            reasons += std::string(reasons.empty() ? "" : "; ") + p.deviceName + ": " + why;
            continue;
        }
        if (typeRank(p.deviceType) > bestRank) {
            bestRank = typeRank(p.deviceType);
            physical_ = d;
        }
    }
    if (!physical_) unavailable("no suitable Vulkan device: " + reasons);
}

// Empty when the device can run this backend, else why not.
std::string VulkanBackendImpl::unsuitable(VkPhysicalDevice d, const VkPhysicalDeviceProperties& p) const {
    if (!options_.deviceName.empty() && std::string(p.deviceName).find(options_.deviceName) == std::string::npos)
        return "name does not contain '" + options_.deviceName + "'";
    if (p.apiVersion < VK_API_VERSION_1_1) return "Vulkan " + versionText(p.apiVersion) + " (1.1 needed)";
    VkPhysicalDeviceFeatures f;
    vkGetPhysicalDeviceFeatures(d, &f);
    if (!f.occlusionQueryPrecise) return "no precise occlusion queries";
    if (!f.shaderFloat64) return "no 64-bit floats in shaders (shaderFloat64)";
    if (!(std::min(p.apiVersion, apiVersion_) >= VK_API_VERSION_1_3 ||
          hasExtension(d, VK_EXT_EXTENDED_DYNAMIC_STATE_EXTENSION_NAME)))
        return "no dynamic depth compare op (Vulkan 1.3 or VK_EXT_extended_dynamic_state)";
    if (graphicsQueue(d) == UINT32_MAX) return "no graphics queue";
    if (!depthAttachment(d, VK_FORMAT_D16_UNORM) && !depthAttachment(d, VK_FORMAT_X8_D24_UNORM_PACK32) &&
        !depthAttachment(d, VK_FORMAT_D32_SFLOAT))
        return "no usable depth format";
    return {};
}

void VulkanBackendImpl::createDevice() {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(physical_, &p);
    readDeviceInfo(p);
    createLogicalDevice(std::min(p.apiVersion, apiVersion_) >= VK_API_VERSION_1_3);
    createCommandObjects();
    ensure(uniform_, sizeof(ViewBlock), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT);
}

// info_, the viewport limits and the depth formats the chosen device has.
void VulkanBackendImpl::readDeviceInfo(const VkPhysicalDeviceProperties& p) {
    info_.device = p.deviceName;
    info_.type = typeText(p.deviceType);
    info_.api = versionText(p.apiVersion);
    info_.subpixelBits = int(p.limits.subPixelPrecisionBits);
    info_.maxViewport = int(std::min(p.limits.maxViewportDimensions[0], p.limits.maxViewportDimensions[1]));
    viewportBoundsMin_ = p.limits.viewportBoundsRange[0];
    maxSide_ = int(std::min({uint64_t(info_.maxViewport), uint64_t(p.limits.maxFramebufferWidth),
                             uint64_t(p.limits.maxFramebufferHeight), uint64_t(p.limits.maxImageDimension2D),
                             uint64_t(kMaxViewportSide)}));
    info_.hasD16 = depthAttachment(physical_, VK_FORMAT_D16_UNORM);
    info_.hasD24 = depthAttachment(physical_, VK_FORMAT_X8_D24_UNORM_PACK32);
    info_.hasD32F = depthAttachment(physical_, VK_FORMAT_D32_SFLOAT);
    info_.driver = "driver " + std::to_string(p.driverVersion);
    if (p.apiVersion >= VK_API_VERSION_1_2) {
        VkPhysicalDeviceDriverProperties dp{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
        VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
        p2.pNext = &dp;
        vkGetPhysicalDeviceProperties2(physical_, &p2);
        info_.driver = std::string(dp.driverName) + ", " + dp.driverInfo;
    }
}

// The device with one graphics queue, precise occlusion queries, 64-bit floats in shaders and
// dynamic depth compare op / write enable (core in 1.3, else VK_EXT_extended_dynamic_state).
void VulkanBackendImpl::createLogicalDevice(bool core13) {
    queueFamily_ = graphicsQueue(physical_);
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo qi{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qi.queueFamilyIndex = queueFamily_;
    qi.queueCount = 1;
    qi.pQueuePriorities = &priority;
    VkPhysicalDeviceFeatures features{};
    features.occlusionQueryPrecise = VK_TRUE;
    features.shaderFloat64 = VK_TRUE;
    VkPhysicalDeviceExtendedDynamicStateFeaturesEXT eds{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_EXTENDED_DYNAMIC_STATE_FEATURES_EXT};
    eds.extendedDynamicState = VK_TRUE;
    std::vector<const char*> extensions;
    VkDeviceCreateInfo ci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    if (!core13) {
        extensions.push_back(VK_EXT_EXTENDED_DYNAMIC_STATE_EXTENSION_NAME);
        ci.pNext = &eds;
    }
    ci.queueCreateInfoCount = 1;
    ci.pQueueCreateInfos = &qi;
    ci.enabledExtensionCount = uint32_t(extensions.size());
    ci.ppEnabledExtensionNames = extensions.data();
    ci.pEnabledFeatures = &features;
    check(vkCreateDevice(physical_, &ci, nullptr, &device_), "vkCreateDevice");
    vkGetDeviceQueue(device_, queueFamily_, 0, &queue_);
    setDepthCompareOp_ = reinterpret_cast<PFN_vkCmdSetDepthCompareOp>(
        vkGetDeviceProcAddr(device_, core13 ? "vkCmdSetDepthCompareOp" : "vkCmdSetDepthCompareOpEXT"));
    setDepthWriteEnable_ = reinterpret_cast<PFN_vkCmdSetDepthWriteEnable>(
        vkGetDeviceProcAddr(device_, core13 ? "vkCmdSetDepthWriteEnable" : "vkCmdSetDepthWriteEnableEXT"));
    if (!setDepthCompareOp_ || !setDepthWriteEnable_) unavailable("no vkCmdSetDepthCompareOp/WriteEnable");
}

// The one command buffer every submission reuses, and the fence it waits on.
void VulkanBackendImpl::createCommandObjects() {
    VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pi.queueFamilyIndex = queueFamily_;
    check(vkCreateCommandPool(device_, &pi, nullptr, &commandPool_), "vkCreateCommandPool");
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = commandPool_;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    check(vkAllocateCommandBuffers(device_, &ai, &commandBuffer_), "vkAllocateCommandBuffers");
    VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    check(vkCreateFence(device_, &fi, nullptr, &fence_), "vkCreateFence");
}

void VulkanBackendImpl::destroy() {
    if (device_) {
        vkDeviceWaitIdle(device_);
        destroyTarget();
        release(vertices_);
        release(indices_);
        release(uniform_);
        release(readback_);
        if (queryPool_) vkDestroyQueryPool(device_, queryPool_, nullptr);
        if (pipeline_) vkDestroyPipeline(device_, pipeline_, nullptr);
        if (renderPass_) vkDestroyRenderPass(device_, renderPass_, nullptr);
        if (shader_) vkDestroyShaderModule(device_, shader_, nullptr);
        if (pipelineLayout_) vkDestroyPipelineLayout(device_, pipelineLayout_, nullptr);
        if (descriptorPool_) vkDestroyDescriptorPool(device_, descriptorPool_, nullptr);
        if (setLayout_) vkDestroyDescriptorSetLayout(device_, setLayout_, nullptr);
        if (fence_) vkDestroyFence(device_, fence_, nullptr);
        if (commandPool_) vkDestroyCommandPool(device_, commandPool_, nullptr);
        vkDestroyDevice(device_, nullptr);
        device_ = VK_NULL_HANDLE;
    }
    if (instance_) {
        if (messenger_) {
            auto destroyMessenger = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
                vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
            if (destroyMessenger) destroyMessenger(instance_, messenger_, nullptr);
            messenger_ = VK_NULL_HANDLE;
        }
        vkDestroyInstance(instance_, nullptr);
        instance_ = VK_NULL_HANDLE;
    }
}

}  // namespace cullide::raster::vk
