// Pair lists (pair_list.h): JSON through the one JSON reader, CSV line by line with strict numbers.
#include "cullide/pipeline/pair_list.h"

#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/json_read.h"
#include "cullide/parse_number.h"

#include <algorithm>
#include <array>
#include <limits>
#include <map>

namespace cullide::pipeline {
namespace {

constexpr uint32_t kMaxIndex = std::numeric_limits<uint32_t>::max();
constexpr std::array<std::string_view, 5> kCsvColumns = {"frame", "object_a", "triangle_a", "object_b",
                                                         "triangle_b"};
const JsonLimits kPairListJson{"a pair list", kMaxPairListBytes};

bool looksLikeJson(std::string_view text) {
    const size_t first = text.find_first_not_of(" \t\r\n");
    return first != std::string_view::npos && text[first] == '{';
}

// Adds the pair (a, b) found at `at` to `frame`, unless it pairs a triangle with itself.
void addPair(PairListFrame& frame, TriangleRef a, TriangleRef b, uint64_t at, const PairList& list) {
    frame.pairs.push_back(TrianglePair::make(a, b));
    frame.at.push_back(at);
    if (a == b) throw InputError(list.source, list.where(frame, frame.pairs.size() - 1) + " pairs a triangle with itself");
}

// ---- JSON ----

// v as an index, or InputError(source, where() + ": " + what + " ... is not an index").
template <class Where>
uint32_t jsonIndex(const nlohmann::json& v, const std::string& source, const Where& where, const char* what) {
    if (!v.is_number_unsigned() || v.get<uint64_t>() > kMaxIndex)
        throw InputError(source, where() + ": " + what + " " +
                                     (v.is_number() ? v.dump() : std::string("(") + v.type_name() + ")") +
                                     " is not an index (a whole number from 0 to 4294967295)");
    return uint32_t(v.get<uint64_t>());
}

// The oracle's row for a degenerate triangle: [o, t, o, t, "degenerate"], no pair.
bool degenerateRow(const nlohmann::json& row) {
    return row.size() >= 5 && row[4] == "degenerate" && row[0] == row[2] && row[1] == row[3];
}

PairListFrame jsonFrame(const nlohmann::json& entry, size_t index, PairList& list) {
    const std::string name = "frames[" + std::to_string(index) + "]";
    if (!entry.is_object()) throw InputError(list.source, name + " is not an object");
    PairListFrame f;
    f.frame = index;
    if (const auto it = entry.find("frame"); it != entry.end())
        f.frame = jsonIndex(*it, list.source, [&] { return name; }, "\"frame\"");
    const auto pairs = entry.find("pairs");
    if (pairs == entry.end() || !pairs->is_array())
        throw InputError(list.source, "frame " + std::to_string(f.frame) + ": no \"pairs\" array");
    for (size_t k = 0; k < pairs->size(); ++k) {
        const nlohmann::json& row = (*pairs)[k];
        const auto where = [&] { return "frame " + std::to_string(f.frame) + ", pair " + std::to_string(k); };
        if (!row.is_array() || row.size() < 4)
            throw InputError(list.source, where() + ": not [object, triangle, object, triangle]");
        if (degenerateRow(row)) continue;
        const auto at = [&](size_t i, const char* what) { return jsonIndex(row[i], list.source, where, what); };
        const TriangleRef a{at(0, "object"), at(1, "triangle")}, b{at(2, "object"), at(3, "triangle")};
        addPair(f, a, b, k, list);
    }
    return f;
}

void parseJsonList(std::string_view text, PairList& list) {
    const nlohmann::json j = parseJson(text, list.source, kPairListJson);
    const auto frames = j.is_object() ? j.find("frames") : j.end();
    if (frames == j.end() || !frames->is_array())
        throw InputError(list.source, "no \"frames\" array: a pair list is {\"frames\": [{\"pairs\": [[object, "
                                      "triangle, object, triangle], ...]}, ...]}");
    for (size_t i = 0; i < frames->size(); ++i) list.frames.push_back(jsonFrame((*frames)[i], i, list));
    std::stable_sort(list.frames.begin(), list.frames.end(),
                     [](const PairListFrame& a, const PairListFrame& b) { return a.frame < b.frame; });
    const auto twice = std::adjacent_find(list.frames.begin(), list.frames.end(),
                                          [](const PairListFrame& a, const PairListFrame& b) { return a.frame == b.frame; });
    if (twice != list.frames.end())
        throw InputError(list.source, "frame " + std::to_string(twice->frame) + " is given twice");
}

// ---- CSV ----

std::vector<std::string_view> splitFields(std::string_view line) {
    std::vector<std::string_view> fields;
    for (size_t start = 0;;) {
        const size_t comma = line.find(',', start);
        fields.push_back(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
        if (comma == std::string_view::npos) return fields;
        start = comma + 1;
    }
}

bool isCsvHeader(const std::vector<std::string_view>& fields) {
    return fields.size() >= kCsvColumns.size() && std::equal(kCsvColumns.begin(), kCsvColumns.end(), fields.begin());
}

uint32_t csvNumber(std::string_view field, size_t column) {
    return uint32_t(parseUnsigned(field, std::string(kCsvColumns[column]), 0, kMaxIndex));
}

void parseCsvList(std::string_view text, PairList& list) {
    std::map<size_t, PairListFrame> frames;
    size_t columns = 0;  // 0 until the header is read
    uint64_t lineNumber = 0;
    for (size_t start = 0; start < text.size();) {
        const size_t end = std::min(text.find('\n', start), text.size());
        std::string_view line = text.substr(start, end - start);
        start = end + 1;
        ++lineNumber;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (line.empty()) continue;
        const std::vector<std::string_view> fields = splitFields(line);
        const auto where = [lineNumber] { return "line " + std::to_string(lineNumber); };
        if (columns == 0) {
            if (!isCsvHeader(fields))
                throw InputError(list.source, where() + ": not the header frame,object_a,triangle_a,object_b,triangle_b "
                                                      "(nor JSON, which begins with '{')");
            columns = fields.size();
            continue;
        }
        if (fields.size() != columns)
            throw InputError(list.source, where() + ": " + std::to_string(fields.size()) + " field(s), the header has " +
                                              std::to_string(columns));
        std::array<uint32_t, 5> v{};
        try {
            for (size_t c = 0; c < v.size(); ++c) v[c] = csvNumber(fields[c], c);
        } catch (const InputError& e) {
            throw InputError(list.source, where() + ": " + e.what());
        }
        PairListFrame& f = frames[v[0]];
        f.frame = v[0];
        addPair(f, {v[1], v[2]}, {v[3], v[4]}, lineNumber, list);
    }
    if (columns == 0) throw InputError(list.source, "empty: no header frame,object_a,triangle_a,object_b,triangle_b");
    for (auto& [frame, f] : frames) list.frames.push_back(std::move(f));
}

}  // namespace

const PairListFrame* PairList::find(size_t frame) const {
    const auto it = std::lower_bound(frames.begin(), frames.end(), frame,
                                     [](const PairListFrame& f, size_t n) { return f.frame < n; });
    return it != frames.end() && it->frame == frame ? &*it : nullptr;
}

std::string PairList::where(const PairListFrame& f, size_t k) const {
    if (format == PairListFormat::Csv) return "line " + std::to_string(f.at[k]);
    return "frame " + std::to_string(f.frame) + ", pair " + std::to_string(f.at[k]);
}

PairList parsePairList(std::string_view text, const std::string& source) {
    PairList list;
    list.source = source;
    if (text.size() > kMaxPairListBytes)
        throw InputError(source, std::to_string(text.size()) + " bytes, over the limit of " +
                                     std::to_string(kMaxPairListBytes) + " bytes for a pair list");
    list.format = looksLikeJson(text) ? PairListFormat::Json : PairListFormat::Csv;
    if (list.format == PairListFormat::Json) parseJsonList(text, list);
    else parseCsvList(text, list);
    return list;
}

PairList readPairList(const std::filesystem::path& path) {
    return parsePairList(readFile(path, kMaxPairListBytes, "a pair list"), pathText(path));
}

void checkPairsInScene(const PairList& list, const PairListFrame& frame, const Scene& scene) {
    const auto check = [&](size_t k, TriangleRef r) {
        if (r.object >= scene.objects.size())
            throw InputError(list.source, list.where(frame, k) + ": the scene has no object " + std::to_string(r.object) +
                                              " (it has " + std::to_string(scene.objects.size()) + ")");
        const size_t n = scene.objects[r.object].mesh.triangles.size();
        if (r.triangle >= n)
            throw InputError(list.source, list.where(frame, k) + ": object " + std::to_string(r.object) +
                                              " has no triangle " + std::to_string(r.triangle) + " (it has " +
                                              std::to_string(n) + ")");
    };
    for (size_t k = 0; k < frame.pairs.size(); ++k) {
        check(k, frame.pairs[k].a);
        check(k, frame.pairs[k].b);
    }
}

}  // namespace cullide::pipeline
