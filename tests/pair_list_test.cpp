// Pair lists as `cullide audit` reads them (pair_list.h): JSON and CSV, told apart by content.
#include "cullide/pipeline/pair_list.h"

#include "cullide/error.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace cullide;
using namespace cullide::pipeline;

namespace {

TrianglePair pairOf(uint32_t oa, uint32_t ta, uint32_t ob, uint32_t tb) {
    return TrianglePair::make({oa, ta}, {ob, tb});
}

// The error a text gets, or "accepted".
std::string errorOf(const std::string& text, const std::string& source = "p") {
    try {
        (void)parsePairList(text, source);
    } catch (const InputError& e) {
        return e.what();
    }
    return "accepted";
}

}  // namespace

// Trap: `oracle --json` output must be read as it is: its other keys, the class after each pair,
// and its rows for degenerate triangles ([o, t, o, t, "degenerate"], no pair) all pass; frames
// keep their own numbers and come out sorted.
TEST(PairList, ReadsTheOraclesJsonAsItIs) {
    const PairList l = parsePairList(R"({"scene": "s.json", "objects": ["a", "b"], "frames": [
        {"frame": 3, "crossing": 1, "pairs": [[0, 1, 1, 0, "crossing"], [1, 2, 1, 2, "degenerate"]]},
        {"frame": 1, "pairs": []}], "provenance": {}})",
                                     "o.json");
    EXPECT_EQ(l.format, PairListFormat::Json);
    ASSERT_EQ(l.frames.size(), 2u);
    EXPECT_EQ(l.frames[0].frame, 1u);
    EXPECT_TRUE(l.frames[0].pairs.empty());
    ASSERT_NE(l.find(3), nullptr);
    EXPECT_EQ(l.find(3)->pairs, std::vector<TrianglePair>{pairOf(0, 1, 1, 0)});
    EXPECT_EQ(l.find(2), nullptr);
}

// Trap: either order within a pair is the same pair, a pair given twice stays in the list (the
// audit dedupes), and a frame without "frame" is numbered by its place; CSV rows of one frame
// gather under it whatever their order, with the line of each pair kept for messages.
TEST(PairList, EitherOrderAndDuplicatesInJsonAndCsv) {
    const PairList j = parsePairList(R"( {"frames": [{"pairs": [[2, 0, 1, 5], [1, 5, 2, 0]]}]})", "j");
    ASSERT_EQ(j.frames.size(), 1u);
    EXPECT_EQ(j.frames[0].frame, 0u);
    EXPECT_EQ(j.frames[0].pairs, (std::vector<TrianglePair>{pairOf(1, 5, 2, 0), pairOf(1, 5, 2, 0)}));
    const PairList c = parsePairList(
        "frame,object_a,triangle_a,object_b,triangle_b,class\r\n1,2,0,1,5,x\r\n\r\n0,0,1,0,2,y\n1,1,5,2,0,z\n", "c.csv");
    EXPECT_EQ(c.format, PairListFormat::Csv);
    ASSERT_EQ(c.frames.size(), 2u);
    EXPECT_EQ(c.frames[1].frame, 1u);
    EXPECT_EQ(c.frames[1].pairs, (std::vector<TrianglePair>{pairOf(1, 5, 2, 0), pairOf(1, 5, 2, 0)}));
    EXPECT_EQ(c.where(c.frames[1], 1), "line 5");
    EXPECT_EQ(j.where(j.frames[0], 1), "frame 0, pair 1");
    EXPECT_TRUE(parsePairList("frame,object_a,triangle_a,object_b,triangle_b\n", "h.csv").frames.empty());
}

// Trap: every refusal must name the file and where (the line, or the frame and pair), never a
// wrapped or rounded index, a pair of a triangle with itself, or a second entry for one frame.
TEST(PairList, BadInputNamesTheLineOrPair) {
    const std::string h = "frame,object_a,triangle_a,object_b,triangle_b\n";
    EXPECT_EQ(errorOf(h + "0,0,1,0,2\n0,0,x,0,2\n", "pairs.csv"),
              "pairs.csv: line 3: triangle_a: 'x' is not an integer");
    EXPECT_EQ(errorOf(h + "0,0,1,0,4294967296\n"), "p: line 2: triangle_b: 4294967296 is out of range (0 to 4294967295)");
    EXPECT_EQ(errorOf(h + "0,0,-1,0,2\n").substr(0, 23), "p: line 2: triangle_a: ");
    EXPECT_EQ(errorOf(h + "0,0,1,0\n"), "p: line 2: 4 field(s), the header has 5");
    EXPECT_EQ(errorOf(h + "0,3,1,3,1\n"), "p: line 2 pairs a triangle with itself");
    EXPECT_NE(errorOf("a,b\n1,2\n").find("p: line 1: not the header"), std::string::npos);
    EXPECT_NE(errorOf("").find("p: empty"), std::string::npos);
    EXPECT_EQ(errorOf(R"({"frames": [{"pairs": [[0, 1, 0, 1.0]]}]})"),
              "p: frame 0, pair 0: triangle 1.0 is not an index (a whole number from 0 to 4294967295)");
    EXPECT_EQ(errorOf(R"({"frames": [{"pairs": [[0, 1, 0]]}]})"),
              "p: frame 0, pair 0: not [object, triangle, object, triangle]");
    EXPECT_EQ(errorOf(R"({"frames": [{"pairs": [[0, 1, 0, 1, "crossing"]]}]})"),
              "p: frame 0, pair 0 pairs a triangle with itself");
    EXPECT_EQ(errorOf(R"({"frames": [{"frame": 2, "pairs": []}, {"frame": 2, "pairs": []}]})"),
              "p: frame 2 is given twice");
    EXPECT_EQ(errorOf(R"({"frames": [{"frame": -1, "pairs": []}]})"),
              "p: frames[0]: \"frame\" -1 is not an index (a whole number from 0 to 4294967295)");
    EXPECT_NE(errorOf(R"({"pairs": []})").find("p: no \"frames\" array"), std::string::npos);
    EXPECT_NE(errorOf(R"({"frames": [{"pairs": [[0, 1, 0, 2]]}]} x)").find("malformed JSON at line 1"),
              std::string::npos);
}

// Trap: the scene check must name where the pair is and what the scene has, for either side.
TEST(PairList, PairsOutsideTheSceneAreNamed) {
    Scene s;
    s.objects.push_back({"a", Mesh{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}}, Transform::Identity()});
    const PairList l = parsePairList("frame,object_a,triangle_a,object_b,triangle_b\n0,0,0,0,3\n0,4,0,0,0\n", "l.csv");
    try {
        checkPairsInScene(l, l.frames[0], s);
        FAIL() << "accepted";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "l.csv: line 2: object 0 has no triangle 3 (it has 1)");
    }
}
