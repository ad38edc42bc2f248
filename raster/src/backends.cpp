// The depth backends by name (see backends.h); in a build without GL or Vulkan, their entry points
// that say so.
#include "cullide/raster/backends.h"

#include "cullide/error.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/gl_backend.h"
#include "cullide/raster/vulkan_backend.h"

namespace cullide::raster {

const std::vector<std::string>& backendNames() {
    static const std::vector<std::string> names{"cpu", "gl", "vulkan"};
    return names;
}

bool isBackendName(const std::string& name) {
    for (const std::string& n : backendNames())
        if (n == name) return true;
    return false;
}

std::string backendNameList() {
    std::string out;
    const std::vector<std::string>& names = backendNames();
    for (size_t i = 0; i < names.size(); ++i) out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
    return out;
}

bool glBuilt() {
    return CULLIDE_GL;
}

bool vulkanBuilt() {
    return CULLIDE_VULKAN;
}

const std::vector<std::string>& gpuBackendNames() {
    static const std::vector<std::string> names{"gl", "vulkan"};
    return names;
}

std::unique_ptr<GpuBackend> makeGpuBackend(const std::string& name) {
    if (name == "gl") return makeGlBackend();
    if (name == "vulkan") return makeVulkanBackend();
    throw InputError("backend", "'" + name + "': gl or vulkan");
}

std::unique_ptr<DepthBackend> makeBackend(const std::string& name, int threads) {
    if (name == "cpu") {
        CpuBackendOptions o;
        o.threads = threads;
        return makeCpuBackend(o);
    }
    if (name == "gl") return makeGlBackend();
    if (name == "vulkan") return makeVulkanBackend();
    throw InputError("backend", "'" + name + "': " + backendNameList());
}

#if !CULLIDE_GL
// Built without raster/gl/ (-DCULLIDE_GL=OFF): the GL backend's entry points say so.
std::unique_ptr<GlBackend> makeGlBackend(const GlBackendOptions&) {
    throw BackendUnavailable(kGlNotBuilt);
}

bool glBackendAvailable(std::string* why, const GlBackendOptions&) {
    if (why) *why = kGlNotBuilt;
    return false;
}
#endif

#if !CULLIDE_VULKAN
// Built without raster/vulkan/ (-DCULLIDE_VULKAN=OFF): the Vulkan backend's entry points say so.
std::unique_ptr<VulkanBackend> makeVulkanBackend(const VulkanBackendOptions&) {
    throw BackendUnavailable(kVulkanNotBuilt, "vulkan backend");
}

bool vulkanBackendAvailable(std::string* why, const VulkanBackendOptions&) {
    if (why) *why = kVulkanNotBuilt;
    return false;
}
#endif

ViewportLimit::ViewportLimit(DepthBackend& inner, int side) : inner_(inner), side_(side) {
    if (side < 1 || side > kMaxViewportSide)
        throw InputError("viewport limit",
                         "a side of 1.." + std::to_string(kMaxViewportSide) + " pixels, got " + std::to_string(side));
}

std::string ViewportLimit::describe() const {
    return inner_.describe() + ", at most " + std::to_string(side_) + " px per side";
}

void ViewportLimit::setView(const OrthoView& view) {
    const int side = maxViewportSide();
    if (view.width > side || view.height > side)
        throw InputError("view",
                         "a " + std::to_string(view.width) + "x" + std::to_string(view.height) +
                             " viewport is larger than this backend draws (" + std::to_string(side) + " px per side)");
    tiles_ += view.tiled() ? 1 : 0;
    inner_.setView(view);
}

}  // namespace cullide::raster
