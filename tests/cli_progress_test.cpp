// --progress, run as a user runs it: the bar on stderr only, silent without a terminal, drawn on
// one, bad values refused.
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
