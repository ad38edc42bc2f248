// Traces (raster/verify/src/trace_*.cpp, tools/cli/trace.cpp): the format round trip, determinism, every
// kind of bad input, replay and compare, the independent Python reader.
#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/raster/gl_backend.h"
#include "cullide/raster/trace.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

namespace cullide {
namespace {

using test::TempDir;
using Json = nlohmann::ordered_json;

const auto slurp = test::readBytes;
const auto spit = test::writeBytes;

// Two interpenetrating boxes and a third apart, moved over three frames (the third frame: the
// same triangles as the second, so their blob is shared).
Animation smallAnimation() {
    Animation a;
    a.scene = test::sceneOf({{test::box({0, 0, 0}, {1, 1, 1}), test::rotation(0, 0, 0)},
                             {test::box({0, 0, 0}, {1, 1, 1}), test::rotation(0.3, 0.2, 0.1, {0.6f, 0.5f, 0.4f})},
                             {test::box({0, 0, 0}, {1, 1, 1}), test::rotation(0, 0, 0, {3, 0, 0})}});
    return a;
}

CullideOptions smallOptions() {
    CullideOptions o;
    o.width = o.height = 64;
    o.hierarchy.leafSize = 2;
    return o;
}

// Records the three frames of `scene` moved by a small translation per frame.
uint64_t recordSmall(const std::filesystem::path& path, int threads = 1) {
    raster::TraceRules rules;
    raster::CpuBackendOptions cpuOptions;
    cpuOptions.threads = threads;
    auto cpu = raster::makeCpuBackend(cpuOptions);
    raster::TraceWriter writer(path, rules, {{"scene", "small"}}, {{"cullide_version", "test"}, {"threads", threads}});
    raster::TraceRecorder recorder(*cpu, writer, rules);
    const Animation a = smallAnimation();
    for (uint32_t f = 0; f < 3; ++f) {
        Scene s = a.scene;
        s.objects[1].transform.pretranslate(Vec3f(0.01f * float(f), 0, 0));
        recorder.setFrame(f);
        runCullide(s, recorder, smallOptions());
    }
    return recorder.finish();
}

// Splits a trace into its header (parsed) and its binary section, and joins them again.
struct Parts {
    Json header;
    std::string binary;
};
Parts split(const std::string& bytes) {
    uint64_t n = 0;
    std::memcpy(&n, bytes.data() + 8, 8);
    return {Json::parse(bytes.substr(16, n)), bytes.substr(16 + n)};
}
std::string join(const Parts& p) {
    std::string text = p.header.dump(1);
    text.append((8 - (16 + text.size()) % 8) % 8, ' ');
    const uint64_t n = text.size();
    std::string out = "CULTRACE";
    out.append(reinterpret_cast<const char*>(&n), 8);
    return out + text + p.binary;
}

// Reads everything a replay reads; throws what the reader throws.
void readAll(const std::filesystem::path& path) {
    const raster::TraceReader r(path);
    std::vector<Vec3f> p;
    std::vector<Triangle> t;
    for (size_t f = 0; f < r.frameCount(); ++f) r.readGeometry(f, p, t);
    for (size_t l = 0; l < r.listCount(); ++l) r.readList(l);
}

// The message of the InputError that reading `bytes` as a trace throws ("" when none).
std::string readError(const TempDir& dir, const std::string& bytes) {
    const auto path = dir / "edited.trace";
    spit(path, bytes);
    try {
        readAll(path);
    } catch (const InputError& e) {
        EXPECT_EQ(e.source(), path.string());
        return e.what();
    }
    return "";
}

// The first samples-passed query (list, query) of the trace whose interval's lower end exceeds
// `above`; list SIZE_MAX when there is none.
std::pair<size_t, size_t> firstSamplesQuery(const raster::TraceReader& trace, uint64_t above) {
    for (size_t l = 0; l < trace.listCount(); ++l) {
        const raster::TraceList tl = trace.readList(l);
        for (size_t q = 0; q < tl.queries.size(); ++q)
            if (tl.kinds[q] == QueryKind::SamplesPassed && tl.queries[q].interval.certain > above) return {l, q};
    }
    return {SIZE_MAX, 0};
}

// Trap: replay forgetting state across lists or frames, or a decode that changes a command: the
// CPU reference replaying its own trace must give every recorded answer back.
TEST(Trace, CpuReplayReproducesEveryRecordedAnswer) {
    TempDir dir;
    recordSmall(dir / "t.trace");
    const raster::TraceReader trace(dir / "t.trace");
    ASSERT_EQ(trace.frameCount(), 3u);
    ASSERT_GT(trace.listCount(), 6u);
    auto cpu = raster::makeCpuBackend();
    const auto results = raster::replayTrace(trace, *cpu);
    ASSERT_EQ(results.size(), trace.listCount());
    size_t queries = 0;
    for (size_t l = 0; l < trace.listCount(); ++l) {
        const raster::TraceList list = trace.readList(l);
        ASSERT_EQ(results[l].size(), list.queries.size());
        for (size_t q = 0; q < list.queries.size(); ++q) {
            EXPECT_EQ(results[l][q], list.queries[q].reference) << "list " << l << " query " << q;
            EXPECT_TRUE(list.queries[q].interval.contains(list.queries[q].reference)) << "list " << l << " query " << q;
        }
        queries += list.queries.size();
    }
    EXPECT_GT(queries, 20u);
    const raster::TraceComparison c = raster::compareTrace(trace, {"cpu", results}, "results");
    EXPECT_TRUE(c.passed());
    EXPECT_EQ(c.all.exact, c.all.queries);
    EXPECT_EQ(c.perFrame.size(), 3u);
}

// Trap: a thread-dependent or uninitialized byte anywhere in the file: two recordings with the
// same options are byte-identical, and with another thread count differ only in the provenance.
TEST(Trace, SameInputSameBytes) {
    TempDir dir;
    recordSmall(dir / "a.trace", 1);
    recordSmall(dir / "b.trace", 1);
    recordSmall(dir / "c.trace", 3);
    EXPECT_EQ(slurp(dir / "a.trace"), slurp(dir / "b.trace"));
    Parts a = split(slurp(dir / "a.trace")), c = split(slurp(dir / "c.trace"));
    EXPECT_EQ(a.binary, c.binary);
    a.header.erase("provenance");
    c.header.erase("provenance");
    EXPECT_EQ(a.header.dump(), c.header.dump());
}

// Trap: a command whose fields do not survive the encoding (the clear depth's 64 bits, every
// depth function, both query kinds, the mask), and unchanged triangles stored twice.
TEST(Trace, EveryCommandRoundTrips) {
    TempDir dir;
    const std::vector<Vec3f> p = {{0, 0, 0.1f}, {1, 0, 0.2f}, {0, 1, 0.3f}, {1, 1, 0.4f}};
    const std::vector<Triangle> t = {{0, 1, 2}, {1, 3, 2}};
    CommandList list;
    list.clear(0.3);  // not a float: all 64 bits matter
    for (int f = 0; f < 8; ++f) list.depthFunc(DepthFunc(f));
    list.depthMask(false);
    list.beginQuery(QueryKind::AnySamplesPassed);
    list.draw(1, 1);
    list.endQuery();
    list.depthMask(true);
    list.beginQuery(QueryKind::SamplesPassed);
    list.draw(0, 2);
    list.endQuery();
    OrthoView view;
    view.xmin = 0, view.xmax = 1, view.ymin = 0, view.ymax = 1, view.znear = 0, view.zfar = 1;
    view.width = 7, view.height = 5;
    view.depth = DepthFormat::float32();
    const std::vector<raster::TraceQuery> answers = {{1, {0, 1}}, {17, {15, 19}}};
    {
        raster::TraceWriter w(dir / "t.trace", {}, {}, {});
        w.beginFrame(4, p, t);
        w.addList(view, list, answers);
        w.beginFrame(5, p, t);
        w.addList(view, list, answers);
        w.finish();
    }
    const raster::TraceReader r(dir / "t.trace");
    ASSERT_EQ(r.listCount(), 2u);
    EXPECT_EQ(r.frameNumber(1), 5u);
    const Json& frames = r.header()["frames"];
    EXPECT_EQ(frames[0]["triangles"], frames[1]["triangles"]);  // one blob
    EXPECT_NE(frames[0]["positions"]["offset"], frames[1]["positions"]["offset"]);
    const raster::TraceList back = r.readList(1);
    ASSERT_EQ(back.commands.commands().size(), list.commands().size());
    for (size_t k = 0; k < list.commands().size(); ++k) {
        const Command &a = list.commands()[k], &b = back.commands.commands()[k];
        EXPECT_EQ(int(a.op), int(b.op)) << k;
        EXPECT_EQ(a.func, b.func) << k;
        EXPECT_EQ(a.mask, b.mask) << k;
        EXPECT_EQ(a.queryKind, b.queryKind) << k;
        EXPECT_EQ(a.clearDepth, b.clearDepth) << k;
        EXPECT_EQ(a.first, b.first) << k;
        EXPECT_EQ(a.count, b.count) << k;
    }
    EXPECT_EQ(back.queries[1].reference, 17u);
    EXPECT_EQ(back.queries[1].interval.possible, 19u);
    EXPECT_EQ(back.view.width, 7);
    EXPECT_EQ(back.view.depth, DepthFormat::float32());
    EXPECT_FALSE(back.view.tiled());
    EXPECT_FALSE(r.header()["frames"][1]["lists"][0]["view"].contains("tile")) << "a whole view reads as before";
    EXPECT_EQ(raster::queryDraws(back.commands, 1), (std::vector<std::pair<uint32_t, uint32_t>>{{0, 2}}));
}

// Trap: a tile's origin and grid (OrthoView::tile) lost in the trace: a replay would draw the
// whole view's corner instead of the tile. Written, read back the same; a tile outside its grid or
// a malformed tile is refused naming the view.
TEST(Trace, TileViewsRoundTrip) {
    TempDir dir;
    const std::vector<Vec3f> p = {{0, 0, 0.1f}, {1, 0, 0.2f}, {0, 1, 0.3f}};
    const std::vector<Triangle> t = {{0, 1, 2}};
    CommandList list;
    list.clear(1.0);
    list.draw(0, 1);
    OrthoView whole;
    whole.xmin = 0, whole.xmax = 1, whole.ymin = 0, whole.ymax = 1, whole.znear = 0, whole.zfar = 1;
    whole.width = 300, whole.height = 200;
    {
        raster::TraceWriter w(dir / "t.trace", {}, {}, {});
        w.beginFrame(0, p, t);
        w.addList(whole.tile(128, 128, 128, 72), list, {});
        w.finish();
    }
    const raster::TraceList back = raster::TraceReader(dir / "t.trace").readList(0);
    EXPECT_EQ(back.view.originX, 128);
    EXPECT_EQ(back.view.originY, 128);
    EXPECT_EQ(back.view.fullWidth(), 300);
    EXPECT_EQ(back.view.fullHeight(), 200);
    EXPECT_EQ(back.view.width, 128);
    EXPECT_EQ(back.view.height, 72);

    const std::string bytes = slurp(dir / "t.trace");
    const Parts good = split(bytes);
    auto edited = [&](const std::function<void(Json&)>& edit) {
        Parts q = good;
        edit(q.header["frames"][0]["lists"][0]["view"]["tile"]);
        return readError(dir, join(q));
    };
    EXPECT_NE(edited([](Json& tile) { tile["origin"][0] = 250; }).find("does not lie inside its"), std::string::npos);
    EXPECT_NE(edited([](Json& tile) { tile["grid"] = "big"; }).find("tile.grid"), std::string::npos);
    EXPECT_NE(edited([](Json& tile) { tile.erase("origin"); }).find("origin"), std::string::npos);
}

// Trap: a trace recorded from the reliable method, whose conservative commands no GPU has.
TEST(Trace, ConservativeCommandsAreRefused) {
    TempDir dir;
    auto cpu = raster::makeCpuBackend();
    raster::TraceWriter writer(dir / "r.trace", {}, {}, {});
    raster::TraceRecorder recorder(*cpu, writer, {});
    CullideOptions o = smallOptions();
    o.method = CullMethod::Reliable;
    EXPECT_THROW(runCullide(smallAnimation().scene, recorder, o), InputError);
}

// Trap: a reader that trusts the preamble, the header or the blobs. Every prefix of a trace (a
// truncated download) is refused with the file named, never read past its end.
TEST(Trace, EveryTruncationIsRefused) {
    TempDir dir;
    recordSmall(dir / "t.trace");
    const std::string bytes = slurp(dir / "t.trace");
    std::mt19937 rng(7);
    std::vector<size_t> cuts = {0, 7, 8, 15, 16, 17, bytes.size() - 1};
    for (int i = 0; i < 60; ++i) cuts.push_back(rng() % bytes.size());
    for (size_t cut : cuts) {
        const std::string what = readError(dir, bytes.substr(0, cut));
        EXPECT_NE(what.find("truncated"), std::string::npos) << cut << ": " << what;
    }
}

// Trap: hand edits a reader must catch, each with its own words.
TEST(Trace, HandEditedTracesAreRefusedWithTheProblemNamed) {
    TempDir dir;
    recordSmall(dir / "t.trace");
    const std::string bytes = slurp(dir / "t.trace");
    const Parts good = split(bytes);
    auto edited = [&](const std::function<void(Parts&)>& edit) {
        Parts p = good;
        edit(p);
        return readError(dir, join(p));
    };
    auto has = [](const std::string& what, const char* words) {
        return what.find(words) != std::string::npos ? ::testing::AssertionSuccess()
                                                     : ::testing::AssertionFailure() << what;
    };
    EXPECT_EQ(readError(dir, join(good)), "");  // the splitting itself is faithful
    EXPECT_TRUE(has(readError(dir, "CULTRACX" + bytes.substr(8)), "not a cullide trace"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header["version"] = 2; }), "newer than this cullide reads"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header["format"] = "other"; }), "not a cullide trace"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header.erase("rules"); }), "has no \"rules\""));
    EXPECT_TRUE(has(edited([](Parts& p) { p.binary += "12345678"; }), "binary section"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header["frames"][0]["positions"]["offset"] = 4; }), "multiple of 8"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header["frames"][0]["positions"]["dtype"] = "<f8"; }), "dtype"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header["frames"][0]["positions"]["shape"][0] = 1u << 30; }),
                    "run past the binary section"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header["frames"][0]["lists"][0]["view"]["viewport"][0] = 0; }), "view"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header["frames"][0]["lists"][0]["view"]["depth"] = "D40"; }), "depth"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header["frames"][0]["lists"][0]["view"]["up"][1] = 2.0; }), "view"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header["rules"]["fill_rule"] = "top-right"; }), "fill_rule"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header["rules"]["fill_rule"] = 1; }), "fill_rule is 1"));
    // A number beyond double's range: the JSON parser's out_of_range, not its parse_error (a fuzz
    // finding: it escaped the reader as an internal error).
    uint64_t headerBytes = 0;
    std::memcpy(&headerBytes, bytes.data() + 8, 8);
    std::string text = bytes.substr(16, headerBytes);
    const size_t at = text.find("\"depth_margin_lsb\": 2.0");
    ASSERT_NE(at, std::string::npos);
    text.replace(at, 23, "\"depth_margin_lsb\": 3e999");
    text.append((8 - (16 + text.size()) % 8) % 8, ' ');
    const uint64_t length = text.size();
    const std::string huge = "CULTRACE" + std::string(reinterpret_cast<const char*>(&length), 8) + text + good.binary;
    EXPECT_TRUE(has(readError(dir, huge), "the header: malformed JSON"));

    // Blob contents: the first list's commands and queries, the first frame's geometry.
    const Json& list0 = good.header["frames"][0]["lists"][0];
    const size_t cmd = list0["commands"]["offset"].get<size_t>(), qry = list0["queries"]["offset"].get<size_t>();
    const size_t tri = good.header["frames"][0]["triangles"]["offset"].get<size_t>();
    const size_t pos = good.header["frames"][0]["positions"]["offset"].get<size_t>();
    auto word = [&](size_t offset, uint32_t value) {
        return [=](Parts& p) { std::memcpy(p.binary.data() + offset, &value, 4); };
    };
    EXPECT_TRUE(has(edited(word(cmd, 9)), "unknown op 9"));
    EXPECT_TRUE(has(edited(word(cmd + 12, 1)), "must be 0"));
    EXPECT_TRUE(has(edited(word(tri, 1u << 31)), "uses vertex"));
    EXPECT_TRUE(has(edited(word(pos, 0x7fc00000u)), "not finite"));
    EXPECT_TRUE(has(edited(word(qry + 8, 0xffffffffu)), "certain"));  // certain > possible
    // The first list: clear, then draws; make the first draw run past the triangles.
    const raster::TraceReader reader(dir / "t.trace");
    const raster::TraceList l0 = reader.readList(0);
    size_t firstDraw = 0, firstBegin = 0, firstEnd = 0;
    for (size_t k = l0.commands.commands().size(); k-- > 0;) {
        const Command::Op op = l0.commands.commands()[k].op;
        if (op == Command::Op::Draw) firstDraw = k;
        if (op == Command::Op::BeginQuery) firstBegin = k;
        if (op == Command::Op::EndQuery) firstEnd = k;
    }
    EXPECT_TRUE(has(edited(word(cmd + 16 * firstDraw + 8, 1u << 30)), "draws triangles"));
    EXPECT_TRUE(has(edited(word(cmd + 16 * firstEnd, 3)), "is open"));  // end -> begin: nested
    EXPECT_TRUE(has(edited(word(cmd + 16 * firstBegin, 4)), "without"));  // begin -> end: unbalanced
}

// Trap: a header whose counts are taken on trust: a trace whose frames were emptied (then every
// one of its zero queries "lies in its interval"), or whose summary or lists were edited, read
// as valid. Each count that disagrees is named, and a trace without frames is refused.
TEST(Trace, SummaryCountsAreCheckedAgainstTheData) {
    TempDir dir;
    recordSmall(dir / "t.trace");
    const Parts good = split(slurp(dir / "t.trace"));
    auto edited = [&](const std::function<void(Parts&)>& edit) {
        Parts p = good;
        edit(p);
        return readError(dir, join(p));
    };
    auto has = [](const std::string& what, const std::string& words) {
        return what.find(words) != std::string::npos ? ::testing::AssertionSuccess()
                                                     : ::testing::AssertionFailure() << what;
    };
    EXPECT_TRUE(
        has(edited([](Parts& p) { p.header["frames"] = Json::array(); }), "summary.frames is 3, but the trace has 0"));
    EXPECT_TRUE(has(edited([](Parts& p) {
                        p.header["frames"] = Json::array();
                        for (auto& [key, count] : p.header["summary"].items()) count = 0;
                    }),
                    "frames is empty"));
    EXPECT_TRUE(has(edited([](Parts& p) { p.header["frames"][1]["lists"].erase(0); }), "summary.lists is"));
    for (const char* key : {"frames", "lists", "commands", "queries", "triangles_drawn"}) {
        EXPECT_TRUE(
            has(edited([&](Parts& p) { p.header["summary"][key] = p.header["summary"][key].get<uint64_t>() + 1; }),
                std::string("summary.") + key + " is "));
        EXPECT_TRUE(has(edited([&](Parts& p) { p.header["summary"].erase(key); }), key));
    }
    EXPECT_TRUE(has(edited([](Parts& p) { p.header.erase("summary"); }), "has no \"summary\""));

    // The command line refuses it before replaying or comparing anything.
    spit(dir / "emptied.trace", join([&] {
             Parts p = good;
             p.header["frames"] = Json::array();
             return p;
         }()));
    const test::CommandRun r =
        test::runCommand(std::string("'") + CULLIDE_CLI_PATH + "' trace replay '" + (dir / "emptied.trace").string() +
                         "' -o '" + (dir / "r.json").string() + "' 2>&1");
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find((dir / "emptied.trace").string() + ": summary.frames is 3"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "r.json"));
}

// Trap: a recording that dies leaving its scratch or a half-written trace beside the output (a
// kill cannot run a destructor): while recording, and after a finish that fails, the folder holds
// nothing the writer made.
TEST(Trace, WriterLeavesNothingBehindWhileWritingOrOnFailure) {
    TempDir dir;
    auto entries = [&] {
        std::vector<std::string> names;
        for (const auto& e : std::filesystem::directory_iterator(dir.path()))
            names.push_back(e.path().filename().string());
        return names;
    };
    const Animation a = smallAnimation();
    {
        auto cpu = raster::makeCpuBackend();
        raster::TraceWriter writer(dir / "t.trace", {}, {}, {});
        raster::TraceRecorder recorder(*cpu, writer, {});
        recorder.setFrame(0);
        runCullide(a.scene, recorder, smallOptions());
        recorder.endFrame();
        EXPECT_EQ(entries(), std::vector<std::string>{}) << "the scratch file has a name while recording";
    }
    EXPECT_EQ(entries(), std::vector<std::string>{});
    // The destination becomes a folder while recording: finish fails naming it, and leaves only
    // that folder. (One that is a folder from the start is refused before any work.)
    {
        auto cpu = raster::makeCpuBackend();
        raster::TraceWriter writer(dir / "t.trace", {}, {}, {});
        raster::TraceRecorder recorder(*cpu, writer, {});
        runCullide(a.scene, recorder, smallOptions());
        std::filesystem::create_directory(dir / "t.trace");
        try {
            recorder.finish();
            ADD_FAILURE() << "finished into a folder";
        } catch (const InputError& e) {
            EXPECT_EQ(e.source(), (dir / "t.trace").string()) << e.what();
        }
    }
    EXPECT_EQ(entries(), std::vector<std::string>{"t.trace"});
    EXPECT_TRUE(std::filesystem::is_directory(dir / "t.trace"));
    EXPECT_THROW(raster::TraceWriter(dir / "t.trace", {}, {}, {}), InputError);
    // A missing folder: named, nothing created.
    EXPECT_THROW(raster::TraceWriter(dir / "no" / "t.trace", {}, {}, {}), InputError);
}

// Trap: a crash, a hang or an exception other than InputError on arbitrary damage (the fuzz
// harness's idea, tests/fuzz/trace_fuzz.cpp, as a fixed-seed slice in every run).
TEST(Trace, MutatedTracesLoadOrThrowInputErrorNeverCrash) {
    TempDir dir;
    recordSmall(dir / "t.trace");
    const std::string original = slurp(dir / "t.trace");
    std::mt19937 rng(424242);
    size_t loaded = 0, refused = 0;
    for (int i = 0; i < 300; ++i) {
        std::string s = original;
        const int edits = 1 + int(rng() % 3);
        for (int e = 0; e < edits && !s.empty(); ++e) {
            const size_t at = rng() % s.size();
            switch (rng() % 3) {
                case 0: s[at] = char(s[at] ^ (1 << (rng() % 8))); break;
                case 1: s[at] = char("0123456789\"[]{},:-.e"[rng() % 20]); break;
                case 2: s[at] = char(rng() & 0xff); break;
            }
        }
        const auto path = dir / "m.trace";
        spit(path, s);
        try {
            readAll(path);
            ++loaded;
        } catch (const InputError& e) {
            EXPECT_EQ(e.source(), path.string()) << e.what();
            ++refused;
        }
    }
    EXPECT_EQ(loaded + refused, 300u);
    EXPECT_GT(refused, 100u);
}

// Trap: results of another trace, or hand-written results, judged without a shape check; a
// moved count not reported as outside with its list and query.
TEST(Trace, CompareChecksTheShapeAndFindsAMovedCount) {
    TempDir dir;
    recordSmall(dir / "t.trace");
    const raster::TraceReader trace(dir / "t.trace");
    auto cpu = raster::makeCpuBackend();
    raster::TraceResults results{"cpu", raster::replayTrace(trace, *cpu)};
    raster::writeTraceResults(dir / "r.json", results, "t.trace", {{"cullide_version", "test"}});
    const raster::TraceResults back = raster::readTraceResults(dir / "r.json");
    EXPECT_EQ(back.results, results.results);
    EXPECT_EQ(back.backend, "cpu");

    raster::TraceResults shorter = results;
    shorter.results.pop_back();
    EXPECT_THROW(raster::compareTrace(trace, shorter, "r.json"), InputError);
    raster::TraceResults extra = results;
    extra.results[2].push_back(0);
    try {
        raster::compareTrace(trace, extra, "r.json");
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("list 2 has"), std::string::npos) << e.what();
    }

    // Move one samples count past its interval.
    const auto [list, query] = firstSamplesQuery(trace, 0);
    ASSERT_NE(list, SIZE_MAX);
    raster::TraceResults moved = results;
    moved.results[list][query] = trace.readList(list).queries[query].interval.possible + 5;
    const raster::TraceComparison c = raster::compareTrace(trace, moved, "r.json");
    EXPECT_FALSE(c.passed());
    EXPECT_EQ(c.all.queries - c.all.inside, 1u);
    const std::vector<size_t> worst = raster::worstQueries(c.queries, 3);
    ASSERT_FALSE(worst.empty());
    EXPECT_EQ(c.queries[worst[0]].list, list);
    EXPECT_EQ(c.queries[worst[0]].query, query);
    EXPECT_EQ(c.queries[worst[0]].outside(), 5u);

    // Malformed results files.
    for (const char* text : {"[1, 2]", "{\"results\": [[1]]}", "{\"backend\": \"x\", \"results\": [[1, -2]]}",
                             "{\"backend\": \"x\", \"results\": [[1.5]]}", "{\"backend\": \"x\", \"results\": [3]}",
                             "{\"backend\": \"x\", \"results\": [[1]"}) {
        spit(dir / "bad.json", text);
        EXPECT_THROW(raster::readTraceResults(dir / "bad.json"), InputError) << text;
    }
}

// ---------------------------------------------------------------------------------------------
// The command line: record, replay, compare, and the independent Python reader.

using CliRun = test::CommandRun;
const auto run = test::runCommand;

std::string cli(const std::string& args) {
    return std::string("'") + CULLIDE_CLI_PATH + "' " + args;
}

std::string q(const std::filesystem::path& p) {
    std::string s(1, '\'');  // (not "'" + ...: GCC 12's -Wrestrict false positive)
    s += p.string();
    s += '\'';
    return s;
}

// Trap: a trace a third party cannot use: the numpy reader (no cullide code) reads what `record`
// wrote and its answers pass `compare`; one count moved outside its interval fails it, naming
// the query; the cpu replay is 100 % exact.
TEST(TraceCli, RecordReplayCompareAndThePythonReader) {
    TempDir dir;
    const std::string scene = std::string(CULLIDE_DATA_DIR) + "/scenes/bunny_through_cow.json";
    CliRun r = run(cli("trace record '" + scene + "' --resolution 96 -o " + q(dir / "t.trace")));
    ASSERT_EQ(r.status, 0) << r.output;
    r = run(cli("trace record '" + scene + "' --resolution 96 -o " + q(dir / "again.trace")));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(slurp(dir / "t.trace"), slurp(dir / "again.trace"));  // same input and options, same bytes
    r = run(cli("trace replay " + q(dir / "t.trace") + " --backend cpu -o " + q(dir / "cpu.json")));
    ASSERT_EQ(r.status, 0) << r.output;
    r = run(cli("trace compare " + q(dir / "t.trace") + " " + q(dir / "cpu.json") + " --json " + q(dir / "v.json")));
    EXPECT_EQ(r.status, 0) << r.output;
    const Json verdict = Json::parse(slurp(dir / "v.json"));
    EXPECT_EQ(verdict["exact_rate"], 1.0);
    EXPECT_TRUE(verdict["passed"].get<bool>());
    EXPECT_TRUE(verdict.contains("provenance"));

    r = run("/usr/bin/python3 '" + std::string(CULLIDE_SOURCE_DIR) + "/tools/trace/replay_reference.py' " +
            q(dir / "t.trace") + " -o " + q(dir / "py.json"));
    ASSERT_EQ(r.status, 0) << r.output;
    r = run(cli("trace compare " + q(dir / "t.trace") + " " + q(dir / "py.json")));
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("exact"), std::string::npos) << r.output;

    Json moved = Json::parse(slurp(dir / "py.json"));
    const raster::TraceReader trace(dir / "t.trace");
    const auto [list, query] = firstSamplesQuery(trace, 3);
    ASSERT_NE(list, SIZE_MAX);
    moved["results"][list][query] = trace.readList(list).queries[query].interval.certain - 1;
    spit(dir / "moved.json", moved.dump());
    r = run(cli("trace compare " + q(dir / "t.trace") + " " + q(dir / "moved.json")));
    EXPECT_EQ(r.status, 1) << r.output;
    const std::string name = "list " + std::to_string(list) + " query " + std::to_string(query);
    EXPECT_NE(r.output.find(name), std::string::npos) << name << "\n" << r.output;
    EXPECT_NE(r.output.find("OUTSIDE by 1"), std::string::npos) << r.output;

    // Shape errors and bad files: exit 2 with the file named.
    Json shorter = Json::parse(slurp(dir / "py.json"));
    shorter["results"].erase(shorter["results"].size() - 1);
    spit(dir / "short.json", shorter.dump());
    r = run(cli("trace compare " + q(dir / "t.trace") + " " + q(dir / "short.json")));
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find((dir / "short.json").string()), std::string::npos) << r.output;
    r = run(cli("trace replay " + q(dir / "py.json") + " -o " + q(dir / "x.json")));
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("not a cullide trace"), std::string::npos) << r.output;
    r = run(cli("trace record '" + scene + "' --method reliable -o " + q(dir / "r.trace")));
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "r.trace"));
}

// Trap: GL replay through the trace losing what `validate` checked before: every query of the
// bundled scene in its interval on the GL (llvmpipe in CI). One frame, the bunny inside the cow
// (frame 4, the most queries of the nine): all nine took 230 s of the ThreadSanitizer stage, and
// RecordReplayCompareAndThePythonReader covers traces of many frames on the CPU.
TEST(TraceCli, GlReplayIsInsideEveryInterval) {
    std::string why;
    if (!raster::glBackendAvailable(&why)) {
        if (std::getenv("CULLIDE_REQUIRE_GL") && raster::glBuilt()) FAIL() << "no GL: " << why;
        GTEST_SKIP() << "no GL context: " << why;
    }
    TempDir dir;
    const std::string scene = std::string(CULLIDE_DATA_DIR) + "/scenes/bunny_through_cow.json";
    CliRun r = run(cli("trace record '" + scene + "' --resolution 128 --frame 4 -o " + q(dir / "t.trace")));
    ASSERT_EQ(r.status, 0) << r.output;
    r = run(cli("trace replay " + q(dir / "t.trace") + " --backend gl -o " + q(dir / "gl.json")));
    ASSERT_EQ(r.status, 0) << r.output;
    r = run(cli("trace compare " + q(dir / "t.trace") + " " + q(dir / "gl.json") + " --json " + q(dir / "v.json")));
    EXPECT_EQ(r.status, 0) << r.output;
    const Json v = Json::parse(slurp(dir / "v.json"));
    EXPECT_EQ(v["in_interval_rate"], 1.0);
    EXPECT_NE(v["backend"].get<std::string>().find("gl"), std::string::npos);
}

}  // namespace
}  // namespace cullide
