// `cullide study` and `cullide tune`, run as a user runs them: bad specs refused by name, the
// recorded command line, tune's recommendation and its bad input.
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

// A number too large for a double in a study spec (found by fuzzing the trace reader, which shares
// the JSON parser): nlohmann throws out_of_range, not parse_error; it once escaped as an internal
// error (exit 70).
TEST(Cli, StudySpecWithAnOverflowingNumberIsBadInput) {
    const fs::path d = freshDir("spec_overflow");
    std::ofstream(d / "spec.json") << R"({"scenes": [1e99999]})";
    const CliRun r = runCli("study " + quote((d / "spec.json").string()) + " -q -o " + quote((d / "s.csv").string()));
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find((d / "spec.json").string() + ": malformed JSON"), std::string::npos) << r.output;
}

// A valid spec mutated field by field (wrong type, empty list, huge and negative numbers) and an
// unknown field: every one is refused with exit status 2 and a message naming the field, before
// anything runs, never by a signal (trap: `"branching": []` ending in an uncaught
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
