// Tests of the validation machinery (cullide/raster/validate.h) and of `cullide validate`: the
// interval evaluator's exact track reproduces the CPU reference, its intervals contain the
// reference's counts, and on llvmpipe no query of the bundled scenes falls outside its interval.
#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/gl_backend.h"
#include "cullide/raster/validate.h"
#include "cullide/scene_io.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>

namespace cullide {
namespace {

using raster::QueryInterval;

// A random soup inside the unit cube and a list of Cullide-like passes: draws under LESS with
// writes, then GREATER / GEQUAL / EQUAL queries with writes off, over every depth function.
struct Soup {
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
};

Soup randomSoup(uint32_t seed, uint32_t n, float size) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f), d(-size, size);
    Soup s;
    for (uint32_t i = 0; i < n; ++i) {
        const Vec3f a(u(rng), u(rng), u(rng));
        s.p.insert(s.p.end(), {a, a + Vec3f(d(rng), d(rng), d(rng)), a + Vec3f(d(rng), d(rng), d(rng))});
        s.t.push_back({3 * i, 3 * i + 1, 3 * i + 2});
    }
    return s;
}

CommandList cullideLikeList(uint32_t triangles, uint32_t group) {
    CommandList list;
    list.clear(1.0);
    for (int pass = 0; pass < 2; ++pass) {
        for (uint32_t first = 0; first < triangles; first += group) {
            const uint32_t count = std::min(group, triangles - first);
            list.depthMask(false);
            list.depthFunc(pass == 0 ? DepthFunc::GEqual : DepthFunc::Greater);
            list.beginQuery(first % (3 * group) == 0 ? QueryKind::AnySamplesPassed : QueryKind::SamplesPassed);
            list.draw(first, count);
            list.endQuery();
            list.depthMask(true);
            list.depthFunc(DepthFunc(first / group % 8));
            list.draw(first, count);
        }
        list.clear(pass == 0 ? 0.0 : 1.0);
    }
    return list;
}

OrthoView fitted(const Soup& s, const Vec3d& dir, int size, const DepthFormat& f) {
    const TriangleRange all{0, uint32_t(s.t.size())};
    return fitView(s.p, s.t, std::span(&all, 1), dir, size, size, f);
}

// Trap: the interval code's re-derivation of the reference's rules drifting from the CPU
// backend (snapping, fill rule, depth plane association, unorm rounding, the depth functions), or
// an interval that does not contain the reference's own count. Needs no GL.
TEST(QueryIntervals, ExactTrackReproducesTheCpuReferenceAndIntervalsContainIt) {
    for (const DepthFormat& f : {DepthFormat::unorm(16), DepthFormat::unorm(24), DepthFormat::float32()}) {
        const Soup s = randomSoup(7, 400, 0.15f);
        std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
        raster::QueryIntervals iv;
        cpu->setGeometry(s.p, s.t);
        iv.setGeometry(s.p, s.t);
        for (const Vec3d& dir : {Vec3d(0, 0, 1), Vec3d(1, -2, 0.5)}) {
            const OrthoView view = fitted(s, dir, 96, f);
            cpu->setView(view);
            iv.setView(view);
            const CommandList list = cullideLikeList(uint32_t(s.t.size()), 10);
            const std::vector<uint64_t> ref = cpu->execute(list);
            std::vector<uint64_t> exact;
            bool valid = false;
            const std::vector<QueryInterval> in = iv.execute(list, &exact, &valid);
            ASSERT_TRUE(valid);
            EXPECT_EQ(exact, ref) << f.name();
            uint64_t ambiguous = 0;
            for (size_t q = 0; q < ref.size(); ++q) {
                EXPECT_TRUE(in[q].contains(ref[q])) << f.name() << " query " << q << ": " << ref[q] << " not in ["
                                                    << in[q].certain << ", " << in[q].possible << "]";
                ambiguous += in[q].possible - in[q].certain;
            }
            EXPECT_GT(ambiguous, 0u);  // sanity: random soups do have edges near centres
        }
    }
}

// Trap: intervals too loose to mean anything: for pixel-aligned, depth-separated boxes nothing
// is ambiguous, so the interval is the exact count.
TEST(QueryIntervals, PixelAlignedSeparatedBoxesHaveNoAmbiguity) {
    std::vector<Vec3f> p = {{2, 2, 0.25f}, {10, 2, 0.25f}, {10, 9, 0.25f},  {2, 9, 0.25f},
                            {5, 0, 0.75f}, {16, 0, 0.75f}, {16, 16, 0.75f}, {5, 16, 0.75f}};
    std::vector<Triangle> t = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
    OrthoView v;
    v.xmin = 0, v.xmax = 16, v.ymin = 0, v.ymax = 16, v.znear = 0, v.zfar = 1, v.width = 16, v.height = 16;
    raster::QueryIntervals iv;
    iv.setGeometry(p, t);
    iv.setView(v);
    CommandList list;
    list.clear();
    list.draw(0, 2);
    list.beginQuery();
    list.draw(2, 2);
    list.endQuery();
    const std::vector<QueryInterval> r = iv.execute(list);
    EXPECT_EQ(r[0].certain, r[0].possible);
    EXPECT_EQ(r[0].certain, uint64_t(11 * 16 - 5 * 7));
}

// Everything execute() reports for one list, for comparing thread counts and band splits.
struct IntervalRun {
    std::vector<QueryInterval> intervals;
    std::vector<uint64_t> exact;
    bool exactValid = false;
    std::vector<uint8_t> classes;
    bool operator==(const IntervalRun& o) const {
        return exactValid == o.exactValid && exact == o.exact && classes == o.classes &&
            std::equal(intervals.begin(), intervals.end(), o.intervals.begin(), o.intervals.end(),
                       [](const QueryInterval& a, const QueryInterval& b) {
                           return a.certain == b.certain && a.possible == b.possible;
                       });
    }
};

// Runs `lists` in order on one evaluator (state carries over, as in GL), capturing query
// `captureQuery` of each list.
std::vector<IntervalRun> runIntervals(int threads, int bandRows, const std::vector<Vec3f>& p,
                                      const std::vector<Triangle>& t, const OrthoView& view,
                                      const std::vector<CommandList>& lists, uint32_t captureQuery) {
    raster::IntervalOptions o;
    o.threads = threads;
    o.bandRows = bandRows;
    raster::QueryIntervals iv(o);
    iv.setGeometry(p, t);
    iv.setView(view);
    std::vector<IntervalRun> out;
    for (const CommandList& list : lists) {
        IntervalRun r;
        raster::CoverageCapture capture;
        capture.query = std::min(captureQuery, list.queryCount() - 1);
        r.intervals = iv.execute(list, &r.exact, &r.exactValid, &capture);
        r.classes = std::move(capture.classes);
        out.push_back(std::move(r));
    }
    return out;
}

// The splits compared: automatic bands at several thread counts, 1-row bands (every triangle
// spans bands), odd band heights, and one band (the serial order).
const std::vector<std::pair<int, int>> kSplits = {{1, 0}, {2, 0}, {3, 0},  {7, 0},      {1, 1},
                                                  {3, 1}, {2, 5}, {7, 13}, {1, 1 << 20}};

// Trap: the band-parallel execute() giving different intervals, exact counts, exactValid or
// coverage classes for different thread counts or band splits (a triangle's fragments lost or
// doubled at band borders, clears or state changes applied to one band only, per-band counters
// summed wrongly, any-samples queries reduced per band instead of at the end), on Cullide-like
// lists with clears between passes, depth-function and mask changes and any-samples queries,
// run back to back so that state carries across lists.
TEST(QueryIntervals, ThreadCountsAndBandSplitsGiveIdenticalResults) {
    for (const DepthFormat& f : {DepthFormat::unorm(24), DepthFormat::float32()}) {
        const Soup s = randomSoup(23, 700, 0.12f);
        const OrthoView view = fitted(s, Vec3d(0.3, 1, -0.4), 83, f);
        std::vector<CommandList> lists = {cullideLikeList(uint32_t(s.t.size()), 9),
                                          cullideLikeList(uint32_t(s.t.size()), 40)};
        CommandList noClear;  // no clear: builds on the previous list's buffer
        noClear.depthFunc(DepthFunc::LEqual);
        noClear.beginQuery(QueryKind::AnySamplesPassed);
        noClear.draw(0, 350);
        noClear.endQuery();
        noClear.depthMask(false);
        noClear.depthFunc(DepthFunc::NotEqual);
        noClear.beginQuery();
        noClear.draw(100, 600);
        noClear.endQuery();
        lists.push_back(noClear);
        const std::vector<IntervalRun> serial = runIntervals(1, 1 << 20, s.p, s.t, view, lists, 3);
        uint64_t counted = 0;
        for (const IntervalRun& r : serial)
            for (const QueryInterval& q : r.intervals) counted += q.possible;
        ASSERT_GT(counted, 0u);  // sanity: the lists do count fragments
        for (const auto& [threads, rows] : kSplits) {
            const std::vector<IntervalRun> got = runIntervals(threads, rows, s.p, s.t, view, lists, 3);
            ASSERT_EQ(got.size(), serial.size());
            for (size_t l = 0; l < got.size(); ++l)
                EXPECT_TRUE(got[l] == serial[l])
                    << f.name() << ", " << threads << " threads, band rows " << rows << ", list " << l;
        }
    }
}

// Trap: a triangle spanning many bands set up or counted in only some of them, or its
// invariance rule (the stored depth written by this very triangle) broken at band borders: big
// triangles covering the viewport drawn over, under and again after small ones.
TEST(QueryIntervals, TriangleSpanningManyBandsIsCountedOnceInEach) {
    Soup s = randomSoup(5, 200, 0.1f);
    const uint32_t big = uint32_t(s.t.size());
    const uint32_t v = uint32_t(s.p.size());
    s.p.insert(s.p.end(), {{-0.2f, -0.3f, 0.45f}, {1.3f, 0.1f, 0.5f}, {0.4f, 1.4f, 0.55f}});
    s.p.insert(s.p.end(), {{1.2f, 1.2f, 0.6f}, {-0.1f, 1.1f, 0.3f}, {0.9f, -0.2f, 0.5f}});
    s.t.push_back({v, v + 1, v + 2});
    s.t.push_back({v + 3, v + 4, v + 5});
    OrthoView view;
    view.xmin = 0, view.xmax = 1, view.ymin = 0, view.ymax = 1, view.znear = 0, view.zfar = 1;
    view.width = 61, view.height = 97;
    CommandList list;
    list.clear();
    list.beginQuery();
    list.draw(big, 2);  // the big ones first: written everywhere
    list.endQuery();
    list.beginQuery();
    list.draw(0, big);
    list.endQuery();
    list.depthMask(false);
    list.depthFunc(DepthFunc::Equal);  // the same triangles again: invariance
    list.beginQuery();
    list.draw(big, 2);
    list.endQuery();
    list.depthFunc(DepthFunc::GEqual);
    list.beginQuery(QueryKind::AnySamplesPassed);
    list.draw(big + 1, 1);
    list.endQuery();
    const std::vector<CommandList> lists = {list};
    const std::vector<IntervalRun> serial = runIntervals(1, 1 << 20, s.p, s.t, view, lists, 2);
    ASSERT_GT(serial[0].intervals[0].certain, uint64_t(61 * 97 / 2));  // sanity: they are big
    ASSERT_GT(serial[0].intervals[2].certain, 0u);  // sanity: the invariance rule applies
    for (const auto& [threads, rows] : kSplits)
        EXPECT_TRUE(runIntervals(threads, rows, s.p, s.t, view, lists, 2)[0] == serial[0])
            << threads << " threads, band rows " << rows;
}

// Trap: exactValid taken only from the bands a clipped triangle touches (or from the pixels it
// counts): a triangle needing clipping (a vertex beyond the far plane) distrusts the exact track
// even when none of its fragments counts (drawn under NEVER, no query open) and its pixels lie in
// the last rows only; a later clear trusts it again, in list order.
TEST(QueryIntervals, ClippedTriangleThatCountsNothingStillClearsExactValid) {
    const std::vector<Vec3f> p = {{2, 30, 0.5f}, {5, 30, 0.5f}, {3, 31.5f, 1.7f}};
    const std::vector<Triangle> t = {{0, 1, 2}};
    OrthoView view;
    view.xmin = 0, view.xmax = 32, view.ymin = 0, view.ymax = 32, view.znear = 0, view.zfar = 1;
    view.width = 32, view.height = 32;
    CommandList clippedLast, clearedAfter, clean;
    clippedLast.clear();
    clippedLast.depthFunc(DepthFunc::Never);
    clippedLast.draw(0, 1);
    clippedLast.beginQuery();
    clippedLast.endQuery();
    clearedAfter.depthFunc(DepthFunc::Never);
    clearedAfter.draw(0, 1);
    clearedAfter.clear();
    clearedAfter.beginQuery();
    clearedAfter.endQuery();
    clean.beginQuery();
    clean.endQuery();
    const std::vector<CommandList> lists = {clean, clippedLast, clean, clearedAfter, clean};
    for (const auto& [threads, rows] : kSplits) {
        const std::vector<IntervalRun> r = runIntervals(threads, rows, p, t, view, lists, 0);
        const std::vector<bool> valid = {r[0].exactValid, r[1].exactValid, r[2].exactValid, r[3].exactValid,
                                         r[4].exactValid};
        EXPECT_EQ(valid, std::vector<bool>({true, false, false, true, true}))
            << threads << " threads, band rows " << rows;
        EXPECT_EQ(r[1].intervals[0].possible, 0u);
    }
}

bool glMissing(std::string& why) {
    return !raster::glBackendAvailable(&why);
}

#define GL_OR_SKIP()                                                                                \
    do {                                                                                            \
        std::string why;                                                                            \
        if (glMissing(why)) {                                                                       \
            if (std::getenv("CULLIDE_REQUIRE_GL") && raster::glBuilt()) FAIL() << "no GL: " << why; \
            GTEST_SKIP() << "no GL context: " << why;                                               \
        }                                                                                           \
    } while (0)

// Trap: GL results outside the intervals on random soups (slivers, steep triangles, every depth
// function, writes under uncertainty), at every format.
TEST(Validate, RandomSoupsOnGlStayInsideTheirIntervals) {
    GL_OR_SKIP();
    std::unique_ptr<raster::GlBackend> gl = raster::makeGlBackend();
    for (const DepthFormat& f : {DepthFormat::unorm(16), DepthFormat::unorm(24), DepthFormat::float32()}) {
        const Soup s = randomSoup(11, 300, 0.2f);
        std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
        raster::TeeBackend tee(*cpu, *gl, {});
        tee.setGeometry(s.p, s.t);
        tee.setView(fitted(s, Vec3d(0.3, 1, -0.2), 128, f));
        tee.execute(cullideLikeList(uint32_t(s.t.size()), 8));
        size_t exact = 0;
        for (const raster::QueryComparison& c : tee.comparisons()) {
            EXPECT_TRUE(c.inInterval()) << f.name() << " query " << c.query << ": gl " << c.other << ", reference "
                                        << c.reference << ", interval [" << c.interval.certain << ", "
                                        << c.interval.possible << "]";
            exact += c.exact() ? 1 : 0;
        }
        std::printf("  [gl] %s: %zu of %zu queries exact\n", f.name().c_str(), exact, tee.comparisons().size());
        EXPECT_EQ(tee.selfCheckMismatches(), 0u);
    }
}

// Trap: the bundled scenes (the paper's bunny-through-cow) producing a GL query outside its
// interval, i.e. a real disagreement between llvmpipe and the reference. One frame of each scene,
// at a resolution that keeps llvmpipe's runtime small (128 under the sanitizers, where 256 took
// 150 s of the ThreadSanitizer stage); `cullide validate` runs them in full.
TEST(Validate, BundledScenesHaveNoQueryOutsideItsInterval) {
    GL_OR_SKIP();
    std::unique_ptr<raster::GlBackend> gl = raster::makeGlBackend();
    for (const char* name : {"bunny_through_cow.json", "two_cows_and_bunny.json"}) {
        const Animation a = loadScene(std::string(CULLIDE_DATA_DIR) + "/scenes/" + name);
        const size_t frame = a.frameCount() / 2;
        CullideOptions o;
        o.width = o.height = CULLIDE_SANITIZED ? 128 : 256;
        std::unique_ptr<raster::CpuBackend> cpu = raster::makeCpuBackend();
        raster::TeeBackend tee(*cpu, *gl, {});
        tee.setFrame(uint32_t(frame));
        runCullide(a.sceneAt(frame), tee, o);
        size_t exact = 0, inside = 0;
        for (const raster::QueryComparison& c : tee.comparisons()) {
            exact += c.exact() ? 1 : 0;
            inside += c.inInterval() ? 1 : 0;
            EXPECT_TRUE(c.inInterval()) << name << " list " << c.list << " query " << c.query << ": gl " << c.other
                                        << ", reference " << c.reference << ", interval [" << c.interval.certain << ", "
                                        << c.interval.possible << "]";
        }
        EXPECT_EQ(tee.selfCheckMismatches(), 0u);
        std::printf("  [gl] %s frame %zu: %zu queries, %zu exact, %zu in interval\n", name, frame,
                    tee.comparisons().size(), exact, inside);
    }
}

// Runs `cullide ARGS`: the exit status (128 + the signal when killed) and stdout and stderr together.
std::pair<int, std::string> cli(const std::string& args) {
    const test::CommandRun r = test::runCommand(std::string("'") + CULLIDE_CLI_PATH + "' " + args);
    return {r.status, r.output};
}

// Trap: the command exiting 0 when it should report, or not listing what it compared.
TEST(Validate, CommandReportsRatesAndExitsZeroWhenEverythingIsInside) {
    GL_OR_SKIP();
    const auto [status, out] = cli("validate '" + std::string(CULLIDE_DATA_DIR) +
                                   "/scenes/bunny_through_cow.json' --frame 0 --resolution 128");
    EXPECT_EQ(status, 0) << out;
    EXPECT_NE(out.find("in interval"), std::string::npos) << out;
    EXPECT_NE(out.find("outside 0"), std::string::npos) << out;
    EXPECT_NE(out.find("PCS reference"), std::string::npos) << out;
}

// A build without GL (-DCULLIDE_GL=OFF) says so for every way of asking for GL, exit status 2.
TEST(Validate, GlNotBuiltIsSaid) {
    if (raster::glBuilt()) GTEST_SKIP() << "GL is built";
    const std::string cow = std::string("'") + CULLIDE_DATA_DIR + "/meshes/cow.off'";
    const test::TempDir out;
    const std::string study =
        "study --scenes bunny:500 --backends gl --no-oracle -q -o '" + out.path().string() + "/s.csv'";
    for (const std::string& args : {"prune " + cow + " --backend gl", "validate " + cow, study}) {
        const auto [status, text] = cli(args);
        EXPECT_EQ(status, 2) << args << ": " << text;
        EXPECT_NE(text.find(raster::kGlNotBuilt), std::string::npos) << args << ": " << text;
    }
}

}  // namespace
}  // namespace cullide
