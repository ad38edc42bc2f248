// The Vulkan backend: the same DepthBackend interface as the CPU reference and the GL backend, on
// Vulkan 1.1+ (headless, through the loader), so that engineers on Vulkan can validate against the
// reference (`cullide validate --backend vulkan`, docs/vulkan-backend.md).
//
// Conventions
//   - Headless: no surface, no swapchain. makeVulkanBackend() picks a discrete GPU, else an
//     integrated one, else a virtual one, else a CPU device (Mesa's lavapipe), among the devices
//     with Vulkan 1.1+, a graphics queue, precise occlusion queries, 64-bit floats in shaders and
//     dynamic depth compare op / write enable (core 1.3 or VK_EXT_extended_dynamic_state).
//   - One depth-only render pass per execute() (load and store the depth attachment), a pipeline
//     with a vertex shader only (SPIR-V compiled from GLSL at build time and embedded), depth test
//     always on, compare op and write enable as dynamic state, no culling, no depth clamp.
//   - Window coordinates: the vertex shader evaluates OrthoView::toWindow() in double, in the same
//     order of operations (GLSL `precise`), rounds to float and scales by 1/P into clip space; the
//     viewport (-P, -P, 2P, 2P) then gives the rasterizer exactly float(toWindow(p)), as the GL
//     backend does. Depth range 0..1 is the window depth itself. Framebuffer row y is GL window
//     row y (row 0 at the bottom of GL's window, as DepthImage wants); see docs/vulkan-backend.md
//     for why the viewport height is positive.
//   - Commands one to one: Clear -> vkCmdClearAttachments (ignores the write mask, as the
//     reference's clear does), SetDepthFunc -> vkCmdSetDepthCompareOp, SetDepthMask ->
//     vkCmdSetDepthWriteEnable, SamplesPassed -> an occlusion query with
//     VK_QUERY_CONTROL_PRECISE_BIT, AnySamplesPassed -> one without (any non-zero result is 1),
//     Draw -> vkCmdDrawIndexed. One query pool per command list; its results are read once,
//     64-bit with WAIT, after the list's single submission.
//   - Depth formats: unorm n bits -> the nearest of D16_UNORM and X8_D24_UNORM_PACK32 (ties to
//     the larger), float -> D32_SFLOAT, each only where the device supports it as a depth
//     attachment (and copy source); otherwise the nearest supported one, with a warning once per
//     requested format.
//   - Use one backend from one thread at a time.
#pragma once

#include "cullide/raster/gpu_backend.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace cullide::raster {

struct VulkanBackendOptions {
    // Enable VK_LAYER_KHRONOS_validation and count its messages through a debug-utils messenger
    // (validationMessages()). Also switched on by the environment variable
    // CULLIDE_VULKAN_VALIDATION=1. When asked for and the layer is missing: BackendUnavailable.
    bool validation = false;
    // Only devices whose name contains this text (empty: any). Tests use a name no device has to
    // exercise the no-device path.
    std::string deviceName;
    // Receives warnings (depth format mapped to another) and, with validation, every validation
    // message; null: printed to stderr.
    std::function<void(const std::string&)> warn;
};

// What the device turned out to be.
struct VulkanInfo {
    std::string device;  // "llvmpipe (LLVM 15.0.6, 256 bits)"
    std::string type;  // "discrete GPU", "integrated GPU", "virtual GPU", "CPU", "other"
    std::string driver;  // driverName + driverInfo where the device reports them (1.2+), e.g. "llvmpipe, Mesa 22.3.6
                         // (LLVM 15.0.6)"
    std::string api;  // the device's Vulkan version, "1.3.230"
    int subpixelBits = 0;  // VkPhysicalDeviceLimits::subPixelPrecisionBits
    int maxViewport = 0;  // maxViewportDimensions (smaller side)
    bool hasD16 = false, hasD24 = false, hasD32F = false;  // usable as depth attachments
};

class VulkanBackend : public GpuBackend {
public:
    ~VulkanBackend() override = default;
    virtual const VulkanInfo& info() const = 0;
    std::string apiName() const override { return "vulkan"; }
    int subpixelBits() const override { return info().subpixelBits; }
    // Validation-layer messages (warnings and errors) received so far; 0 without validation.
    virtual uint64_t validationMessages() const = 0;
    virtual std::vector<std::string> validationLog() const = 0;
};

// Creates a Vulkan backend with its own instance and device. Throws BackendUnavailable (source
// "vulkan backend", saying why for every device considered) when none can be made.
std::unique_ptr<VulkanBackend> makeVulkanBackend(const VulkanBackendOptions& options = {});

// Whether a Vulkan backend can be made here; when not, `why` receives the reason.
bool vulkanBackendAvailable(std::string* why = nullptr, const VulkanBackendOptions& options = {});

}  // namespace cullide::raster
