// The `cullide` command, run as a user runs it: exit codes, messages, bytes written.
#include "test_util.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <tbb/info.h>

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <unistd.h>
#include <vector>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

using CliRun = cullide::test::CommandRun;

std::string quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

CliRun runCli(const std::string& args) {
    return cullide::test::runCommand(quote(CULLIDE_CLI_PATH) + " " + args);
}

std::string readAll(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

// Every regular file under `dir`, in sorted path order, concatenated with its relative path.
std::string readTree(const fs::path& dir) {
    std::vector<fs::path> files;
    for (const auto& e : fs::recursive_directory_iterator(dir))
        if (e.is_regular_file()) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    std::string all;
    for (const fs::path& f : files) all += fs::relative(f, dir).string() + "\n" + readAll(f);
    return all;
}

// A folder of its own under this process's temporary folder, which goes when the process ends
// (one test process per case under ctest: a folder left per process adds up).
fs::path freshDir(const std::string& name) {
    static const cullide::test::TempDir root;
    fs::path d = root / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

const std::string kData = CULLIDE_DATA_DIR;

}  // namespace

// The acceptance figure: CGAL's cow has 5,804 triangles; also checks the JSON is parseable and
// that the text and JSON forms agree.
TEST(Cli, InfoReportsCowTriangles) {
    const CliRun text = runCli("info " + quote(kData + "/meshes/cow.off"));
    ASSERT_EQ(text.status, 0) << text.output;
    EXPECT_NE(text.output.find("triangles 5804"), std::string::npos) << text.output;

    const CliRun json = runCli("info --json " + quote(kData + "/meshes/cow.off"));
    ASSERT_EQ(json.status, 0) << json.output;
    const auto j = nlohmann::json::parse(json.output);
    EXPECT_EQ(j.at(0).at("total").at("triangles").get<size_t>(), 5804u);
    EXPECT_EQ(j.at(0).at("total").at("vertices").get<size_t>(), 2904u);
}

// Every bundled scene and mesh loads (a scene whose relative mesh paths break, or a data file
// that stops parsing, fails here).
TEST(Cli, InfoOnEveryBundledScene) {
    for (const char* dir : {"scenes", "meshes"})
        for (const auto& e : fs::directory_iterator(kData + "/" + dir)) {
            const CliRun r = runCli("info " + quote(e.path().string()));
            EXPECT_EQ(r.status, 0) << e.path() << ": " << r.output;
        }
}

// Every malformed input under tests/data/bad is refused with exit status 2 and a message that
// names the file, never a crash (a signal gives status >= 128) or a silent success.
TEST(Cli, InfoRefusesEveryBadFile) {
    size_t n = 0;
    for (const auto& e : fs::directory_iterator(fs::path(CULLIDE_TEST_DATA_DIR) / "bad")) {
        const std::string path = e.path().string();
        const CliRun r = runCli("info " + quote(path));
        EXPECT_EQ(r.status, 2) << path << ": " << r.output;
        // Scenes that refer to a broken mesh name that mesh; either way the user sees the path.
        EXPECT_NE(r.output.find(e.path().filename().string()), std::string::npos) << path << ": " << r.output;
        EXPECT_NE(r.output.find("error"), std::string::npos) << r.output;
        ++n;
    }
    EXPECT_GT(n, 10u) << "expected the bad-input corpus under tests/data/bad";
}

// A file that does not exist: the commonest mistake, and the message must say so.
TEST(Cli, InfoMissingFile) {
    const CliRun r = runCli("info /nonexistent/dir/none.off");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("/nonexistent/dir/none.off"), std::string::npos) << r.output;
}

// Absurd option values are refused by name, before any work is done.
TEST(Cli, AbsurdOptionsAreRefused) {
    const fs::path d = freshDir("absurd");
    const std::string out = quote((d / "s.json").string());
    const std::pair<std::string, std::string> cases[] = {
        {"make-scene bunny --triangles 0 -o " + out, "--triangles"},
        {"make-scene bunny --triangles 99999999999 -o " + out, "--triangles"},
        {"make-scene bunny --triangles -5 -o " + out, "--triangles"},
        {"make-scene bunny --frames 100000 -o " + out, "--frames"},
        {"make-scene cylinders --count 0 -o " + out, "--count"},
        {"make-scene teapot -o " + out, "teapot"},
        {"make-scene bunny -o " + quote((d / "s.txt").string()), "--out"},
        {"info --frame -1 " + quote(kData + "/meshes/cow.off"), "--frame"},
        {"info --frame 7 " + quote(kData + "/meshes/cow.off"), "--frame"},
        {"info", "paths"},
        {"frobnicate", "frobnicate"},
    };
    for (const auto& [args, needle] : cases) {
        const CliRun r = runCli(args);
        EXPECT_EQ(r.status, 2) << args << ": " << r.output;
        EXPECT_NE(r.output.find(needle), std::string::npos) << args << ": " << r.output;
    }
    EXPECT_FALSE(fs::exists(d / "s.json")) << "a refused command wrote its output";
}

// Same kind, options and seed: the same bytes in every file written (the generators use no
// unordered containers, threads or implementation-defined distributions). A different seed
// changes the randomized scene.
TEST(Cli, MakeSceneIsByteReproducible) {
    for (const std::string kind : {"bunny", "cows", "cylinders", "twist"}) {
        const fs::path a = freshDir(kind + "_a"), b = freshDir(kind + "_b");
        const std::string opts =
            std::string(" --triangles 3000 --frames 2") + (kind == "cylinders" ? " --count 10 --seed 7" : "") + " -o ";
        ASSERT_EQ(runCli("make-scene " + kind + opts + quote((a / "s.json").string())).status, 0);
        ASSERT_EQ(runCli("make-scene " + kind + opts + quote((b / "s.json").string())).status, 0);
        size_t files = 0;
        for (const auto& e : fs::recursive_directory_iterator(a)) {
            if (!e.is_regular_file()) continue;
            const fs::path other = b / fs::relative(e.path(), a);
            ASSERT_TRUE(fs::exists(other)) << other;
            EXPECT_EQ(readAll(e.path()), readAll(other)) << "differs: " << e.path();
            ++files;
        }
        EXPECT_GE(files, 2u) << kind;
        const CliRun info = runCli("info " + quote((a / "s.json").string()));
        EXPECT_EQ(info.status, 0) << info.output;
    }
    const fs::path c = freshDir("cyl_c"), d = freshDir("cyl_d");
    ASSERT_EQ(runCli("make-scene cylinders --count 10 --seed 1 -o " + quote((c / "s.json").string())).status, 0);
    ASSERT_EQ(runCli("make-scene cylinders --count 10 --seed 2 -o " + quote((d / "s.json").string())).status, 0);
    EXPECT_NE(readTree(c), readTree(d)) << "seeds 1 and 2 gave the same cylinders";
}

// A generator whose input is bad fails before writing: nothing half-written is left behind.
TEST(Cli, MakeSceneWithBadMeshWritesNothing) {
    const fs::path d = freshDir("badmesh");
    const CliRun r = runCli("make-scene bunny --mesh /nonexistent.off -o " + quote((d / "s.json").string()));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("/nonexistent.off"), std::string::npos) << r.output;
    EXPECT_TRUE(fs::is_empty(d)) << "files were written although the input was bad";
}

// Every prune option's absurd values are refused by name before any work, exit status 2.
TEST(Cli, PruneRefusesBadOptions) {
    const std::string scene = quote(kData + "/meshes/cow.off");
    const std::pair<std::string, std::string> cases[] = {
        {"--resolution 0", "--resolution"},
        {"--resolution 20000", "--resolution"},
        {"--resolution 10x", "--resolution"},
        {"--resolution axb", "--resolution"},
        {"--depth 7", "--depth"},
        {"--depth 33", "--depth"},
        {"--depth half", "--depth"},
        {"--directions '0 0 0'", "--directions"},
        {"--directions x,w", "--directions"},
        {"--directions 0", "--directions"},
        {"--method reliable-ish", "--method"},
        {"--hierarchy octree", "--hierarchy"},
        {"--views clusters", "--views"},
        {"--leaf-size 0", "--leaf-size"},
        {"--branching 1", "--branching"},
        {"--threads -1", "--threads"},
        {"--frame 3", "--frame"},
        {"--backend metal", "--backend"},
        {"--max-viewport 0", "--max-viewport"},
        {"--max-viewport 20000", "--max-viewport"},
    };
    for (const auto& [args, needle] : cases) {
        const CliRun r = runCli("prune " + scene + " " + args);
        EXPECT_EQ(r.status, 2) << args << ": " << r.output;
        EXPECT_NE(r.output.find(needle), std::string::npos) << args << ": " << r.output;
    }
}

// The same bad value gets the same message from every command, under the name the user typed:
// `prune --depth`, `study --depths`, a spec's key `depths` (issue 12: the study once said only
// "depth format: ...", naming no option).
TEST(Cli, BadDepthSameMessageFromEveryCommand) {
    const fs::path d = freshDir("same_message");
    std::ofstream(d / "spec.json") << R"({"scenes": ["bunny:500"], "depths": [7]})";
    const CliRun prune = runCli("prune " + quote(kData + "/meshes/cow.off") + " --depth 7");
    const CliRun study = runCli("study --scenes bunny:500 --depths 7 -q -o " + quote((d / "a.csv").string()));
    const CliRun spec =
        runCli("study " + quote((d / "spec.json").string()) + " -q -o " + quote((d / "b.csv").string()));
    // The message after `name: `, to the end of its line ("" when the name is not there).
    auto cause = [](const CliRun& r, const std::string& name) {
        const size_t at = r.output.find(name + ": ");
        if (at == std::string::npos) return std::string();
        const size_t from = at + name.size() + 2;
        return r.output.substr(from, r.output.find('\n', from) - from);
    };
    for (const CliRun* r : {&prune, &study, &spec}) EXPECT_EQ(r->status, 2) << r->output;
    const std::string expected = cause(prune, "option --depth");
    EXPECT_NE(expected.find("8 to 32"), std::string::npos) << prune.output;
    EXPECT_EQ(cause(study, "option --depths"), expected) << study.output;
    EXPECT_EQ(cause(spec, "field 'depths'"), expected) << spec.output;
    EXPECT_FALSE(fs::exists(d / "a.csv") || fs::exists(d / "b.csv")) << "a refused study wrote its output";
}

// A number too large for a double in a study spec (found by fuzzing the trace reader, which shares
// the JSON parser): nlohmann throws out_of_range, not parse_error; it once escaped as an internal
// error (exit 70).
TEST(Cli, StudySpecWithAnOverflowingNumberIsBadInput) {
    const fs::path d = freshDir("spec_overflow");
    std::ofstream(d / "spec.json") << R"({"scenes": [1e99999]})";
    const CliRun r = runCli("study " + quote((d / "spec.json").string()) + " -q -o " + quote((d / "s.csv").string()));
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find((d / "spec.json").string() + ": not JSON"), std::string::npos) << r.output;
}

// prune --json: the PCS as sorted [object, triangle] pairs inside the scene, per-pass statistics
// whose triangle counts chain (each call's output is the next call's input within a level), and
// the same PCS for 1 and 2 threads; --out writes a PLY with one colour per face.
TEST(Cli, PruneJsonAndPly) {
    const fs::path d = freshDir("prune");
    const std::string scene = quote(kData + "/scenes/bunny_through_cow.json");
    std::string pcs[2];
    for (int threads : {1, 2}) {
        const std::string json = (d / ("pcs" + std::to_string(threads) + ".json")).string();
        const CliRun r = runCli("prune " + scene + " --frame 4 --resolution 200 --threads " + std::to_string(threads) +
                                " --json " + quote(json) + " --out " + quote((d / "pcs.ply").string()));
        ASSERT_EQ(r.status, 0) << r.output;
        const auto j = nlohmann::json::parse(readAll(json));
        const auto& frame = j.at("frames").at(0);
        EXPECT_EQ(frame.at("frame").get<int>(), 4);
        const auto& list = frame.at("pcs");
        ASSERT_GT(list.size(), 0u) << "the bunny crosses the cow in frame 4";
        std::vector<std::pair<uint32_t, uint32_t>> pairs;
        for (const auto& p : list) pairs.push_back({p.at(0).get<uint32_t>(), p.at(1).get<uint32_t>()});
        EXPECT_TRUE(std::is_sorted(pairs.begin(), pairs.end()));
        EXPECT_LT(pairs.back().first, 2u);
        const auto& passes = frame.at("passes");
        ASSERT_GT(passes.size(), 1u);
        for (size_t i = 1; i < passes.size(); ++i)
            if (passes[i].at("level") == passes[i - 1].at("level")) {
                EXPECT_EQ(passes[i].at("triangles_in"), passes[i - 1].at("triangles_out"));
            }
        EXPECT_EQ(passes.back().at("triangles_out").get<size_t>(), list.size());
        pcs[threads - 1] = list.dump();
    }
    EXPECT_EQ(pcs[0], pcs[1]) << "PCS differs between 1 and 2 threads";
    const std::string ply = readAll(d / "pcs.ply");
    EXPECT_EQ(ply.rfind("ply\n", 0), 0u);
    EXPECT_NE(ply.find("property uchar red"), std::string::npos);
}

// --views (docs/cullide.md#views-per-cluster). Traps: a default run whose JSON changes (fit records
// no "views", as before the option), a clustered run that does not say so in its options and per
// call, and a study that drops the axis from its CSV (the ids: Study.RunIdsAreStableAndDistinct).
TEST(Cli, ViewsInPruneJsonAndStudy) {
    const fs::path d = freshDir("views");
    const std::string scene = quote(kData + "/scenes/two_cows_and_bunny.json");
    for (const char* views : {"fit", "clustered"}) {
        const std::string json = (d / (std::string(views) + ".json")).string();
        const CliRun r = runCli("prune " + scene + " --resolution 64 --views " + views + " --json " + quote(json));
        ASSERT_EQ(r.status, 0) << r.output;
        const auto j = nlohmann::json::parse(readAll(json));
        const bool clustered = std::string(views) == "clustered";
        EXPECT_EQ(j.at("options").contains("views"), clustered) << views;
        if (clustered) {
            EXPECT_EQ(j["options"]["views"], "clustered");
        }
        size_t most = 0;
        for (const auto& p : j.at("frames").at(0).at("passes")) {
            EXPECT_EQ(p.contains("views"), clustered) << views;
            if (clustered) most = std::max(most, p.at("views").get<size_t>());
        }
        if (clustered) {
            EXPECT_GT(most, 1u) << "the two cows and the bunny's contacts should split";
        }
    }
    const std::string csv = (d / "s.csv").string();
    const CliRun st = runCli(
        "study --scenes cows:600 --resolutions 64 --views fit clustered --repeats 1 --no-oracle -q -o " + quote(csv));
    ASSERT_EQ(st.status, 0) << st.output;
    const std::string text = readAll(csv);
    EXPECT_NE(text.find(",views,"), std::string::npos) << text;
    EXPECT_NE(text.find(",fit,"), std::string::npos) << text;
    EXPECT_NE(text.find(",clustered,"), std::string::npos) << text;
}

// --max-viewport: the run drawn as on a backend with a smaller viewport limit. Traps: an option that
// clamps the resolution instead of tiling (a different PCS), or tiles that are not recorded.
TEST(Cli, PruneMaxViewportTilesWithTheSamePcs) {
    const fs::path d = freshDir("max-viewport");
    const std::string scene = quote(kData + "/scenes/two_cows_and_bunny.json");
    std::string pcs[2];
    size_t tiled = 0;
    for (int limited : {0, 1}) {
        const std::string json = (d / ("pcs" + std::to_string(limited) + ".json")).string();
        const CliRun r = runCli("prune " + scene + " --resolution 600 --json " + quote(json) +
                                (limited ? " --max-viewport 256" : ""));
        ASSERT_EQ(r.status, 0) << r.output;
        const auto j = nlohmann::json::parse(readAll(json));
        pcs[limited] = j.at("frames").at(0).at("pcs").dump();
        for (const auto& p : j.at("frames").at(0).at("passes")) {
            EXPECT_EQ(p.at("width"), 600);
            if (p.contains("tiles")) tiled += p.at("tiles").get<size_t>() > 1 ? 1 : 0;
        }
        if (limited) {
            EXPECT_NE(r.output.find("at most 256 px per side"), std::string::npos) << r.output;
        }
    }
    EXPECT_EQ(pcs[0], pcs[1]);
    EXPECT_GT(tiled, 0u) << "no call records its tiles";
}

// Trap: prune gives a still scene up to the run (emptied once uploaded) when nothing reads it
// afterwards, but --exact-switch auto's cost model calibrates on that scene during the run: on
// the emptied scene it would predict an exact stage of 0 ms and always switch. The prediction
// printed without --exact must be that of a run with it (a real, non-zero cost).
TEST(Cli, PruneAutoSwitchCalibratesOnTheWholeScene) {
    const CliRun r = runCli("prune " + quote(kData + "/scenes/two_cows_and_bunny.json") + " --exact-switch auto");
    ASSERT_EQ(r.status, 0) << r.output;
    const size_t at = r.output.find("exact stage ");
    ASSERT_NE(at, std::string::npos) << r.output;
    EXPECT_GT(std::stod(r.output.substr(at + 12)), 0.0) << r.output;
}

// prune over every frame keeps each object's hierarchy while its triangles are unchanged, and
// --rebuild-hierarchy builds them every frame as the paper does. Traps: a reused hierarchy that
// changes the PCS or a pass; a cache that never reuses (hierarchies_reused stays 0).
TEST(Cli, PruneReusesHierarchiesAcrossFrames) {
    const fs::path d = freshDir("prune-reuse");
    const std::string scene = quote(kData + "/scenes/bunny_through_cow.json");
    nlohmann::json runs[2];
    const char* modes[2] = {"", " --rebuild-hierarchy"};
    for (int k = 0; k < 2; ++k) {
        std::string json = (d / ("run" + std::to_string(k) + ".json")).string();
        std::string command = "prune " + scene + " --resolution 128 --json ";
        command += quote(json);
        command += modes[k];
        const CliRun r = runCli(command);
        ASSERT_EQ(r.status, 0) << r.output;
        runs[k] = nlohmann::json::parse(readAll(json));
        if (k == 0) EXPECT_NE(r.output.find("(reused)"), std::string::npos) << r.output;
        else EXPECT_EQ(r.output.find("reused"), std::string::npos) << r.output;
    }
    const auto& reused = runs[0].at("frames");
    const auto& rebuilt = runs[1].at("frames");
    ASSERT_EQ(reused.size(), rebuilt.size());
    ASSERT_GT(reused.size(), 1u);
    for (size_t f = 0; f < reused.size(); ++f) {
        EXPECT_EQ(reused[f].at("pcs"), rebuilt[f].at("pcs")) << "frame " << f;
        ASSERT_EQ(reused[f].at("passes").size(), rebuilt[f].at("passes").size());
        for (size_t p = 0; p < reused[f].at("passes").size(); ++p)
            EXPECT_EQ(reused[f].at("passes")[p].at("triangles_out"), rebuilt[f].at("passes")[p].at("triangles_out"));
        EXPECT_EQ(reused[f].at("hierarchies_reused").get<int>(), f == 0 ? 0 : 2) << "two objects, frame " << f;
        EXPECT_EQ(rebuilt[f].at("hierarchies_reused").get<int>(), 0);
    }
}

// A valid spec mutated field by field (wrong type, empty list, huge and negative numbers) and an
// unknown field: every one is refused with exit status 2 and a message naming the field, before
// anything runs, never by a signal (the issue's `"branching": []` once ended in an uncaught
// std::out_of_range, status 134).
TEST(Cli, StudySpecMutationsAreRefusedByName) {
    const fs::path d = freshDir("spec");
    const nlohmann::json valid = nlohmann::json::parse(R"({"scenes": ["bunny:500"], "methods": ["modified"],
        "resolutions": [64], "depths": [16], "directions": ["axes"], "views": ["fit"], "hierarchies": ["connectivity"],
        "leaf_sizes": [16], "backends": ["cpu"], "threads": [1], "branching": 4, "seed": 1, "repeats": 1,
        "oracle": false})");
    auto run = [&](const nlohmann::json& spec) {
        const fs::path file = d / "spec.json";
        std::ofstream(file) << spec.dump();
        return runCli("study " + quote(file.string()) + " -q -o " + quote((d / "out.csv").string()));
    };
    const CliRun ok = run(valid);
    ASSERT_EQ(ok.status, 0) << ok.output;

    const nlohmann::json huge = nlohmann::json::parse("18446744073709551616");  // beyond uint64: a float
    const std::vector<nlohmann::json> mutations = {nlohmann::json::object({{"a", 1}}),
                                                   nlohmann::json::array(),
                                                   nlohmann::json::array({nlohmann::json::array()}),
                                                   true,
                                                   2.5,
                                                   -1,
                                                   4294967297LL,
                                                   1e300,
                                                   huge,
                                                   ""};
    size_t refused = 0;
    for (const auto& [key, value] : valid.items()) {
        for (const nlohmann::json& m : mutations) {
            if (m == value) continue;
            if (key == "seed" && m == 4294967297LL) continue;  // a valid seed
            if (key == "oracle" && m.is_boolean()) continue;
            nlohmann::json spec = valid;
            spec[key] = m;
            const CliRun r = run(spec);
            EXPECT_EQ(r.status, 2) << key << " = " << m.dump() << ": " << r.output;
            EXPECT_NE(r.output.find("'" + key + "'"), std::string::npos)
                << key << " = " << m.dump() << ": " << r.output;
            ++refused;
        }
    }
    EXPECT_GT(refused, 100u);
    nlohmann::json unknown = valid;
    unknown["branchng"] = 4;
    const CliRun u = run(unknown);
    EXPECT_EQ(u.status, 2) << u.output;
    EXPECT_NE(u.output.find("'branchng'"), std::string::npos) << u.output;

    const CliRun issue = run(nlohmann::json::parse(R"({"scenes":["bunny:500"],"branching":[]})"));
    EXPECT_EQ(issue.status, 2) << issue.output;
    EXPECT_NE(issue.output.find("branching"), std::string::npos) << issue.output;
}

// An option that does not apply to the kind, hierarchy, backend or mode is refused by name, never
// silently ignored; --triangles for 'twist' resamples the source mesh, as the study's twist:N.
TEST(Cli, OptionsThatDoNotApplyAreRefused) {
    const fs::path d = freshDir("inapplicable");
    const std::string out = quote((d / "s.json").string());
    const std::string cow = quote(kData + "/meshes/cow.off");
    const std::pair<std::string, std::string> cases[] = {
        {"make-scene bunny --count 5 -o " + out, "--count"},
        {"make-scene twist --seed 2 -o " + out, "--seed"},
        {"make-scene cows --seed 1 -o " + out, "--seed"},
        {"make-scene cylinders --mesh " + cow + " -o " + out, "--mesh"},
        {"prune " + cow + " --seed 3", "--seed"},
        {"prune " + cow + " --backend gl --threads 2", "--threads"},
        {"study --stability tilt --repeats 2 -o " + quote((d / "t.csv").string()), "--repeats"},
        {"study --stability penetration --scenes bunny:500 -o " + quote((d / "t.csv").string()), "--scenes"},
        {"study --scenes bunny:500 --trials 3 -o " + quote((d / "t.csv").string()), "--trials"},
    };
    for (const auto& [args, needle] : cases) {
        const CliRun r = runCli(args);
        EXPECT_EQ(r.status, 2) << args << ": " << r.output;
        EXPECT_NE(r.output.find(needle), std::string::npos) << args << ": " << r.output;
    }
    EXPECT_TRUE(fs::is_empty(d)) << "a refused command wrote its output";

    const CliRun twist = runCli("make-scene twist --triangles 20000 -o " + out);
    ASSERT_EQ(twist.status, 0) << twist.output;
    // "<path>: 1 object(s), N triangles, ...": about the request, not the source's 3,674.
    const size_t at = twist.output.find(" triangles,");
    ASSERT_NE(at, std::string::npos) << twist.output;
    const size_t from = twist.output.rfind(' ', at - 1);
    EXPECT_NEAR(std::stod(twist.output.substr(from + 1, at - from - 1)), 20000.0, 1000.0) << twist.output;
}

// Writing into a folder that does not exist says so, naming the folder; nothing is created.
TEST(Cli, MissingOutputFolderIsNamed) {
    const fs::path missing = freshDir("nofolder") / "not_there";
    const std::string cow = quote(kData + "/meshes/cow.off");
    for (const std::string& args : {"prune " + cow + " --resolution 64 --json " + quote((missing / "p.json").string()),
                                    "oracle " + cow + " --json " + quote((missing / "o.json").string()),
                                    "make-scene cylinders --count 2 -o " + quote((missing / "s.json").string())}) {
        const CliRun r = runCli(args);
        EXPECT_EQ(r.status, 2) << args << ": " << r.output;
        EXPECT_NE(r.output.find("folder " + missing.string() + " does not exist"), std::string::npos)
            << args << ": " << r.output;
    }
    EXPECT_FALSE(fs::exists(missing));
}

// Every JSON output carries the provenance of its run (cullide/provenance.h), with the thread
// count the command was given, the build's commit and no drivers for the CPU backend; the study
// puts it in each JSON line but not in its CSV, whose columns stay as they were. Trap: a command
// that writes threads 0 for "--threads 1", drops the key, or writes a commit other than the one
// --version says.
TEST(Cli, JsonOutputsCarryProvenance) {
    const fs::path d = freshDir("provenance");
    const std::string scene = quote(kData + "/scenes/bunny_through_cow.json");
    const std::regex date(R"(\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}Z)");
    // The commit as `cullide --version` says it: "cullide 0.2.0 (commit <hash>; Embree ...)".
    const CliRun v = runCli("--version");
    ASSERT_EQ(v.status, 0) << v.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(v.output, m, std::regex(R"(^cullide (\S+) \(commit ([^;]+);)"))) << v.output;
    EXPECT_EQ(m[1].str(), CULLIDE_EXPECTED_VERSION) << v.output;
    const std::string commit = m[2].str();
    auto check = [&](const nlohmann::json& p, int threads, const std::string& what) {
        EXPECT_EQ(p.at("cullide_version").get<std::string>(), CULLIDE_EXPECTED_VERSION) << what;
        EXPECT_EQ(p.at("git_commit").get<std::string>(), commit) << what;
        EXPECT_FALSE(p.at("compiler").get<std::string>().empty()) << what;
        EXPECT_FALSE(p.at("cpu_model").get<std::string>().empty()) << what;
        EXPECT_EQ(p.at("threads").get<int>(), threads) << what;
        EXPECT_TRUE(std::regex_match(p.at("date").get<std::string>(), date)) << what;
        EXPECT_FALSE(p.contains("drivers")) << what << ": the CPU backend has no driver";
    };
    const std::string prune = (d / "prune.json").string(), oracle = (d / "oracle.json").string();
    CliRun r = runCli("prune " + scene + " --frame 4 --resolution 64 --threads 1 --json " + quote(prune));
    ASSERT_EQ(r.status, 0) << r.output;
    check(nlohmann::json::parse(readAll(prune)).at("provenance"), 1, "prune --json");
    r = runCli("oracle " + scene + " --frame 4 --threads 1 --json " + quote(oracle));
    ASSERT_EQ(r.status, 0) << r.output;
    check(nlohmann::json::parse(readAll(oracle)).at("provenance"), 1, "oracle --json");
    r = runCli("info --json " + scene);
    ASSERT_EQ(r.status, 0) << r.output;
    check(nlohmann::json::parse(r.output).at(0).at("provenance"), int(tbb::info::default_concurrency()), "info");

    r = runCli("study --scenes cows:600 --resolutions 64 --repeats 1 --threads 1 2 --no-oracle -q -o " +
               quote((d / "s.csv").string()));
    ASSERT_EQ(r.status, 0) << r.output;
    std::istringstream lines(readAll(d / "s.jsonl"));
    int n = 0;
    for (std::string line; std::getline(lines, line); ++n) {
        const auto rec = nlohmann::json::parse(line);
        check(rec.at("provenance"), rec.at("threads").get<int>(), "study record " + std::to_string(n));
    }
    EXPECT_EQ(n, 2);
    EXPECT_EQ(readAll(d / "s.csv").find("provenance"), std::string::npos) << "the CSV keeps its columns";
}

namespace {

// A run with stdout and stderr apart, each into its own file under `dir`.
struct SplitRun {
    int status = -1;
    std::string out, err;
};
SplitRun runCliSplit(const std::string& args, const fs::path& dir, const std::string& name) {
    const fs::path out = dir / (name + ".stdout"), err = dir / (name + ".stderr");
    // In a subshell: runCommand's own trailing 2>&1 must not undo the redirections.
    const CliRun r = cullide::test::runCommand("( " + quote(CULLIDE_CLI_PATH) + " " + args + " >" +
                                               quote(out.string()) + " 2>" + quote(err.string()) + " )");
    return {r.status, readAll(out), readAll(err)};
}

// Timings masked: every decimal number ("3.2 ms", "0.41 s") becomes '#'; counts stay.
std::string maskTimes(const std::string& text) {
    return std::regex_replace(text, std::regex(R"([0-9]+\.[0-9]+)"), "#");
}

// A JSON output without what differs from run to run: keys ending in "seconds" and the provenance.
nlohmann::json withoutTimes(nlohmann::json j) {
    if (j.is_object()) {
        nlohmann::json out = nlohmann::json::object();
        for (auto& [key, value] : j.items()) {
            const bool timing = key.size() >= 7 && key.compare(key.size() - 7, 7, "seconds") == 0;
            if (!timing && key != "provenance") out[key] = withoutTimes(value);
        }
        return out;
    }
    if (j.is_array())
        for (auto& e : j) e = withoutTimes(e);
    return j;
}

}  // namespace

// --progress always: the bar goes to stderr and nowhere else. Trap: a bar drawn on stdout (which
// may carry JSON or a pipe), or a progress hook that changes what is computed or written: the
// files (prune and oracle JSON, the trace byte for byte, the replay's results) and stdout (timings
// masked) are those of a --progress never run, whose stderr stays empty.
TEST(Cli, ProgressAlwaysWritesOnlyToStderr) {
    const fs::path d = freshDir("progress_always");
    const std::string scene = quote(kData + "/scenes/bunny_through_cow.json");
    struct Case {
        std::string name, args, bar, file;  // `file`: written by the command; {} is its path
    };
    const std::vector<Case> cases = {
        {"prune", "prune " + scene + " --resolution 64 --json {}", "prune [", "prune.json"},
        {"oracle", "oracle " + scene + " --json {}", "oracle [", "oracle.json"},
        {"record", "trace record " + scene + " --resolution 32 -o {}", "trace record [", "t.trace"},
    };
    for (const Case& c : cases) {
        std::string shown[2];
        for (const char* mode : {"always", "never"}) {
            // One path for both runs (stdout names it), kept under the mode's name after.
            const std::string name = c.name + "_" + mode, file = (d / c.file).string();
            std::string args = std::regex_replace(c.args, std::regex(R"(\{\})"), quote(file));
            args += " --progress ";
            args += mode;
            const SplitRun r = runCliSplit(args, d, name);
            ASSERT_EQ(r.status, 0) << name << ": " << r.out << r.err;
            EXPECT_EQ(r.out.find('\r'), std::string::npos) << name << ": a bar on stdout";
            EXPECT_EQ(r.out.find(c.bar), std::string::npos) << name << ": a bar on stdout";
            if (std::string(mode) == "always") {
                EXPECT_NE(r.err.find(c.bar), std::string::npos) << name << ": no bar on stderr: " << r.err;
                EXPECT_NE(r.err.find("9/9 frames"), std::string::npos) << name << ": no final state: " << r.err;
                EXPECT_EQ(r.err.back(), '\n') << name << ": the line is not ended";
            } else {
                EXPECT_EQ(r.err, "") << name;
            }
            shown[std::string(mode) == "always" ? 0 : 1] = maskTimes(r.out);
            fs::rename(file, d / (name + "_" + c.file));
        }
        EXPECT_EQ(shown[0], shown[1]) << c.name << ": stdout differs with the bar";
        const std::string always = readAll(d / (c.name + "_always_" + c.file)),
                          never = readAll(d / (c.name + "_never_" + c.file));
        ASSERT_FALSE(never.empty()) << c.name;
        if (c.name == "record") EXPECT_EQ(always, never) << "the trace differs with the bar";
        else
            EXPECT_EQ(withoutTimes(nlohmann::json::parse(always)), withoutTimes(nlohmann::json::parse(never)))
                << c.name;
    }
    // Replay, per command list: the same answers with and without the bar.
    const std::string trace = quote((d / "record_never_t.trace").string());
    std::string results[2];
    for (const char* mode : {"always", "never"}) {
        const fs::path file = d / (std::string("replay_") + mode + ".json");
        std::string args = "trace replay " + trace + " -o " + quote(file.string()) + " --progress ";
        args += mode;
        const SplitRun r = runCliSplit(args, d, std::string("replay_") + mode);
        ASSERT_EQ(r.status, 0) << r.out << r.err;
        EXPECT_EQ(r.out.find("trace replay ["), std::string::npos) << "a bar on stdout";
        if (std::string(mode) == "always") EXPECT_NE(r.err.find("command lists"), std::string::npos) << r.err;
        else EXPECT_EQ(r.err, "");
        results[std::string(mode) == "always" ? 0 : 1] = nlohmann::json::parse(readAll(file)).at("results").dump();
    }
    EXPECT_EQ(results[0], results[1]) << "replayed answers differ with the bar";
}

// --progress auto (the default) with stderr not a terminal (a file, as under CI or a pipe): no
// bar, not a byte. Trap: a bar that tests stdout's terminal instead of stderr's, or draws anyway.
TEST(Cli, ProgressAutoIsSilentWithoutATerminal) {
    const fs::path d = freshDir("progress_auto");
    const std::string scene = quote(kData + "/scenes/bunny_through_cow.json");
    const std::string trace = quote((d / "t.trace").string());
    const std::vector<std::string> commands = {
        "prune " + scene + " --resolution 32",
        "prune " + scene + " --resolution 32 --progress auto",
        "oracle " + scene + " --frame 4",
        "trace record " + scene + " --frame 4 --resolution 32 -o " + trace,
        "trace replay " + trace + " -o " + quote((d / "r.json").string()),
        "study --scenes cows:600 --resolutions 32 --repeats 1 --no-oracle -o " + quote((d / "s.csv").string()),
    };
    for (size_t i = 0; i < commands.size(); ++i) {
        const SplitRun r = runCliSplit(commands[i], d, "run" + std::to_string(i));
        ASSERT_EQ(r.status, 0) << commands[i] << ": " << r.out << r.err;
        EXPECT_EQ(r.err, "") << commands[i];
    }
}

// --progress auto on a terminal draws the bar (through `script`, which gives the command a pseudo
// terminal for stdout and stderr both), the stdout lines still there; with stdout the terminal and
// stderr a file, nothing. Traps: auto that never draws, so that the default hides the bar from the
// users it is for; auto that asks whether stdout is a terminal instead of stderr.
TEST(Cli, ProgressAutoDrawsOnATerminal) {
    if (std::system("script --version >/dev/null 2>&1") != 0) GTEST_SKIP() << "no `script` to give a terminal";
    const std::string command =
        quote(CULLIDE_CLI_PATH) + " prune " + quote(kData + "/scenes/bunny_through_cow.json") + " --resolution 32";
    const CliRun r = cullide::test::runCommand("script -qec " + quote(command) + " /dev/null </dev/null");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("prune ["), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("frame 8: PCS"), std::string::npos) << "stdout lost: " << r.output;

    const fs::path err = freshDir("progress_tty") / "stderr";
    const CliRun s = cullide::test::runCommand("script -qec " + quote(command + " 2>" + quote(err.string())) +
                                               " /dev/null </dev/null");
    ASSERT_EQ(s.status, 0) << s.output;
    EXPECT_NE(s.output.find("frame 8: PCS"), std::string::npos) << s.output;
    EXPECT_EQ(s.output.find("prune ["), std::string::npos) << s.output;
    EXPECT_EQ(readAll(err), "");
}

// A bad --progress value is refused with exit status 2, naming the option, the value and the
// accepted ones, by every command that has the option, before any work (no file written); and the
// option is refused where it does not apply (study --stability). Trap: CLI11's generic message,
// or a misspelt value silently taken as auto.
TEST(Cli, BadProgressValueIsRefused) {
    const fs::path d = freshDir("progress_bad");
    const std::string scene = quote(kData + "/scenes/bunny_through_cow.json");
    const std::string out = quote((d / "out").string());
    for (const std::string& command : {"prune " + scene + " --json " + out, "oracle " + scene + " --json " + out,
                                       "trace record " + scene + " -o " + out, "trace replay " + scene + " -o " + out,
                                       "validate " + scene + " --json " + out, "study --scenes cows:600 -o " + out}) {
        const CliRun r = runCli(command + " --progress sometimes");
        EXPECT_EQ(r.status, 2) << command << ": " << r.output;
        EXPECT_NE(r.output.find("option --progress: 'sometimes'"), std::string::npos) << command << ": " << r.output;
        EXPECT_NE(r.output.find("always or never"), std::string::npos) << command << ": " << r.output;
        EXPECT_FALSE(fs::exists(d / "out")) << command << ": wrote before refusing";
    }
    const CliRun r = runCli("study --stability tilt --progress always -o " + out);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("--progress"), std::string::npos) << r.output;
}

// A study records the command line that ran it in each JSON line (not in the CSV), quoted so that
// a shell reads it back as the same arguments: run again as recorded, it finds every run done.
// Trap: arguments joined with spaces, which a path with a space or a quote splits when pasted.
TEST(Cli, StudyRecordsItsCommandLine) {
    const fs::path d = freshDir("command") / "it's here";
    fs::create_directories(d);
    const std::string out = (d / "s.csv").string();
    const CliRun r = runCli("study --scenes cows:600 --resolutions 32 --repeats 1 --no-oracle -q -o " + quote(out));
    ASSERT_EQ(r.status, 0) << r.output;
    const auto rec = nlohmann::json::parse(readAll(d / "s.jsonl"));
    const std::string command = rec.at("command").get<std::string>();
    EXPECT_EQ(command, "cullide study --scenes cows:600 --resolutions 32 --repeats 1 --no-oracle -q -o " + quote(out));
    EXPECT_EQ(readAll(d / "s.csv").find("command"), std::string::npos) << "the CSV keeps its columns";
    // As recorded, with this build's path for "cullide": the shell gives it the same output path.
    const CliRun again =
        cullide::test::runCommand(quote(CULLIDE_CLI_PATH) + command.substr(std::string("cullide").size()));
    ASSERT_EQ(again.status, 0) << again.output;
    EXPECT_NE(again.output.find("0 run(s) done"), std::string::npos) << again.output;
}

namespace {

bool haveMatplotlib() {
    return std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0;
}

// The report of a small mixed study (one single-object scene, one of three objects; two methods,
// two resolutions), made once for the report tests: its folder, or empty when `cullide report`
// failed (the first test to use it says how).
struct ReportRun {
    fs::path dir;
    CliRun study, report;
};
const ReportRun& smallReport() {
    static const ReportRun run = [] {
        ReportRun r;
        r.dir = freshDir("report");
        const std::string csv = quote((r.dir / "s.csv").string());
        r.study = runCli("study --scenes bunny:1500 " + quote(kData + "/scenes/two_cows_and_bunny.json") +
                         " --methods original modified --resolutions 32 64 --repeats 1 -q -o " + csv);
        r.report = runCli("report " + csv + " -o " + quote((r.dir / "page").string()));
        return r;
    }();
    return run;
}

// The elements of an HTML page, checked for balance: every element closed in order (void elements
// excepted), text without a stray '<'. Returns "" or the first problem.
std::string checkWellFormed(const std::string& html) {
    static const std::vector<std::string> voids = {"meta", "img", "br", "hr", "link", "input", "col", "wbr"};
    std::vector<std::string> open;
    size_t i = 0;
    while ((i = html.find('<', i)) != std::string::npos) {
        const size_t end = html.find('>', i);
        if (end == std::string::npos) return "a tag without its '>' at " + std::to_string(i);
        const std::string tag = html.substr(i + 1, end - i - 1);
        i = end + 1;
        if (tag.empty() || tag[0] == '!') continue;  // <!DOCTYPE html>
        const bool closing = tag[0] == '/';
        const size_t nameStart = closing ? 1 : 0;
        size_t nameEnd = tag.find_first_of(" \t\n/", nameStart);
        if (nameEnd == std::string::npos) nameEnd = tag.size();
        std::string name = tag.substr(nameStart, nameEnd - nameStart);
        if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0])))
            return "'<' in text: <" + tag.substr(0, 20);
        if (closing) {
            if (open.empty() || open.back() != name)
                return "</" + name + "> closes <" + (open.empty() ? std::string("nothing") : open.back()) + ">";
            open.pop_back();
        } else if (std::find(voids.begin(), voids.end(), name) == voids.end() && tag.back() != '/') {
            open.push_back(name);
        }
        // The text of <style> is not markup.
        if (!closing && name == "style") {
            const size_t close = html.find("</style>", i);
            if (close == std::string::npos) return "<style> not closed";
            i = close;
        }
    }
    if (!open.empty()) return "<" + open.back() + "> not closed";
    return "";
}

// The values of attribute `attr` in every tag that has it. (Not std::regex: libstdc++'s recursion
// overflows the stack on a value as long as a chart's base64.)
std::vector<std::string> attributeValues(const std::string& html, const std::string& attr) {
    std::vector<std::string> out;
    const std::string key = attr + "=\"";
    for (size_t i = html.find(key); i != std::string::npos; i = html.find(key, i + 1)) {
        if (i == 0 || !std::isspace(static_cast<unsigned char>(html[i - 1]))) continue;
        const size_t start = i + key.size(), end = html.find('"', start);
        if (end == std::string::npos) break;
        out.push_back(html.substr(start, end - start));
    }
    return out;
}

size_t countOf(const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t i = text.find(what); i != std::string::npos; i = text.find(what, i + 1)) ++n;
    return n;
}

}  // namespace

// `cullide report`: one page with nothing outside it, well-formed, with a Pareto table per scene,
// the provenance (this build's commit) and the command that made the data. Traps: a chart linked
// as a file beside the page (lost when the page is mailed), a script or stylesheet from the web,
// a table for one scene only, an unescaped '<' or a quote in a path breaking the markup.
TEST(Cli, ReportIsOneSelfContainedPage) {
    if (!haveMatplotlib()) GTEST_SKIP() << "no matplotlib for /usr/bin/python3";
    const ReportRun& run = smallReport();
    ASSERT_EQ(run.study.status, 0) << run.study.output;
    ASSERT_EQ(run.report.status, 0) << run.report.output;
    const std::string html = readAll(run.dir / "page" / "report.html");
    ASSERT_FALSE(html.empty());
    EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_EQ(checkWellFormed(html), "");

    const std::vector<std::string> images = attributeValues(html, "src");
    EXPECT_GE(images.size(), 3u) << "speed against accuracy, false prunes by cause, per-call charts";
    for (const std::string& src : images) EXPECT_EQ(src.rfind("data:image/png;base64,", 0), 0u) << src.substr(0, 60);
    for (const std::string& href : attributeValues(html, "href")) EXPECT_EQ(href.rfind('#', 0), 0u) << href;
    for (const char* external : {"<script", "<link", "<iframe", "<object", "<embed", "url("})
        EXPECT_EQ(html.find(external), std::string::npos) << external;

    const std::vector<std::string> scenes = attributeValues(html, "data-scene");
    ASSERT_EQ(scenes.size(), 2u) << "one Pareto table per scene";
    EXPECT_EQ(scenes[0], "bunny:1500");
    EXPECT_EQ(scenes[1], kData + "/scenes/two_cows_and_bunny.json");
    EXPECT_EQ(countOf(html, "<table class=\"pareto\""), 2u);

    const CliRun v = runCli("--version");
    std::smatch m;
    ASSERT_TRUE(std::regex_search(v.output, m, std::regex(R"(\(commit ([^;]+);)"))) << v.output;
    EXPECT_NE(html.find("<td>" + m[1].str() + "</td>"), std::string::npos) << "the provenance names the commit";
    EXPECT_NE(html.find("<pre class=\"command\">cullide study --scenes bunny:1500 "), std::string::npos)
        << "the command that made the data";

    // Not a study: refused by name, nothing written.
    const fs::path d = freshDir("report_bad");
    { std::ofstream(d / "sweep.csv") << "sweep,method\npenetration,modified\n"; }
    CliRun bad = runCli("report " + quote((d / "sweep.csv").string()) + " -o " + quote((d / "page").string()));
    EXPECT_EQ(bad.status, 2) << bad.output;
    EXPECT_NE(bad.output.find("sweep.csv"), std::string::npos) << bad.output;
    bad = runCli("report " + quote((d / "missing.csv").string()) + " -o " + quote((d / "page").string()));
    EXPECT_EQ(bad.status, 2) << bad.output;
    EXPECT_NE(bad.output.find("missing.csv: no such file"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(d / "page" / "report.html"));
}

// The report renders in a browser: headless Chromium (Debian's `chromium`) reads the page into a
// DOM with both Pareto tables and every chart, and draws it. Required when CULLIDE_REQUIRE_CHROMIUM
// is set (tools/test.sh, where tools/setup.sh installs it); skipped otherwise without chromium.
// Trap: a page a parser accepts that a browser does not render (a broken data: URI, bad markup).
TEST(Cli, ReportRendersInChromium) {
    if (std::system("command -v chromium >/dev/null 2>&1") != 0) {
        if (std::getenv("CULLIDE_REQUIRE_CHROMIUM")) FAIL() << "no chromium (tools/setup.sh installs it)";
        GTEST_SKIP() << "no chromium on PATH (Debian: apt-get install chromium)";
    }
    if (!haveMatplotlib()) GTEST_SKIP() << "no matplotlib for /usr/bin/python3";
    const ReportRun& run = smallReport();
    ASSERT_EQ(run.report.status, 0) << run.study.output << run.report.output;
    const fs::path page = run.dir / "page" / "report.html", shot = run.dir / "shot.png";
    // A profile of its own: none written to $HOME, no lock shared with another Chromium.
    const std::string browser =
        "timeout 300 chromium --headless --no-sandbox --disable-gpu --hide-scrollbars "
        "--window-size=1200,2400 --user-data-dir=" +
        quote((run.dir / "chromium-profile").string()) + " ";
    const std::string url = quote("file://" + page.string());
    const CliRun dom = cullide::test::runCommand("( " + browser + "--dump-dom " + url + " 2>/dev/null )");
    ASSERT_EQ(dom.status, 0) << dom.output;
    EXPECT_EQ(countOf(dom.output, "<table class=\"pareto\""), 2u) << dom.output.substr(0, 2000);
    EXPECT_EQ(countOf(dom.output, "<img src=\"data:image/png;base64,"), attributeValues(readAll(page), "src").size());
    const CliRun draw = cullide::test::runCommand(browser + "--screenshot=" + quote(shot.string()) + " " + url);
    ASSERT_EQ(draw.status, 0) << draw.output;
    // A PNG of the window's size (its IHDR: width and height, big-endian, at bytes 16 and 20), and
    // more than a blank page's few kilobytes.
    const std::string png = readAll(shot);
    ASSERT_GT(png.size(), 24u) << draw.output;
    EXPECT_EQ(png.substr(1, 3), "PNG");
    auto be32 = [&](size_t at) {
        return (uint32_t(uint8_t(png[at])) << 24) | (uint32_t(uint8_t(png[at + 1])) << 16) |
            (uint32_t(uint8_t(png[at + 2])) << 8) | uint32_t(uint8_t(png[at + 3]));
    };
    EXPECT_EQ(be32(16), 1200u);
    EXPECT_EQ(be32(20), 2400u);
    EXPECT_GT(png.size(), 50000u) << "a blank page";
}

// Trap: a tune that prints a recommendation that prune refuses (an option spelled as the study
// spells it, a generated scene name), that ignores --max-false-prunes, or that exits 0 when
// nothing meets the target. On a small bunny file: a Pareto front and a prune command line
// that itself runs; the recommendation meets K = 0; a budget nothing meets exits 1 with a
// message (the second tune resumes from the first's output, so it runs nothing new).
TEST(Cli, TuneRecommendsACommandThatRuns) {
    const fs::path d = freshDir("tune");
    const std::string scene = quote((d / "s.json").string());
    ASSERT_EQ(runCli("make-scene bunny --triangles 1500 -o " + scene).status, 0);
    const std::string out = quote((d / "t.csv").string());
    const CliRun r = runCli("tune " + scene + " --repeats 1 --threads 1 --progress never -o " + out);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("Pareto front"), std::string::npos) << r.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(
        r.output, m,
        std::regex(
            R"(cheapest meeting the target \(at most 0 false prune\(s\)\): [0-9.]+ ms to exact pairs, ([0-9]+) false)")))
        << r.output;
    EXPECT_EQ(m[1].str(), "0");
    ASSERT_TRUE(std::regex_search(r.output, m, std::regex("recommended: cullide (prune [^\n]*)"))) << r.output;
    const CliRun prune = runCli(m[1].str() + " --progress never");
    EXPECT_EQ(prune.status, 0) << prune.output;
    EXPECT_NE(prune.output.find("time to exact pairs"), std::string::npos) << prune.output;
    const CliRun none =
        runCli("tune " + scene + " --repeats 1 --threads 1 --progress never --budget-ms 0.000001 -o " + out);
    EXPECT_EQ(none.status, 1) << none.output;
    EXPECT_NE(none.output.find("no configuration measured meets the target"), std::string::npos) << none.output;
}

// Trap: tune's bad input reaching the study engine (an exception deep inside) or running for
// minutes before failing. Each is refused up front with exit status 2, naming the option or file.
TEST(Cli, TuneRefusesBadInput) {
    const fs::path d = freshDir("tune_bad");
    const std::string cow = quote(kData + "/meshes/cow.off");
    for (const std::string& args :
         {std::string("tune /nonexistent/scene.json"), "tune " + cow + " --max-false-prunes -1",
          "tune " + cow + " --max-false-prunes lots", "tune " + cow + " --budget-ms 0", "tune " + cow + " --repeats 0",
          "tune " + cow + " --threads 5000", "tune " + cow + " -o " + quote((d / "t.txt").string()),
          "tune " + cow + " --progress sometimes", std::string("tune")}) {
        const CliRun r = runCli(args);
        EXPECT_EQ(r.status, 2) << args << "\n" << r.output;
    }
    const CliRun missing = runCli("tune /nonexistent/scene.json");
    EXPECT_NE(missing.output.find("/nonexistent/scene.json"), std::string::npos) << missing.output;
}
