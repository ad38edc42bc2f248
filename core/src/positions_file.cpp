// Positions files (see positions_file.h and docs/scene-format.md).
//
// Numbers are little-endian on disk; a little-endian host reads a frame straight into its
// positions and a big-endian one swaps each float in place, so the bytes mean the same everywhere.
#include "cullide/positions_file.h"

#include "cullide/error.h"
#include "cullide/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace cullide {

namespace fs = std::filesystem;

// A frame is read into (and written from) Vec3f storage as it lies in memory: three floats.
static_assert(sizeof(Vec3f) == 12, "Vec3f must be three packed floats");

namespace {

uint64_t littleEndian(std::string_view bytes, size_t at, int size) {
    uint64_t v = 0;
    for (int k = size - 1; k >= 0; --k) v = (v << 8) | uint8_t(bytes[at + size_t(k)]);
    return v;
}

void appendLittleEndian(std::string& out, uint64_t v, int size) {
    for (int k = 0; k < size; ++k) out.push_back(char(uint8_t(v >> (8 * k))));
}

// Swaps every float of `bytes` between little-endian and the host's order (nothing on a
// little-endian host).
void toFromLittleEndian(char* bytes, size_t floats) {
    if constexpr (std::endian::native == std::endian::big)
        for (size_t i = 0; i < floats; ++i) std::reverse(bytes + 4 * i, bytes + 4 * i + 4);
    else
        (void)bytes, (void)floats;
}

std::string printable(std::string_view bytes) {
    std::string s;
    for (char c : bytes) {
        if (c >= 0x20 && c < 0x7f) {
            s += c;
        } else {
            char hex[8];
            std::snprintf(hex, sizeof hex, "\\x%02x", unsigned(uint8_t(c)));
            s += hex;
        }
    }
    return s;
}

std::string framesText(const PositionsHeader& h) {
    return std::to_string(h.frameCount) + " frame(s) of " + std::to_string(h.vertexCount) + " vertices";
}

// Reads exactly `n` bytes at `offset`; false when the file ends first.
bool readAt(int fd, char* out, size_t n, uint64_t offset, const std::string& source) {
    size_t got = 0;
    while (got < n) {
        const ssize_t r = ::pread(fd, out + got, n - got, off_t(offset + got));
        if (r == 0) return false;
        if (r < 0) {
            if (errno == EINTR) continue;
            throw InputError(source, std::string("cannot read: ") + std::strerror(errno));
        }
        got += size_t(r);
    }
    return true;
}

// Opens `path` for reading if it is a regular file; the checks and their messages are
// inputFileSize's (a FIFO is refused before it is opened, and opened without waiting should it
// be swapped in between).
// `size` is set to the file's size as opened.
int openRegular(const fs::path& path, const std::string& source, uint64_t& size) {
    (void)inputFileSize(path);
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) throw InputError(source, std::string("cannot open: ") + std::strerror(errno));
    struct stat info;
    if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
        ::close(fd);
        (void)inputFileSize(path);  // names what it is now
        throw InputError(source, "cannot read: not a regular file");
    }
    size = uint64_t(info.st_size);
    return fd;
}

}  // namespace

PositionsHeader parsePositionsHeader(std::string_view bytes, uint64_t fileBytes, const std::string& source) {
    if (fileBytes < kPositionsHeaderBytes || bytes.size() < kPositionsHeaderBytes)
        throw InputError(source, "truncated: " + std::to_string(fileBytes) + " bytes, shorter than the " +
                                     std::to_string(kPositionsHeaderBytes) + "-byte header of a positions file");
    const std::string_view magic = bytes.substr(0, 8);
    if (magic != std::string_view(kPositionsMagic, 8))
        throw InputError(source, "wrong magic '" + printable(magic) + "': not a cullide positions file (they begin '" +
                                     std::string(kPositionsMagic, 8) + "')");
    const uint64_t version = littleEndian(bytes, 8, 4);
    if (version != kPositionsVersion)
        throw InputError(source, "unsupported version " + std::to_string(version) + " (this build reads version " +
                                     std::to_string(kPositionsVersion) + ")");
    if (littleEndian(bytes, 24, 8) != 0) throw InputError(source, "reserved header bytes 24 to 31 are not zero");
    PositionsHeader h;
    h.vertexCount = uint32_t(littleEndian(bytes, 12, 4));
    h.frameCount = littleEndian(bytes, 16, 8);
    if (h.vertexCount == 0) throw InputError(source, "no vertices: the header's vertex count is 0");
    if (h.frameCount == 0) throw InputError(source, "no frames: the header's frame count is 0");
    if (h.frameCount > kMaxPositionsFrames)
        throw InputError(source, "too many frames: the header says " + std::to_string(h.frameCount) +
                                     ", over the limit of " + std::to_string(kMaxPositionsFrames));
    const uint64_t expected = h.fileBytes();
    if (fileBytes < expected)
        throw InputError(source, "truncated: " + std::to_string(fileBytes) + " bytes, but the header's " +
                                     framesText(h) + " need " + std::to_string(expected));
    if (fileBytes > expected)
        throw InputError(source, "size mismatch: " + std::to_string(fileBytes) + " bytes, but the header's " +
                                     framesText(h) + " need " + std::to_string(expected) + " (" +
                                     std::to_string(fileBytes - expected) + " bytes after the last frame)");
    return h;
}

PositionsFile::PositionsFile(const fs::path& path) : source_(pathText(path)) {
    uint64_t size = 0;
    fd_ = openRegular(path, source_, size);
    try {
        char head[kPositionsHeaderBytes] = {};
        const size_t want = size_t(std::min<uint64_t>(size, kPositionsHeaderBytes));
        if (!readAt(fd_, head, want, 0, source_)) throw InputError(source_, "truncated: the file shrank while read");
        header_ = parsePositionsHeader(std::string_view(head, want), size, source_);
    } catch (...) {
        ::close(fd_);
        throw;
    }
}

PositionsFile::~PositionsFile() {
    ::close(fd_);
}

void PositionsFile::readFrame(uint64_t f, std::vector<Vec3f>& out) const {
    const std::string at = "frame " + std::to_string(f);
    if (f >= header_.frameCount)
        throw InputError(source_, at + ": the file has only " + std::to_string(header_.frameCount) + " frame(s)");
    const size_t n = header_.vertexCount;
    try {
        out.resize(n);
    } catch (const std::bad_alloc&) {
        throw InputError(source_, at + ": out of memory for its " + std::to_string(n) + " vertices");
    }
    char* bytes = reinterpret_cast<char*>(out.data());
    const uint64_t offset = kPositionsHeaderBytes + f * uint64_t(n) * 12;
    if (!readAt(fd_, bytes, n * 12, offset, source_))
        throw InputError(source_, at + ": truncated: the file ends inside the frame (it shrank since it was opened)");
    toFromLittleEndian(bytes, n * 3);
    for (size_t v = 0; v < n; ++v)
        if (!out[v].allFinite())
            throw InputError(source_, at + ": vertex " + std::to_string(v) + " is not finite (NaN or Inf)");
}

void writePositionsFile(const fs::path& path, uint32_t vertexCount, uint64_t frameCount,
                        const std::function<std::span<const Vec3f>(uint64_t)>& frame) {
    CULLIDE_CHECK(vertexCount > 0 && frameCount > 0 && frameCount <= kMaxPositionsFrames,
                  "a positions file needs vertices and 1 to kMaxPositionsFrames frames");
    OutputFile out(path);
    std::string head(kPositionsMagic, 8);
    appendLittleEndian(head, kPositionsVersion, 4);
    appendLittleEndian(head, vertexCount, 4);
    appendLittleEndian(head, frameCount, 8);
    appendLittleEndian(head, 0, 8);
    out.write(head);
    std::vector<Vec3f> swapped;
    for (uint64_t f = 0; f < frameCount && !out.failed(); ++f) {
        std::span<const Vec3f> p = frame(f);
        CULLIDE_CHECK(p.size() == vertexCount, "a frame of a positions file has the wrong vertex count");
        if constexpr (std::endian::native == std::endian::big) {
            swapped.assign(p.begin(), p.end());
            toFromLittleEndian(reinterpret_cast<char*>(swapped.data()), swapped.size() * 3);
            p = swapped;
        }
        out.write({reinterpret_cast<const char*>(p.data()), p.size() * sizeof(Vec3f)});
    }
    out.commit();
}

}  // namespace cullide
