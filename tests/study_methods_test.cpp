// The study's method families (tools/study: methods.cpp, pair_run.cpp): the exact method and the
// peers in one sweep with the image-space methods, each row measured the same way.
#include "cullide/study/methods.h"
#include "cullide/study/study.h"

#include "test_util.h"

#include "cullide/error.h"
#include "cullide/oracle/audit.h"

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>

namespace {

using namespace cullide;
using namespace cullide::study;

const std::string kBunnyThroughCow = std::string(CULLIDE_DATA_DIR) + "/scenes/bunny_through_cow.json";

// Trap: a pair method has no resolution, depth or backend; crossing it with those axes would run
// it once per combination, the same run under different ids.
TEST(StudyMethods, PairMethodsRunOncePerFrameAndThreadCount) {
    Spec s;
    s.scenes = {"cows:800"};
    s.methods = {"modified", "exact", "embree"};
    s.resolutions = {"32", "64"};
    s.depths = {"16", "24"};
    s.threads = {1, 2};
    const std::vector<RunConfig> runs = expand(s);
    std::map<std::string, size_t> perMethod;
    std::set<std::string> ids;
    for (const RunConfig& c : runs) ++perMethod[c.method], ids.insert(c.id());
    EXPECT_EQ(perMethod["modified"], 8u);
    EXPECT_EQ(perMethod["exact"], 2u);
    EXPECT_EQ(perMethod["embree"], 2u);
    EXPECT_EQ(ids.size(), runs.size());
    for (const RunConfig& c : runs)
        if (c.method != "modified") {
            EXPECT_TRUE(c.resolution.empty() && c.backend.empty()) << c.key();
        }
    // The tolerance is part of a pair method's key only (image-space rows do not use it).
    Spec t = s;
    t.tolerance = 1e-4;
    const std::vector<RunConfig> tolerant = expand(t);
    for (size_t i = 0; i < runs.size(); ++i)
        EXPECT_EQ(runs[i].id() == tolerant[i].id(), runs[i].method == "modified") << runs[i].key();
}

// Trap: a typo in a method name must be refused before anything runs, naming the field and the
// methods there are, not fail deep inside a run.
TEST(StudyMethods, UnknownMethodsAreRefusedListingEveryFamily) {
    EXPECT_EQ(methodFamily("reliable", "m"), MethodFamily::ImageSpace);
    EXPECT_EQ(methodFamily("exact", "m"), MethodFamily::Exact);
    EXPECT_EQ(methodFamily("cgal", "m"), MethodFamily::Peer);
    try {
        (void)parseSpec(nlohmann::json::parse(R"({"scenes": "cows:800", "methods": ["fcll"]})"), "spec.json");
        ADD_FAILURE() << "accepted fcll";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("spec.json: field 'methods'"), std::string::npos) << what;
        EXPECT_NE(what.find("exact, fcl, embree, bullet, cgal"), std::string::npos) << what;
    }
}

// Trap: the families measure time to pairs differently (image-space through the exact stage, the
// others directly); a row that leaves a column empty or judges the exact method against itself
// wrongly would put a method off the chart. The exact method must agree with the oracle, and no
// peer may leave a disagreement unexplained.
TEST(StudyMethods, EveryFamilyFillsTheSameMeasures) {
    test::TempDir dir;
    StudyOptions o;
    o.spec.scenes = {kBunnyThroughCow + "@5"};
    o.spec.methods = {"modified", "exact", "fcl", "embree", "bullet", "cgal"};
    o.spec.resolutions = {"64"};
    o.spec.repeats = 1;
    o.out = dir / "methods.csv";
    runStudy(o);
    const auto records = readRecords(o.out);
    ASSERT_EQ(records.size(), 6u);
    for (const auto& r : records) {
        SCOPED_TRACE(r["method"].get<std::string>());
        EXPECT_GE(r["time_to_pairs_ms"].get<double>(), 0);
        const size_t truth = r["oracle_pairs"].get<size_t>();
        EXPECT_EQ(truth, 505u);
        EXPECT_EQ(r["pairs_found"].get<size_t>() + r["pairs_missed"].get<size_t>(), truth);
        if (r["family"] == "image-space") {
            EXPECT_EQ(r["pairs_spurious"], 0);
            EXPECT_TRUE(r["missed_unexplained"].is_null());
            continue;
        }
        EXPECT_EQ(r["missed_unexplained"], 0);
        EXPECT_EQ(r["spurious_unexplained"], 0);
        EXPECT_TRUE(r["resolution"].is_null());
        size_t missed = 0;
        for (oracle::AuditCause c : oracle::missedCauses()) missed += r[std::string("missed_") + toString(c)].get<size_t>();
        EXPECT_EQ(missed, r["pairs_missed"].get<size_t>());
        if (r["family"] == "exact") {
            EXPECT_EQ(r["pairs_missed"], 0);
        }
        if (r["method"] == "fcl" || r["method"] == "bullet") {  // between objects only: the 101 self pairs untested
            EXPECT_EQ(r["missed_untested"], 101);
        }
    }
    const std::string csv = test::readBytes(o.out);
    EXPECT_NE(csv.find(",family,time_to_pairs_ms,pairs_found,pairs_missed,pairs_spurious,tolerance,"), std::string::npos);
}

// Trap: a peer rebuilt on every frame would be timed as no user runs it on a deforming sequence;
// one never rebuilt after a change of triangles would answer for stale geometry. Over a file's
// frames the peer is built once (build_ms on the first frame only) and its pairs follow the frames.
TEST(StudyMethods, PeersBuildOncePerSequenceThenRefit) {
    test::TempDir dir;
    StudyOptions o;
    o.spec.scenes = {kBunnyThroughCow};  // every frame
    o.spec.methods = {"embree"};
    o.spec.repeats = 1;
    o.out = dir / "sequence.jsonl";
    runStudy(o);
    const auto records = readRecords(o.out);
    ASSERT_EQ(records.size(), 9u);
    for (size_t f = 0; f < records.size(); ++f) {
        EXPECT_EQ(records[f].contains("build_ms"), f == 0) << f;
        EXPECT_EQ(records[f]["pairs_found"].get<size_t>() + records[f]["pairs_missed"].get<size_t>(),
                  records[f]["oracle_pairs"].get<size_t>());
        EXPECT_EQ(records[f]["missed_unexplained"], 0) << f;
        EXPECT_EQ(records[f]["spurious_unexplained"], 0) << f;
    }
    EXPECT_NE(records[5]["oracle_pairs"], records[8]["oracle_pairs"]);  // the frames differ
}

// Trap: a library that cannot take a scene's geometry (CGAL wants a valid polygon mesh; a
// resampled cow is not one) would end the whole sweep, the other methods' runs lost with it. Its
// row says why, its measures empty, and the sweep goes on.
TEST(StudyMethods, APeerThatCannotTakeASceneLeavesARowSayingWhy) {
    test::TempDir dir;
    StudyOptions o;
    o.spec.scenes = {"cows:500"};
    o.spec.methods = {"cgal", "exact"};
    o.spec.repeats = 1;
    o.out = dir / "refused.csv";
    runStudy(o);
    const auto records = readRecords(o.out);
    ASSERT_EQ(records.size(), 2u);
    EXPECT_NE(records[0].value("error", "").find("CGAL Surface_mesh"), std::string::npos) << records[0].dump();
    EXPECT_TRUE(records[0]["time_to_pairs_ms"].is_null());
    EXPECT_TRUE(records[0]["pairs_missed"].is_null());
    EXPECT_GT(records[0]["oracle_pairs"].get<size_t>(), 0u);
    EXPECT_EQ(records[1]["pairs_missed"], 0);
}

}  // namespace
