// The depth backends by name, as the commands and study specs take them: the one list of names
// (`prune --backend`, `study --backends`, a spec's "backends", `validate`).
//   "cpu": the CPU reference rasterizer (cpu_backend.h), `threads` workers (0: all cores);
//   "gl":  OpenGL 4.5 through headless EGL (gl_backend.h). A build configured with
//          -DCULLIDE_GL=OFF has no GL backend: making one throws BackendUnavailable saying so.
//   "vulkan": Vulkan 1.1+ through the loader, headless (vulkan_backend.h); likewise absent with
//          -DCULLIDE_VULKAN=OFF.
#pragma once

#include "cullide/depth_backend.h"
#include "cullide/raster/gpu_backend.h"

#include <memory>
#include <string>
#include <vector>

namespace cullide::raster {

// Every backend name, in the order help texts list them: cpu, gl, vulkan (also when GL or Vulkan is
// not built, so that asking for it says why it cannot be had).
const std::vector<std::string>& backendNames();
bool isBackendName(const std::string& name);
// "cpu, gl or vulkan": the names for messages.
std::string backendNameList();

// Whether this build has the GL backend (CMake option CULLIDE_GL).
bool glBuilt();
// The message of a GL request in a build without GL.
inline constexpr const char* kGlNotBuilt = "GL backend not built (configure with -DCULLIDE_GL=ON)";
// Whether this build has the Vulkan backend (CMake option CULLIDE_VULKAN).
bool vulkanBuilt();
inline constexpr const char* kVulkanNotBuilt = "Vulkan backend not built (configure with -DCULLIDE_VULKAN=ON)";

// The backend of a name. InputError("backend", ...) for an unknown name; BackendUnavailable (an
// InputError) when no GL context or Vulkan device can be made, or that backend is not built.
std::unique_ptr<DepthBackend> makeBackend(const std::string& name, int threads);
// The GPU backend ("gl" or "vulkan") of a name, for `validate` and `trace replay`; InputError
// ("backend", ...) for another name, BackendUnavailable as above.
std::unique_ptr<GpuBackend> makeGpuBackend(const std::string& name);
// The GPU backend names: gl, vulkan.
const std::vector<std::string>& gpuBackendNames();

}  // namespace cullide::raster
