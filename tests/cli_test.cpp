// The `cullide` command, run as a user runs it: exit codes, messages, bytes written. Here info,
// make-scene and what every command shares (option checks, output folders, provenance); prune,
// study and tune, --progress and report in cli_prune_test.cpp, cli_study_test.cpp,
// cli_progress_test.cpp and cli_report_test.cpp.
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
#include <map>
#include <regex>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using namespace cullide::test::cli;

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
        {"make-scene nbody --count 0 -o " + out, "--count"},
        {"make-scene cloth --frames 0 -o " + out, "option --frames: 0 is out of range for 'cloth' (1 to 1000)"},
        {"make-scene nbody --frames 1001 -o " + out, "option --frames: 1001 is out of range for 'nbody'"},
        {"make-scene cloth --triangles 2000001 -o " + out, "option --triangles: 2000001 is out of range for 'cloth'"},
        {"make-scene cloth --self-collision sometimes -o " + out, "--self-collision"},
        {"make-scene cloth --triangles 2000000 --frames 1000 -o " + out, "option --frames: 1000 frames of 2000000"},
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

// Trap: a number on the command line wrapped, clamped, NaN or half read (CLI11 takes "nan" for a
// double and wraps -1 for an unsigned; sscanf wrapped 4294967396 to 100): every number an option
// takes goes through the one strict parser, and a bad one is exit status 2 with the option and
// the cause, before any work and with nothing written. One row per class and per way in
// (an option's value, a part of a value, a list item, a study).
TEST(Cli, NumbersAreReadStrictly) {
    const fs::path d = freshDir("numbers");
    const std::string cow = quote(kData + "/meshes/cow.off"), out = quote((d / "s.json").string());
    const std::string csv = quote((d / "s.csv").string());
    const std::pair<std::string, std::string> cases[] = {
        {"prune " + cow + " --resolution 4294967396", "option --resolution: 4294967396 is out of range (1 to 16384)"},
        {"study --scenes bunny:100 --resolutions 4294967396 -o " + csv, "option --resolutions: 4294967396 is out"},
        {"make-scene sheets --tilt nan -o " + out, "option --tilt: 'nan' is not a finite number"},
        {"tune " + cow + " --budget-ms nan", "option --budget-ms: 'nan' is not a finite number"},
        {"trace record " + cow + " -o " + quote((d / "t.trace").string()) + " --depth-margin inf",
         "option --depth-margin: 'inf' is not a finite number"},
        {"prune " + cow + " --hierarchy random --seed -1", "option --seed: -1 is out of range"},
        {"prune " + cow + " --hierarchy random --seed 18446744073709551616",
         "option --seed: 18446744073709551616 is out of range"},
        {"trace compare a.trace r.json --worst -1", "option --worst: -1 is out of range"},
        {"prune " + cow + " --max-viewport 12abc", "option --max-viewport: '12abc' is not an integer"},
        {"prune " + cow + " --max-viewport 63", "option --max-viewport: 63 is out of range (64 to 16384)"},
        {"make-scene cylinders --count 1e3 -o " + out, "option --count: '1e3' is not an integer"},
        {"study --scenes bunny:100 --leaf-sizes 16 -1 -o " + csv, "option --leaf-sizes: -1 is out of range"},
        {"study --scenes bunny:100 --shard 0/18446744073709551617 -o " + csv, "option --shard"},
        {"info --frame 99999999999999999999 " + cow, "option --frame: 99999999999999999999 is out of range"},
    };
    for (const auto& [args, message] : cases) {
        const CliRun r = runCli(args);
        EXPECT_EQ(r.status, 2) << args << ": " << r.output;
        EXPECT_NE(r.output.find("cullide: error: " + message), std::string::npos) << args << ": " << r.output;
    }
    EXPECT_TRUE(fs::is_empty(d)) << "a refused command wrote its output";
}

// Trap: a generator or writer that depends on anything but its options (unordered containers,
// threads, implementation-defined distributions, a simulator's floating-point order): same kind,
// options and seed must give the same bytes in every file written (meshes, binary positions, the
// scene); a different seed changes the randomized scenes (cylinders, cloth).
TEST(Cli, MakeSceneIsByteReproducible) {
    const std::map<std::string, std::string> extra = {
        {"cylinders", " --count 10 --seed 7"}, {"nbody", " --count 6 --seed 7"}, {"cloth", " --seed 7"}};
    fs::path clothA;
    for (const std::string kind : {"bunny", "cows", "cylinders", "twist", "cloth", "nbody"}) {
        const fs::path a = freshDir(kind + "_a"), b = freshDir(kind + "_b");
        if (kind == "cloth") clothA = a;
        const std::string opts = std::string(kind == "cloth" ? " --triangles 800" : " --triangles 3000") +
                                 " --frames 2" + (extra.contains(kind) ? extra.at(kind) : "") + " -o ";
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
    const fs::path e = freshDir("cloth_e");
    ASSERT_EQ(runCli("make-scene cloth --triangles 800 --frames 2 --seed 8 -o " + quote((e / "s.json").string())).status, 0);
    EXPECT_NE(readTree(clothA), readTree(e)) << "seeds 7 and 8 gave the same cloth";
}

// Trap: a summary of every frame that reads one frame and repeats it, or holds them all at once:
// `info --all-frames` gives one entry per frame, and a deforming object's entries differ (the
// twist grows), while the total stays that of the frame asked for.
TEST(Cli, InfoSummarisesEveryFrame) {
    const fs::path d = freshDir("info_frames");
    const std::string scene = quote((d / "t.json").string());
    ASSERT_EQ(runCli("make-scene twist --triangles 1000 --frames 3 -o " + scene).status, 0);
    const CliRun r = runCli("info --json --all-frames " + scene);
    ASSERT_EQ(r.status, 0) << r.output;
    const auto j = nlohmann::json::parse(r.output);
    const auto& frames = j[0]["every_frame"];
    ASSERT_EQ(frames.size(), 3u) << r.output;
    EXPECT_EQ(frames[0]["triangles"], frames[2]["triangles"]);
    EXPECT_NE(frames[0]["bounds"], frames[2]["bounds"]) << "the twist does not change the bounds";
    const CliRun text = runCli("info --all-frames " + scene);
    EXPECT_EQ(text.status, 0) << text.output;
}

// A generator whose input is bad fails before writing: nothing half-written is left behind.
TEST(Cli, MakeSceneWithBadMeshWritesNothing) {
    const fs::path d = freshDir("badmesh");
    const CliRun r = runCli("make-scene bunny --mesh /nonexistent.off -o " + quote((d / "s.json").string()));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("/nonexistent.off"), std::string::npos) << r.output;
    EXPECT_TRUE(fs::is_empty(d)) << "files were written although the input was bad";
}

// The same bad value gets the same message from every command, under the name the user typed:
// `prune --depth`, `study --depths`, a spec's key `depths`. Trap: a message such as "depth format:
// ..." that names no option.
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
        {"make-scene cloth --mesh " + cow + " -o " + out, "--mesh"},
        {"make-scene nbody --self-collision none -o " + out, "--self-collision"},
        {"make-scene cloth --count 3 -o " + out, "--count"},
        {"study --scenes cloth:5000 --no-oracle --near-distance 0.01 -o " + quote((d / "t.csv").string()),
         "--no-oracle"},
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

// Trap: output lost on a full disk while the command says it succeeded (exit 0): a write error on
// stdout, in cullide's own output (printf) or CLI11's (std::cout, --help), is exit status 2 naming
// stdout and the cause.
TEST(Cli, StdoutWriteErrorIsAnError) {
    if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
    for (const std::string& args : {"info --json " + quote(kData + "/meshes/cow.off"), std::string("--help")}) {
        const CliRun r = cullide::test::runCommand("( " + quote(CULLIDE_CLI_PATH) + " " + args + " > /dev/full )");
        EXPECT_EQ(r.status, 2) << args << ": " << r.output;
        EXPECT_NE(r.output.find("cullide: error: stdout: No space left on device"), std::string::npos) << r.output;
    }
}
