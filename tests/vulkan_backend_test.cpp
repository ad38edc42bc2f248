// Tests of the Vulkan backend (raster/vulkan/): the same commands give the same results as the CPU
// reference where the reference's rules leave no freedom (pixel-aligned, depth-separated boxes;
// coverage counts of single triangles; edges through pixel centres), at D16, D24 and D32F, with the
// Khronos validation layer on and no message from it; the no-device path; the command line.
//
// The Vulkan tests skip, with the reason printed, only when no Vulkan device can be made here. Set
// CULLIDE_REQUIRE_VULKAN=1 (CI, where tools/setup.sh installs lavapipe and the validation layers;
// tools/test.sh sets it) to make that a failure instead.
#include "cullide/depth_backend.h"
#include "cullide/error.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/vulkan_backend.h"
#include "cullide/study/study.h"
#include "window_geometry.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

namespace cullide {
namespace {

using test::addQuad;

using raster::VulkanBackend;

// One device check per process (with validation, as the tests use it); every test then makes its
// own backend.
const std::string& vulkanUnavailableReason() {
    static const std::string why = [] {
        std::string w;
        raster::VulkanBackendOptions o;
        o.validation = true;
        return raster::vulkanBackendAvailable(&w, o) ? std::string() : w;
    }();
    return why;
}

#define VULKAN_OR_SKIP()                                                                                     \
    do {                                                                                                     \
        if (!vulkanUnavailableReason().empty()) {                                                            \
            if (std::getenv("CULLIDE_REQUIRE_VULKAN")) FAIL() << "no Vulkan: " << vulkanUnavailableReason(); \
            GTEST_SKIP() << "no Vulkan device: " << vulkanUnavailableReason();                               \
        }                                                                                                    \
    } while (0)

// A backend with the validation layer on; validation messages are collected, not printed.
std::unique_ptr<VulkanBackend> makeValidated(std::vector<std::string>* warnings = nullptr) {
    raster::VulkanBackendOptions o;
    o.validation = true;
    o.warn = [warnings](const std::string& w) {
        if (warnings && w.rfind("vulkan validation", 0) != 0) warnings->push_back(w);
    };
    return raster::makeVulkanBackend(o);
}

std::string validationText(const VulkanBackend& vk) {
    std::string s;
    for (const std::string& m : vk.validationLog()) s += m + "\n";
    return s;
}

#define EXPECT_NO_VALIDATION_MESSAGES(vk) EXPECT_EQ((vk).validationMessages(), 0u) << validationText(vk)

class VulkanFormats : public ::testing::TestWithParam<DepthFormat> {};

std::string formatName(const ::testing::TestParamInfo<DepthFormat>& info) {
    return info.param.name();
}

// Trap: anything in the Vulkan path that is not one-to-one with the reference where the rules leave
// no freedom: the window transform (Vulkan's y-down framebuffer, half-pixel offsets), depth
// conversion of binary-fraction depths, each of the eight depth functions as a dynamic compare op,
// the write mask as dynamic state (also for clears: vkCmdClearAttachments must clear with the mask
// off, as the reference does), any-samples queries (without the precise bit: any non-zero is 1),
// state (function, mask, contents) persisting across execute() and setView(), readDepth (X8_D24's
// undefined top byte, D16's 2-byte texels, row order).
TEST_P(VulkanFormats, PixelAlignedDepthSeparatedBoxesAgreeExactly) {
    VULKAN_OR_SKIP();
    const DepthFormat f = GetParam();
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    addQuad(p, t, 4, 4, 40, 30, 0.5f);  // tris 0-1: the occluder
    addQuad(p, t, 10, 2, 60, 20, 0.25f);  // tris 2-3: in front, partly overlapping
    addQuad(p, t, 20, 10, 50, 45, 0.75f);  // tris 4-5: behind
    addQuad(p, t, 0, 0, 64, 48, 0.5f);  // tris 6-7: the whole viewport at the occluder's depth
    addQuad(p, t, 0, 40, 16, 48, 0.125f);  // tris 8-9: top-left corner (a y flip would show)
    const OrthoView view = test::windowView(64, 48, f);

    std::unique_ptr<VulkanBackend> vk = makeValidated();
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
    DepthBackend* backends[2] = {cpu.get(), vk.get()};
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
    EXPECT_NO_VALIDATION_MESSAGES(*vk);
}

// Trap: coverage differing from the reference's (8 subpixel bits, round to nearest, bottom-left
// fill rule, zero-area triangles dropped) on general triangles, including the window transform's
// rounding (double in the shader, then float) and clipping at the guard band (x, y in [-4, 68]).
// Each triangle is its own precise query over a cleared buffer, so the count is its coverage; 300
// queries in one list also grow the query pool. Fixed seed.
TEST_P(VulkanFormats, SamplesPassedOfRandomTrianglesAgreeExactly) {
    VULKAN_OR_SKIP();
    const DepthFormat f = GetParam();
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    test::randomWindowTriangles(p, t);
    const OrthoView view = test::windowView(64, 64, f);
    const CommandList list = test::coverageQueries(t.size());
    std::unique_ptr<VulkanBackend> vk = makeValidated();
    std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
    std::vector<uint64_t> r[2];
    DepthBackend* backends[2] = {cpu.get(), vk.get()};
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
    EXPECT_NO_VALIDATION_MESSAGES(*vk);
}

// Trap: the simplest exact cases. A half-screen triangle at 64x64 whose hypotenuse runs through 64
// pixel centres covers 2016 pixels (the hypotenuse is a top-right edge: excluded); drawn again at
// equal depth under LESS it passes nowhere; a full-screen quad behind it passes on the other 2080;
// in front, on all 4096. Also the tie direction on horizontal and vertical edges through pixel
// centres (bottom and left included, as in llvmpipe's GL FBOs and the reference): a viewport flipped
// with a negative height turns Vulkan's top-left rule into GL's top-left. Tried on lavapipe: the
// triangle on a horizontal bottom edge then covers 123 pixels instead of 143, and the rectangle
// keeps its count (100) but moves from rows 20..24 to rows 21..25.
TEST_P(VulkanFormats, HalfScreenTriangleAndEdgesThroughPixelCentres) {
    VULKAN_OR_SKIP();
    const DepthFormat f = GetParam();
    std::vector<Vec3f> p{{0, 0, 0.5f}, {64, 0, 0.5f}, {0, 64, 0.5f}};
    std::vector<Triangle> t{{0, 1, 2}};
    addQuad(p, t, 0, 0, 64, 64, 0.75f);  // tris 1-2
    addQuad(p, t, 0, 0, 64, 64, 0.25f);  // tris 3-4
    addQuad(p, t, 10.5f, 20.5f, 30.5f, 25.5f, 0.5f);  // tris 5-6: all four edges through centres
    p.push_back({20.25f, 33.75f, 0.5f});  // tri 7: on the rectangle's bottom edge, apex off-centre
    t.push_back({11, 12, 15});  // (10.5, 20.5), (30.5, 20.5), the apex
    const OrthoView view = test::windowView(64, 64, f);
    CommandList list;
    list.beginQuery();
    list.draw(0, 1);
    list.endQuery();
    list.beginQuery();
    list.draw(0, 1);
    list.endQuery();
    list.beginQuery();
    list.draw(1, 2);
    list.endQuery();
    list.clear();
    list.draw(0, 1);
    list.beginQuery();
    list.draw(3, 2);
    list.endQuery();
    list.clear();
    list.beginQuery();
    list.draw(5, 2);
    list.endQuery();
    list.clear();
    list.beginQuery();
    list.draw(7, 1);
    list.endQuery();
    std::unique_ptr<VulkanBackend> vk = makeValidated();
    vk->setGeometry(p, t);
    vk->setView(view);
    const std::vector<uint64_t> r = vk->execute(list);
    EXPECT_EQ(r, (std::vector<uint64_t>{2016, 0, 2080, 4096, 20 * 5, 143}));
    std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
    cpu->setGeometry(p, t);
    cpu->setView(view);
    EXPECT_EQ(cpu->execute(list), r);
    // Which 100 pixels: rows 20..24 (the bottom edge's row 20 in, the top edge's row 25 out).
    CommandList one;
    one.clear();
    one.draw(5, 2);
    vk->execute(one);
    const DepthImage img = vk->readDepth();
    EXPECT_NE(img.at(10, 20), img.at(0, 0));
    EXPECT_EQ(img.at(10, 25), img.at(0, 0));
    EXPECT_EQ(img.at(30, 20), img.at(0, 0));
    EXPECT_NO_VALIDATION_MESSAGES(*vk);
}

INSTANTIATE_TEST_SUITE_P(VulkanBackend, VulkanFormats,
                         ::testing::Values(DepthFormat::unorm(16), DepthFormat::unorm(24), DepthFormat::float32()),
                         formatName);

// Trap: a tile (OrthoView::tile, how Cullide draws a call larger than the backend's limit) whose
// shader ignores the origin or scales by the tile's size instead of the grid's: each tile would
// draw the whole view's corner, or another grid. The 300 random triangles of the test above, each
// a query, drawn in 24-pixel tiles of the 64x64 view (the last tiles 16 wide): per triangle, the
// tiles' counts add up to the reference's count over the whole view.
TEST(VulkanBackend, TilesAddUpToTheWholeViewsCoverage) {
    VULKAN_OR_SKIP();
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    test::randomWindowTriangles(p, t);
    const OrthoView view = test::windowView(64, 64);
    const CommandList list = test::coverageQueries(t.size());
    std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
    cpu->setGeometry(p, t);
    cpu->setView(view);
    const std::vector<uint64_t> want = cpu->execute(list);
    auto gpu = makeValidated();
    gpu->setGeometry(p, t);
    EXPECT_EQ(test::tiledResults(*gpu, view, list, 24), want);
    EXPECT_NO_VALIDATION_MESSAGES(*gpu);
}

// Trap: a backend that reports nothing useful about what it got (device, driver, format actually
// used), or a format other than the one asked for without saying so.
TEST(VulkanBackend, DescribeNamesDeviceDriverAndFormat) {
    VULKAN_OR_SKIP();
    std::unique_ptr<VulkanBackend> vk = makeValidated();
    EXPECT_FALSE(vk->info().device.empty());
    EXPECT_FALSE(vk->info().driver.empty());
    EXPECT_GE(vk->info().subpixelBits, 4);
    EXPECT_EQ(vk->subpixelBits(), vk->info().subpixelBits);
    EXPECT_EQ(vk->apiName(), "vulkan");
    vk->setView(test::windowView(8, 8, DepthFormat::unorm(24)));
    const std::string d = vk->describe();
    EXPECT_NE(d.find(vk->info().device), std::string::npos) << d;
    EXPECT_NE(d.find(vk->info().driver), std::string::npos) << d;
    EXPECT_NE(d.find("subpixel bits"), std::string::npos) << d;
    EXPECT_NE(d.find("X8_D24_UNORM_PACK32"), std::string::npos) << d;
    std::printf("  [vulkan] %s\n", d.c_str());
    EXPECT_NO_VALIDATION_MESSAGES(*vk);
}

// Trap: a requested depth format Vulkan lacks (any unorm other than 16 and 24; Vulkan has no
// 32-bit unorm depth) silently changing the results: it must map to the nearest format with a
// warning, once per requested format, and readDepth must say which format it holds.
TEST(VulkanBackend, UnavailableDepthFormatMapsToTheNearestWithAWarning) {
    VULKAN_OR_SKIP();
    std::vector<std::string> warnings;
    std::unique_ptr<VulkanBackend> vk = makeValidated(&warnings);
    EXPECT_EQ(vk->effectiveFormat(DepthFormat::unorm(12)), DepthFormat::unorm(16));
    EXPECT_EQ(vk->effectiveFormat(DepthFormat::unorm(16)), DepthFormat::unorm(16));
    EXPECT_EQ(vk->effectiveFormat(DepthFormat::unorm(20)), DepthFormat::unorm(24));
    EXPECT_EQ(vk->effectiveFormat(DepthFormat::unorm(32)), DepthFormat::unorm(24));
    EXPECT_EQ(vk->effectiveFormat(DepthFormat::float32()), DepthFormat::float32());
    vk->setView(test::windowView(8, 8, DepthFormat::unorm(20)));
    vk->setView(test::windowView(8, 8, DepthFormat::unorm(20)));
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("D20"), std::string::npos) << warnings[0];
    EXPECT_EQ(vk->readDepth().format, DepthFormat::unorm(24));
    EXPECT_EQ(vk->readDepth().values[0], (1u << 24) - 1);  // a new buffer holds the far value
    vk->setView(test::windowView(8, 8, DepthFormat::unorm(24)));
    EXPECT_EQ(warnings.size(), 1u);
    vk->setView(test::windowView(8, 8, DepthFormat::float32()));
    EXPECT_EQ(vk->readDepth().values[0], 0x3F800000u);  // 1.0f after a format change
    EXPECT_NO_VALIDATION_MESSAGES(*vk);
}

// Trap: misuse reaching Vulkan (out-of-range draws read past the index buffer; conservative
// commands it cannot do) instead of being refused as the CPU backend refuses it; the query pool
// growing and shrinking between lists.
TEST(VulkanBackend, CommandListMisuseIsRefusedBeforeExecuting) {
    VULKAN_OR_SKIP();
    std::unique_ptr<VulkanBackend> vk = makeValidated();
    EXPECT_FALSE(vk->supportsConservative());
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    addQuad(p, t, 0, 0, 4, 4, 0.5f);
    vk->setGeometry(p, t);
    CommandList list;
    list.draw(1, 2);
    EXPECT_THROW(vk->execute(list), InputError);  // before setView
    EXPECT_THROW(vk->readDepth(), InputError);
    vk->setView(test::windowView(8, 8, DepthFormat::unorm(24)));
    EXPECT_THROW(vk->execute(list), InputError);  // triangles [1, 3) of 2
    CommandList conservative;
    conservative.clearIntervals();
    conservative.drawConservative(0, 2, true, true);
    EXPECT_THROW(vk->execute(conservative), InputError);
    CommandList ok;
    ok.depthFunc(DepthFunc::Always);
    ok.beginQuery();
    ok.draw(0, 2);
    ok.endQuery();
    EXPECT_EQ(vk->execute(ok), std::vector<uint64_t>{16});
    CommandList many;
    for (int k = 0; k < 100; ++k) {
        many.beginQuery(k % 2 ? QueryKind::AnySamplesPassed : QueryKind::SamplesPassed);
        many.draw(0, 2);
        many.endQuery();
    }
    const std::vector<uint64_t> r = vk->execute(many);
    ASSERT_EQ(r.size(), 100u);
    for (int k = 0; k < 100; ++k) EXPECT_EQ(r[k], k % 2 ? 1u : 16u) << k;
    EXPECT_EQ(vk->execute(ok), std::vector<uint64_t>{16});
    EXPECT_EQ(vk->execute(CommandList()), std::vector<uint64_t>{});
    EXPECT_NO_VALIDATION_MESSAGES(*vk);
}

// Trap: a machine without a usable Vulkan device crashing or failing silently; the error must say
// why (per device), be an InputError (the CLI exits 2), and the CPU path must be unaffected. A
// device-name filter no device matches stands in for "no device". Runs without Vulkan too.
TEST(VulkanBackend, NoDeviceGivesAClearErrorAndTheCpuPathStillWorks) {
    raster::VulkanBackendOptions o;
    o.deviceName = "cullide-test-no-such-device";
    try {
        raster::makeVulkanBackend(o);
        FAIL() << "expected BackendUnavailable";
    } catch (const raster::BackendUnavailable& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("vulkan backend"), std::string::npos) << m;
        if (raster::vulkanBuilt()) EXPECT_NE(m.find("device"), std::string::npos) << m;
        else EXPECT_NE(m.find(raster::kVulkanNotBuilt), std::string::npos) << m;
    }
    std::string why;
    EXPECT_FALSE(raster::vulkanBackendAvailable(&why, o));
    EXPECT_FALSE(why.empty());
    EXPECT_THROW(raster::makeVulkanBackend(o), InputError);
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

// A study record of a Vulkan run names the device and driver in its provenance. Trap: a provenance
// that says only "vulkan", which cannot tell lavapipe from a GPU.
TEST(VulkanBackend, StudyRecordNamesTheDriver) {
    VULKAN_OR_SKIP();
    const std::unique_ptr<DepthBackend> vk = raster::makeBackend("vulkan", 0);
    study::RunConfig c;
    c.scene = "cows:600", c.method = "modified", c.resolution = "64", c.depth = "24", c.directions = "axes";
    c.hierarchy = "connectivity", c.backend = "vulkan";
    const nlohmann::ordered_json r = study::runOne(c, study::loadStudyScene(c.scene, 0), nullptr, 1, *vk);
    EXPECT_EQ(r.at("provenance").at("drivers"), nlohmann::ordered_json::array({vk->describe()}));
    EXPECT_NE(vk->describe().find("vulkan"), std::string::npos) << vk->describe();
}

// Runs `cullide ARGS` with the validation layer on: the exit status and stdout and stderr together.
std::pair<int, std::string> cli(const std::string& args) {
    FILE* p =
        popen((std::string("CULLIDE_VULKAN_VALIDATION=1 '") + CULLIDE_CLI_PATH + "' " + args + " 2>&1").c_str(), "r");
    if (!p) return {-1, "popen failed"};
    std::string out;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) out.append(buf.data(), n);
    const int status = pclose(p);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), out};
}

// Trap: `validate --backend vulkan` and `trace replay --backend vulkan` not reaching the Vulkan
// backend, or it disagreeing with the reference's intervals on a real Cullide workload (bundled
// scene, frame 0, 128x128): exit 0, every query in its interval, the PCS identical, no validation
// message (printed as a "vulkan validation" warning).
TEST(VulkanBackend, CliValidateAndTraceReplayAreInsideEveryInterval) {
    VULKAN_OR_SKIP();
    const std::string scene = std::string("'") + CULLIDE_DATA_DIR + "/scenes/bunny_through_cow.json'";
    test::TempDir dir;
    auto [status, out] = cli("validate " + scene + " --backend vulkan --frame 0 --resolution 128 --json '" +
                             (dir / "v.json").string() + "'");
    EXPECT_EQ(status, 0) << out;
    EXPECT_NE(out.find("replayed on Vulkan"), std::string::npos) << out;
    EXPECT_NE(out.find("outside 0"), std::string::npos) << out;
    EXPECT_NE(out.find("identical"), std::string::npos) << out;
    EXPECT_EQ(out.find("vulkan validation"), std::string::npos) << out;
    std::ifstream in(dir / "v.json");
    std::stringstream text;
    text << in.rdbuf();
    const nlohmann::json v = nlohmann::json::parse(text.str());
    EXPECT_EQ(v["in_interval_rate"], 1.0);
    EXPECT_EQ(v["frames_with_different_pcs"], 0);
    EXPECT_NE(v["backend"].get<std::string>().find("vulkan"), std::string::npos);

    std::tie(status, out) =
        cli("trace record " + scene + " --resolution 128 --frame 0 -o '" + (dir / "t.trace").string() + "'");
    ASSERT_EQ(status, 0) << out;
    std::tie(status, out) = cli("trace replay '" + (dir / "t.trace").string() + "' --backend vulkan -o '" +
                                (dir / "vk.json").string() + "'");
    ASSERT_EQ(status, 0) << out;
    EXPECT_EQ(out.find("vulkan validation"), std::string::npos) << out;
    std::tie(status, out) =
        cli("trace compare '" + (dir / "t.trace").string() + "' '" + (dir / "vk.json").string() + "'");
    EXPECT_EQ(status, 0) << out;
    EXPECT_NE(out.find("every query lies in its interval"), std::string::npos) << out;
}

}  // namespace
}  // namespace cullide
