// Trace files: writing, reading (every field checked), recording and replaying
// (cullide/raster/trace.h, docs/trace-format.md).
#include "cullide/raster/trace.h"

#include "cullide/error.h"
#include "cullide/file_io.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

namespace cullide::raster {

// The blobs are the host's arrays written as they are: the format says little-endian.
static_assert(std::endian::native == std::endian::little, "trace blobs are written in host order");
static_assert(sizeof(Vec3f) == 3 * sizeof(float) && sizeof(Triangle) == 3 * sizeof(uint32_t));

namespace {

using Json = nlohmann::ordered_json;

constexpr char kMagic[8] = {'C', 'U', 'L', 'T', 'R', 'A', 'C', 'E'};
constexpr size_t kPreamble = 16;  // magic + header length
// Op codes of the command rows (the format's table; Command::Op order for 0-5).
enum TraceOp : uint32_t { OpClear = 0, OpDepthFunc, OpDepthMask, OpBeginQuery, OpEndQuery, OpDraw, OpCount };

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

std::string fileSize(uint64_t n) {
    return std::to_string(n) + " byte" + (n == 1 ? "" : "s");
}

}  // namespace

IntervalOptions TraceRules::intervalOptions() const {
    IntervalOptions o;
    o.subpixelBits = subpixelBits;
    o.fillRule = fillRule;
    o.otherSubpixelBits = otherSubpixelBits;
    o.depthLsb = depthLsb;
    o.depthFloatUlps = depthFloatUlps;
    return o;
}

// ---------------------------------------------------------------------------------------------
// TraceWriter

TraceWriter::TraceWriter(std::filesystem::path path, const TraceRules& rules, Json workload, Json provenance)
    : path_(std::move(path)), rules_(rules), workload_(std::move(workload)), provenance_(std::move(provenance)) {
    static std::atomic<unsigned> counter{0};
    scratchPath_ = path_;
    scratchPath_ += ".blobs.tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
    scratch_ = std::fopen(scratchPath_.string().c_str(), "w+b");
    if (!scratch_) {
        const int openErrno = errno;
        const std::filesystem::path folder = path_.parent_path();
        std::error_code ec;
        if (!folder.empty() && !std::filesystem::exists(folder, ec))
            throw InputError(path_.string(), "folder " + folder.string() + " does not exist");
        throw InputError(path_.string(), std::string("cannot write: ") + std::strerror(openErrno));
    }
}

TraceWriter::~TraceWriter() {
    if (scratch_) std::fclose(scratch_);
    std::error_code ec;
    std::filesystem::remove(scratchPath_, ec);
}

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

    // The file: preamble and header, then the scratch file's bytes, renamed into place.
    static std::atomic<unsigned> counter{0};
    std::filesystem::path tmp = path_;
    tmp += ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
    std::FILE* out = std::fopen(tmp.string().c_str(), "wb");
    if (!out) throw InputError(where, std::string("cannot write: ") + std::strerror(errno));
    bool ok = std::fwrite(head.data(), 1, head.size(), out) == head.size();
    std::rewind(scratch_);
    std::vector<char> buf(1 << 20);
    size_t n;
    while (ok && (n = std::fread(buf.data(), 1, buf.size(), scratch_)) > 0)
        ok = std::fwrite(buf.data(), 1, n, out) == n;
    ok = ok && !std::ferror(scratch_);
    const int err = errno;
    ok = (std::fclose(out) == 0) && ok;
    std::error_code ec;
    if (!ok) {
        std::filesystem::remove(tmp, ec);
        throw InputError(where, std::string("cannot write: ") + std::strerror(err));
    }
    std::filesystem::rename(tmp, path_, ec);
    if (ec) {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        throw InputError(where, "cannot write: " + ec.message());
    }
    return head.size() + binaryBytes_;
}

// ---------------------------------------------------------------------------------------------
// TraceReader

namespace {

// Checked access to the header, naming where a problem is ("frames[2].lists[5].view").
const Json& field(const Json& obj, const char* key, const std::string& where) {
    if (!obj.is_object()) throw std::invalid_argument(where + " is not a JSON object");
    const auto it = obj.find(key);
    if (it == obj.end()) throw std::invalid_argument(where + " has no \"" + key + "\"");
    return *it;
}

uint64_t unsignedField(const Json& obj, const char* key, const std::string& where, uint64_t max) {
    const Json& v = field(obj, key, where);
    if (!v.is_number_unsigned() || v.get<uint64_t>() > max)
        throw std::invalid_argument(where + "." + key + " is " + v.dump() + ", not an integer in 0.." +
                                    std::to_string(max));
    return v.get<uint64_t>();
}

double numberField(const Json& v, const std::string& where) {
    if (!v.is_number()) throw std::invalid_argument(where + " is " + v.dump() + ", not a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) throw std::invalid_argument(where + " is not finite");
    return d;
}

std::vector<double> numbers(const Json& obj, const char* key, const std::string& where, size_t count) {
    const Json& v = field(obj, key, where);
    if (!v.is_array() || v.size() != count)
        throw std::invalid_argument(where + "." + key + " is not an array of " + std::to_string(count) + " numbers");
    std::vector<double> out;
    for (size_t i = 0; i < count; ++i)
        out.push_back(numberField(v[i], where + "." + key + "[" + std::to_string(i) + "]"));
    return out;
}

OrthoView parseView(const Json& j, const std::string& where) {
    OrthoView v;
    const auto r = numbers(j, "right", where, 3), u = numbers(j, "up", where, 3), d = numbers(j, "dir", where, 3);
    v.right = {r[0], r[1], r[2]};
    v.up = {u[0], u[1], u[2]};
    v.dir = {d[0], d[1], d[2]};
    const auto box = numbers(j, "box", where, 6);
    v.xmin = box[0], v.xmax = box[1], v.ymin = box[2], v.ymax = box[3], v.znear = box[4], v.zfar = box[5];
    const Json& vp = field(j, "viewport", where);
    if (!vp.is_array() || vp.size() != 2 || !vp[0].is_number_unsigned() || !vp[1].is_number_unsigned() ||
        vp[0].get<uint64_t>() > uint64_t(kMaxViewportSide) || vp[1].get<uint64_t>() > uint64_t(kMaxViewportSide))
        throw std::invalid_argument(where + ".viewport is not [width, height] with sides 1.." +
                                    std::to_string(kMaxViewportSide));
    v.width = int(vp[0].get<uint64_t>());
    v.height = int(vp[1].get<uint64_t>());
    if (j.contains("tile")) {
        const Json& tile = j["tile"];
        auto pair = [&](const char* key) {
            const Json& p = field(tile, key, where + ".tile");
            if (!p.is_array() || p.size() != 2 || !p[0].is_number_unsigned() || !p[1].is_number_unsigned() ||
                p[0].get<uint64_t>() > uint64_t(kMaxViewportSide) || p[1].get<uint64_t>() > uint64_t(kMaxViewportSide))
                throw std::invalid_argument(where + ".tile." + key + " is not a pair of integers 0.." +
                                            std::to_string(kMaxViewportSide));
            return std::pair{int(p[0].get<uint64_t>()), int(p[1].get<uint64_t>())};
        };
        std::tie(v.originX, v.originY) = pair("origin");
        std::tie(v.gridWidth, v.gridHeight) = pair("grid");
    }
    const Json& depth = field(j, "depth", where);
    if (!depth.is_string()) throw std::invalid_argument(where + ".depth is not a string");
    try {
        v.depth = DepthFormat::parse(depth.get<std::string>());
        v.validate();
    } catch (const InputError& e) {
        throw std::invalid_argument(where + ": " + e.what());
    }
    return v;
}

}  // namespace

void TraceReader::fail(const std::string& problem) const {
    throw InputError(pathText_, problem);
}

TraceReader::TraceReader(std::filesystem::path path) : path_(std::move(path)), pathText_(path_.string()) {
    std::error_code ec;
    const auto status = std::filesystem::status(path_, ec);
    if (ec || !std::filesystem::exists(status)) fail("cannot open: no such file");
    if (std::filesystem::is_directory(status)) fail("cannot read: it is a directory, not a file");
    fileBytes_ = std::filesystem::file_size(path_, ec);
    if (ec) fail("cannot read: " + ec.message());
    std::ifstream in(path_, std::ios::binary);
    if (!in) fail("cannot open: " + std::string(std::strerror(errno)));
    char pre[kPreamble];
    if (fileBytes_ < kPreamble || !in.read(pre, kPreamble))
        fail("truncated: " + fileSize(fileBytes_) + ", shorter than the 16-byte preamble of a trace");
    if (std::memcmp(pre, kMagic, sizeof kMagic) != 0) fail("not a cullide trace (it does not start with CULTRACE)");
    uint64_t length = 0;
    for (int i = 0; i < 8; ++i) length |= uint64_t(uint8_t(pre[8 + i])) << (8 * i);
    if (length > fileBytes_ - kPreamble)
        fail("truncated: the preamble announces a " + fileSize(length) + " header, the file has " +
             fileSize(fileBytes_ - kPreamble) + " after the preamble");
    std::string text(size_t(length), '\0');
    if (!in.read(text.data(), std::streamsize(length))) fail("cannot read the header");
    try {
        header_ = Json::parse(text);
    } catch (const nlohmann::json::exception& e) {  // parse_error, and out_of_range for 1e99999
        fail(std::string("the header is not valid JSON: ") + e.what());
    }
    binaryStart_ = kPreamble + length;

    try {
        const Json& format = field(header_, "format", "the header");
        if (format != "cullide-trace") fail("not a cullide trace (format is " + format.dump() + ")");
        const uint64_t version = unsignedField(header_, "version", "the header", std::numeric_limits<uint32_t>::max());
        if (version > uint64_t(kTraceFormatVersion))
            fail("trace format version " + std::to_string(version) + " is newer than this cullide reads (" +
                 std::to_string(kTraceFormatVersion) + "); use a newer cullide");
        if (version < 1) fail("trace format version 0 does not exist");
        binaryBytes_ = unsignedField(header_, "binary_bytes", "the header", std::numeric_limits<uint64_t>::max());
        if (binaryBytes_ != fileBytes_ - binaryStart_)
            fail((binaryBytes_ > fileBytes_ - binaryStart_ ? std::string("truncated: ") : std::string("")) +
                 "the header announces a binary section of " + fileSize(binaryBytes_) + ", the file has " +
                 fileSize(fileBytes_ - binaryStart_) + " after the header");

        const Json& rules = field(header_, "rules", "the header");
        rules_.subpixelBits = int(unsignedField(rules, "subpixel_bits", "rules", kMaxSubpixelBits));
        if (rules_.subpixelBits < kMinSubpixelBits) throw std::invalid_argument("rules.subpixel_bits is 0");
        const Json& fill = field(rules, "fill_rule", "rules");
        const std::optional<FillRule> rule = fill.is_string() ? parseFillRule(fill.get<std::string>()) : std::nullopt;
        if (!rule) throw std::invalid_argument("rules.fill_rule is " + fill.dump() + ", not " + kFillRuleNames);
        rules_.fillRule = *rule;
        rules_.otherSubpixelBits = int(unsignedField(rules, "other_subpixel_bits", "rules", 24));
        if (rules_.otherSubpixelBits < 1) throw std::invalid_argument("rules.other_subpixel_bits is 0");
        rules_.depthLsb = numberField(field(rules, "depth_margin_lsb", "rules"), "rules.depth_margin_lsb");
        rules_.depthFloatUlps = numberField(field(rules, "depth_float_ulps", "rules"), "rules.depth_float_ulps");
        if (rules_.depthLsb < 0 || rules_.depthFloatUlps < 0) throw std::invalid_argument("rules: a negative margin");

        const Json& frames = field(header_, "frames", "the header");
        if (!frames.is_array()) throw std::invalid_argument("frames is not an array");
        for (size_t f = 0; f < frames.size(); ++f) {
            const std::string where = "frames[" + std::to_string(f) + "]";
            FrameInfo info;
            info.frame = uint32_t(unsignedField(frames[f], "frame", where, std::numeric_limits<uint32_t>::max()));
            info.positions = parseBlob(field(frames[f], "positions", where), where + ".positions", "<f4", 3);
            info.triangles = parseBlob(field(frames[f], "triangles", where), where + ".triangles", "<u4", 3);
            if (info.positions.rows > std::numeric_limits<uint32_t>::max() ||
                info.triangles.rows > std::numeric_limits<uint32_t>::max())
                throw std::invalid_argument(where + ": more than 2^32 vertices or triangles");
            const Json& lists = field(frames[f], "lists", where);
            if (!lists.is_array()) throw std::invalid_argument(where + ".lists is not an array");
            info.firstList = lists_.size();
            info.lists = lists.size();
            for (size_t l = 0; l < lists.size(); ++l) {
                const std::string lw = where + ".lists[" + std::to_string(l) + "]";
                ListInfo li;
                li.frameIndex = f;
                li.view = parseView(field(lists[l], "view", lw), lw + ".view");
                li.commands = parseBlob(field(lists[l], "commands", lw), lw + ".commands", "<u4", 4);
                li.queryRows = parseBlob(field(lists[l], "queries", lw), lw + ".queries", "<u8", 3);
                li.queries = size_t(li.queryRows.rows);
                lists_.push_back(li);
            }
            frames_.push_back(info);
        }
    } catch (const std::invalid_argument& e) {
        fail(e.what());
    } catch (const nlohmann::json::exception& e) {
        fail(std::string("the header: ") + e.what());
    }
}

TraceReader::BlobRef TraceReader::parseBlob(const Json& j, const std::string& where, const char* dtype,
                                            size_t cols) const {
    BlobRef b;
    b.offset = unsignedField(j, "offset", where, binaryBytes_);
    if (b.offset % 8 != 0)
        throw std::invalid_argument(where + ".offset " + std::to_string(b.offset) + " is not a multiple of 8");
    const Json& type = field(j, "dtype", where);
    if (type != dtype) throw std::invalid_argument(where + ".dtype is " + type.dump() + ", expected \"" + dtype + "\"");
    const Json& shape = field(j, "shape", where);
    if (!shape.is_array() || shape.size() != 2 || !shape[0].is_number_unsigned() || shape[1] != cols)
        throw std::invalid_argument(where + ".shape is " + shape.dump() + ", expected [rows, " + std::to_string(cols) +
                                    "]");
    b.rows = shape[0].get<uint64_t>();
    const uint64_t item = dtype[2] == '8' ? 8 : 4;
    if (b.rows > (binaryBytes_ - b.offset) / (item * cols))
        throw std::invalid_argument(where + ": " + std::to_string(b.rows) + " rows at offset " +
                                    std::to_string(b.offset) + " run past the binary section's " +
                                    fileSize(binaryBytes_));
    return b;
}

void TraceReader::readBlob(const BlobRef& ref, size_t itemBytes, size_t cols, void* out) const {
    const uint64_t bytes = ref.rows * cols * itemBytes;
    if (bytes == 0) return;
    std::ifstream in(path_, std::ios::binary);
    in.seekg(std::streamoff(binaryStart_ + ref.offset));
    if (!in || !in.read(static_cast<char*>(out), std::streamsize(bytes)))
        fail("cannot read " + fileSize(bytes) + " at offset " + std::to_string(binaryStart_ + ref.offset) +
             " (was the file changed while it was read?)");
}

void TraceReader::readGeometry(size_t f, std::vector<Vec3f>& positions, std::vector<Triangle>& triangles) const {
    const FrameInfo& info = frames_.at(f);
    positions.resize(size_t(info.positions.rows));
    triangles.resize(size_t(info.triangles.rows));
    readBlob(info.positions, 4, 3, positions.data());
    readBlob(info.triangles, 4, 3, triangles.data());
    for (size_t i = 0; i < positions.size(); ++i)
        if (!positions[i].allFinite())
            fail("frames[" + std::to_string(f) + "]: vertex " + std::to_string(i) + " is not finite (NaN or Inf)");
    const uint64_t n = positions.size();
    for (size_t t = 0; t < triangles.size(); ++t)
        for (uint32_t v : triangles[t])
            if (v >= n)
                fail("frames[" + std::to_string(f) + "]: triangle " + std::to_string(t) + " uses vertex " +
                     std::to_string(v) + ", but the frame has " + std::to_string(n) + " vertices");
}

TraceList TraceReader::readList(size_t index) const {
    const ListInfo& info = lists_.at(index);
    const FrameInfo& frame = frames_[info.frameIndex];
    TraceList out;
    out.frameIndex = info.frameIndex;
    out.frame = frame.frame;
    out.index = index;
    out.view = info.view;
    const std::string where = "list " + std::to_string(index) + " (frame " + std::to_string(frame.frame) + ")";

    std::vector<uint32_t> rows(size_t(info.commands.rows) * 4);
    readBlob(info.commands, 4, 4, rows.data());
    for (size_t k = 0; k < info.commands.rows; ++k) {
        const uint32_t op = rows[4 * k], a = rows[4 * k + 1], b = rows[4 * k + 2], c = rows[4 * k + 3];
        const std::string cw = where + " command " + std::to_string(k);
        auto unused = [&](bool ok) {
            if (!ok) fail(cw + ": words it does not use must be 0");
        };
        try {
            switch (op) {
                case OpClear: {
                    unused(c == 0);
                    const double depth = std::bit_cast<double>(uint64_t(a) | (uint64_t(b) << 32));
                    out.commands.clear(depth);
                    break;
                }
                case OpDepthFunc:
                    if (a > 7) fail(cw + ": depth function " + std::to_string(a) + " (0..7)");
                    unused(b == 0 && c == 0);
                    out.commands.depthFunc(DepthFunc(a));
                    break;
                case OpDepthMask:
                    if (a > 1) fail(cw + ": depth mask " + std::to_string(a) + " (0 or 1)");
                    unused(b == 0 && c == 0);
                    out.commands.depthMask(a == 1);
                    break;
                case OpBeginQuery:
                    if (a > 1) fail(cw + ": query kind " + std::to_string(a) + " (0 samples, 1 any samples)");
                    unused(b == 0 && c == 0);
                    out.kinds.push_back(a == 1 ? QueryKind::AnySamplesPassed : QueryKind::SamplesPassed);
                    out.commands.beginQuery(out.kinds.back());
                    break;
                case OpEndQuery:
                    unused(a == 0 && b == 0 && c == 0);
                    out.commands.endQuery();
                    break;
                case OpDraw:
                    unused(c == 0);
                    if (uint64_t(a) + b > frame.triangles.rows)
                        fail(cw + ": draws triangles [" + std::to_string(a) + ", " + std::to_string(uint64_t(a) + b) +
                             "), but the frame has " + std::to_string(frame.triangles.rows));
                    out.commands.draw(a, b);
                    break;
                default: fail(cw + ": unknown op " + std::to_string(op) + " (version 1 has 0..5)");
            }
        } catch (const InputError& e) {
            if (e.source() == pathText_) throw;
            fail(cw + ": " + e.what());
        }
    }
    if (out.commands.queryOpen()) fail(where + ": a query is begun and never ended");
    if (out.commands.queryCount() != info.queries)
        fail(where + ": " + std::to_string(out.commands.queryCount()) + " begin_query commands but " +
             std::to_string(info.queries) + " query rows");

    std::vector<uint64_t> answers(info.queries * 3);
    readBlob(info.queryRows, 8, 3, answers.data());
    out.queries.resize(info.queries);
    for (size_t q = 0; q < info.queries; ++q) {
        TraceQuery& tq = out.queries[q];
        tq.reference = answers[3 * q];
        tq.interval = {answers[3 * q + 1], answers[3 * q + 2]};
        const std::string qw = where + " query " + std::to_string(q);
        if (tq.interval.certain > tq.interval.possible)
            fail(qw + ": certain " + std::to_string(tq.interval.certain) + " > possible " +
                 std::to_string(tq.interval.possible));
        if (out.kinds[q] == QueryKind::AnySamplesPassed && (tq.reference > 1 || tq.interval.possible > 1))
            fail(qw + ": an any-samples query with values above 1");
    }
    return out;
}

// ---------------------------------------------------------------------------------------------
// Recording and replaying

namespace {
IntervalOptions withThreads(IntervalOptions o, int threads) {
    o.threads = threads;
    return o;
}
}  // namespace

TraceRecorder::TraceRecorder(CpuBackend& reference, TraceWriter& writer, const TraceRules& rules, int threads)
    : reference_(reference), writer_(writer), intervals_(withThreads(rules.intervalOptions(), threads)) {}

void TraceRecorder::setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
    endFrame();  // the previous frame's lists
    reference_.borrowGeometry(positions, triangles);
    writer_.beginFrame(frame_, positions, triangles);
}

void TraceRecorder::setView(const OrthoView& view) {
    reference_.setView(view);
    view_ = view;
}

std::vector<uint64_t> TraceRecorder::execute(const CommandList& list) {
    if (list.conservativeCount() > 0) refuseConservative();
    std::vector<uint64_t> results = reference_.execute(list);
    pending_.push_back({view_, list, results});
    return results;
}

void TraceRecorder::endFrame() {
    reference_.releaseScratch();  // and forgets the borrowed geometry
    if (pending_.empty()) return;
    // The geometry comes back from the writer's scratch file (the caller's copy is gone by now),
    // handed over, not copied.
    {
        std::vector<Vec3f> positions;
        std::vector<Triangle> triangles;
        writer_.frameGeometry(positions, triangles);
        intervals_.setGeometry(std::move(positions), std::move(triangles));
    }
    // The evaluator sees the same setView/execute sequence as the reference did.
    for (const PendingList& p : pending_) {
        intervals_.setView(p.view);
        const std::vector<QueryInterval> iv = intervals_.execute(p.commands);
        std::vector<TraceQuery> queries(p.results.size());
        for (size_t q = 0; q < p.results.size(); ++q) {
            queries[q] = {p.results[q], iv[q]};
            if (!iv[q].contains(p.results[q])) ++referenceOutside_;
        }
        queries_ += p.results.size();
        writer_.addList(p.view, p.commands, queries);
    }
    intervals_.releaseScratch();
    intervals_.setGeometry(std::vector<Vec3f>{}, std::vector<Triangle>{});
    std::vector<PendingList>().swap(pending_);
}

uint64_t TraceRecorder::finish() {
    endFrame();
    return writer_.finish();
}

std::vector<std::vector<uint64_t>> replayTrace(const TraceReader& trace, DepthBackend& backend,
                                               const std::function<void(size_t, size_t)>& onList) {
    std::vector<std::vector<uint64_t>> out;
    out.reserve(trace.listCount());
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;
    size_t list = 0;
    for (size_t f = 0; f < trace.frameCount(); ++f) {
        trace.readGeometry(f, positions, triangles);
        backend.setGeometry(positions, triangles);
        // The backend keeps its own copy: release ours (a frame of 10^6 triangles holds ~18 MB).
        std::vector<Vec3f>().swap(positions);
        std::vector<Triangle>().swap(triangles);
        for (size_t l = 0; l < trace.listCount(f); ++l, ++list) {
            const TraceList tl = trace.readList(list);
            backend.setView(tl.view);
            out.push_back(backend.execute(tl.commands));
            CULLIDE_CHECK(out.back().size() == tl.queries.size(), "a backend returned the wrong number of results");
            if (onList) onList(list + 1, trace.listCount());
        }
    }
    return out;
}

// ---------------------------------------------------------------------------------------------
// Results files and the comparison

TraceResults readTraceResults(const std::filesystem::path& path) {
    const std::string where = path.string();
    const std::string text = readFile(path);
    Json j;
    try {
        j = Json::parse(text);
    } catch (const nlohmann::json::exception& e) {  // parse_error, and out_of_range for 1e99999
        throw InputError(where, std::string("not valid JSON: ") + e.what());
    }
    if (!j.is_object()) throw InputError(where, "not a results file (a JSON object with \"backend\" and \"results\")");
    TraceResults r;
    const auto backend = j.find("backend");
    if (backend == j.end() || !backend->is_string()) throw InputError(where, "no \"backend\" string");
    r.backend = backend->get<std::string>();
    const auto results = j.find("results");
    if (results == j.end() || !results->is_array()) throw InputError(where, "no \"results\" array");
    r.results.reserve(results->size());
    for (size_t l = 0; l < results->size(); ++l) {
        const Json& list = (*results)[l];
        if (!list.is_array()) throw InputError(where, "results[" + std::to_string(l) + "] is not an array");
        std::vector<uint64_t>& out = r.results.emplace_back();
        out.reserve(list.size());
        for (size_t q = 0; q < list.size(); ++q) {
            if (!list[q].is_number_unsigned())
                throw InputError(where,
                                 "list " + std::to_string(l) + " query " + std::to_string(q) + ": " + list[q].dump() +
                                     " is not a non-negative integer");
            out.push_back(list[q].get<uint64_t>());
        }
    }
    return r;
}

void writeTraceResults(const std::filesystem::path& path, const TraceResults& results, const std::string& tracePath,
                       const Json& provenance) {
    // One line per list, so that a diff of two results files points at the list.
    std::string text = "{\"backend\": " + Json(results.backend).dump() + ",\n \"trace\": " + Json(tracePath).dump() +
        ",\n \"provenance\": " + provenance.dump() + ",\n \"results\": [";
    for (size_t l = 0; l < results.results.size(); ++l) {
        text += l ? ",\n  [" : "\n  [";
        for (size_t q = 0; q < results.results[l].size(); ++q) {
            if (q) text.push_back(',');
            text += std::to_string(results.results[l][q]);
        }
        text += "]";
    }
    text += "]}\n";
    writeFileAtomically(path, text);
}

TraceComparison compareTrace(const TraceReader& trace, const TraceResults& results, const std::string& resultsPath) {
    if (results.results.size() != trace.listCount())
        throw InputError(resultsPath,
                         "has " + std::to_string(results.results.size()) + " result lists, but " + trace.path() +
                             " has " + std::to_string(trace.listCount()) + " command lists");
    for (size_t l = 0; l < trace.listCount(); ++l)
        if (results.results[l].size() != trace.queryCount(l))
            throw InputError(resultsPath,
                             "list " + std::to_string(l) + " has " + std::to_string(results.results[l].size()) +
                                 " results, but the trace's list " + std::to_string(l) + " has " +
                                 std::to_string(trace.queryCount(l)) + " queries");
    TraceComparison c;
    c.formats.reserve(trace.listCount());
    for (size_t l = 0; l < trace.listCount(); ++l) {
        const TraceList tl = trace.readList(l);
        c.formats.push_back(tl.view.depth);
        TraceComparison::Rates& frame = c.perFrame[tl.frame];
        TraceComparison::Rates& format = c.perFormat[tl.view.depth.name()];
        for (uint32_t q = 0; q < tl.queries.size(); ++q) {
            QueryComparison qc;
            qc.frame = tl.frame;
            qc.list = uint32_t(l);
            qc.query = q;
            qc.kind = tl.kinds[q];
            qc.reference = tl.queries[q].reference;
            qc.interval = tl.queries[q].interval;
            qc.other = results.results[l][q];
            for (TraceComparison::Rates* r : {&frame, &format, &c.all}) {
                ++r->queries;
                r->exact += qc.exact() ? 1 : 0;
                r->inside += qc.inInterval() ? 1 : 0;
            }
            c.queries.push_back(qc);
        }
    }
    return c;
}

std::vector<size_t> worstQueries(const std::vector<QueryComparison>& queries, size_t count) {
    std::vector<size_t> order;
    for (size_t i = 0; i < queries.size(); ++i)
        if (!queries[i].exact() || !queries[i].inInterval()) order.push_back(i);
    auto diff = [](const QueryComparison& c) {
        return c.other > c.reference ? c.other - c.reference : c.reference - c.other;
    };
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        if (queries[a].outside() != queries[b].outside()) return queries[a].outside() > queries[b].outside();
        return diff(queries[a]) > diff(queries[b]);
    });
    order.resize(std::min(order.size(), count));
    return order;
}

std::vector<std::pair<uint32_t, uint32_t>> queryDraws(const CommandList& list, uint32_t query) {
    std::vector<std::pair<uint32_t, uint32_t>> draws;
    int64_t open = -1, next = 0;
    for (const Command& c : list.commands()) {
        if (c.op == Command::Op::BeginQuery) open = next++;
        else if (c.op == Command::Op::EndQuery) open = -1;
        else if (c.op == Command::Op::Draw && open == int64_t(query)) draws.push_back({c.first, c.count});
    }
    return draws;
}

void captureTraceQueries(const TraceReader& trace, const std::map<size_t, uint32_t>& wanted,
                         const std::function<void(const TraceList&, uint32_t, const CoverageCapture&)>& captured) {
    if (wanted.empty()) return;
    const size_t last = wanted.rbegin()->first;
    QueryIntervals intervals(trace.rules().intervalOptions());
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;
    size_t list = 0;
    for (size_t f = 0; f < trace.frameCount() && list <= last; ++f) {
        trace.readGeometry(f, positions, triangles);
        intervals.setGeometry(positions, triangles);
        for (size_t l = 0; l < trace.listCount(f) && list <= last; ++l, ++list) {
            const TraceList tl = trace.readList(list);
            intervals.setView(tl.view);
            const auto it = wanted.find(list);
            if (it == wanted.end()) {
                intervals.execute(tl.commands);
                continue;
            }
            CoverageCapture capture;
            capture.query = it->second;
            intervals.execute(tl.commands, nullptr, nullptr, &capture);
            captured(tl, it->second, capture);
        }
    }
}

}  // namespace cullide::raster
