// The study engine (tools/study): sweeps, shards and merging, resuming, the causes of false
// prunes, and the four stability sweeps at small sizes.
#include "cullide/study/causes.h"
#include "cullide/study/probes.h"
#include "cullide/study/study.h"

#include "test_util.h"

#include "cullide/error.h"
#include "cullide/oracle/oracle.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/rules.h"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>

namespace {

using namespace cullide;
using namespace cullide::study;
namespace fs = std::filesystem;

// A small but non-trivial sweep: two scenes, both methods, two depth formats.
Spec smallSpec() {
    Spec s;
    s.scenes = {"cows:800", "bunny:800"};
    s.methods = {"original", "modified"};
    s.resolutions = {"64"};
    s.depths = {"16", "24"};
    s.repeats = 1;
    return s;
}

// Records without their timing columns (and per-call seconds), their provenance (its date differs
// between runs, its machine between shards) and their command (a shard's --shard): what must not
// depend on the run.
nlohmann::ordered_json withoutTimings(nlohmann::ordered_json r) {
    for (auto it = r.begin(); it != r.end();) it = isTimingColumn(it.key()) ? r.erase(it) : std::next(it);
    for (auto& p : r["passes"]) p.erase("seconds");
    r.erase("provenance");
    r.erase("command");
    return r;
}

// Trap: contiguous slices computed with integer rounding can overlap or leave a gap at the ends.
TEST(Study, ShardsAreDisjointAndCoverTheSweep) {
    const std::vector<RunConfig> all = expand(smallSpec());
    ASSERT_EQ(all.size(), 8u);
    for (size_t n : {1u, 3u, 8u, 11u}) {
        std::multiset<std::string> seen;
        for (size_t i = 0; i < n; ++i)
            for (const RunConfig& c : slice(all, {i, n})) seen.insert(c.id());
        EXPECT_EQ(seen.size(), all.size()) << n;
        for (const RunConfig& c : all) EXPECT_EQ(seen.count(c.id()), 1u) << n;
    }
    EXPECT_THROW(parseShard("3/3"), InputError);
    EXPECT_THROW(parseShard("1/0"), InputError);
    EXPECT_THROW(parseShard("a/b"), InputError);
}

// Trap: an id derived from std::hash or from the run's position would change between builds or
// between a shard and the full sweep. FNV-1a of the key is fixed forever.
TEST(Study, RunIdsAreStableAndDistinct) {
    const std::vector<RunConfig> all = expand(smallSpec());
    std::set<std::string> ids;
    for (const RunConfig& c : all) ids.insert(c.id());
    EXPECT_EQ(ids.size(), all.size());
    EXPECT_EQ(all[0].key(), "cows:800|0|original|64|16|axes|connectivity|16|4|1|cpu|0");
    EXPECT_EQ(all[0].id(), "e0aa55aee0e7e225");
    // The views axis: fit keeps the key (and id) it had before the axis, so that resuming an older
    // study does not redo its runs; clustered is another run.
    Spec v = smallSpec();
    v.views = {"fit", "clustered"};
    const std::vector<RunConfig> both = expand(v);
    ASSERT_EQ(both.size(), 2 * all.size());
    EXPECT_EQ(both[0].id(), all[0].id());
    EXPECT_EQ(both[1].views, "clustered");
    EXPECT_EQ(both[1].key(), all[0].key() + "|views=clustered");
    v.views = {"cluster"};
    EXPECT_THROW(expand(v), InputError);
}

// Trap: shards each compute their own oracle and backend; anything that leaks between runs (a
// backend's state, a cached scene) would make the merge differ from the unsharded sweep.
TEST(Study, MergeOfShardsEqualsTheUnshardedRunModuloTimings) {
    test::TempDir dir;
    StudyOptions o;
    o.spec = smallSpec();
    o.out = dir / "all.csv";
    EXPECT_EQ(runStudy(o), 8u);
    std::vector<fs::path> shards;
    for (size_t i = 0; i < 3; ++i) {
        o.shard = {i, 3};
        o.out = dir / ("shard" + std::to_string(i) + ".csv");
        runStudy(o);
        shards.push_back(o.out);
    }
    EXPECT_EQ(mergeOutputs(shards, dir / "merged.csv"), 8u);
    const auto all = readRecords(dir / "all.csv"), merged = readRecords(dir / "merged.jsonl");
    ASSERT_EQ(all.size(), merged.size());
    for (size_t i = 0; i < all.size(); ++i) EXPECT_EQ(withoutTimings(all[i]), withoutTimings(merged[i])) << i;
    // The CSV has one header and one row per run.
    std::ifstream csv(dir / "merged.csv");
    size_t lines = 0;
    for (std::string line; std::getline(csv, line);) ++lines;
    EXPECT_EQ(lines, 9u);
}

// Each record carries its provenance (the threads it ran with, the CPU backend without drivers),
// and the CSV does not: its header and rows are the columns as before. Trap: a CSV writer that
// follows the record's keys would grow a "provenance" column of nested JSON.
TEST(Study, RecordsCarryProvenanceTheCsvDoesNot) {
    test::TempDir dir;
    StudyOptions o;
    o.spec = smallSpec();
    o.spec.scenes = {"cows:800"}, o.spec.methods = {"modified"}, o.spec.depths = {"24"};
    o.spec.threads = {2}, o.spec.oracle = false;
    o.out = dir / "p.csv";
    EXPECT_EQ(runStudy(o), 1u);
    const auto records = readRecords(dir / "p.csv");
    ASSERT_EQ(records.size(), 1u);
    const auto& p = records[0].at("provenance");
    EXPECT_EQ(p.at("threads").get<int>(), 2);
    EXPECT_FALSE(p.at("git_commit").get<std::string>().empty());
    EXPECT_TRUE(p.contains("date"));
    EXPECT_FALSE(p.contains("drivers"));
    auto without = records[0];
    without.erase("provenance");
    EXPECT_EQ(csvRow(records[0]), csvRow(without));
    std::ifstream csv(dir / "p.csv");
    std::string header;
    std::getline(csv, header);
    EXPECT_EQ(header + "\n", csvHeader());
    EXPECT_EQ(header.find("provenance"), std::string::npos);
}

// Trap: a run killed while writing leaves half a JSON line; resuming must drop it and redo that
// run, not crash on it or count it as done.
TEST(Study, ResumeSkipsDoneRunsAndHealsACutLine) {
    test::TempDir dir;
    StudyOptions o;
    o.spec = smallSpec();
    o.spec.scenes = {"cows:800"};
    o.out = dir / "r.csv";
    EXPECT_EQ(runStudy(o), 4u);
    EXPECT_EQ(runStudy(o), 0u);
    {
        // Lines that are no records of ours are skipped too: an id that is not a string (it ended
        // the resume in a type_error, exit 70) and nesting past the JSON reader's depth.
        std::ofstream f(dir / "r.jsonl", std::ios::app);
        f << "{\"id\": 5}\n" << std::string(1000, '[') << std::string(1000, ']') << "\n";
        f << "{\"index\": 3, \"id\": \"cut";
    }
    EXPECT_EQ(runStudy(o), 0u);
    EXPECT_EQ(readRecords(dir / "r.jsonl").size(), 4u);
    // Drop the last record: exactly that run is redone.
    auto recs = readRecords(dir / "r.jsonl");
    std::ofstream(dir / "r.jsonl", std::ios::trunc) << recs[0].dump() << "\n"
                                                    << recs[1].dump() << "\n"
                                                    << recs[2].dump() << "\n";
    EXPECT_EQ(runStudy(o), 1u);
    EXPECT_EQ(readRecords(dir / "r.jsonl").size(), 4u);
}

// Trap: a sweep is the product of its axes: a spec of a few lines (or a few command-line lists)
// made 7.5x10^7 runs that grew to 8 GB before anything ran. Refused before it is expanded, with
// its count, whether the configurations alone or the scenes' frames take it over the limit.
TEST(Study, SweepsOverTheRunLimitAreRefusedBeforeExpanding) {
    auto refusal = [](const Spec& s) -> std::string {
        try {
            (void)expand(s);
        } catch (const InputError& e) {
            return e.what();
        }
        return "";
    };
    Spec s;
    s.source = "sweep.json";
    s.scenes = {"bunny:500"};
    s.leafSizes.assign(1001, 16);
    s.threads.assign(1000, 1);
    EXPECT_EQ(refusal(s).rfind("sweep.json: the sweep has 1001000 runs (1 scene frames x 1001000 configurations), "
                               "more than the limit of 1000000 runs",
                               0),
              0u)
        << refusal(s);
    for (std::vector<std::string>* axis : {&s.methods, &s.resolutions, &s.depths, &s.directions, &s.hierarchies})
        axis->assign(10000, axis->front());
    EXPECT_NE(refusal(s).find("the sweep has over 2^64 runs (1 scene frames x over 2^64 configurations)"),
              std::string::npos)
        << refusal(s);
    for (std::vector<std::string>* axis : {&s.methods, &s.resolutions, &s.hierarchies}) axis->resize(1);
    s.depths = {"24"}, s.directions = {"axes"}, s.leafSizes = {16};
    s.scenes = {"bunny:500", "cows:800"};
    s.threads.assign(kMaxStudyRuns / 2 + 1, 1);
    EXPECT_NE(refusal(s).find("the sweep has 1000002 runs (2 scene frames x 500001 configurations)"), std::string::npos)
        << refusal(s);
}

// Trap: a study spec that gives a field twice: the JSON parser kept the last value without a
// word. Refused, naming the key.
TEST(Study, SpecKeysGivenTwiceAreRefused) {
    test::TempDir dir;
    std::ofstream(dir / "spec.json") << R"({"scenes": "bunny:500", "depths": [16], "depths": [24]})";
    try {
        (void)loadSpec((dir / "spec.json").string());
        FAIL() << "accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find((dir / "spec.json").string() + ": duplicate key 'depths'"),
                  std::string::npos)
            << e.what();
    }
}

// samplePair's measures the way it took them before it drew a tile: each triangle alone over the
// whole view, every pixel read (the plane depths from the unsnapped window corners).
PairSample wholeViewSample(DepthBackend& backend, const std::array<Vec3f, 3>& t, const std::array<Vec3f, 3>& x,
                           const OrthoView& view) {
    const std::array<Vec3f, 6> positions{t[0], t[1], t[2], x[0], x[1], x[2]};
    const std::array<Triangle, 2> triangles{Triangle{0, 1, 2}, Triangle{3, 4, 5}};
    backend.setGeometry(positions, triangles);
    backend.setView(view);
    DepthImage img[2];
    for (uint32_t k = 0; k < 2; ++k) {
        CommandList list;
        list.clear(1.0);
        list.depthFunc(DepthFunc::Always);
        list.draw(k, 1);
        backend.execute(list);
        img[k] = backend.readDepth();
    }
    const uint32_t cleared = raster::encodeDepth(1.0, view.depth);
    auto plane = [&](const std::array<Vec3f, 3>& c, double px, double py) {  // depth at (px, py)
        const Vec3d w[3] = {view.toWindow(c[0]), view.toWindow(c[1]), view.toWindow(c[2])};
        const double ux = w[1].x() - w[0].x(), uy = w[1].y() - w[0].y(), uz = w[1].z() - w[0].z();
        const double vx = w[2].x() - w[0].x(), vy = w[2].y() - w[0].y(), vz = w[2].z() - w[0].z();
        const double det = ux * vy - uy * vx;
        return w[0].z() + (uz * vy - uy * vz) / det * (px - w[0].x()) + (ux * vz - uz * vx) / det * (py - w[0].y());
    };
    PairSample s;
    s.maxDiffSteps = -std::numeric_limits<double>::infinity();
    for (int yy = 0; yy < view.height; ++yy)
        for (int xx = 0; xx < view.width; ++xx) {
            const uint32_t a = img[0].at(xx, yy), b = img[1].at(xx, yy);
            s.coveredT += a != cleared, s.coveredX += b != cleared;
            if (a == cleared || b == cleared) continue;
            ++s.shared;
            s.maxStoredDiff = std::max(s.maxStoredDiff, int64_t(a) - int64_t(b));
            s.maxDiffSteps =
                std::max(s.maxDiffSteps,
                         (plane(t, xx + 0.5, yy + 0.5) - plane(x, xx + 0.5, yy + 0.5)) / view.depth.resolution());
        }
    return s;
}

// Trap: samplePair draws only a tile of the view around the two triangles. A box a pixel too
// tight would lose the fragments on its border, a pixel centre without the tile's origin would
// misplace the plane depths. Small random pairs (a few pixels, crossing each other in depth), some
// across the view's border, some off it, in a view whose pixels are not powers of two: the same
// counts and depths as the whole view drawn and read.
TEST(StudyCauses, SamplePairSeesTheWholeViewsFragments) {
    auto backend = raster::makeCpuBackend({});
    OrthoView view;
    view.xmin = -1.3, view.xmax = 2.1, view.ymin = -0.7, view.ymax = 1.9, view.znear = -1, view.zfar = 1;
    view.width = 37, view.height = 29;
    view.depth = DepthFormat::unorm(16);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<float> where(-1.5f, 2.3f), offset(-0.3f, 0.3f), depth(-0.5f, 0.5f);
    PairSampleScratch scratch;
    size_t shared = 0, border = 0;
    for (int pair = 0; pair < 300; ++pair) {
        const Vec3f c(where(rng), where(rng) * 0.7f, 0.0f);
        std::array<Vec3f, 3> t, x;
        for (int k = 0; k < 3; ++k) {
            t[size_t(k)] = c + Vec3f(offset(rng), offset(rng), depth(rng));
            x[size_t(k)] = c + Vec3f(offset(rng), offset(rng), depth(rng));
        }
        const PairSample got = samplePair(*backend, t, x, view, scratch);
        const PairSample want = wholeViewSample(*backend, t, x, view);
        EXPECT_EQ(got.coveredT, want.coveredT) << pair;
        EXPECT_EQ(got.coveredX, want.coveredX) << pair;
        EXPECT_EQ(got.shared, want.shared) << pair;
        EXPECT_EQ(got.maxStoredDiff, want.maxStoredDiff) << pair;
        if (want.shared > 0) {
            EXPECT_NEAR(got.maxDiffSteps, want.maxDiffSteps, 1e-6) << pair;
        }
        shared += want.shared > 0;
        border += (c.x() < view.xmin + 0.3f || c.x() > view.xmax - 0.3f) && want.coveredT > 0;
    }
    EXPECT_GT(shared, 50u);  // the pairs overlap often enough to test the depths
    EXPECT_GT(border, 5u);  // and some lie across the view's border
}

// Trap: the thresholds differ by method (GREATER needs one stored step, GEQUAL none); a rule that
// used one threshold for both would call the original's rounding misses unexplained.
TEST(StudyCauses, DecideFollowsTheRules) {
    PairSample s;
    s.coveredT = 0, s.coveredX = 5;
    EXPECT_EQ(decide(CullMethod::Modified, s), Cause::Sampling);  // too small to cover a centre anyway
    s.largeT = true;
    EXPECT_EQ(decide(CullMethod::Modified, s), Cause::EdgeOn);  // large: no fragments for its tilt
    s.coveredT = 5, s.shared = 0;
    EXPECT_EQ(decide(CullMethod::Modified, s), Cause::Sampling);
    s.shared = 3, s.maxStoredDiff = 0, s.maxDiffSteps = 0.4, s.reachSteps = 0.6;
    EXPECT_EQ(decide(CullMethod::Modified, s), Cause::DepthRounding);
    EXPECT_EQ(decide(CullMethod::Original, s), Cause::Unexplained);  // equal stored depths pass GEQUAL
    s.maxStoredDiff = -1, s.maxDiffSteps = -0.7;
    EXPECT_EQ(decide(CullMethod::Original, s), Cause::DepthRounding);
    s.maxDiffSteps = -3, s.reachSteps = 5;
    EXPECT_EQ(decide(CullMethod::Original, s), Cause::Sampling);
    EXPECT_EQ(decide(CullMethod::Modified, s), Cause::Sampling);
    s.reachSteps = 0;  // a contact: never a full step behind
    EXPECT_EQ(decide(CullMethod::Modified, s), Cause::DepthRounding);
    s.maxStoredDiff = 1;
    EXPECT_EQ(decide(CullMethod::Modified, s), Cause::Unexplained);
    s.maxStoredDiff = 0, s.maxDiffSteps = 1.5;  // a gap of 1.5 steps that rounding lost
    EXPECT_EQ(decide(CullMethod::Modified, s), Cause::Unexplained);
}

// The acceptance criterion: every false prune on every bundled and generated scene has a cause.
// Trap: the pass views shrink with the PCS; judging a pair in the whole-scene view (as
// measurePcs's explanations do) calls sampling misses in a finer grid unexplained. Under the
// sanitizers at 100 x 100 only (both resolutions took 54 s of the ThreadSanitizer stage).
TEST(StudyCauses, NoUnexplainedFalsePrunesOnBundledAndGeneratedScenes) {
    Spec s;
    s.scenes = {std::string(CULLIDE_DATA_DIR) + "/scenes/bunny_through_cow.json@0",
                std::string(CULLIDE_DATA_DIR) + "/scenes/two_cows_and_bunny.json@0",
                "bunny:3000",
                "cows:3000",
                "cylinders:3000",
                "twist:3000"};
    s.methods = {"original", "modified"};
    s.resolutions = {"100", "500"};
    if (CULLIDE_SANITIZED) s.resolutions = {"100"};
    s.depths = {"16", "24"};
    s.repeats = 1;
    test::TempDir dir;
    StudyOptions o;
    o.spec = s;
    o.out = dir / "c.csv";
    runStudy(o);
    size_t falsePrunes = 0;
    for (const auto& r : readRecords(o.out)) {
        EXPECT_EQ(r["fp_unexplained"], 0)
            << r["scene"] << " " << r["method"] << " " << r["resolution"] << " " << r["depth"];
        EXPECT_EQ(r["mp_unexplained"], 0) << r["scene"];
        const size_t sum = r["fp_depth_rounding"].get<size_t>() + r["fp_sampling"].get<size_t>() +
            r["fp_edge_on"].get<size_t>() + r["fp_untested"].get<size_t>();
        EXPECT_EQ(sum, r["false_prunes"].get<size_t>()) << r["scene"];
        falsePrunes += sum;
    }
    EXPECT_GT(falsePrunes, 0u);  // the attribution was exercised
}

// Trap: the attribution refits each pruning call's view to find the cause of a false prune; with
// adaptive resolution it must use the call's own viewport (PassStats), not the option's base, or
// the refitted view is another one and false prunes come out unexplained. Every record's calls
// carry their viewports, never below the base.
TEST(StudyCauses, AdaptiveResolutionFalsePrunesAreExplained) {
    Spec s;
    s.scenes = {"bunny:3000", "cows:3000", "twist:3000"};
    s.methods = {"modified"};
    s.resolutions = {"auto:1", "auto"};
    s.depths = {"16"};
    s.repeats = 1;
    test::TempDir dir;
    StudyOptions o;
    o.spec = s;
    o.out = dir / "a.csv";
    runStudy(o);
    const auto records = readRecords(o.out);
    ASSERT_EQ(records.size(), 6u);
    for (const auto& r : records) {
        EXPECT_EQ(r["fp_unexplained"], 0) << r["scene"] << " " << r["resolution"];
        EXPECT_EQ(r["mp_unexplained"], 0) << r["scene"] << " " << r["resolution"];
        ASSERT_FALSE(r["passes"].empty());
        for (const auto& p : r["passes"]) EXPECT_GE(std::max(p["width"].get<int>(), p["height"].get<int>()), 500);
    }
}

// Trap: a new axis that enters every run's key would change the ids of every output written
// before it (resume and merge key on them), and auto's timing-dependent switch would make the
// instrumented run prune another PCS than the timed one (every false prune then unexplained).
// The exact_switches axis: "never" keeps the old key; each run records its switch and its time to
// exact pairs (prune + exact stage); a switch keeps a superset of never's PCS, and no run has
// unexplained false prunes. The spec field is read and checked like the others.
TEST(Study, ExactSwitchAxis) {
    Spec s;
    s.scenes = {"cows:3000"};
    s.resolutions = {"64"};
    s.exactSwitches = {"never", "auto", "2000"};
    s.repeats = 1;
    const std::vector<RunConfig> all = expand(s);
    ASSERT_EQ(all.size(), 3u);
    EXPECT_EQ(all[0].key(), "cows:3000|0|modified|64|24|axes|connectivity|16|4|1|cpu|0");
    EXPECT_EQ(all[1].key(), "cows:3000|0|modified|64|24|axes|connectivity|16|4|1|cpu|0|exact=auto");
    test::TempDir dir;
    StudyOptions o;
    o.spec = s;
    o.out = dir / "x.csv";
    runStudy(o);
    const auto records = readRecords(o.out);
    ASSERT_EQ(records.size(), 3u);
    for (const auto& r : records) {
        EXPECT_EQ(r["fp_unexplained"], 0) << r["exact_switch"];
        ASSERT_TRUE(r["time_to_exact_ms"].is_number()) << r["exact_switch"];
        EXPECT_GE(r["time_to_exact_ms"].get<double>(), r["time_ms"].get<double>());
        EXPECT_GE(r["pcs"].get<size_t>(), records[0]["pcs"].get<size_t>());
        EXPECT_LE(r["false_prunes"].get<size_t>(), records[0]["false_prunes"].get<size_t>());
    }
    EXPECT_TRUE(records[0]["switched_at_level"].is_null());
    EXPECT_TRUE(records[2]["switched_at_level"].is_number());  // cows:3000 falls below 2000 triangles
    EXPECT_NE(csvHeader().find(",exact_switch,"), std::string::npos);
    const Spec parsed =
        parseSpec(nlohmann::json::parse(R"({"scenes": "cows:800", "exact_switches": ["auto", 500]})"), "spec.json");
    EXPECT_EQ(parsed.exactSwitches, (std::vector<std::string>{"auto", "500"}));
    try {
        (void)parseSpec(nlohmann::json::parse(R"({"scenes": "cows:800", "exact_switches": ["sometimes"]})"),
                        "spec.json");
        ADD_FAILURE() << "accepted a bad switch";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("field 'exact_switches'"), std::string::npos) << e.what();
    }
}

// Trap: near contacts counted when not asked for (every study would pay for them), or a near
// distance that does not change the run's id (a resumed study would mix two distances). cows:800
// (two crossing copies in one object) has near contacts, more at a larger distance; a bad
// distance, or one without the oracle, is refused.
TEST(Study, NearContactsAreCountedWhenAsked) {
    Spec s;
    s.scenes = {"cows:800"};
    s.resolutions = {"64"};
    s.repeats = 1;
    const RunConfig plain = expand(s)[0];
    s.nearDistance = 0.002;
    const RunConfig nearer = expand(s)[0];
    EXPECT_EQ(nearer.key(), plain.key() + "|near=0.002");
    test::TempDir dir;
    StudyOptions o;
    o.spec = s;
    o.out = dir / "near.csv";
    runStudy(o);
    o.spec.nearDistance = 0.02;
    runStudy(o);  // another id: a second record, not a resumed one
    s.nearDistance = 0;
    o.spec = s;
    runStudy(o);
    const auto records = readRecords(o.out);
    ASSERT_EQ(records.size(), 3u);
    EXPECT_GT(records[0]["near_contacts"].get<size_t>(), 0u);
    EXPECT_GT(records[1]["near_contacts"].get<size_t>(), records[0]["near_contacts"].get<size_t>());
    EXPECT_EQ(records[1]["near_contacts_self"], records[1]["near_contacts"]);  // one object
    EXPECT_NEAR(records[1]["near_distance"].get<double>() / records[0]["near_distance"].get<double>(), 10.0, 1e-9);
    EXPECT_TRUE(records[2]["near_contacts"].is_null());
    for (const char* bad : {R"({"scenes": "cows:800", "near_distance": -0.1})",
                            R"({"scenes": "cows:800", "near_distance": 0.5})",
                            R"({"scenes": "cows:800", "near_distance": "0.01"})"}) {
        try {
            (void)parseSpec(nlohmann::json::parse(bad), "spec.json");
            ADD_FAILURE() << "accepted " << bad;
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("field 'near_distance'"), std::string::npos) << e.what();
        }
    }
    Spec blind = parseSpec(nlohmann::json::parse(R"({"scenes": "cows:800", "near_distance": 0.01, "oracle": false})"),
                           "spec.json");
    EXPECT_THROW((void)expand(blind), InputError);
}

// Trap: a preset naming a scene the sweep cannot run fails only when its turn comes, hours in:
// the deforming preset expands (every scene string parsed) to 18 runs, near contacts on.
TEST(Study, DeformingPresetExpands) {
    const std::vector<RunConfig> runs = expand(deformingPreset(1));
    ASSERT_EQ(runs.size(), 18u);
    EXPECT_EQ(runs[8].scene + runs.back().scene + runs.back().method, "cloth:92000nbody:146000reliable");
    EXPECT_GT(runs.back().nearDistance, 0);
}

// Trap: a study output of which one file could not be written leaving the other behind (a CSV
// with its header only and no records): the CSV and its JSON lines appear together or not at all.
TEST(Study, OutputsAreWrittenTogetherOrNotAtAll) {
    for (const char* taken : {"m.jsonl", "m.csv"}) {
        test::TempDir dir;
        fs::create_directory(dir / taken);  // where the file would go
        try {
            (void)mergeOutputs({}, dir / "m.csv");
            ADD_FAILURE() << taken << ": written";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(taken), std::string::npos) << e.what();
        }
        size_t files = 0;
        for (const auto& e : fs::directory_iterator(dir.path())) files += e.is_regular_file();
        EXPECT_EQ(files, 0u) << taken << ": a file was left";
    }
}

size_t sumOf(const std::vector<nlohmann::ordered_json>& rows, const char* key) {
    size_t n = 0;
    for (const auto& r : rows) n += r[key].get<size_t>();
    return n;
}

// Penetration depth (paper Section 5, Figure 5(a)). The guarantee that holds: a penetration of
// one stored step (far-near)/(2^n-1) at a pixel centre both triangles cover is always seen by the
// modified method; the original sees every crossing. Trap: the paper's (far-near)/2^n is a factor
// 2^n/(2^n-1) short, so the test keys on the sampled penetration in stored steps, not on delta.
TEST(StudyStability, PenetrationAtLeastOneStoredStepIsDetected) {
    ProbeOptions o;
    o.resolution = 64;
    o.trials = 6;
    o.depths = {"16", "24"};
    const auto rows = penetrationSweep(o, {0.1, 0.5, 1.0, 1.5, 3.0, 10.0});
    EXPECT_EQ(sumOf(rows, "fp_unexplained"), 0u);
    size_t shallowMissed = 0, guaranteed = 0;
    for (const auto& r : rows) {
        if (r["method"] == "original") {
            EXPECT_EQ(r["detected"], 1) << r;
            continue;
        }
        ASSERT_FALSE(r["sampled_steps"].is_null());
        if (r["sampled_steps"].get<double>() >= 1.0) {
            ++guaranteed;
            EXPECT_EQ(r["detected"], 1) << r;
        }
        if (r["factor"].get<double>() >= 1.5) {
            EXPECT_EQ(r["detected"], 1) << r;
        }
        if (r["factor"].get<double>() <= 0.5 && r["detected"] == 0) {
            ++shallowMissed;
            EXPECT_GT(r["fp_depth_rounding"].get<size_t>(), 0u) << r;
        }
    }
    EXPECT_GT(guaranteed, 0u);
    EXPECT_GT(shallowMissed, 0u);  // below a step the modified method does lose crossings
}

// Tilt towards edge-on (Section 5, last paragraph). Trap: at exactly 90 degrees the triangle
// has zero projected area and no fragments; its loss must be counted as edge-on, not sampling.
TEST(StudyStability, TiltEdgeOnLossesAreAttributed) {
    ProbeOptions o;
    o.resolution = 64;
    o.trials = 4;
    o.methods = {"modified"};
    const auto rows = tiltSweep(o, {30.0, 60.0, 90.0}, {"z", "axes"});
    EXPECT_EQ(sumOf(rows, "fp_unexplained"), 0u);
    for (const auto& r : rows) {
        if (r["directions"] == "z" && r["angle"].get<double>() < 70) {
            EXPECT_EQ(r["detected"], 1) << r;
        }
        if (r["directions"] == "z" && r["angle"].get<double>() == 90) {
            EXPECT_EQ(r["detected"], 0) << r;
            EXPECT_GT(r["fp_edge_on"].get<size_t>(), 0u) << r;
        }
    }
}

// Overlap size against the pixel diagonal (Figure 5(b)). An overlap whose inscribed circle is 3
// pixel diagonals wide always holds centres on both sides of the crossing; a tenth of a diagonal
// mostly holds none. Trap: the depth range is fixed by the anchor, so these misses can only be
// sampling (or edge-on), never depth rounding.
TEST(StudyStability, SmallOverlapsAreLostToSampling) {
    ProbeOptions o;
    o.resolution = 64;
    o.trials = 8;
    o.depths = {"24"};
    const auto rows = overlapSweep(o, {0.1, 3.0});
    EXPECT_EQ(sumOf(rows, "fp_unexplained"), 0u);
    EXPECT_EQ(sumOf(rows, "fp_depth_rounding"), 0u);
    size_t smallMissed = 0;
    for (const auto& r : rows) {
        if (r["size"].get<double>() == 3.0) {
            EXPECT_EQ(r["detected"], 1) << r;
        }
        if (r["size"].get<double>() == 0.1 && r["detected"] == 0) ++smallMissed;
    }
    EXPECT_GT(smallMissed, 4u);
}

// Jitter of the paper's scenes: rotations and perturbations move the PCS and the false prunes,
// but every false prune keeps a cause. Trap: perturbing shared vertices per triangle (instead of
// per vertex) would tear the mesh and create pairs the scene never had.
TEST(StudyStability, JitterKeepsEveryFalsePruneExplained) {
    ProbeOptions o;
    o.resolution = 128;
    o.trials = 2;
    o.depths = {"24"};
    const auto rows = jitterSweep(o, {"bunny:1500"}, {1e-7, 1e-3});
    ASSERT_EQ(rows.size(), 2u * (1 + 2 + 2 * 2));
    EXPECT_EQ(sumOf(rows, "fp_unexplained"), 0u);
    for (const auto& r : rows) {
        // The original method never tests an object against itself: the bunny is pruned whole.
        if (r["method"] == "modified") EXPECT_GT(r["pcs"].get<size_t>(), 0u) << r;
        else EXPECT_EQ(r["false_prunes"], r["fp_untested"]) << r;
        if (r["kind"] == "perturb" && r["magnitude"].get<double>() == 1e-7) {
            EXPECT_GT(r["oracle_pairs"].get<size_t>(), 0u);
        }
    }
}

// `cullide study`, `study merge` and `plot` as a user runs them (status, files written).
int runCli(const std::string& args, std::string* output = nullptr) {
    FILE* p = popen((std::string(CULLIDE_CLI_PATH) + " " + args + " 2>&1").c_str(), "r");
    if (!p) return -1;
    char buf[4096];
    std::string out;
    for (size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
    const int st = pclose(p);
    if (output) *output = out;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

// Trap: CLI11 would take "merge" for the optional SPEC positional if the subcommand were not
// matched first; and a bad shard must be refused by name before any run starts.
TEST(StudyCli, StudyMergeAndPlotFromTheCommandLine) {
    test::TempDir dir;
    const std::string common = " --scenes cows:600 --methods original modified --resolutions 64 --repeats 1 -q";
    std::string out;
    EXPECT_EQ(runCli("study" + common + " --shard 2/2 -o " + (dir / "x.csv").string(), &out), 2);
    EXPECT_NE(out.find("--shard"), std::string::npos) << out;
    EXPECT_EQ(runCli("study" + common + " --shard 0/2 -o " + (dir / "a.csv").string(), &out), 0) << out;
    EXPECT_EQ(runCli("study" + common + " --shard 1/2 -o " + (dir / "b.csv").string(), &out), 0) << out;
    EXPECT_EQ(runCli("study merge " + (dir / "a.csv").string() + " " + (dir / "b.jsonl").string() + " -o " +
                         (dir / "m.csv").string(),
                     &out),
              0)
        << out;
    EXPECT_EQ(readRecords(dir / "m.csv").size(), 2u);
    if (std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") != 0) GTEST_SKIP() << "no matplotlib";
    {
        std::ofstream bench(dir / "bench.json");
        bench
            << R"({"benchmarks": [)"
               R"({"name": "BM_Prune/scene:0/tris:5000", "run_type": "iteration", "real_time": 20.0, "time_unit": "ms"},)"
               R"({"name": "BM_Prune/scene:0/tris:270000", "run_type": "iteration", "real_time": 600.0,)"
               R"( "time_unit": "ms"}]})";
    }
    EXPECT_EQ(runCli("plot " + (dir / "m.csv").string() + " " + (dir / "bench.json").string() + " -o " +
                         (dir / "fig").string(),
                     &out),
              0)
        << out;
    EXPECT_TRUE(fs::exists(dir / "fig" / "speed_vs_accuracy.png")) << out;
    EXPECT_TRUE(fs::exists(dir / "fig" / "figure9_10_passes.svg")) << out;
    EXPECT_TRUE(fs::exists(dir / "fig" / "figure11_accumulated.png")) << out;
    EXPECT_FALSE(fs::exists(dir / "fig" / "figure8_time_vs_triangles.png")) << "one size: no line to draw";
    EXPECT_TRUE(fs::exists(dir / "fig" / "bench_bench_vs_triangles.png")) << out;
}

// Figures 9-11 come from runs with several reducePCS calls, of the method asked for. Trap: the
// per-call charts of the original method on a scene of one object (one call: one bar, one point),
// drawn because it came first in the sweep.
TEST(StudyCli, PlotDrawsPerCallChartsOfTheMethodAskedFor) {
    if (std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") != 0) GTEST_SKIP() << "no matplotlib";
    test::TempDir dir;
    std::string out;
    ASSERT_EQ(runCli("study --scenes bunny:1500 --methods original modified --resolutions 64 --repeats 1 -q -o " +
                         (dir / "s.csv").string(),
                     &out),
              0)
        << out;
    for (const auto& r : readRecords(dir / "s.csv"))
        if (r["method"] == "original") {
            ASSERT_EQ(r["calls"], 1) << "the trap needs a one-call run";
        }
    EXPECT_EQ(runCli("plot " + (dir / "s.csv").string() + " --method original -o " + (dir / "a").string(), &out), 0)
        << out;
    EXPECT_NE(out.find("no run of method 'original' has several reducePCS calls"), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(dir / "a" / "figure9_10_passes.png"));
    EXPECT_EQ(runCli("plot " + (dir / "s.csv").string() + " -o " + (dir / "b").string(), &out), 0) << out;
    EXPECT_TRUE(fs::exists(dir / "b" / "figure9_10_passes.png")) << out;
    EXPECT_NE(out.find("figure11_accumulated.png"), std::string::npos) << out;
}

// Trap: the per-call chart of an adaptive run, whose calls each have their own viewport (written
// above the bars), failing or dropping the run: the chart is drawn from the study's JSON lines.
TEST(StudyCli, PlotDrawsPerCallViewportsOfAnAdaptiveRun) {
    if (std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") != 0) GTEST_SKIP() << "no matplotlib";
    test::TempDir dir;
    std::string out;
    ASSERT_EQ(runCli("study --scenes bunny:1500 --methods modified --resolutions auto:4 --repeats 1 -q -o " +
                         (dir / "s.csv").string(),
                     &out),
              0)
        << out;
    EXPECT_EQ(runCli("plot " + (dir / "s.csv").string() + " -o " + (dir / "p").string(), &out), 0) << out;
    EXPECT_TRUE(fs::exists(dir / "p" / "figure9_10_passes.png")) << out;
}

}  // namespace
