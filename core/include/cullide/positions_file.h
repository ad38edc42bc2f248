// Positions files: every frame of one deforming object's vertex positions in one binary file, read
// one frame at a time (docs/scene-format.md, "Positions files", gives the layout byte by byte).
//
// Layout: a 32-byte header (magic "CULVERTS", uint32 version 1, uint32 vertex count, uint64 frame
// count, 8 reserved zero bytes), then frame after frame, each vertex count x 3 float32 (x, y, z);
// every number little-endian. The file's size is exactly what its header says: a file cut short,
// or with bytes after its last frame, is refused when it is opened, before any frame is read.
//
// Why binary and one file per object: the field's deforming scenes have tens of thousands of
// vertices and about a hundred frames; as text (an OFF per frame) that is several times the size
// and a parse per frame, where a frame here is one read of 12 bytes per vertex.
#pragma once

#include "cullide/mesh.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace cullide {

inline constexpr char kPositionsMagic[8] = {'C', 'U', 'L', 'V', 'E', 'R', 'T', 'S'};
inline constexpr uint32_t kPositionsVersion = 1;
inline constexpr size_t kPositionsHeaderBytes = 32;
// The most frames a positions file may hold: far more than any benchmark sequence (hundreds), and
// few enough that an animation's per-frame bookkeeping stays small whatever a header claims.
inline constexpr uint64_t kMaxPositionsFrames = 100'000;

struct PositionsHeader {
    uint32_t vertexCount = 0;
    uint64_t frameCount = 0;

    // The exact size of a file with this header (fits in 64 bits: at most kMaxPositionsFrames
    // frames of 2^32 - 1 vertices).
    uint64_t fileBytes() const { return kPositionsHeaderBytes + frameCount * uint64_t(vertexCount) * 12; }
};

// The header of a positions file of `fileBytes` bytes whose first bytes are `bytes` (at least
// min(fileBytes, kPositionsHeaderBytes) of them). Throws InputError(source, cause) unless the file
// is one this build reads: "truncated: ..." (shorter than the header, or than its frames),
// "wrong magic ...", "unsupported version ...", "reserved header bytes ... are not zero", "no
// vertices", "no frames", "too many frames ...", "size mismatch: ..." (bytes after the frames).
PositionsHeader parsePositionsHeader(std::string_view bytes, uint64_t fileBytes, const std::string& source);

// An open positions file whose header and size were checked. Not copyable; reads are positioned
// (pread), so one file may serve several threads.
class PositionsFile {
public:
    // Opens `path` (a regular file only: a FIFO or device is refused before it is opened, as every
    // input is, file_io.h) and checks its header and size. Throws InputError(pathText(path), ...).
    explicit PositionsFile(const std::filesystem::path& path);
    ~PositionsFile();
    PositionsFile(const PositionsFile&) = delete;
    PositionsFile& operator=(const PositionsFile&) = delete;

    const PositionsHeader& header() const { return header_; }
    const std::string& source() const { return source_; }

    // Frame f's positions, read with one positioned read of exactly that frame into `out` (resized
    // to the vertex count). Throws InputError(source(), "frame f: ...") when f is not a frame of
    // the file, the read fails or comes up short (the file shrank), or a coordinate is not finite.
    void readFrame(uint64_t f, std::vector<Vec3f>& out) const;

private:
    std::string source_;
    int fd_ = -1;
    PositionsHeader header_;
};

// Writes a positions file of `frameCount` frames of `vertexCount` positions at `path`, frame f
// being frame(f) (exactly vertexCount positions, kept valid until the next call), all or nothing:
// through a temporary beside `path` renamed into place, removed again when a write or frame(f)
// throws. The same frames give the same bytes. Throws InputError(path, cause) when it cannot be
// written; what frame(f) throws passes through.
void writePositionsFile(const std::filesystem::path& path, uint32_t vertexCount, uint64_t frameCount,
                        const std::function<std::span<const Vec3f>(uint64_t)>& frame);

}  // namespace cullide
