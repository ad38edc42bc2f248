// Writing trace files: the header's rules, views and command rows, the blobs staged in a scratch
// file, and the file assembled and renamed into place (cullide/raster/trace.h, docs/trace-format.md).
// Both files are unnamed while they are written (O_TMPFILE), so a recording that dies, killed
// or not, leaves nothing beside its output.
#include "cullide/raster/trace.h"

#include "trace_format.h"

#include "cullide/error.h"
#include "cullide/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cstring>

namespace cullide::raster {

using namespace trace_format;

namespace {

Json rulesJson(const TraceRules& r) {
    return {
        {"window_transform",
         "x = right.p, y = up.p, z = dir.p in double from float32 p; xw = (x - xmin) / (xmax - xmin) * width, "
         "yw = (y - ymin) / (ymax - ymin) * height, zw = (z - znear) / (zfar - znear); origin bottom-left, y up; "
         "for a view with a tile, width and height are the tile's grid and the tile's origin is subtracted"},
        {"pixel_centers", "(i + 0.5, j + 0.5), one sample per pixel"},
        {"subpixel_bits", r.subpixelBits},
        {"fill_rule", toString(r.fillRule)},
        {"depth_encoding",
         {{"unorm", "k = round(clamp(z, 0, 1) * (2^n - 1)), ties up"},
          {"float32", "the nearest float32 of clamp(z, 0, 1)"}}},
        {"depth_plane", "through the unsnapped vertices, evaluated in double at the pixel centre"},
        {"other_subpixel_bits", r.otherSubpixelBits},
        {"depth_margin_lsb", r.depthLsb},
        {"depth_float_ulps", r.depthFloatUlps},
    };
}

Json vec3Json(const Vec3d& v) {
    return Json::array({v.x(), v.y(), v.z()});
}

Json viewJson(const OrthoView& v) {
    Json j = {{"right", vec3Json(v.right)},
              {"up", vec3Json(v.up)},
              {"dir", vec3Json(v.dir)},
              {"box", Json::array({v.xmin, v.xmax, v.ymin, v.ymax, v.znear, v.zfar})},
              {"viewport", Json::array({v.width, v.height})},
              {"depth", v.depth.name()}};
    // A tile of a larger view (OrthoView::tile): only then, so whole views read as before.
    if (v.tiled())
        j["tile"] = {{"origin", Json::array({v.originX, v.originY})},
                     {"grid", Json::array({v.fullWidth(), v.fullHeight()})}};
    return j;
}

// The reliable method's commands: refused by the writer and the recorder alike.
[[noreturn]] void refuseConservative() {
    throw InputError("trace",
                     "conservative commands (the reliable method) have no GL or Vulkan counterpart and "
                     "cannot be recorded; record the original or modified method");
}

// One command as a row [op, a, b, c].
std::array<uint32_t, 4> encodeCommand(const Command& c) {
    switch (c.op) {
        case Command::Op::Clear: {
            const uint64_t bits = std::bit_cast<uint64_t>(c.clearDepth);
            return {OpClear, uint32_t(bits), uint32_t(bits >> 32), 0};
        }
        case Command::Op::SetDepthFunc: return {OpDepthFunc, uint32_t(c.func), 0, 0};
        case Command::Op::SetDepthMask: return {OpDepthMask, c.mask ? 1u : 0u, 0, 0};
        case Command::Op::BeginQuery: return {OpBeginQuery, c.queryKind == QueryKind::AnySamplesPassed ? 1u : 0u, 0, 0};
        case Command::Op::EndQuery: return {OpEndQuery, 0, 0, 0};
        case Command::Op::Draw: return {OpDraw, c.first, c.count, 0};
        case Command::Op::ClearIntervals:
        case Command::Op::DrawConservative: break;
    }
    refuseConservative();
}

}  // namespace

// A file being written for `destination`, in its folder (same file system: the final rename is
// atomic). Where the file system has O_TMPFILE it has no name until commit(), so no death of the
// process leaves it behind; elsewhere it is a temporary named after the destination, removed by
// the destructor unless committed (a kill -9 then leaves it: the one case that can).
class TraceWriter::PendingFile {
public:
    explicit PendingFile(std::filesystem::path destination)
        : destination_(std::move(destination)), renameOnto_(assembledFor(destination_)) {
        const std::filesystem::path folder = renameOnto_.parent_path().empty() ? "." : renameOnto_.parent_path();
        // Naming an unnamed file needs /proc/self/fd (linkat of its descriptor).
        if (::access("/proc/self/fd", X_OK) == 0) fd_ = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0666);
        if (fd_ < 0) {  // no O_TMPFILE here, or another problem, which the named open then reports
            named_ = temporaryBeside(renameOnto_);
            fd_ = ::open(named_.c_str(), O_CREAT | O_EXCL | O_RDWR | O_CLOEXEC, 0666);
            if (fd_ < 0) throw cannotWrite(destination_, errno);
        }
        file_ = ::fdopen(fd_, "w+b");
        if (!file_) {
            const int err = errno;
            discard();
            throw cannotWrite(destination_, err);
        }
    }
    ~PendingFile() { discard(); }
    PendingFile(const PendingFile&) = delete;
    PendingFile& operator=(const PendingFile&) = delete;

    std::FILE* stream() const { return file_; }

    // A scratch file that is never committed: its name, if it has one, goes now.
    void unname() {
        if (!named_.empty()) ::unlink(named_.c_str());
        named_.clear();
    }

    // Flushes the file and gives it the destination's name (replacing a file there); throws
    // InputError(destination, ...) and leaves nothing when that fails.
    void commit() {
        int err = 0;
        if (std::fflush(file_) != 0) err = errno;
        std::filesystem::path named = named_;
        if (err == 0 && named.empty()) {  // O_TMPFILE: a name beside the destination, then the rename
            named = temporaryBeside(renameOnto_);
            const std::string self = "/proc/self/fd/" + std::to_string(fd_);
            if (::linkat(AT_FDCWD, self.c_str(), AT_FDCWD, named.c_str(), AT_SYMLINK_FOLLOW) != 0) err = errno;
            else named_ = named;
        }
        if (std::fclose(file_) != 0 && err == 0) err = errno;
        file_ = nullptr;
        fd_ = -1;
        if (err == 0 && std::rename(named_.c_str(), renameOnto_.c_str()) != 0) err = errno;
        if (err != 0) {
            discard();
            throw cannotWrite(destination_, err);
        }
        named_.clear();
    }

private:
    // Where the assembled trace is renamed (outputTarget): never a device or a FIFO, since a trace
    // is written, then read back and completed, in a file of its own.
    static std::filesystem::path assembledFor(const std::filesystem::path& destination) {
        const OutputTarget target = outputTarget(destination);
        if (target.inPlace())
            throw InputError(pathText(destination),
                             "cannot write: a trace is assembled in a file and renamed into place, not written "
                             "into a device or FIFO");
        return target.renameOnto;
    }

    void discard() {
        if (file_) std::fclose(file_);
        else if (fd_ >= 0) ::close(fd_);
        file_ = nullptr;
        fd_ = -1;
        unname();
    }

    std::filesystem::path destination_, renameOnto_, named_;
    int fd_ = -1;
    std::FILE* file_ = nullptr;
};

TraceWriter::TraceWriter(std::filesystem::path path, const TraceRules& rules, Json workload, Json provenance)
    : path_(std::move(path)), rules_(rules), workload_(std::move(workload)), provenance_(std::move(provenance)) {
    // Beside the destination (its file system has room for the trace), never named for longer
    // than its creation takes.
    scratchFile_ = std::make_unique<PendingFile>(path_);
    scratchFile_->unname();
    scratch_ = scratchFile_->stream();
}

TraceWriter::~TraceWriter() = default;

Json TraceWriter::blob(const void* data, size_t bytes, const char* dtype, size_t rows, size_t cols) {
    static const char zeros[8] = {};
    const size_t pad = size_t((8 - binaryBytes_ % 8) % 8);
    const bool ok =
        std::fwrite(zeros, 1, pad, scratch_) == pad && (bytes == 0 || std::fwrite(data, 1, bytes, scratch_) == bytes);
    if (!ok) throw InputError(path_.string(), std::string("cannot write: ") + std::strerror(errno));
    binaryBytes_ += pad;
    Json ref = {{"offset", binaryBytes_}, {"dtype", dtype}, {"shape", Json::array({rows, cols})}};
    binaryBytes_ += bytes;
    return ref;
}

// The scratch file is the only copy of what was written: the previous frame's triangles are
// compared against it, and the recorder reads a frame's geometry back from it, instead of keeping
// them in memory (a 10^6-triangle frame is 12 MB of triangles).
void TraceWriter::scratchRead(uint64_t offset, void* out, size_t bytes) {
    const std::string where = path_.string();
    bool ok = std::fflush(scratch_) == 0 && fseeko(scratch_, off_t(offset), SEEK_SET) == 0 &&
        std::fread(out, 1, bytes, scratch_) == bytes;
    ok = fseeko(scratch_, 0, SEEK_END) == 0 && ok;  // writes go on at the end
    if (!ok) throw InputError(where, std::string("cannot read back the scratch file: ") + std::strerror(errno));
}

bool TraceWriter::scratchEquals(uint64_t offset, const void* data, size_t bytes) {
    std::vector<char> buf(std::min<size_t>(bytes, size_t(1) << 20));
    for (size_t done = 0; done < bytes; done += buf.size()) {
        const size_t n = std::min(buf.size(), bytes - done);
        scratchRead(offset + done, buf.data(), n);
        if (std::memcmp(buf.data(), static_cast<const char*>(data) + done, n) != 0) return false;
    }
    return true;
}

void TraceWriter::beginFrame(uint32_t frame, std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
    CULLIDE_CHECK(!finished_, "TraceWriter::beginFrame after finish");
    Json positionsRef = blob(positions.data(), positions.size_bytes(), "<f4", positions.size(), 3);
    const bool sameTriangles = !lastTrianglesRef_.is_null() &&
        lastTrianglesRef_["shape"][0].get<size_t>() == triangles.size() &&
        scratchEquals(lastTrianglesRef_["offset"].get<uint64_t>(), triangles.data(), triangles.size_bytes());
    if (!sameTriangles) lastTrianglesRef_ = blob(triangles.data(), triangles.size_bytes(), "<u4", triangles.size(), 3);
    frames_.push_back({{"frame", frame},
                       {"positions", std::move(positionsRef)},
                       {"triangles", lastTrianglesRef_},
                       {"lists", Json::array()}});
}

void TraceWriter::frameGeometry(std::vector<Vec3f>& positions, std::vector<Triangle>& triangles) {
    CULLIDE_CHECK(!finished_ && !frames_.empty(), "TraceWriter::frameGeometry before beginFrame");
    const Json& f = frames_.back();
    positions.resize(f["positions"]["shape"][0].get<size_t>());
    triangles.resize(f["triangles"]["shape"][0].get<size_t>());
    scratchRead(f["positions"]["offset"].get<uint64_t>(), positions.data(), positions.size() * sizeof(Vec3f));
    scratchRead(f["triangles"]["offset"].get<uint64_t>(), triangles.data(), triangles.size() * sizeof(Triangle));
}

void TraceWriter::addList(const OrthoView& view, const CommandList& commands, std::span<const TraceQuery> queries) {
    CULLIDE_CHECK(!finished_ && !frames_.empty(), "TraceWriter::addList before beginFrame");
    CULLIDE_CHECK(queries.size() == commands.queryCount(), "TraceWriter::addList: one entry per query");
    std::vector<uint32_t> rows;
    rows.reserve(commands.commands().size() * 4);
    for (const Command& c : commands.commands()) {
        const std::array<uint32_t, 4> row = encodeCommand(c);
        rows.insert(rows.end(), row.begin(), row.end());
        if (c.op == Command::Op::Draw) trianglesDrawn_ += c.count;
    }
    std::vector<uint64_t> answers;
    answers.reserve(queries.size() * 3);
    for (const TraceQuery& q : queries) {
        answers.push_back(q.reference);
        answers.push_back(q.interval.certain);
        answers.push_back(q.interval.possible);
    }
    Json list = {{"view", viewJson(view)}};
    list["commands"] = blob(rows.data(), rows.size() * sizeof(uint32_t), "<u4", commands.commands().size(), 4);
    list["queries"] = blob(answers.data(), answers.size() * sizeof(uint64_t), "<u8", queries.size(), 3);
    frames_.back()["lists"].push_back(std::move(list));
    ++lists_;
    commands_ += commands.commands().size();
    queries_ += queries.size();
}

uint64_t TraceWriter::finish() {
    CULLIDE_CHECK(!finished_, "TraceWriter::finish twice");
    finished_ = true;
    const std::string where = path_.string();
    if (std::fflush(scratch_) != 0) throw InputError(where, std::string("cannot write: ") + std::strerror(errno));

    Json header = {{"format", "cullide-trace"},
                   {"version", kTraceFormatVersion},
                   {"cullide_version",
                    provenance_.is_object() ? provenance_.value("cullide_version", std::string("unknown"))
                                            : std::string("unknown")},
                   {"provenance", provenance_.is_object() ? provenance_ : Json::object()},
                   {"rules", rulesJson(rules_)},
                   {"workload", workload_},
                   {"summary",
                    {{"frames", frames_.size()},
                     {"lists", lists_},
                     {"commands", commands_},
                     {"queries", queries_},
                     {"triangles_drawn", trianglesDrawn_}}},
                   {"binary_bytes", binaryBytes_},
                   {"frames", frames_}};
    std::string text = header.dump(1) + "\n";
    text.append(size_t((8 - (kPreamble + text.size()) % 8) % 8), ' ');
    const uint64_t length = text.size();
    std::string head(kMagic, sizeof kMagic);
    for (int i = 0; i < 8; ++i) head.push_back(char((length >> (8 * i)) & 0xff));
    head += text;

    // The file: preamble and header, then the scratch file's bytes, named into place at the end.
    PendingFile out(path_);
    bool ok = std::fwrite(head.data(), 1, head.size(), out.stream()) == head.size();
    std::rewind(scratch_);
    std::vector<char> buf(1 << 20);
    size_t n;
    while (ok && (n = std::fread(buf.data(), 1, buf.size(), scratch_)) > 0)
        ok = std::fwrite(buf.data(), 1, n, out.stream()) == n;
    ok = ok && !std::ferror(scratch_);
    if (!ok) throw InputError(where, std::string("cannot write: ") + std::strerror(errno));
    out.commit();
    scratchFile_.reset();
    scratch_ = nullptr;
    return head.size() + binaryBytes_;
}

}  // namespace cullide::raster
