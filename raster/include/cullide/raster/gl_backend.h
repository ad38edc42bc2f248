// The OpenGL backend: the same DepthBackend interface as the CPU reference, on real OpenGL 4.5
// with real occlusion queries, so that GPU results can be compared with the reference
// (`cullide validate`, docs/gl-backend.md).
//
// Conventions
//   - Headless: an EGL context without any surface, loaded through libepoxy. makeGlBackend()
//     tries, in order, the EGL devices that are not software renderers (a real GPU), Mesa's
//     surfaceless platform (llvmpipe on a machine without a GPU), then the remaining (software)
//     EGL devices. OpenGL 4.5 core is required (glClipControl, DSA, query buffer objects,
//     double-precision vertex shaders).
//   - Rendering goes to a depth-only framebuffer object of the view's size. The requested depth
//     format maps to the nearest one GL has: unorm n bits -> GL_DEPTH_COMPONENT16, 24 or 32
//     (nearest bit count; ties to the larger), float -> GL_DEPTH_COMPONENT32F. When the mapping
//     changes the format a warning is given (once per requested format) and the effective format
//     is the one readDepth() reports.
//   - Window coordinates: the vertex shader evaluates OrthoView::toWindow() in double, in the same
//     order of operations (GLSL `precise`), and rounds the result to float. With
//     glClipControl(LOWER_LEFT, ZERO_TO_ONE) and a viewport of (-P, -P, 2P, 2P) (P a power of two
//     >= twice the larger side where GL_MAX_VIEWPORT_DIMS allows, else >= it) GL's viewport transform is then exact, so
//     the rasterizer sees exactly float(toWindow(p)); the reference sees toWindow(p) in double. (When 2P would exceed
//     GL_MAX_VIEWPORT_DIMS the ordinary viewport is used and the transform rounds in float.)
//   - Same commands, one to one: Clear -> glClearDepth + glClear (depth writes enabled for the
//     clear, as the reference clears regardless of the mask), SetDepthFunc -> glDepthFunc,
//     SetDepthMask -> glDepthMask, Begin/EndQuery -> glBeginQuery/glEndQuery on
//     GL_SAMPLES_PASSED / GL_ANY_SAMPLES_PASSED (pooled query objects), Draw ->
//     glDrawElements(GL_TRIANGLES, 3*count, GL_UNSIGNED_INT, 12*first). The geometry is uploaded
//     once per setGeometry(); all query results of a command list are written by the GL into one
//     query buffer object and read back with a single call after the list.
//   - A backend owns its EGL context and makes it current on the calling thread at every call;
//     use one backend from one thread at a time.
#pragma once

#include "cullide/raster/gpu_backend.h"

#include <functional>
#include <memory>
#include <string>

namespace cullide::raster {

// makeGlBackend() throws BackendUnavailable (gpu_backend.h, source "gl backend") when no GL
// context can be made (no EGL library, no display or device, no OpenGL 4.5 core), saying why for
// every platform tried.

struct GlBackendOptions {
    enum class Platform : uint8_t {
        Auto,  // hardware EGL devices, then Mesa surfaceless, then software devices
        Device,  // EGL devices only (EGL_EXT_platform_device)
        Surfaceless,  // Mesa's surfaceless platform only (EGL_MESA_platform_surfaceless)
    };
    Platform platform = Platform::Auto;
    // The EGL library libepoxy will load. It is opened first to check that it exists, so that a
    // machine without EGL gets a BackendUnavailable, not libepoxy's abort. (Tests point it at a
    // missing file to exercise that path.)
    std::string eglLibrary = "libEGL.so.1";
    // Receives warnings (depth format mapped to another); null: printed to stderr.
    std::function<void(const std::string&)> warn;
};

// What the context turned out to be.
struct GlInfo {
    std::string platform;  // "EGL device 0 (software)", "Mesa surfaceless"
    std::string renderer, version, vendor;
    int subpixelBits = 0;  // GL_SUBPIXEL_BITS
    int maxViewport = 0;  // GL_MAX_VIEWPORT_DIMS (smaller side)
    bool hasUnorm32 = false;  // GL_DEPTH_COMPONENT32 is renderable
};

class GlBackend : public GpuBackend {
public:
    ~GlBackend() override = default;
    virtual const GlInfo& info() const = 0;
    std::string apiName() const override { return "gl"; }
    int subpixelBits() const override { return info().subpixelBits; }
    // effectiveFormat(): the depth format GL stores for a requested one (see the conventions).
    // Depth bits of the current framebuffer as GL reports them (GL_RENDERBUFFER_DEPTH_SIZE);
    // 0 before the first setView().
    virtual int depthBits() const = 0;
};

// Creates a GL backend with its own context. Throws BackendUnavailable (saying why) when no
// context can be made.
std::unique_ptr<GlBackend> makeGlBackend(const GlBackendOptions& options = {});

// Whether a GL backend can be made here; when not, `why` receives the reason. Creates (and
// destroys) a context, so it costs a few milliseconds.
bool glBackendAvailable(std::string* why = nullptr, const GlBackendOptions& options = {});

}  // namespace cullide::raster
