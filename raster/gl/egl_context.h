// A headless OpenGL 4.5 core context through EGL (libepoxy). Private to raster/gl/.
#pragma once

#include "cullide/raster/gl_backend.h"

#include <epoxy/egl.h>

#include <string>

namespace cullide::raster::gl {

class EglContext {
public:
    // Throws BackendUnavailable with the reason for every platform tried.
    explicit EglContext(const GlBackendOptions& options);
    ~EglContext();
    EglContext(const EglContext&) = delete;
    EglContext& operator=(const EglContext&) = delete;

    // Makes the context current on the calling thread (a no-op when it already is).
    void makeCurrent() const;
    const std::string& platform() const { return platform_; }

private:
    EGLDisplay display_ = EGL_NO_DISPLAY;
    EGLContext context_ = EGL_NO_CONTEXT;
    std::string platform_;
};

}  // namespace cullide::raster::gl
