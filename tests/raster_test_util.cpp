// Helpers of the CPU rasterizer's tests (raster_test_util.h).
#include "raster_test_util.h"

#include "cullide/error.h"
#include "cullide/raster/png.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace cullide::test {

using raster::CpuBackendOptions;
using raster::FillRule;
using raster::writeDepthPng;
using raster::writeMaskPng;

CommandList alwaysQueries(std::initializer_list<std::pair<uint32_t, uint32_t>> ranges) {
    CommandList l;
    l.clear();
    l.depthFunc(DepthFunc::Always);
    for (const auto& [first, count] : ranges) {
        l.beginQuery();
        l.draw(first, count);
        l.endQuery();
    }
    return l;
}

std::string failPath(const std::string& name) {
    return ::testing::TempDir() + "cullide_raster_" + name + ".png";
}

std::string dumpDiff(const std::string& name, const DepthImage& a, const DepthImage& b) {
    if (a.width != b.width || a.height != b.height || a.values.empty()) return "(sizes differ)";
    std::vector<uint8_t> mask(a.values.size());
    for (size_t i = 0; i < mask.size(); ++i) mask[i] = a.values[i] == b.values[i] ? 0 : 2;
    try {
        writeDepthPng(a, failPath(name + "_a"));
        writeDepthPng(b, failPath(name + "_b"));
        writeMaskPng(a.width, a.height, mask, failPath(name + "_diff"));
    } catch (const InputError& e) {
        return std::string("(could not write pictures: ") + e.what() + ")";
    }
    return "pictures: " + failPath(name + "_{a,b,diff}");
}

RandomScene randomScene(uint64_t seed, int W, int H, int triangles, int commands, double bigSize) {
    if (bigSize <= 0) bigSize = 3.0 * std::max(W, H);
    std::mt19937_64 rng(seed);
    auto uni = [&](double lo, double hi) { return lo + (hi - lo) * double(rng() >> 11) * 0x1p-53; };
    RandomScene s;
    for (int t = 0; t < triangles; ++t) {
        const int kind = int(rng() % 10);
        const double size = kind < 4 ? uni(0.2, 3) : kind < 8 ? uni(2, 20) : uni(20, bigSize);
        const double cx = uni(-0.2 * W, 1.2 * W), cy = uni(-0.2 * H, 1.2 * H);
        const double zc = kind == 9 ? uni(-0.5, 1.5) : uni(0, 1);
        Vec3f p[3];
        for (auto& v : p)
            v = Vec3f(float(cx + uni(-size, size)), float(cy + uni(-size, size)),
                      float(zc + uni(-0.3, 0.3) * (kind == 9 ? 3 : 1)));
        if (rng() % 25 == 0) p[2] = p[0] + (p[1] - p[0]) * 0.5f;  // degenerate
        if (rng() % 40 == 0) p[1].x() = float(uni(-1e8, 1e8));  // beyond the guard band
        if (rng() % 7 == 0) {  // on the subpixel grid / centres
            for (auto& v : p) {
                v.x() = std::round(v.x() * 2) / 2;
                v.y() = std::round(v.y() * 2) / 2;
            }
        } else if (rng() % 6 == 0) {  // on half subpixels of 4, 8 or 12 bits: snapping's ties
            const float grid = float(1 << (5 + 4 * int(rng() % 3)));
            for (auto& v : p) {
                v.x() = std::round(v.x() * grid) / grid;
                v.y() = std::round(v.y() * grid) / grid;
            }
        }
        s.geo.tri(p[0], p[1], p[2]);
    }
    const DepthFunc funcs[] = {DepthFunc::Never,   DepthFunc::Less,     DepthFunc::Equal,  DepthFunc::LEqual,
                               DepthFunc::Greater, DepthFunc::NotEqual, DepthFunc::GEqual, DepthFunc::Always};
    s.list.clear(uni(0.5, 1.0));
    bool open = false;
    for (int c = 0; c < commands; ++c) {
        const int op = int(rng() % 12);
        if (op < 6) {
            const uint32_t first = uint32_t(rng() % uint64_t(triangles));
            const uint32_t count =
                uint32_t(rng() % uint64_t(std::min<uint64_t>(triangles - first, 1 + rng() % 40) + 1));
            s.list.draw(first, count);
        } else if (op == 6) {
            s.list.depthFunc(funcs[rng() % 8]);
        } else if (op == 7) {
            s.list.depthFunc(rng() % 2 ? DepthFunc::Less : DepthFunc::GEqual);
        } else if (op == 8) {
            s.list.depthMask(rng() % 3 != 0);
        } else if (op == 9 || op == 10) {
            if (open) s.list.endQuery();
            else s.list.beginQuery(rng() % 4 == 0 ? QueryKind::AnySamplesPassed : QueryKind::SamplesPassed);
            open = !open;
        } else if (rng() % 8 == 0) {
            s.list.clear(uni(0, 1));
        }
    }
    if (open) s.list.endQuery();
    return s;
}

Outcome run(const RandomScene& s, const OrthoView& view, CpuBackendOptions o, int lists) {
    auto b = backendFor(s.geo, view, o);
    Outcome out;
    for (int i = 0; i < lists; ++i) {  // later lists start from the previous state
        out.results = b->execute(s.list);
        out.stats = b->lastStats();
    }
    out.depth = b->readDepth();
    return out;
}

CpuBackendOptions scalarReference(uint64_t seed, int subpixelBits) {
    CpuBackendOptions o;
    o.scalarReference = true;
    o.fillRule = seed % 2 ? FillRule::BottomLeft : FillRule::TopLeft;
    o.subpixelBits = subpixelBits;
    return o;
}

void expectSame(const Outcome& a, const Outcome& b, const std::string& what) {
    EXPECT_EQ(a.results, b.results) << what;
    EXPECT_EQ(a.stats, b.stats) << what;
    if (a.depth.values != b.depth.values) {
        size_t diff = 0;
        for (size_t i = 0; i < a.depth.values.size(); ++i) diff += a.depth.values[i] != b.depth.values[i];
        ADD_FAILURE() << what << ": " << diff << " depth values differ; " << dumpDiff("diff", a.depth, b.depth);
    }
}

void expectDirectOnThreads(const RandomScene& s, const OrthoView& view, const CpuBackendOptions& ref,
                           const Outcome& expected, const std::string& what) {
    for (int threads : {1, 2}) {
        CpuBackendOptions o = ref;
        o.scalarReference = false;
        o.threads = threads;
        auto direct = backendFor(s.geo, view, o);
        Outcome got;
        got.results = direct->execute(s.list);
        got.stats = direct->lastStats();
        got.depth = direct->readDepth();
        EXPECT_TRUE(direct->lastRanDirect()) << what << " threads " << threads;
        expectSame(expected, got, what + " threads " + std::to_string(threads));
    }
}

}  // namespace cullide::test
