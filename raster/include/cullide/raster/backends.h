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

#include <algorithm>
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

// Another backend as one that draws at most `side` pixels per side (1..kMaxViewportSide) would
// look: maxViewportSide() says `side` (or the inner backend's limit, if smaller) and setView()
// refuses a larger view (InputError "view").
// Everything else goes to `inner`, which must outlive it. Cullide then draws larger calls in tiles
// (docs/cullide.md#adaptive-resolution): the tests and BM_Tiles run that on the CPU reference, as a
// GPU with small limits would.
class ViewportLimit final : public DepthBackend {
public:
    ViewportLimit(DepthBackend& inner, int side);
    std::string describe() const override;
    void setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) override {
        inner_.setGeometry(positions, triangles);
    }
    bool borrowGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) override {
        return inner_.borrowGeometry(positions, triangles);
    }
    void setView(const OrthoView& view) override;
    std::vector<uint64_t> execute(const CommandList& commands) override { return inner_.execute(commands); }
    bool supportsConservative() const override { return inner_.supportsConservative(); }
    int maxViewportSide() const override { return std::min(side_, inner_.maxViewportSide()); }
    DepthImage readDepth() override { return inner_.readDepth(); }
    void readDepthInto(DepthImage& out) override { inner_.readDepthInto(out); }
    uint64_t tilesSet() const { return tiles_; }  // views set that were tiles (OrthoView::tiled)

private:
    DepthBackend& inner_;
    int side_;
    uint64_t tiles_ = 0;
};

}  // namespace cullide::raster
