// Tests for core/src/file_io.cpp: whole reads, all-or-nothing writes, and what a failed one says.
#include "cullide/file_io.h"

#include "cullide/error.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace cullide {
namespace {

namespace fs = std::filesystem;

// A folder of its own under this process's temporary folder, which goes when the process ends.
fs::path freshDir(const std::string& name) {
    static const test::TempDir root;
    const fs::path d = root / name;
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

// Trap: readFile reads a regular file's size first, into one buffer (the middle of a large one
// advised to huge pages), then reads on in 64 KiB steps for whatever is left. Every size around
// those steps and pages must come back byte for byte, NUL bytes included: nothing dropped at the
// end of the first read, nothing read twice.
TEST(FileIo, ReadsEveryByteOfFilesOfEverySize) {
    const fs::path d = freshDir("read");
    for (size_t n : {size_t(0), size_t(1), size_t(65535), size_t(65536), size_t(65537), (size_t(5) << 20) + 7}) {
        std::string bytes(n, '\0');
        for (size_t i = 0; i < n; ++i) bytes[i] = char((i * 131 + i / 7) & 0xff);
        writeFileAtomically(d / "f.bin", bytes);
        EXPECT_EQ(readFile(d / "f.bin"), bytes) << n << " bytes";
    }
}

// Trap: a file may say it is empty and still have bytes (procfs files are regular files of size
// 0): the size read first must not be taken as the whole file.
TEST(FileIo, ReadsAFileWhoseSizeSaysNothing) {
    if (!fs::exists("/proc/self/status")) GTEST_SKIP() << "no /proc";
    const std::string status = readFile("/proc/self/status");
    EXPECT_NE(status.find("Name:"), std::string::npos) << status;
}

// Trap: what cannot be read is said with the path, never an empty string returned.
TEST(FileIo, UnreadableIsNamed) {
    const fs::path d = freshDir("unreadable");
    try {
        readFile(d / "none.off");
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_EQ(e.source(), (d / "none.off").string());
        EXPECT_NE(std::string(e.what()).find("no such file"), std::string::npos) << e.what();
    }
    try {
        readFile(d);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("directory"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace cullide
