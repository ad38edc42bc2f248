// Tests for core/src/positions_file.cpp: the binary positions file's layout, its header checks,
// frame reads and the all-or-nothing writer.
#include "cullide/positions_file.h"

#include "cullide/error.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace cullide {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// `frames` frames of `vertices` positions, each coordinate distinct: frame f, vertex v, axis k is
// f * 1000 + v * 10 + k (frame 0 vertex 0 x is -0.0, which must come back as -0.0).
std::vector<std::vector<Vec3f>> sampleFrames(uint64_t frames, uint32_t vertices) {
    std::vector<std::vector<Vec3f>> all(frames, std::vector<Vec3f>(vertices));
    for (uint64_t f = 0; f < frames; ++f)
        for (uint32_t v = 0; v < vertices; ++v)
            all[f][v] = Vec3f(float(f * 1000 + v * 10), float(f * 1000 + v * 10 + 1), float(f * 1000 + v * 10 + 2));
    all[0][0].x() = -0.0f;
    return all;
}

void writeSample(const fs::path& p, const std::vector<std::vector<Vec3f>>& all) {
    writePositionsFile(p, uint32_t(all[0].size()), all.size(), [&](uint64_t f) { return std::span<const Vec3f>(all[f]); });
}

// A 32-byte header as the format lays it out, with each field given.
std::string header(const std::string& magic, uint32_t version, uint32_t vertices, uint64_t frames, uint64_t reserved) {
    std::string h = magic;
    const auto put = [&](uint64_t v, int bytes) {
        for (int k = 0; k < bytes; ++k) h.push_back(char(uint8_t(v >> (8 * k))));
    };
    put(version, 4), put(vertices, 4), put(frames, 8), put(reserved, 8);
    return h;
}

std::string causeOf(const std::string& bytes) {
    try {
        (void)parsePositionsHeader(bytes, bytes.size(), "p.pos");
    } catch (const InputError& e) {
        return e.what();
    }
    return "accepted";
}

// Trap: a layout other than the documented one (field order, width or byte order), or floats
// that do not come back bit for bit (-0.0 as 0.0): the header and the first frame's bytes are
// checked against docs/scene-format.md's table, and every frame reads back as written.
TEST(PositionsFile, LayoutIsTheDocumentedOneAndFramesReadBackBitExact) {
    TempDir d;
    const auto all = sampleFrames(3, 4);
    writeSample(d / "a.pos", all);
    const std::string bytes = test::readBytes(d / "a.pos");
    ASSERT_EQ(bytes.size(), 32u + 3 * 4 * 12);
    EXPECT_EQ(bytes.substr(0, 32), header("CULVERTS", 1, 4, 3, 0));
    uint32_t x1 = 0;  // frame 0, vertex 0, y = 1.0f: 0x3f800000 little-endian at byte 36
    for (int k = 3; k >= 0; --k) x1 = (x1 << 8) | uint8_t(bytes[size_t(36 + k)]);
    EXPECT_EQ(x1, std::bit_cast<uint32_t>(1.0f));

    const PositionsFile file(d / "a.pos");
    EXPECT_EQ(file.header().vertexCount, 4u);
    EXPECT_EQ(file.header().frameCount, 3u);
    std::vector<Vec3f> got;
    for (uint64_t f : {2u, 0u, 1u}) {
        file.readFrame(f, got);
        ASSERT_EQ(got.size(), 4u);
        for (size_t v = 0; v < 4; ++v)
            for (int k = 0; k < 3; ++k)
                EXPECT_EQ(std::bit_cast<uint32_t>(got[v][k]), std::bit_cast<uint32_t>(all[f][v][k])) << f << " " << v;
    }
    file.readFrame(0, got);
    EXPECT_TRUE(std::signbit(got[0].x()));
    writeSample(d / "b.pos", all);
    EXPECT_EQ(test::readBytes(d / "b.pos"), bytes);  // same frames, same bytes
}

// Trap: a wrong file taken for positions (another format, another version, a header whose counts
// do not fit the file's size, counts of zero, a frame count that would allocate without bound):
// each refused with its cause before any frame is read.
TEST(PositionsFile, HeaderChecksNameTheCause) {
    const std::string frame(12, '\0');
    EXPECT_EQ(causeOf(header("CULVERTS", 1, 1, 1, 0) + frame), "accepted");
    EXPECT_EQ(causeOf("CULVERTS"), "p.pos: truncated: 8 bytes, shorter than the 32-byte header of a positions file");
    EXPECT_EQ(causeOf(header("OFF\n3 1 ", 1, 1, 1, 0) + frame),
              "p.pos: wrong magic 'OFF\\x0a3 1 ': not a cullide positions file (they begin 'CULVERTS')");
    EXPECT_EQ(causeOf(header("CULVERTS", 2, 1, 1, 0) + frame), "p.pos: unsupported version 2 (this build reads version 1)");
    EXPECT_EQ(causeOf(header("CULVERTS", 1, 1, 1, 7) + frame), "p.pos: reserved header bytes 24 to 31 are not zero");
    EXPECT_EQ(causeOf(header("CULVERTS", 1, 0, 1, 0)), "p.pos: no vertices: the header's vertex count is 0");
    EXPECT_EQ(causeOf(header("CULVERTS", 1, 1, 0, 0)), "p.pos: no frames: the header's frame count is 0");
    EXPECT_EQ(causeOf(header("CULVERTS", 1, 1, ~uint64_t(0), 0)),
              "p.pos: too many frames: the header says 18446744073709551615, over the limit of 100000");
    EXPECT_EQ(causeOf(header("CULVERTS", 1, 2, 2, 0) + frame + frame + frame),
              "p.pos: truncated: 68 bytes, but the header's 2 frame(s) of 2 vertices need 80");
    EXPECT_EQ(causeOf(header("CULVERTS", 1, 1, 1, 0) + frame + "x"),
              "p.pos: size mismatch: 45 bytes, but the header's 1 frame(s) of 1 vertices need 44 (1 bytes after the "
              "last frame)");
    // The largest header's size does not overflow: 2^32 - 1 vertices, the most frames.
    EXPECT_NE(causeOf(header("CULVERTS", 1, ~uint32_t(0), kMaxPositionsFrames, 0)).find("truncated"), std::string::npos);
}

// Trap: values trusted because the header was (a NaN in one frame reaching the culler), a frame
// index past the file, a file that shrank after it was opened, or a FIFO whose open waits for a
// writer forever: each an InputError naming the file (and the frame), the other frames readable.
TEST(PositionsFile, FramesAreCheckedWhenReadAndOnlyRegularFilesOpen) {
    TempDir d;
    auto all = sampleFrames(3, 4);
    all[2][3].y() = std::numeric_limits<float>::quiet_NaN();
    writePositionsFile(d / "nan.pos", 4, 3, [&](uint64_t f) { return std::span<const Vec3f>(all[f]); });
    const std::string path = (d / "nan.pos").string();
    const PositionsFile file(path);
    std::vector<Vec3f> got;
    EXPECT_NO_THROW(file.readFrame(1, got));
    const auto refused = [&](uint64_t f, const std::string& message) {
        try {
            file.readFrame(f, got);
            ADD_FAILURE() << "frame " << f << " read";
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()), path + ": " + message);
        }
    };
    refused(2, "frame 2: vertex 3 is not finite (NaN or Inf)");
    refused(3, "frame 3: the file has only 3 frame(s)");
    fs::resize_file(path, 32 + 12 * 4 * 2 + 5);
    refused(2, "frame 2: truncated: the file ends inside the frame (it shrank since it was opened)");

    ASSERT_EQ(::mkfifo((d / "fifo.pos").c_str(), 0600), 0);
    try {
        const PositionsFile fifo(d / "fifo.pos");
        ADD_FAILURE() << "a FIFO opened";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("not a regular file (a FIFO)"), std::string::npos) << e.what();
    }
    EXPECT_THROW(PositionsFile(d / "missing.pos"), InputError);
}

// Trap: a failed write leaving a partial file (or its temporary) behind: a missing folder and a
// frame that throws while the file is written both leave the folder as it was.
TEST(PositionsFile, FailedWritesLeaveNothing) {
    TempDir d;
    const auto all = sampleFrames(2, 3);
    try {
        writeSample(d / "no_folder" / "a.pos", all);
        ADD_FAILURE() << "written";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
    }
    EXPECT_THROW(writePositionsFile(d / "a.pos", 3, 2,
                                    [&](uint64_t f) -> std::span<const Vec3f> {
                                        if (f == 1) throw InputError("source.pos", "frame 1: gone");
                                        return all[f];
                                    }),
                 InputError);
    EXPECT_TRUE(fs::is_empty(d.path()));
}

}  // namespace
}  // namespace cullide
