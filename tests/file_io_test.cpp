// Tests for core/src/file_io.cpp: whole reads, all-or-nothing writes, and what a failed one says.
#include "cullide/file_io.h"

#include "cullide/error.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
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

// Trap: an output renamed onto a device or a FIFO replaces it: `prune --json /dev/null`, run as
// root, left /dev/null a regular file for every later process. A FIFO stands in for the device
// (a test must not risk /dev/null itself; outputTarget only looks at it): its reader gets the
// bytes and it stays a FIFO; one that nobody reads is refused at once, not waited for. Through a
// symbolic link the file it leads to is replaced whole and the link stays a link.
TEST(FileIo, DevicesFifosAndLinksStayWhatTheyAre) {
    EXPECT_TRUE(outputTarget("/dev/null").inPlace());
    const fs::path d = freshDir("special");
    const fs::path fifo = d / "out.fifo";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    try {
        writeFileAtomically(fifo, "nobody reads");
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("no process reads"), std::string::npos) << e.what();
    }
    const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
    ASSERT_GE(reader, 0);
    writeFileAtomically(fifo, "through the pipe\n");
    char got[64] = {};
    EXPECT_EQ(::read(reader, got, sizeof got), ssize_t(17));
    EXPECT_STREQ(got, "through the pipe\n");
    ::close(reader);
    struct stat st {};
    ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
    EXPECT_TRUE(S_ISFIFO(st.st_mode));

    writeFileAtomically(d / "target.txt", "old");
    fs::create_symlink("target.txt", d / "link.txt");
    writeFileAtomically(d / "link.txt", "new");
    EXPECT_TRUE(fs::is_symlink(d / "link.txt"));
    EXPECT_EQ(test::readBytes((d / "target.txt").string()), "new");
    EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator()), 3);  // no temporary left
    EXPECT_THROW(writeFileAtomically(d, "a folder"), InputError);
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

// Trap: input that is not a regular file: a FIFO blocked the open forever (no writer comes), a
// device never ends (/dev/zero grew to 16.8 GB, then "out of memory" without the file). Refused
// before the open, naming the kind, by readFile and by inputFileSize (readers that open the file
// themselves); a file over the size bound is refused before it is read.
TEST(FileIo, OnlyRegularFilesOfBoundedSizeAreInput) {
    const fs::path d = freshDir("special");
    ASSERT_EQ(::mkfifo((d / "fifo.off").c_str(), 0600), 0);
    struct Case {
        fs::path path;
        const char* cause;
    };
    for (const Case& c : {Case{d / "fifo.off", "cannot read: not a regular file (a FIFO)"},
                          Case{"/dev/zero", "cannot read: not a regular file (a character device)"},
                          Case{d, "cannot read: it is a directory, not a file"}}) {
        if (!fs::exists(c.path)) continue;
        for (int reader = 0; reader < 2; ++reader) {
            try {
                if (reader == 0) (void)readFile(c.path);
                else (void)inputFileSize(c.path);
                ADD_FAILURE() << c.path << " read";
            } catch (const InputError& e) {
                EXPECT_EQ(e.source(), c.path.string());
                EXPECT_NE(std::string(e.what()).find(c.cause), std::string::npos) << e.what();
            }
        }
    }
    writeFileAtomically(d / "eleven.txt", "eleven byte");
    EXPECT_EQ(readFile(d / "eleven.txt", 11), "eleven byte");
    try {
        (void)readFile(d / "eleven.txt", 10, "a test file");
        FAIL() << "read past its bound";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("11 bytes, over the limit of 10 bytes for a test file"), std::string::npos)
            << e.what();
    }
}

// Trap: paths whose cause was lost: a symbolic link loop said "no such file"; a path with a NUL
// byte (possible from Python and from a scene's JSON) opened the file named by its part before the
// NUL, or printed a message cut at the NUL. Both are refused with their cause, the NUL shown as \0,
// for reading and writing alike.
TEST(FileIo, SymlinkLoopsAndNulBytesAreSaidSo) {
    const fs::path d = freshDir("paths");
    fs::create_symlink(d / "b.off", d / "a.off");
    fs::create_symlink(d / "a.off", d / "b.off");
    try {
        (void)readFile(d / "a.off");
        FAIL() << "read a loop";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cannot open: too many levels of symbolic links"), std::string::npos)
            << e.what();
    }
    writeFileAtomically(d / "x", "real");
    const fs::path withNul = (d / "x").string() + std::string("\0.off", 5);
    const std::string shown = (d / "x").string() + "\\0.off";
    for (int op = 0; op < 2; ++op) {
        try {
            if (op == 0) (void)readFile(withNul);
            else writeFileAtomically(withNul, "overwritten?");
            FAIL() << "used the part before the NUL";
        } catch (const InputError& e) {
            EXPECT_EQ(e.source(), shown);
            EXPECT_NE(std::string(e.what()).find("the path contains a NUL byte"), std::string::npos) << e.what();
        }
    }
    EXPECT_EQ(readFile(d / "x"), "real");
}

}  // namespace
}  // namespace cullide
