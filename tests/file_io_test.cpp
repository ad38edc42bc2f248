// Tests for core/src/file_io.cpp: all-or-nothing writes, and what a failed one says.
#include "cullide/file_io.h"

#include "cullide/error.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace cullide {
namespace {

namespace fs = std::filesystem;

fs::path freshDir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("cullide_file_io_test_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

TEST(FileIo, WritesTheBytesAndLeavesNoTemporary) {
    const fs::path d = freshDir("write");
    writeFileAtomically(d / "a.txt", "first");
    writeFileAtomically(d / "a.txt", "second\n");
    std::ifstream f(d / "a.txt", std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    EXPECT_EQ(s.str(), "second\n");
    EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator()), 1);
}

// Trap: a missing folder is the commonest cause of a failed write; the message says so (not
// "cannot write: No such file or directory") and no folder is created.
TEST(FileIo, MissingFolderIsNamed) {
    const fs::path missing = freshDir("missing") / "not_there" / "deeper";
    try {
        writeFileAtomically(missing / "a.txt", "x");
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_EQ(e.source(), (missing / "a.txt").string());
        EXPECT_NE(std::string(e.what()).find("folder " + missing.string() + " does not exist"), std::string::npos)
            << e.what();
    }
    EXPECT_FALSE(fs::exists(missing.parent_path()));
}

}  // namespace
}  // namespace cullide
