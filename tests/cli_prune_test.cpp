// `cullide prune`, run as a user runs it: bad options, the JSON and PLY outputs, views, tiles,
// the exact switch's calibration, hierarchies kept across frames.
#include "cli_test_util.h"

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
using namespace cullide::test::cli;

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
