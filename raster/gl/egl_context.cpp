// Headless EGL context creation: EGL devices (EGL_EXT_device_enumeration + EGL_EXT_platform_device)
// and Mesa's surfaceless platform (EGL_MESA_platform_surfaceless), OpenGL 4.5 core, no surface
// (EGL_KHR_surfaceless_context). See gl_backend.h for the order in which they are tried.
#include "egl_context.h"

#include <dlfcn.h>

#include <cstdio>
#include <vector>

namespace cullide::raster::gl {

namespace {

std::string eglErrorName(EGLint e) {
    switch (e) {
        case EGL_SUCCESS: return "EGL_SUCCESS";
        case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
        case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
        case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
        case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
        case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
        case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
        case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
        case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
        case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
        default: {
            char buf[32];
            std::snprintf(buf, sizeof buf, "EGL error 0x%04x", unsigned(e));
            return buf;
        }
    }
}

// Creates a 4.5 core context on an initialized display; returns EGL_NO_CONTEXT and sets `why`.
EGLContext createCoreContext(EGLDisplay display, std::string& why) {
    if (!epoxy_has_egl_extension(display, "EGL_KHR_surfaceless_context")) {
        why = "no EGL_KHR_surfaceless_context";
        return EGL_NO_CONTEXT;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        why = "no desktop OpenGL API (eglBindAPI: " + eglErrorName(eglGetError()) + ")";
        return EGL_NO_CONTEXT;
    }
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!epoxy_has_egl_extension(display, "EGL_KHR_no_config_context")) {
        const EGLint want[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, 0, EGL_NONE};
        EGLint n = 0;
        if (!eglChooseConfig(display, want, &config, 1, &n) || n < 1) {
            why = "no EGL config for desktop OpenGL";
            return EGL_NO_CONTEXT;
        }
    }
    const EGLint attributes[] = {
        EGL_CONTEXT_MAJOR_VERSION,           4,       EGL_CONTEXT_MINOR_VERSION, 5, EGL_CONTEXT_OPENGL_PROFILE_MASK,
        EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, attributes);
    if (context == EGL_NO_CONTEXT) why = "no OpenGL 4.5 core context (" + eglErrorName(eglGetError()) + ")";
    return context;
}

}  // namespace

EglContext::EglContext(const GlBackendOptions& options) {
    // libepoxy aborts the process when it cannot load libEGL: check first.
    void* lib = dlopen(options.eglLibrary.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        const char* err = dlerror();
        throw BackendUnavailable("no EGL: cannot load " + options.eglLibrary + " (" + (err ? err : "?") +
                                 "); install Mesa's EGL (Debian: libegl1 libegl-mesa0 libgl1-mesa-dri)");
    }
    dlclose(lib);

    struct Candidate {
        EGLDisplay display;
        std::string name;
    };
    std::vector<Candidate> hardware, software, surfaceless;
    std::string reasons;
    auto note = [&](const std::string& what) { reasons += (reasons.empty() ? "" : "; ") + what; };

    const bool wantDevices = options.platform != GlBackendOptions::Platform::Surfaceless;
    const bool wantSurfaceless = options.platform != GlBackendOptions::Platform::Device;
    if (wantDevices) {
        if (epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_device_enumeration") &&
            epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_platform_device")) {
            EGLint n = 0;
            eglQueryDevicesEXT(0, nullptr, &n);
            std::vector<EGLDeviceEXT> devices(size_t(n > 0 ? n : 0));
            if (n > 0) eglQueryDevicesEXT(n, devices.data(), &n);
            if (n <= 0) note("EGL devices: none found");
            for (EGLint i = 0; i < n; ++i) {
                const char* ext = eglQueryDeviceStringEXT(devices[size_t(i)], EGL_EXTENSIONS);
                const bool isSoftware = ext && std::string(ext).find("EGL_MESA_device_software") != std::string::npos;
                EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[size_t(i)], nullptr);
                const std::string name = "EGL device " + std::to_string(i) + (isSoftware ? " (software)" : "");
                if (d == EGL_NO_DISPLAY) {
                    note(name + ": no display (" + eglErrorName(eglGetError()) + ")");
                    continue;
                }
                (isSoftware ? software : hardware).push_back({d, name});
            }
        } else {
            note("EGL devices: the EGL library has no EGL_EXT_device_enumeration/EGL_EXT_platform_device");
        }
    }
    if (wantSurfaceless) {
        if (epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless")) {
            EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
            if (d == EGL_NO_DISPLAY) note("Mesa surfaceless: no display (" + eglErrorName(eglGetError()) + ")");
            else surfaceless.push_back({d, "Mesa surfaceless"});
        } else {
            note("Mesa surfaceless: the EGL library has no EGL_MESA_platform_surfaceless");
        }
    }
    std::vector<Candidate> order = hardware;
    order.insert(order.end(), surfaceless.begin(), surfaceless.end());
    order.insert(order.end(), software.begin(), software.end());
    for (const Candidate& c : order) {
        EGLint major = 0, minor = 0;
        if (!eglInitialize(c.display, &major, &minor)) {
            note(c.name + ": eglInitialize failed (" + eglErrorName(eglGetError()) + ")");
            continue;
        }
        std::string why;
        EGLContext ctx = createCoreContext(c.display, why);
        if (ctx == EGL_NO_CONTEXT) {
            note(c.name + ": " + why);
            continue;
        }
        if (!eglMakeCurrent(c.display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
            note(c.name + ": eglMakeCurrent failed (" + eglErrorName(eglGetError()) + ")");
            eglDestroyContext(c.display, ctx);
            continue;
        }
        display_ = c.display;
        context_ = ctx;
        platform_ = c.name;
        return;
    }
    if (order.empty() && reasons.empty()) note("no EGL platform to try");
    throw BackendUnavailable("no OpenGL 4.5 core context could be made: " + reasons);
}

EglContext::~EglContext() {
    if (context_ == EGL_NO_CONTEXT) return;
    if (eglGetCurrentContext() == context_) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    // No eglTerminate: the display is shared by every context on it in this process.
}

void EglContext::makeCurrent() const {
    if (eglGetCurrentContext() == context_) return;
    eglBindAPI(EGL_OPENGL_API);
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
        throw BackendUnavailable("eglMakeCurrent failed (" + eglErrorName(eglGetError()) +
                                 "); is the context current on another thread?");
}

}  // namespace cullide::raster::gl
