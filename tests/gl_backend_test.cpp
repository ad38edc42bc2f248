// Tests of the GL backend (raster/gl/): the same commands give the same results as the CPU
// reference where the reference's rules leave GL no freedom (pixel-aligned, depth-separated
// boxes; coverage counts of single triangles), at D16, D24 and D32F; the no-context path.
//
// The GL tests skip, with the reason printed, only when no OpenGL 4.5 context can be made here.
// Set CULLIDE_REQUIRE_GL=1 (CI, where Mesa's EGL is installed) to make that a failure instead.
#include "cullide/depth_backend.h"
#include "cullide/error.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/gl_backend.h"
#include "cullide/study/study.h"
#include "window_geometry.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

namespace cullide {
namespace {

using test::addQuad;

using raster::GlBackend;

// One context check per process; every GL test then makes its own backend.
const std::string& glUnavailableReason() {
    static const std::string why = [] {
        std::string w;
        return raster::glBackendAvailable(&w) ? std::string() : w;
    }();
    return why;
}

#define GL_OR_SKIP()                                                                             \
    do {                                                                                         \
        if (!glUnavailableReason().empty()) {                                                    \
            if (std::getenv("CULLIDE_REQUIRE_GL")) FAIL() << "no GL: " << glUnavailableReason(); \
            GTEST_SKIP() << "no GL context: " << glUnavailableReason();                          \
        }                                                                                        \
    } while (0)

class GlFormats : public ::testing::TestWithParam<DepthFormat> {};

std::string formatName(const ::testing::TestParamInfo<DepthFormat>& info) {
    return info.param.name();
}

// Trap: anything in the GL path that is not one-to-one with the reference where the rules leave no
// freedom: the window transform (y flip, half-pixel offsets), depth conversion of binary-fraction
// depths, each of the eight depth functions, the depth mask (also for clears: glClear honours
// glDepthMask, the reference's clear does not), ANY_SAMPLES_PASSED, state persisting across lists,
// and readDepth's unorm scaling (GL returns k scaled to 32 bits).
TEST_P(GlFormats, PixelAlignedDepthSeparatedBoxesAgreeExactly) {
    GL_OR_SKIP();
    const DepthFormat f = GetParam();
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    addQuad(p, t, 4, 4, 40, 30, 0.5f);  // tris 0-1: the occluder
    addQuad(p, t, 10, 2, 60, 20, 0.25f);  // tris 2-3: in front, partly overlapping
    addQuad(p, t, 20, 10, 50, 45, 0.75f);  // tris 4-5: behind
    addQuad(p, t, 0, 0, 64, 48, 0.5f);  // tris 6-7: the whole viewport at the occluder's depth
    const OrthoView view = test::windowView(64, 48, f);

    std::unique_ptr<GlBackend> gl = raster::makeGlBackend();
    std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
    CommandList list;
    list.clear(1.0);
    list.depthFunc(DepthFunc::Less);
    list.beginQuery();
    list.draw(0, 2);
    list.endQuery();
    list.depthMask(false);
    for (int k = 0; k < 8; ++k) {
        list.depthFunc(DepthFunc(k));
        for (uint32_t box : {2u, 4u, 6u}) {
            list.beginQuery();
            list.draw(box, 2);
            list.endQuery();
        }
    }
    list.beginQuery(QueryKind::AnySamplesPassed);
    list.draw(4, 2);
    list.endQuery();
    list.clear(1.0);  // with the mask off: must still clear
    list.depthMask(true);
    list.depthFunc(DepthFunc::LEqual);
    list.draw(0, 4);
    CommandList second;  // state (LEQUAL, mask on) carries over
    second.beginQuery();
    second.draw(6, 2);
    second.endQuery();

    std::vector<uint64_t> results[2];
    std::vector<uint64_t> seconds[2];
    DepthImage images[2];
    DepthBackend* backends[2] = {cpu.get(), gl.get()};
    for (int b = 0; b < 2; ++b) {
        backends[b]->setGeometry(p, t);
        backends[b]->setView(view);
        results[b] = backends[b]->execute(list);
        seconds[b] = backends[b]->execute(second);
        images[b] = backends[b]->readDepth();
    }
    EXPECT_EQ(results[0], results[1]);
    EXPECT_EQ(seconds[0], seconds[1]);
    EXPECT_EQ(results[0][0], uint64_t(36 * 26));  // sanity: the occluder's pixel count
    ASSERT_EQ(images[1].format, f);
    EXPECT_EQ(images[0].values, images[1].values);
}

// Trap: coverage differing from the reference's (8 subpixel bits, round to nearest, bottom-left
// fill rule, zero-area triangles dropped) on general triangles. Each triangle is its own
// SAMPLES_PASSED query over a cleared buffer, so the count is its coverage. Fixed seed.
TEST_P(GlFormats, SamplesPassedOfRandomTrianglesAgreeExactly) {
    GL_OR_SKIP();
    const DepthFormat f = GetParam();
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    test::randomWindowTriangles(p, t);
    const OrthoView view = test::windowView(64, 64, f);
    const CommandList list = test::coverageQueries(t.size());
    std::unique_ptr<GlBackend> gl = raster::makeGlBackend();
    std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
    std::vector<uint64_t> r[2];
    DepthBackend* backends[2] = {cpu.get(), gl.get()};
    for (int b = 0; b < 2; ++b) {
        backends[b]->setGeometry(p, t);
        backends[b]->setView(view);
        r[b] = backends[b]->execute(list);
    }
    uint64_t total = 0;
    for (size_t i = 0; i < t.size(); ++i) {
        EXPECT_EQ(r[0][i], r[1][i]) << "triangle " << i;
        total += r[0][i];
    }
    EXPECT_GT(total, 10000u);  // sanity: the triangles do cover pixels
}

INSTANTIATE_TEST_SUITE_P(GlBackend, GlFormats,
                         ::testing::Values(DepthFormat::unorm(16), DepthFormat::unorm(24), DepthFormat::float32()),
                         formatName);

// Trap: a tile (OrthoView::tile, how Cullide draws a call larger than the backend's limit) whose
// shader ignores the origin or scales by the tile's size instead of the grid's: each tile would
// draw the whole view's corner, or another grid. The 300 random triangles of the test above, each
// a query, drawn in 24-pixel tiles of the 64x64 view (the last tiles 16 wide): per triangle, the
// tiles' counts add up to the reference's count over the whole view.
TEST(GlBackend, TilesAddUpToTheWholeViewsCoverage) {
    GL_OR_SKIP();
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    test::randomWindowTriangles(p, t);
    const OrthoView view = test::windowView(64, 64);
    const CommandList list = test::coverageQueries(t.size());
    std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
    cpu->setGeometry(p, t);
    cpu->setView(view);
    const std::vector<uint64_t> want = cpu->execute(list);
    auto gpu = raster::makeGlBackend();
    gpu->setGeometry(p, t);
    EXPECT_EQ(test::tiledResults(*gpu, view, list, 24), want);
}

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

// Trap: a requested depth format GL lacks silently changing the results: it must map to the
// nearest GL format with a warning, once, and readDepth must say which format it holds.
TEST(GlBackend, UnavailableDepthFormatMapsToTheNearestWithAWarning) {
    GL_OR_SKIP();
    raster::GlBackendOptions o;
    std::vector<std::string> warnings;
    o.warn = [&](const std::string& w) { warnings.push_back(w); };
    std::unique_ptr<GlBackend> gl = raster::makeGlBackend(o);
    EXPECT_EQ(gl->effectiveFormat(DepthFormat::unorm(12)), DepthFormat::unorm(16));
    EXPECT_EQ(gl->effectiveFormat(DepthFormat::unorm(16)), DepthFormat::unorm(16));
    EXPECT_EQ(gl->effectiveFormat(DepthFormat::unorm(20)), DepthFormat::unorm(24));
    EXPECT_EQ(gl->effectiveFormat(DepthFormat::float32()), DepthFormat::float32());
    gl->setView(test::windowView(8, 8, DepthFormat::unorm(20)));
    gl->setView(test::windowView(8, 8, DepthFormat::unorm(20)));
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("D20"), std::string::npos) << warnings[0];
    EXPECT_EQ(gl->readDepth().format, DepthFormat::unorm(24));
    EXPECT_EQ(gl->readDepth().values[0], (1u << 24) - 1);  // a new buffer holds the far value
    gl->setView(test::windowView(8, 8, DepthFormat::unorm(24)));
    EXPECT_EQ(warnings.size(), 1u);
}

// Trap: misuse reaching GL (out-of-range draws read past the index buffer) instead of being
// refused as the CPU backend refuses it.
TEST(GlBackend, CommandListMisuseIsRefusedBeforeExecuting) {
    GL_OR_SKIP();
    std::unique_ptr<GlBackend> gl = raster::makeGlBackend();
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    addQuad(p, t, 0, 0, 4, 4, 0.5f);
    gl->setGeometry(p, t);
    CommandList list;
    list.draw(1, 2);
    EXPECT_THROW(gl->execute(list), InputError);  // before setView
    gl->setView(test::windowView(8, 8, DepthFormat::unorm(24)));
    EXPECT_THROW(gl->execute(list), InputError);  // triangles [1, 3) of 2
    CommandList ok;
    ok.beginQuery();
    ok.draw(0, 2);
    ok.endQuery();
    EXPECT_EQ(gl->execute(ok), std::vector<uint64_t>{16});
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
    std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    addQuad(p, t, 0, 0, 4, 4, 0.5f);
    cpu->setGeometry(p, t);
    cpu->setView(test::windowView(8, 8, DepthFormat::unorm(24)));
    CommandList ok;
    ok.beginQuery();
    ok.draw(0, 2);
    ok.endQuery();
    EXPECT_EQ(cpu->execute(ok), std::vector<uint64_t>{16});
}

// A study record of a GL run names the driver in its provenance, as the backend describes itself
// (renderer, GL version, Mesa or vendor driver). Trap: a provenance that says only "gl", which
// cannot tell llvmpipe from a GPU when two studies disagree.
TEST(GlBackend, StudyRecordNamesTheDriver) {
    GL_OR_SKIP();
    const std::unique_ptr<DepthBackend> gl = raster::makeBackend("gl", 0);
    study::RunConfig c;
    c.scene = "cows:600", c.method = "modified", c.resolution = "64", c.depth = "24", c.directions = "axes";
    c.hierarchy = "connectivity", c.backend = "gl";
    const nlohmann::ordered_json r = study::runOne(c, study::loadStudyScene(c.scene, 0), nullptr, 1, *gl);
    EXPECT_EQ(r.at("provenance").at("drivers"), nlohmann::ordered_json::array({gl->describe()}));
    EXPECT_NE(gl->describe().find("gl"), std::string::npos) << gl->describe();
}

}  // namespace
}  // namespace cullide
