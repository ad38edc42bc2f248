// Reading trace files, every field checked and every problem named by where it is
// (cullide/raster/trace.h, docs/trace-format.md).
#include "cullide/raster/trace.h"

#include "trace_format.h"

#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/json_read.h"

#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

namespace cullide::raster {

using namespace trace_format;

namespace {

// 256 MiB: some 350,000 command lists (a list takes some 730 bytes of header).
constexpr JsonLimits kHeaderJson{.kind = "a trace header", .maxBytes = uint64_t(256) << 20, .part = "the header"};

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
    fileBytes_ = inputFileSize(path_);  // a regular file (a FIFO would block the open)
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
    checkJsonSize(length, pathText_, kHeaderJson);  // before its bytes are read into memory
    std::string text(size_t(length), '\0');
    if (!in.read(text.data(), std::streamsize(length))) fail("cannot read the header");
    header_ = parseOrderedJson(text, pathText_, kHeaderJson);
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
        checkSummary();
        if (frames_.empty()) throw std::invalid_argument("frames is empty: a trace records at least one frame");
    } catch (const std::invalid_argument& e) {
        fail(e.what());
    } catch (const nlohmann::json::exception& e) {
        fail(std::string("the header: ") + e.what());
    }
}

// The summary's counts are statements about the data: a reader that took them on trust would
// judge a trace whose frames were emptied (no queries: "every query lies in its interval").
void TraceReader::checkSummary() const {
    const Json& summary = field(header_, "summary", "the header");
    uint64_t commands = 0, queries = 0;
    for (const ListInfo& l : lists_) commands += l.commands.rows, queries += l.queries;
    const std::pair<const char*, uint64_t> counts[] = {{"frames", frames_.size()},
                                                       {"lists", lists_.size()},
                                                       {"commands", commands},
                                                       {"queries", queries},
                                                       {"triangles_drawn", trianglesDrawn()}};
    for (const auto& [key, count] : counts) {
        const uint64_t said = unsignedField(summary, key, "summary", std::numeric_limits<uint64_t>::max());
        if (said != count)
            throw std::invalid_argument("summary." + std::string(key) + " is " + std::to_string(said) +
                                        ", but the trace has " + std::to_string(count) +
                                        " (the header disagrees with its data)");
    }
}

// The triangles the lists' draw commands draw, each list's commands read once, one list at a
// time. A draw beyond its frame's triangles is refused here as readList refuses it.
uint64_t TraceReader::trianglesDrawn() const {
    uint64_t drawn = 0;
    std::vector<uint32_t> rows;
    for (size_t l = 0; l < lists_.size(); ++l) {
        const ListInfo& info = lists_[l];
        rows.resize(size_t(info.commands.rows) * 4);
        readBlob(info.commands, 4, 4, rows.data());
        const FrameInfo& frame = frames_[info.frameIndex];
        for (size_t k = 0; k < info.commands.rows; ++k) {
            if (rows[4 * k] != OpDraw) continue;
            const uint64_t first = rows[4 * k + 1], count = rows[4 * k + 2];
            if (first + count > frame.triangles.rows) fail(drawPastTheEnd(l, k, first, count));
            drawn += count;
        }
    }
    return drawn;
}

std::string TraceReader::drawPastTheEnd(size_t list, size_t command, uint64_t first, uint64_t count) const {
    const FrameInfo& frame = frames_[lists_[list].frameIndex];
    return "list " + std::to_string(list) + " (frame " + std::to_string(frame.frame) + ") command " +
        std::to_string(command) + ": draws triangles [" + std::to_string(first) + ", " + std::to_string(first + count) +
        "), but the frame has " + std::to_string(frame.triangles.rows);
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
                    if (uint64_t(a) + b > frame.triangles.rows) fail(drawPastTheEnd(index, k, a, b));
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

}  // namespace cullide::raster
