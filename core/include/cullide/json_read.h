// Reading JSON input: the one reader behind every JSON document cullide takes from a user (scene
// files, trace headers, results files, study specs, study records).
//
// Strict and bounded, so that no document can crash, hang or exhaust the process:
//   - the text's length is checked against the caller's limit before anything is parsed;
//   - nesting deeper than JsonLimits::maxDepth is refused (a deeply nested value would overflow
//     the stack of any recursive copy or comparison of it later);
//   - a key that appears twice in one object is refused (nlohmann would keep the last one and
//     drop the first without a word); detected in O(log n) per key;
//   - errors are InputError(source, cause) with the position: "malformed JSON at line L, column
//     C: ...", "JSON nested deeper than 256 levels at byte N (line L, column C)", "duplicate key
//     'k' at byte N (line L, column C)", "N bytes of JSON, over the limit of M bytes (X MiB) for a
//     scene file".
// Parsed by nlohmann's SAX interface (no recursion, whatever the depth) into the value.
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace cullide {

inline constexpr size_t kMaxJsonDepth = 256;

struct JsonLimits {
    const char* kind = "a JSON file";  // what the document is, in the size error ("a scene file")
    uint64_t maxBytes = uint64_t(16) << 20;
    size_t maxDepth = kMaxJsonDepth;
    // Where the text lies in the file when it is not the whole file ("the header"): the causes
    // begin with it, and positions count from the text's start.
    const char* part = nullptr;
};

// `text` as one JSON document read from `source` (InputError(source, cause) otherwise). The
// ordered variant keeps the objects' keys in the order of the text.
nlohmann::json parseJson(std::string_view text, const std::string& source, const JsonLimits& limits);
nlohmann::ordered_json parseOrderedJson(std::string_view text, const std::string& source, const JsonLimits& limits);

// InputError(source, cause) when a text of `bytes` bytes is over limits.maxBytes: for callers that
// check before they read the text (parseJson checks it too).
void checkJsonSize(uint64_t bytes, const std::string& source, const JsonLimits& limits);

// The JSON document in the file at `path` (readFile with limits.maxBytes, then parseJson).
nlohmann::json readJsonFile(const std::filesystem::path& path, const JsonLimits& limits);

}  // namespace cullide
