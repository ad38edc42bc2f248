// `cullide audit`, run as a user runs it: an `oracle --json` output accepted as is, exit 0 / 1 / 2,
// the --json report's shape, frames chosen from the list.
#include "cli_test_util.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>

namespace fs = std::filesystem;
using namespace cullide::test::cli;

namespace {

const char* kCube = "OFF\n8 12 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
                    "3 0 2 1\n3 0 3 2\n3 4 5 6\n3 4 6 7\n3 0 1 5\n3 0 5 4\n3 2 3 7\n3 2 7 6\n3 1 2 6\n3 1 6 5\n"
                    "3 0 4 7\n3 0 7 3\n";

void writeText(const fs::path& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
}

// Two unit cubes, the second shifted by (0.5, 0.25, 0.125) in frame 0 (crossing faces) and far
// away in frame 1 (no pairs).
fs::path twoCubes(const fs::path& d) {
    writeText(d / "cube.off", kCube);
    writeText(d / "scene.json", R"({"objects": [{"name": "a", "mesh": "cube.off"},
        {"name": "b", "mesh": "cube.off", "transform": {"translate": [0.5, 0.25, 0.125]}}],
        "animation": {"frames": [{}, {"objects": {"b": {"transform": {"translate": [5, 0, 0]}}}}]}})");
    return d / "scene.json";
}

}  // namespace

// Trap: the list `oracle --json` writes (classes after each pair, degenerate rows, other keys)
// must be taken as it is and agree with the oracle on every frame: exit 0.
TEST(CliAudit, TheOraclesOwnJsonAgrees) {
    const fs::path d = freshDir("audit_agrees");
    const std::string scene = quote(twoCubes(d).string()), list = quote((d / "o.json").string());
    ASSERT_EQ(runCli("oracle " + scene + " --json " + list).status, 0);
    const CliRun r = runCli("audit " + scene + " " + list);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("2 of 2 frame(s) agree with the oracle"), std::string::npos) << r.output;
}

// Trap: a list with a pair removed and one added must exit 1 and report both in --json with their
// cause, class and distance, with counts by every cause (zeros included) for the study's columns.
TEST(CliAudit, DisagreementsExitOneWithTheirCausesInJson) {
    const fs::path d = freshDir("audit_disagrees");
    const std::string scene = quote(twoCubes(d).string());
    ASSERT_EQ(runCli("oracle " + scene + " --frame 0 --json " + quote((d / "o.json").string())).status, 0);
    const auto truth = nlohmann::json::parse(readAll(d / "o.json")).at("frames").at(0).at("pairs");
    ASSERT_GE(truth.size(), 2u);
    std::string csv = "frame,object_a,triangle_a,object_b,triangle_b\n";
    for (size_t k = 1; k < truth.size(); ++k)  // the first pair left out; the rest reversed
        csv += "0," + truth[k][2].dump() + "," + truth[k][3].dump() + "," + truth[k][0].dump() + "," +
               truth[k][1].dump() + "\n";
    csv += "0,0,0,0,5\n";  // two faces of cube a that share a vertex: spurious
    writeText(d / "pairs.csv", csv);
    const CliRun r = runCli("audit " + scene + " " + quote((d / "pairs.csv").string()) + " --frame 0 --json " +
                            quote((d / "a.json").string()));
    ASSERT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find("1 missed"), std::string::npos) << r.output;
    const auto f = nlohmann::json::parse(readAll(d / "a.json")).at("frames").at(0);
    EXPECT_EQ(f.at("frame"), 0);
    EXPECT_EQ(f.at("found"), truth.size() - 1);
    ASSERT_EQ(f.at("missed").size(), 1u);
    EXPECT_EQ(f.at("missed")[0].at("pair"), nlohmann::json({truth[0][0], truth[0][1], truth[0][2], truth[0][3]}));
    EXPECT_EQ(f.at("missed")[0].at("class"), truth[0][4]);
    const bool crossing = truth[0][4] == "crossing";  // deep (cubes 1/8 apart) or on a boundary
    EXPECT_EQ(f.at("missed")[0].at("cause"), crossing ? "unexplained" : "touching");
    EXPECT_EQ(f.at("missed")[0].at("distance").get<double>() > 0.01, crossing);
    ASSERT_EQ(f.at("spurious").size(), 1u);
    EXPECT_EQ(f.at("spurious")[0].at("cause"), "shared_vertex");
    EXPECT_EQ(f.at("missed_by_cause").size(), 7u);
    EXPECT_EQ(f.at("spurious_by_cause").at("shared_vertex"), 1);
}

// Trap: bad input must exit 2 naming the file and the line (or what is missing), and write no
// report: a bad number, a triangle the scene lacks, a list without the scene's frames.
TEST(CliAudit, BadInputExitsTwoNamingTheLine) {
    const fs::path d = freshDir("audit_bad");
    const std::string scene = quote(twoCubes(d).string()), out = quote((d / "a.json").string());
    const std::string header = "frame,object_a,triangle_a,object_b,triangle_b\n";
    writeText(d / "bad.csv", header + "0,0,1,1,2\n0,0,1,1,z\n");
    writeText(d / "far.csv", header + "0,0,1,1,12\n");
    writeText(d / "one.json", R"({"frames": [{"frame": 1, "pairs": []}]})");
    const std::tuple<std::string, std::string, std::string> cases[] = {
        {"bad.csv", "", "bad.csv: line 3: triangle_b: 'z' is not an integer"},
        {"far.csv", "--frame 0", "far.csv: line 2: object 1 has no triangle 12 (it has 12)"},
        {"one.json", "", "one.json: no entry for frame 0"},
        {"one.json", "--tolerance 0.5", "--tolerance"},
    };
    for (const auto& [list, args, needle] : cases) {
        const CliRun r = runCli("audit " + scene + " " + quote((d / list).string()) + " " + args + " --json " + out);
        EXPECT_EQ(r.status, 2) << args << ": " << r.output;
        EXPECT_NE(r.output.find(needle), std::string::npos) << args << ": " << r.output;
        EXPECT_FALSE(fs::exists(d / "a.json")) << args;
    }
    // The list's only frame judges the frame asked for: frame 1 of the scene has no pairs either.
    EXPECT_EQ(runCli("audit " + scene + " " + quote((d / "one.json").string()) + " --frame 0").status, 1);
    EXPECT_EQ(runCli("audit " + scene + " " + quote((d / "one.json").string()) + " --frame 1").status, 0);
}
