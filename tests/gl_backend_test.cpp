// Tests of what only the GL backend (raster/gl/) has: what it reports about its context (renderer,
// version, depth bits) and the no-EGL path. What every GPU backend must do alike (agreement with
// the CPU reference, depth formats, misuse, provenance) is in gpu_backend_test.cpp, run on GL too.
//
// The GL tests skip, with the reason printed, only when no OpenGL 4.5 context can be made here.
// Set CULLIDE_REQUIRE_GL=1 (CI, where Mesa's EGL is installed) to make that a failure instead.
#include "cullide/depth_backend.h"
#include "cullide/error.h"
#include "cullide/raster/gl_backend.h"
#include "gpu_test_util.h"
#include "window_geometry.h"

#include <gtest/gtest.h>

#include <cstdio>

namespace cullide {
namespace {

using raster::GlBackend;

// Trap: a backend that reports nothing useful about what it got (renderer, version, subpixel and
// depth bits), or depth bits that differ from the format asked for.
TEST(GlBackend, DescribeReportsRendererVersionSubpixelAndDepthBits) {
    GL_OR_SKIP();
    std::unique_ptr<GlBackend> gl = raster::makeGlBackend();
    EXPECT_FALSE(gl->info().renderer.empty());
    EXPECT_NE(gl->info().version.find("4."), std::string::npos);
    EXPECT_GE(gl->info().subpixelBits, 4);
    gl->setView(test::windowView(8, 8, DepthFormat::unorm(24)));
    EXPECT_EQ(gl->depthBits(), 24);
    const std::string d = gl->describe();
    EXPECT_NE(d.find(gl->info().renderer), std::string::npos) << d;
    EXPECT_NE(d.find("subpixel bits"), std::string::npos) << d;
    EXPECT_NE(d.find("24 depth bits"), std::string::npos) << d;
    std::printf("  [gl] %s\n", d.c_str());
}

// Trap: a machine without EGL aborting in libepoxy (which abort()s when libEGL cannot be loaded)
// or failing silently; the error must say why, and the CPU path must be unaffected. Runs without
// GL too.
TEST(GlBackend, NoContextGivesAClearErrorAndTheCpuPathStillWorks) {
    raster::GlBackendOptions o;
    o.eglLibrary = "libEGL-cullide-test-missing.so.1";
    try {
        raster::makeGlBackend(o);
        FAIL() << "expected BackendUnavailable";
    } catch (const raster::BackendUnavailable& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("gl backend"), std::string::npos) << m;
        EXPECT_NE(m.find("no EGL"), std::string::npos) << m;
        EXPECT_NE(m.find("libEGL-cullide-test-missing.so.1"), std::string::npos) << m;
    }
    std::string why;
    EXPECT_FALSE(raster::glBackendAvailable(&why, o));
    EXPECT_NE(why.find("no EGL"), std::string::npos);
    // BackendUnavailable is an InputError: the command line prints it and exits 2.
    EXPECT_THROW(raster::makeGlBackend(o), InputError);
    test::expectCpuPathWorks();
}

}  // namespace
}  // namespace cullide
