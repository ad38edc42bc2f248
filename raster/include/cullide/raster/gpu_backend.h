// What the GPU backends (OpenGL in raster/gl/, Vulkan in raster/vulkan/) have in common beyond
// DepthBackend, so that `cullide validate` and `trace replay` treat them alike: the depth format
// they store for a requested one, and their subpixel bits (the trace rules' "other" grid).
#pragma once

#include "cullide/depth_backend.h"
#include "cullide/error.h"

#include <string>

namespace cullide::raster {

// No context or device could be made (no library, no display or device, a missing feature), or the
// backend was not built. An InputError whose source names the backend ("gl backend", "vulkan
// backend"), so the command line prints it and exits 2; the message says why.
class BackendUnavailable : public InputError {
public:
    explicit BackendUnavailable(const std::string& cause, const std::string& source = "gl backend")
        : InputError(source, cause) {}
};

class GpuBackend : public DepthBackend {
public:
    ~GpuBackend() override = default;
    // "gl" or "vulkan": the backend's name in backends.h, for labels and messages.
    virtual std::string apiName() const = 0;
    // The depth format the backend stores for a requested one (nearest available; setView warns
    // once per requested format when it differs).
    virtual DepthFormat effectiveFormat(const DepthFormat& requested) const = 0;
    // Subpixel precision of the rasterizer (GL_SUBPIXEL_BITS, VkPhysicalDeviceLimits::subPixelPrecisionBits).
    virtual int subpixelBits() const = 0;
};

// Whether make() succeeds (a backend can be made here); otherwise false with BackendUnavailable's
// message in *why. The one body behind glBackendAvailable and vulkanBackendAvailable.
template <typename Make>
bool backendAvailable(const Make& make, std::string* why) {
    try {
        make();
        return true;
    } catch (const BackendUnavailable& e) {
        if (why) *why = e.what();
        return false;
    }
}

}  // namespace cullide::raster
