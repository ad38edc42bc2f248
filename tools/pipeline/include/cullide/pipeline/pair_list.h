// Pair lists: the triangle pairs a collision detector reported, per frame, as `cullide audit`
// reads them (docs/cli.md#cullide-audit), for the command and the Python module alike.
//
// Formats, told apart by content (the first character that is not white space: `{` is JSON,
// anything else CSV; the file's extension is not looked at):
//   - JSON: {"frames": [{"frame": F, "pairs": [[objectA, triangleA, objectB, triangleB], ...]},
//     ...]}, the shape `cullide oracle --json` writes. Other keys are ignored, and so are the
//     elements of a pair after the fourth (the oracle's class); the oracle's rows for degenerate
//     triangles, [o, t, o, t, "degenerate"], are no pairs and are skipped. "frame" may be left out:
//     the entry's index in "frames" is then its frame. Objects and triangles are indices
//     (integers from 0 to 2^32 - 1, written as such: 3.0 is refused).
//   - CSV: a header whose first five columns are frame,object_a,triangle_a,object_b,triangle_b
//     (later columns ignored), then one row per pair with as many fields as the header, numbers
//     read strictly (cullide/parse_number.h); blank lines and a "\r" before each "\n" are allowed.
//     A frame with no rows has no pairs.
//   - Either order within a pair (TrianglePair::make orders it); a pair given twice stays twice
//     (the audit counts it once).
//   - At most kMaxPairListBytes; the JSON reader's limits (cullide/json_read.h).
//
// Errors: InputError(source, cause), the cause naming where: "line 7: ..." (CSV), "frame 2,
// pair 5: ..." (JSON), and "... pairs a triangle with itself".
#pragma once

#include "cullide/scene.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace cullide::pipeline {

inline constexpr uint64_t kMaxPairListBytes = uint64_t(256) << 20;

enum class PairListFormat : uint8_t { Json, Csv };

struct PairListFrame {
    size_t frame = 0;
    std::vector<TrianglePair> pairs;  // in the file's order
    std::vector<uint64_t> at;  // per pair, where it is: its line (CSV, from 1) or index in "pairs" (JSON)
};

struct PairList {
    std::string source;  // what errors name
    PairListFormat format = PairListFormat::Json;
    std::vector<PairListFrame> frames;  // sorted by frame, each frame once

    const PairListFrame* find(size_t frame) const;  // nullptr when the list has no entry for it
    // Where pair k of `f` is, as errors say it: "line 7" or "frame 2, pair 5".
    std::string where(const PairListFrame& f, size_t k) const;
};

PairList parsePairList(std::string_view text, const std::string& source);
PairList readPairList(const std::filesystem::path& path);  // source: the path as given

// InputError(list.source, "<where>: ...") unless every pair of `frame` names a triangle of `scene`
// ("line 7: object 1 has no triangle 40 (it has 12)", "frame 0, pair 3: the scene has no object 5").
void checkPairsInScene(const PairList& list, const PairListFrame& frame, const Scene& scene);

}  // namespace cullide::pipeline
