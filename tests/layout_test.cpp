// The source tree as docs/layout.md describes it: files of one job (at most 700 lines), and
// includes that point one way (core includes nothing above it; no private header of the
// rasterizer includes its public backend header; the rasterizer never includes its harness).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

const fs::path kRoot = CULLIDE_SOURCE_DIR;

// Every C++ and Python source under the given top-level folders.
std::vector<fs::path> sources(std::initializer_list<const char*> folders) {
    std::vector<fs::path> out;
    for (const char* folder : folders) {
        if (!fs::exists(kRoot / folder)) continue;
        for (const auto& e : fs::recursive_directory_iterator(kRoot / folder)) {
            const std::string ext = e.path().extension().string();
            if (e.is_regular_file() && (ext == ".cpp" || ext == ".h" || ext == ".py")) out.push_back(e.path());
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<std::string> linesOf(const fs::path& p) {
    std::ifstream f(p);
    std::vector<std::string> lines;
    for (std::string line; std::getline(f, line);) lines.push_back(line);
    return lines;
}

// The #include lines of a file that name one of `prefixes` ("cullide/raster/", ...).
std::vector<std::string> includesOf(const fs::path& p, std::initializer_list<const char*> prefixes) {
    std::vector<std::string> hits;
    for (const std::string& line : linesOf(p)) {
        if (line.rfind("#include", 0) != 0) continue;
        for (const char* prefix : prefixes)
            if (line.find(prefix) != std::string::npos) hits.push_back(line);
    }
    return hits;
}

std::string shortName(const fs::path& p) {
    return fs::relative(p, kRoot).string();
}

// Trap: a file that grows past one job. The limit is the one docs/layout.md states; a file over
// it is named with its length.
TEST(Layout, NoSourceFileOver700Lines) {
    const auto all = sources({"core", "raster", "oracle", "peers", "tools", "python", "tests", "bench"});
    ASSERT_GT(all.size(), 100u) << "the source tree was not found at " << kRoot;
    for (const fs::path& p : all) EXPECT_LE(linesOf(p).size(), 700u) << shortName(p);
}

// Trap: an arrow that runs back up. core must not include raster, oracle, peers, the pipeline or
// the study; the rasterizer must not include its verification harness or the oracle; raster,
// oracle and peers stand on core only, never on each other.
TEST(Layout, IncludesPointOneWay) {
    for (const fs::path& p : sources({"core"}))
        EXPECT_TRUE(
            includesOf(p,
                       {"cullide/raster/", "cullide/oracle/", "cullide/peers/", "cullide/pipeline/", "cullide/study/"})
                .empty())
            << shortName(p);
    for (const fs::path& p : sources({"raster/src", "raster/include", "raster/gpu", "raster/gl", "raster/vulkan"}))
        EXPECT_TRUE(
            includesOf(p, {"cullide/raster/trace.h", "cullide/raster/validate.h", "cullide/oracle/", "cullide/peers/"})
                .empty())
            << shortName(p);
    for (const fs::path& p : sources({"oracle"}))
        EXPECT_TRUE(
            includesOf(p, {"cullide/raster/", "cullide/cullide.h", "cullide/peers/", "cullide/pipeline/"}).empty())
            << shortName(p);
    for (const fs::path& p : sources({"peers"}))
        EXPECT_TRUE(
            includesOf(
                p, {"cullide/raster/", "cullide/cullide.h", "cullide/oracle/", "cullide/pipeline/", "cullide/study/"})
                .empty())
            << shortName(p);
}

// Trap: a private header of the CPU rasterizer that needs the public backend header (for its
// options or statistics) and so runs an arrow back up; cpu_options.h is what they include.
TEST(Layout, PrivateRasterHeadersDoNotIncludeTheBackend) {
    for (const fs::path& p : sources({"raster/src"})) {
        if (p.extension() != ".h") continue;
        EXPECT_TRUE(includesOf(p, {"cullide/raster/cpu_backend.h"}).empty()) << shortName(p);
    }
}

}  // namespace
