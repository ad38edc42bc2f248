// Tests every GPU backend must pass alike (raster/gl/, raster/vulkan/), each run once per backend
// this build has (test names end in Gl or Vulkan): the same commands give the same results as the
// CPU reference where the reference's rules leave the GPU no freedom (pixel-aligned,
// depth-separated boxes; coverage counts of single triangles; tiles), at D16, D24 and D32F; depth
// formats the device lacks; misuse refused; the study record's provenance. Vulkan runs with the
// Khronos validation layer on and no message from it.
//
// What only one backend has is tested in gl_backend_test.cpp and vulkan_backend_test.cpp; the
// skip rules (CULLIDE_REQUIRE_GL, CULLIDE_REQUIRE_VULKAN) are in gpu_test_util.h.
#include "cullide/depth_backend.h"
#include "cullide/error.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/study/study.h"
#include "gpu_test_util.h"
#include "window_geometry.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <tuple>

namespace cullide {
namespace {

using test::addQuad;

class GpuFormats : public ::testing::TestWithParam<std::tuple<std::string, DepthFormat>> {
protected:
    const std::string& kind() const { return std::get<0>(GetParam()); }
    const DepthFormat& format() const { return std::get<1>(GetParam()); }
};

std::string kindAndFormatName(const ::testing::TestParamInfo<GpuFormats::ParamType>& info) {
    return test::gpuTestLabel(std::get<0>(info.param)) + "_" + std::get<1>(info.param).name();
}

// Trap: anything in the GPU path that is not one-to-one with the reference where the rules leave
// no freedom: the window transform (a y flip, e.g. Vulkan's y-down framebuffer; half-pixel
// offsets), depth conversion of binary-fraction depths, each of the eight depth functions (GL's
// glDepthFunc, Vulkan's dynamic compare op), the depth mask (also for clears: glClear honours
// glDepthMask and vkCmdClearAttachments must clear with the mask off, as the reference does),
// any-samples queries (Vulkan's without the precise bit: any non-zero is 1), state (function,
// mask, contents) persisting across execute() and setView(), readDepth (GL returns k scaled to 32
// bits; X8_D24's undefined top byte, D16's 2-byte texels, row order).
TEST_P(GpuFormats, PixelAlignedDepthSeparatedBoxesAgreeExactly) {
    GPU_OR_SKIP(kind());
    const DepthFormat f = format();
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    addQuad(p, t, 4, 4, 40, 30, 0.5f);  // tris 0-1: the occluder
    addQuad(p, t, 10, 2, 60, 20, 0.25f);  // tris 2-3: in front, partly overlapping
    addQuad(p, t, 20, 10, 50, 45, 0.75f);  // tris 4-5: behind
    addQuad(p, t, 0, 0, 64, 48, 0.5f);  // tris 6-7: the whole viewport at the occluder's depth
    addQuad(p, t, 0, 40, 16, 48, 0.125f);  // tris 8-9: top-left corner (a y flip would show)
    const OrthoView view = test::windowView(64, 48, f);

    std::unique_ptr<raster::GpuBackend> gpu = test::makeGpuUnderTest(kind());
    std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
    CommandList list;
    list.clear(1.0);
    list.depthFunc(DepthFunc::Less);
    list.beginQuery();
    list.draw(0, 2);
    list.endQuery();
    list.draw(8, 2);
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
    list.beginQuery(QueryKind::AnySamplesPassed);
    list.draw(6, 2);  // equal depth under ALWAYS: passes, result 1 (not the count)
    list.endQuery();
    list.clear(1.0);  // with the mask off: must still clear
    list.depthMask(true);
    list.depthFunc(DepthFunc::LEqual);
    list.draw(0, 4);
    list.draw(8, 2);
    CommandList second;  // state (LEQUAL, mask on, the contents) carries over
    second.beginQuery();
    second.draw(6, 2);
    second.endQuery();
    second.clear(0.5);  // a clear value other than 1
    second.depthFunc(DepthFunc::Less);
    second.beginQuery();
    second.draw(2, 6);
    second.endQuery();

    std::vector<uint64_t> results[2], seconds[2], thirds[2];
    DepthImage images[2], afterView[2];
    DepthBackend* backends[2] = {cpu.get(), gpu.get()};
    for (int b = 0; b < 2; ++b) {
        backends[b]->setGeometry(p, t);
        backends[b]->setView(view);
        results[b] = backends[b]->execute(list);
        seconds[b] = backends[b]->execute(second);
        images[b] = backends[b]->readDepth();
        backends[b]->setView(view);  // the same size and format: contents kept
        thirds[b] = backends[b]->execute(second);
        afterView[b] = backends[b]->readDepth();
    }
    EXPECT_EQ(results[0], results[1]);
    EXPECT_EQ(seconds[0], seconds[1]);
    EXPECT_EQ(thirds[0], thirds[1]);
    EXPECT_EQ(results[0][0], uint64_t(36 * 26));  // sanity: the occluder's pixel count
    EXPECT_EQ(results[1][results[1].size() - 1], 1u);  // any-samples is 0 or 1
    ASSERT_EQ(images[1].format, f);
    EXPECT_EQ(images[0].values, images[1].values);
    EXPECT_EQ(afterView[0].values, afterView[1].values);
    EXPECT_NO_VALIDATION_MESSAGES(*gpu);
}

// Trap: coverage differing from the reference's (8 subpixel bits, round to nearest, bottom-left
// fill rule, zero-area triangles dropped) on general triangles, including the window transform's
// rounding (double in the shader, then float) and clipping at the guard band (x, y in [-4, 68]).
// Each triangle is its own SAMPLES_PASSED (Vulkan: precise) query over a cleared buffer, so the
// count is its coverage; 300 queries in one list also grow the query pools. Fixed seed.
TEST_P(GpuFormats, SamplesPassedOfRandomTrianglesAgreeExactly) {
    GPU_OR_SKIP(kind());
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    test::randomWindowTriangles(p, t);
    const OrthoView view = test::windowView(64, 64, format());
    const CommandList list = test::coverageQueries(t.size());
    std::unique_ptr<raster::GpuBackend> gpu = test::makeGpuUnderTest(kind());
    std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
    std::vector<uint64_t> r[2];
    DepthBackend* backends[2] = {cpu.get(), gpu.get()};
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
    EXPECT_NO_VALIDATION_MESSAGES(*gpu);
}

INSTANTIATE_TEST_SUITE_P(GpuBackend, GpuFormats,
                         ::testing::Combine(::testing::ValuesIn(test::builtGpuBackends()),
                                            ::testing::Values(DepthFormat::unorm(16), DepthFormat::unorm(24),
                                                              DepthFormat::float32())),
                         kindAndFormatName);

class GpuKinds : public ::testing::TestWithParam<std::string> {
protected:
    const std::string& kind() const { return GetParam(); }
};

std::string kindName(const ::testing::TestParamInfo<std::string>& info) {
    return test::gpuTestLabel(info.param);
}

// Trap: a tile (OrthoView::tile, how Cullide draws a call larger than the backend's limit) whose
// shader ignores the origin or scales by the tile's size instead of the grid's: each tile would
// draw the whole view's corner, or another grid. The 300 random triangles of the test above, each
// a query, drawn in 24-pixel tiles of the 64x64 view (the last tiles 16 wide): per triangle, the
// tiles' counts add up to the reference's count over the whole view.
TEST_P(GpuKinds, TilesAddUpToTheWholeViewsCoverage) {
    GPU_OR_SKIP(kind());
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    test::randomWindowTriangles(p, t);
    const OrthoView view = test::windowView(64, 64);
    const CommandList list = test::coverageQueries(t.size());
    std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
    cpu->setGeometry(p, t);
    cpu->setView(view);
    const std::vector<uint64_t> want = cpu->execute(list);
    auto gpu = test::makeGpuUnderTest(kind());
    gpu->setGeometry(p, t);
    EXPECT_EQ(test::tiledResults(*gpu, view, list, 24), want);
    EXPECT_NO_VALIDATION_MESSAGES(*gpu);
}

// Trap: a requested depth format the device lacks silently changing the results: it must map to
// the nearest format the device has with a warning, once per requested format, and readDepth must
// say which format it holds; a new buffer (also after a format change) holds the far value.
TEST_P(GpuKinds, UnavailableDepthFormatMapsToTheNearestWithAWarning) {
    GPU_OR_SKIP(kind());
    std::vector<std::string> warnings;
    std::unique_ptr<raster::GpuBackend> gpu = test::makeGpuUnderTest(kind(), &warnings);
    EXPECT_EQ(gpu->effectiveFormat(DepthFormat::unorm(12)), DepthFormat::unorm(16));
    EXPECT_EQ(gpu->effectiveFormat(DepthFormat::unorm(16)), DepthFormat::unorm(16));
    EXPECT_EQ(gpu->effectiveFormat(DepthFormat::unorm(20)), DepthFormat::unorm(24));
    EXPECT_EQ(gpu->effectiveFormat(DepthFormat::float32()), DepthFormat::float32());
    gpu->setView(test::windowView(8, 8, DepthFormat::unorm(20)));
    gpu->setView(test::windowView(8, 8, DepthFormat::unorm(20)));
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("D20"), std::string::npos) << warnings[0];
    EXPECT_EQ(gpu->readDepth().format, DepthFormat::unorm(24));
    EXPECT_EQ(gpu->readDepth().values[0], (1u << 24) - 1);  // a new buffer holds the far value
    gpu->setView(test::windowView(8, 8, DepthFormat::unorm(24)));
    EXPECT_EQ(warnings.size(), 1u);
    gpu->setView(test::windowView(8, 8, DepthFormat::float32()));
    EXPECT_EQ(gpu->readDepth().values[0], 0x3F800000u);  // 1.0f after a format change
    EXPECT_NO_VALIDATION_MESSAGES(*gpu);
}

// Trap: misuse reaching the device (out-of-range draws read past the index buffer; conservative
// commands it cannot do; a list or a read before any view) instead of being refused as the CPU
// backend refuses it; the default depth function on a new buffer; the query pools growing and
// shrinking between lists.
TEST_P(GpuKinds, CommandListMisuseIsRefusedBeforeExecuting) {
    GPU_OR_SKIP(kind());
    std::unique_ptr<raster::GpuBackend> gpu = test::makeGpuUnderTest(kind());
    EXPECT_FALSE(gpu->supportsConservative());
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    addQuad(p, t, 0, 0, 4, 4, 0.5f);
    gpu->setGeometry(p, t);
    CommandList list;
    list.draw(1, 2);
    EXPECT_THROW(gpu->execute(list), InputError);  // before setView
    EXPECT_THROW(gpu->readDepth(), InputError);
    gpu->setView(test::windowView(8, 8, DepthFormat::unorm(24)));
    EXPECT_THROW(gpu->execute(list), InputError);  // triangles [1, 3) of 2
    CommandList conservative;
    conservative.clearIntervals();
    conservative.drawConservative(0, 2, true, true);
    EXPECT_THROW(gpu->execute(conservative), InputError);
    CommandList lessOnNew;  // the default function (LESS) against the far value
    lessOnNew.beginQuery();
    lessOnNew.draw(0, 2);
    lessOnNew.endQuery();
    EXPECT_EQ(gpu->execute(lessOnNew), std::vector<uint64_t>{16});
    CommandList ok;
    ok.depthFunc(DepthFunc::Always);
    ok.beginQuery();
    ok.draw(0, 2);
    ok.endQuery();
    EXPECT_EQ(gpu->execute(ok), std::vector<uint64_t>{16});
    CommandList many;
    for (int k = 0; k < 100; ++k) {
        many.beginQuery(k % 2 ? QueryKind::AnySamplesPassed : QueryKind::SamplesPassed);
        many.draw(0, 2);
        many.endQuery();
    }
    const std::vector<uint64_t> r = gpu->execute(many);
    ASSERT_EQ(r.size(), 100u);
    for (int k = 0; k < 100; ++k) EXPECT_EQ(r[k], k % 2 ? 1u : 16u) << k;
    EXPECT_EQ(gpu->execute(ok), std::vector<uint64_t>{16});
    EXPECT_EQ(gpu->execute(CommandList()), std::vector<uint64_t>{});
    EXPECT_NO_VALIDATION_MESSAGES(*gpu);
}

// A study record of a GPU run names the driver in its provenance, as the backend describes itself
// (GL: renderer, version, Mesa or vendor driver; Vulkan: device and driver). Trap: a provenance
// that says only "gl" or "vulkan", which cannot tell llvmpipe or lavapipe from a GPU when two
// studies disagree.
TEST_P(GpuKinds, StudyRecordNamesTheDriver) {
    GPU_OR_SKIP(kind());
    const std::unique_ptr<DepthBackend> gpu = raster::makeBackend(kind(), 0);
    study::RunConfig c;
    c.scene = "cows:600", c.method = "modified", c.resolution = "64", c.depth = "24", c.directions = "axes";
    c.hierarchy = "connectivity", c.backend = kind();
    const nlohmann::ordered_json r = study::runOne(c, study::loadStudyScene(c.scene, 0), nullptr, 1, *gpu);
    EXPECT_EQ(r.at("provenance").at("drivers"), nlohmann::ordered_json::array({gpu->describe()}));
    EXPECT_NE(gpu->describe().find(kind()), std::string::npos) << gpu->describe();
}

INSTANTIATE_TEST_SUITE_P(GpuBackend, GpuKinds, ::testing::ValuesIn(test::builtGpuBackends()), kindName);

}  // namespace
}  // namespace cullide
