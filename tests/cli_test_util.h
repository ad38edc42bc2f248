// Helpers shared by the `cullide` command's test files (cli_test.cpp, cli_prune_test.cpp,
// cli_study_test.cpp, cli_progress_test.cpp, cli_report_test.cpp): the command run as a user runs
// it, files read back, scratch folders.
#pragma once

#include "test_util.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace cullide::test::cli {

namespace fs = std::filesystem;

using CliRun = CommandRun;

inline std::string quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

inline CliRun runCli(const std::string& args) {
    return cullide::test::runCommand(quote(CULLIDE_CLI_PATH) + " " + args);
}

inline std::string readAll(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

// Every regular file under `dir`, in sorted path order, concatenated with its relative path.
inline std::string readTree(const fs::path& dir) {
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
inline fs::path freshDir(const std::string& name) {
    static const cullide::test::TempDir root;
    fs::path d = root / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

inline const std::string kData = CULLIDE_DATA_DIR;

}  // namespace cullide::test::cli
