// The JSON reader (core/src/json_read.cpp) and every input read through it: scene files, trace
// headers, results files, study specs and study records.
#include "cullide/json_read.h"

#include "cullide/error.h"
#include "cullide/raster/trace.h"
#include "cullide/scene_io.h"
#include "cullide/study/study.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <string>

namespace cullide {
namespace {

namespace fs = std::filesystem;

const JsonLimits kSmall{.kind = "a test document", .maxBytes = 1 << 20};

// The cause of the InputError that `read` throws ("" when it throws none), its source checked.
std::string errorOf(const std::function<void()>& read, const std::string& source) {
    try {
        read();
    } catch (const InputError& e) {
        EXPECT_EQ(e.source(), source) << e.what();
        return e.what();
    }
    return "";
}

bool has(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

// Trap: a document nested 10^5 deep parses (nlohmann's parser does not recurse) and then crashes
// the first recursive copy of the value (exit 139). Every reader entry point refuses it at the
// 257th level, with its position, before any copy.
struct DeepCase {
    const char* name;
    std::function<void(const fs::path&)> read;
    std::string prefix;  // what the file holds before the JSON
};

class JsonReadDeep : public ::testing::TestWithParam<DeepCase> {};

TEST_P(JsonReadDeep, EveryEntryPointRefusesDeepNesting) {
    const test::TempDir dir;
    const fs::path file = dir / (std::string(GetParam().name) + ".json");
    std::string json = std::string(100'000, '[') + std::string(100'000, ']');
    std::string bytes = GetParam().prefix;
    if (!bytes.empty()) {  // a trace: its preamble gives the header's length
        const uint64_t n = json.size();
        for (int i = 0; i < 8; ++i) bytes.push_back(char(n >> (8 * i)));
    }
    test::writeBytes(file, bytes + json);
    const std::string what = errorOf([&] { GetParam().read(file); }, file.string());
    EXPECT_TRUE(has(what, "JSON nested deeper than 256 levels at byte 257 (line 1, column 257)")) << what;
}

INSTANTIATE_TEST_SUITE_P(
    JsonRead, JsonReadDeep,
    ::testing::Values(DeepCase{"scene", [](const fs::path& p) { (void)loadScene(p); }, ""},
                      DeepCase{"trace", [](const fs::path& p) { (void)raster::TraceReader(p); }, "CULTRACE"},
                      DeepCase{"results", [](const fs::path& p) { (void)raster::readTraceResults(p); }, ""},
                      DeepCase{"spec", [](const fs::path& p) { (void)study::loadSpec(p.string()); }, ""},
                      DeepCase{"file", [](const fs::path& p) { (void)readJsonFile(p, kSmall); }, ""}),
    [](const auto& param) { return std::string(param.param.name); });

// Trap: a key given twice in one object: nlohmann keeps the last and drops the first without a
// word (a study spec's "depths" silently replaced). Refused in both value kinds, in small objects
// and in objects large enough for the ordered kind's key set, with the position of the second.
TEST(JsonRead, DuplicateKeysAreRefusedWhereTheyAre) {
    const std::string small = "{\"a\": 1,\n \"b\": {\"c\": 2, \"c\": 3}}";
    const std::string expected = "duplicate key 'c' at byte 27 (line 2, column 18)";
    EXPECT_TRUE(has(errorOf([&] { parseJson(small, "s.json", kSmall); }, "s.json"), expected));
    EXPECT_TRUE(has(errorOf([&] { parseOrderedJson(small, "s.json", kSmall); }, "s.json"), expected));
    std::string large = "{";
    for (int k = 0; k < 100; ++k) large += "\"k" + std::to_string(k) + "\": " + std::to_string(k) + ", ";
    EXPECT_EQ(parseOrderedJson(large + "\"last\": 0}", "l.json", kSmall).size(), 101u);
    EXPECT_TRUE(has(errorOf([&] { parseOrderedJson(large + "\"k7\": 0}", "l.json", kSmall); }, "l.json"),
                    "duplicate key 'k7'"));
    EXPECT_TRUE(
        has(errorOf([&] { parseJson(large + "\"k99\": 0}", "l.json", kSmall); }, "l.json"), "duplicate key 'k99'"));
    // A key with a NUL or a newline is shown escaped: the message stays one whole line.
    EXPECT_TRUE(has(errorOf([&] { parseJson(R"({"a\u0000\n": 1, "a\u0000\n": 2})", "n.json", kSmall); }, "n.json"),
                    R"(duplicate key 'a\u0000\n')"));
    // The key order of the ordered kind is the text's.
    const nlohmann::ordered_json o = parseOrderedJson(R"({"z": 1, "a": [true, null, "x", -1, 2.5]})", "o", kSmall);
    EXPECT_EQ(o.dump(), R"({"z":1,"a":[true,null,"x",-1,2.5]})");
}

// Trap: a document of any size parsed whole (a results file of gigabytes exhausts memory): a text
// over the caller's limit is refused before parsing, and a file over it before it is read, with
// the limit stated.
TEST(JsonRead, OversizeIsRefusedWithTheLimit) {
    const JsonLimits tiny{.kind = "a tiny file", .maxBytes = 16};
    EXPECT_EQ(parseJson("[1,2,3,4,5,6]", "t", tiny).size(), 6u);
    const std::string what = errorOf([&] { parseJson("[1, 2, 3, 4, 5, 6, 7]", "t", tiny); }, "t");
    EXPECT_TRUE(has(what, "21 bytes of JSON, over the limit of 16 bytes for a tiny file")) << what;
    const test::TempDir dir;
    test::writeBytes(dir / "big.json", std::string(3 << 20, ' ') + "1");
    EXPECT_TRUE(has(errorOf([&] { readJsonFile(dir / "big.json", kSmall); }, (dir / "big.json").string()),
                    "over the limit of 1048576 bytes (1 MiB) for a test document"));
}

// Trap: errors that point nowhere or escape as another exception: a syntax error and a number
// beyond double's range (nlohmann's out_of_range, not parse_error) are both InputError with the
// line and column.
TEST(JsonRead, MalformedJsonSaysWhere) {
    EXPECT_TRUE(has(errorOf([&] { parseJson("{\n  \"a\": tru }", "m", kSmall); }, "m"),
                    "malformed JSON at line 2, column 11: syntax error while parsing value"));
    EXPECT_TRUE(has(errorOf([&] { parseJson("[1,\n 1e99999]", "m", kSmall); }, "m"),
                    "malformed JSON at line 2, column 8: number overflow parsing '1e99999'"));
    EXPECT_TRUE(has(errorOf([&] { parseJson("{} {}", "m", kSmall); }, "m"), "expected end of input"));
    EXPECT_TRUE(has(errorOf([&] { parseJson("", "m", kSmall); }, "m"), "malformed JSON at line 1, column 1"));
}

}  // namespace
}  // namespace cullide
