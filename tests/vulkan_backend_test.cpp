// Tests of what only the Vulkan backend (raster/vulkan/) has: edges through pixel centres (its
// viewport's tie rule), what it reports about its device, Vulkan's depth formats, the no-device
// path, and the command line on Vulkan, with the Khronos validation layer on and no message from
// it. What every GPU backend must do alike (agreement with the CPU reference, depth formats, misuse,
// provenance) is in gpu_backend_test.cpp, run on Vulkan too.
//
// The Vulkan tests skip, with the reason printed, only when no Vulkan device can be made here. Set
// CULLIDE_REQUIRE_VULKAN=1 (CI, where tools/setup.sh installs lavapipe and the validation layers;
// tools/test.sh sets it) to make that a failure instead.
#include "cullide/depth_backend.h"
#include "cullide/error.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/vulkan_backend.h"
#include "gpu_test_util.h"
#include "window_geometry.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace cullide {
namespace {

using test::addQuad;

using raster::VulkanBackend;

class VulkanFormats : public ::testing::TestWithParam<DepthFormat> {};

std::string formatName(const ::testing::TestParamInfo<DepthFormat>& info) {
    return info.param.name();
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
    std::unique_ptr<VulkanBackend> vk = test::makeValidated();
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

// Trap: a backend that reports nothing useful about what it got (device, driver, format actually
// used), or a format other than the one asked for without saying so.
TEST(VulkanBackend, DescribeNamesDeviceDriverAndFormat) {
    VULKAN_OR_SKIP();
    std::unique_ptr<VulkanBackend> vk = test::makeValidated();
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

// Trap: Vulkan has no 32-bit unorm depth: a request for one must map to the nearest format it has,
// D24 (gpu_backend_test.cpp tests the mapping and its warning on every backend).
TEST(VulkanBackend, Unorm32DepthMapsToD24) {
    VULKAN_OR_SKIP();
    std::unique_ptr<VulkanBackend> vk = test::makeValidated();
    EXPECT_EQ(vk->effectiveFormat(DepthFormat::unorm(32)), DepthFormat::unorm(24));
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
    test::expectCpuPathWorks();
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
