// Shared by the GPU backend tests (gpu_backend_test.cpp, gl_backend_test.cpp,
// vulkan_backend_test.cpp): whether a backend can be made here, skipping when it cannot, making the
// backend under test, and the Vulkan validation layer's messages.
//
// A GPU test skips, with the reason printed, only when no OpenGL 4.5 context (GL) or no Vulkan
// device (Vulkan) can be made here. Set CULLIDE_REQUIRE_GL=1 / CULLIDE_REQUIRE_VULKAN=1 (CI, where
// Mesa's EGL, lavapipe and the validation layers are installed; tools/test.sh sets both) to make
// that a failure instead.
#pragma once

#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/gl_backend.h"
#include "cullide/raster/vulkan_backend.h"
#include "window_geometry.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace cullide::test {

// One context check per process; every GL test then makes its own backend.
inline const std::string& glUnavailableReason() {
    static const std::string why = [] {
        std::string w;
        return raster::glBackendAvailable(&w) ? std::string() : w;
    }();
    return why;
}

// One device check per process (with validation, as the tests use it); every test then makes its
// own backend.
inline const std::string& vulkanUnavailableReason() {
    static const std::string why = [] {
        std::string w;
        raster::VulkanBackendOptions o;
        o.validation = true;
        return raster::vulkanBackendAvailable(&w, o) ? std::string() : w;
    }();
    return why;
}

#define GL_OR_SKIP()                                                                                              \
    do {                                                                                                          \
        if (!::cullide::test::glUnavailableReason().empty()) {                                                    \
            if (std::getenv("CULLIDE_REQUIRE_GL")) FAIL() << "no GL: " << ::cullide::test::glUnavailableReason(); \
            GTEST_SKIP() << "no GL context: " << ::cullide::test::glUnavailableReason();                          \
        }                                                                                                         \
    } while (0)

#define VULKAN_OR_SKIP()                                                                        \
    do {                                                                                        \
        if (!::cullide::test::vulkanUnavailableReason().empty()) {                              \
            if (std::getenv("CULLIDE_REQUIRE_VULKAN"))                                          \
                FAIL() << "no Vulkan: " << ::cullide::test::vulkanUnavailableReason();          \
            GTEST_SKIP() << "no Vulkan device: " << ::cullide::test::vulkanUnavailableReason(); \
        }                                                                                       \
    } while (0)

// GL_OR_SKIP() or VULKAN_OR_SKIP() for a GPU backend name ("gl", "vulkan").
#define GPU_OR_SKIP(kind)     \
    do {                      \
        if ((kind) == "gl") { \
            GL_OR_SKIP();     \
        } else {              \
            VULKAN_OR_SKIP(); \
        }                     \
    } while (0)

// The GPU backend names this build has, in gpuBackendNames() order: what the shared GPU tests
// run on.
inline std::vector<std::string> builtGpuBackends() {
    std::vector<std::string> kinds;
    if (raster::glBuilt()) kinds.push_back("gl");
    if (raster::vulkanBuilt()) kinds.push_back("vulkan");
    return kinds;
}

// "Gl", "Vulkan": a GPU backend name as it appears in test names (gtest filters such as
// *Vulkan* select the backend's cases).
inline std::string gpuTestLabel(const std::string& kind) {
    return kind == "gl" ? "Gl" : "Vulkan";
}

// A Vulkan backend with the validation layer on; validation messages are collected, not printed.
// Other warnings go to `warnings` when given.
inline std::unique_ptr<raster::VulkanBackend> makeValidated(std::vector<std::string>* warnings = nullptr) {
    raster::VulkanBackendOptions o;
    o.validation = true;
    o.warn = [warnings](const std::string& w) {
        if (warnings && w.rfind("vulkan validation", 0) != 0) warnings->push_back(w);
    };
    return raster::makeVulkanBackend(o);
}

// The backend under test: GL as made by default (its warnings to `warnings` when given), Vulkan
// with the validation layer on (makeValidated).
inline std::unique_ptr<raster::GpuBackend> makeGpuUnderTest(const std::string& kind,
                                                            std::vector<std::string>* warnings = nullptr) {
    if (kind != "gl") return makeValidated(warnings);
    raster::GlBackendOptions o;
    if (warnings) o.warn = [warnings](const std::string& w) { warnings->push_back(w); };
    return raster::makeGlBackend(o);
}

// Validation-layer messages a backend received (0 for GL, which has no validation layer), and
// their text for the failure message.
inline uint64_t validationMessages(const raster::GpuBackend& b) {
    const auto* vk = dynamic_cast<const raster::VulkanBackend*>(&b);
    return vk ? vk->validationMessages() : 0;
}

inline std::string validationText(const raster::GpuBackend& b) {
    std::string s;
    if (const auto* vk = dynamic_cast<const raster::VulkanBackend*>(&b))
        for (const std::string& m : vk->validationLog()) s += m + "\n";
    return s;
}

#define EXPECT_NO_VALIDATION_MESSAGES(b) \
    EXPECT_EQ(::cullide::test::validationMessages(b), 0u) << ::cullide::test::validationText(b)

// The CPU path still works (for the no-context and no-device cases): a 4x4 quad in an 8x8 view
// passes on 16 samples.
inline void expectCpuPathWorks() {
    std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    addQuad(p, t, 0, 0, 4, 4, 0.5f);
    cpu->setGeometry(p, t);
    cpu->setView(windowView(8, 8, DepthFormat::unorm(24)));
    CommandList ok;
    ok.beginQuery();
    ok.draw(0, 2);
    ok.endQuery();
    EXPECT_EQ(cpu->execute(ok), std::vector<uint64_t>{16});
}

}  // namespace cullide::test
