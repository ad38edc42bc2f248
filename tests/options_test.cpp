// The one option parser (core/include/cullide/options.h): text -> CullideOptions, and errors that
// name the option as the user typed it; and the one number parser under it (parse_number.h).
#include "cullide/options.h"

#include "cullide/error.h"
#include "cullide/parse_number.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>

using namespace cullide;

namespace {

// The message of the InputError `parse` throws ("" when it throws none).
template <typename F>
std::string messageOf(F&& parse) {
    try {
        parse();
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

// The defaults of the text form are CullideOptions' defaults.
TEST(Options, DefaultsAreCullideDefaults) {
    const CullideOptions o = parseCullideOptions({});
    const CullideOptions d;
    EXPECT_EQ(o.method, d.method);
    EXPECT_EQ(o.width, d.width);
    EXPECT_EQ(o.height, d.height);
    EXPECT_EQ(o.depth, d.depth);
    EXPECT_EQ(o.directions, d.directions);
    EXPECT_EQ(o.directionMode, d.directionMode);
    EXPECT_EQ(o.hierarchy.kind, d.hierarchy.kind);
    EXPECT_EQ(o.hierarchy.leafSize, d.hierarchy.leafSize);
    EXPECT_EQ(o.hierarchy.branching, d.hierarchy.branching);
    EXPECT_EQ(o.hierarchy.seed, d.hierarchy.seed);
    EXPECT_EQ(o.autoCoverage, d.autoCoverage);
    EXPECT_EQ(o.autoCoverage, 0.0) << "fixed resolution unless asked";
}

TEST(Options, EveryFieldIsParsed) {
    OptionText t;
    t.method = "original", t.resolution = "640x480", t.depth = "float", t.directions = "x,-y";
    t.hierarchy = "random", t.leafSize = 8, t.branching = 2, t.seed = 9;
    const CullideOptions o = parseCullideOptions(t);
    EXPECT_EQ(o.method, CullMethod::Original);
    EXPECT_EQ(o.width, 640);
    EXPECT_EQ(o.height, 480);
    EXPECT_EQ(o.depth, DepthFormat::float32());
    ASSERT_EQ(o.directions.size(), 2u);
    EXPECT_EQ(o.directions[1], Vec3d(0, -1, 0));
    EXPECT_EQ(o.hierarchy.kind, HierarchyKind::Random);
    EXPECT_EQ(o.hierarchy.leafSize, 8u);
    EXPECT_EQ(o.hierarchy.branching, 2u);
    EXPECT_EQ(o.hierarchy.seed, 9u);
    EXPECT_EQ(parseResolution("300"), std::make_pair(300, 300));
    EXPECT_EQ(parseDirections("5").size(), 5u);
}

// Every field's bad value: refused under the name given for that field, never another one (a
// value parsed by a piece that names its own default source, "depth format" or "option --method",
// must come out under the caller's name).
TEST(Options, ErrorsNameTheFieldAsTyped) {
    OptionNames names;
    names.method = "M", names.resolution = "R", names.depth = "D", names.directions = "V", names.hierarchy = "H";
    names.leafSize = "L", names.branching = "B", names.views = "W";
    const struct {
        void (*bad)(OptionText&);
        const char* name;
    } cases[] = {
        {[](OptionText& t) { t.method = "reliable-ish"; }, "M: "},
        // (std::string(...) for the one-character values: GCC 12 warns falsely, -Wrestrict, on = "0")
        {[](OptionText& t) { t.resolution = std::string("0"); }, "R: "},
        {[](OptionText& t) { t.resolution = "20000x10"; }, "R: "},
        {[](OptionText& t) { t.resolution = "axb"; }, "R: "},
        {[](OptionText& t) { t.resolution = "auto:0"; }, "R: "},
        {[](OptionText& t) { t.resolution = "auto:x"; }, "R: "},
        {[](OptionText& t) { t.resolution = "auto:"; }, "R: "},
        {[](OptionText& t) { t.resolution = "auto:-1"; }, "R: "},
        {[](OptionText& t) { t.resolution = "auto:4x"; }, "R: "},
        {[](OptionText& t) { t.resolution = "auto:5000"; }, "R: "},
        {[](OptionText& t) { t.resolution = "autox"; }, "R: "},
        {[](OptionText& t) { t.depth = std::string("7"); }, "D: "},
        {[](OptionText& t) { t.depth = "33"; }, "D: "},
        {[](OptionText& t) { t.depth = "half"; }, "D: "},
        {[](OptionText& t) { t.directions = std::string("0"); }, "V: "},
        {[](OptionText& t) { t.directions = "20000"; }, "V: "},
        {[](OptionText& t) { t.directions = "1234567"; }, "V: "},
        {[](OptionText& t) { t.directions = "x,w"; }, "V: "},
        {[](OptionText& t) { t.directions = "0 0 0"; }, "V: "},
        {[](OptionText& t) { t.directions = ""; }, "V: "},
        {[](OptionText& t) { t.hierarchy = "octree"; }, "H: "},
        {[](OptionText& t) { t.views = "Fit"; }, "W: "},  // case matters, as for the method
        {[](OptionText& t) { t.views = "cluster"; }, "W: "},
        {[](OptionText& t) { t.views = ""; }, "W: "},
        {[](OptionText& t) { t.leafSize = 0; }, "L: "},
        {[](OptionText& t) { t.leafSize = kMaxLeafSize + 1; }, "L: "},
        {[](OptionText& t) { t.branching = 1; }, "B: "},
        {[](OptionText& t) { t.branching = kMaxBranching + 1; }, "B: "},
    };
    for (const auto& c : cases) {
        OptionText t;
        c.bad(t);
        const std::string m = messageOf([&] { parseCullideOptions(t, names); });
        EXPECT_EQ(m.rfind(c.name, 0), 0u) << m;
        // The cause follows the name directly: no second source inside.
        EXPECT_EQ(m.find("option --"), std::string::npos) << m;
        EXPECT_EQ(m.find("depth format:"), std::string::npos) << m;
    }
}

// Trap: a view mode that parses to the wrong enum, or a default other than fit (the paper's one
// view per call, bit for bit what prune gave before the option).
TEST(Options, ViewModes) {
    OptionText t;
    EXPECT_EQ(parseCullideOptions(t).views, ViewMode::Fit);
    t.views = "clustered";
    EXPECT_EQ(parseCullideOptions(t).views, ViewMode::Clustered);
    t.views = "fit";
    EXPECT_EQ(parseCullideOptions(t).views, ViewMode::Fit);
    EXPECT_STREQ(toString(ViewMode::Clustered), "clustered");
    const std::string m = messageOf([] { parseViewMode("all"); });
    EXPECT_EQ(m, "option --views: unknown view mode 'all' (expected fit or clustered)");
}

// Trap: "auto" read as a viewport (sscanf of "auto" fails, but "auto:4" must not become 4x4), or
// adaptive resolution changing the base viewport a fixed run would use. "auto" is the default K
// on a 500x500 base; "auto:K" takes a decimal K.
TEST(Options, AdaptiveResolution) {
    OptionText t;
    t.resolution = "auto";
    CullideOptions o = parseCullideOptions(t);
    EXPECT_EQ(o.autoCoverage, kDefaultAutoCoverage);
    EXPECT_EQ(o.width, 500);
    EXPECT_EQ(o.height, 500);
    t.resolution = "auto:4";
    EXPECT_EQ(parseCullideOptions(t).autoCoverage, 4.0);
    t.resolution = "auto:2.5";
    EXPECT_EQ(parseCullideOptions(t).autoCoverage, 2.5);
    EXPECT_EQ(parseResolutionSetting("640x480").autoCoverage, 0.0);
    EXPECT_EQ(parseResolutionSetting("640x480").width, 640);
    const std::string m = messageOf([] { parseResolutionSetting("auto:0", "option --resolutions"); });
    EXPECT_EQ(m.rfind("option --resolutions: ", 0), 0u) << m;
    EXPECT_NE(m.find("auto:0"), std::string::npos) << m;
}

// Trap: `prune --depth 7` named the option while `study --depths 7` did not. The same
// bad value gives the same cause under any name; the default names are prune's options.
TEST(Options, SameBadValueSameCause) {
    OptionText t;
    t.depth = "7";
    OptionNames study;
    study.depth = "option --depths";
    const std::string prune = messageOf([&] { parseCullideOptions(t); });
    const std::string sweep = messageOf([&] { parseCullideOptions(t, study); });
    ASSERT_EQ(prune.rfind("option --depth: ", 0), 0u) << prune;
    ASSERT_EQ(sweep.rfind("option --depths: ", 0), 0u) << sweep;
    EXPECT_EQ(prune.substr(prune.find(": ")), sweep.substr(sweep.find(": ")));
    EXPECT_NE(prune.find("8 to 32"), std::string::npos) << prune;
}

// Trap: "pca" or "coherent" read as a list of named directions (an error) or as the axes with no
// mode; "coherent:LIST" losing its list; a fixed text gaining a mode. Bad ones are InputError
// under the directions' name.
TEST(Options, ChosenDirections) {
    auto parsed = [](const std::string& directions) {
        OptionText t;
        t.directions = directions;
        return parseCullideOptions(t);
    };
    EXPECT_EQ(parsed("axes").directionMode, DirectionMode::Fixed);
    EXPECT_EQ(parsed("14").directionMode, DirectionMode::Fixed);
    const CullideOptions pca = parsed("pca");
    EXPECT_EQ(pca.directionMode, DirectionMode::Pca);
    EXPECT_EQ(pca.directions, axisDirections());
    const CullideOptions coherent = parsed("coherent");
    EXPECT_EQ(coherent.directionMode, DirectionMode::Coherent);
    EXPECT_EQ(coherent.directions, axisDirections());
    EXPECT_EQ(parsed("coherent:14").directions, spreadDirections(14));
    EXPECT_EQ(parsed("coherent:x,-y").directions.size(), 2u);
    EXPECT_EQ(parsed("coherent:axes").directionMode, DirectionMode::Coherent);
    EXPECT_EQ(parseDirections("pca"), axisDirections());
    EXPECT_EQ(parseDirectionMode("coherent:14"), DirectionMode::Coherent);
    EXPECT_STREQ(toString(DirectionMode::Pca), "pca");
    for (const char* bad : {"coherent:", "coherent:pca", "coherent:coherent", "coherent:0", "pcaa", "Pca"}) {
        try {
            parsed(bad);
            ADD_FAILURE() << bad << " accepted";
        } catch (const InputError& e) {
            EXPECT_EQ(e.source(), "option --directions") << bad;
        }
    }
}

// Trap: text the parser half reads ("12abc", "-5", "auto:3", a count past 10^12) taken as a
// value, or the error named by the default option in a study. never/auto/N read; a bad value
// is an InputError under the caller's name.
TEST(Options, ExactSwitch) {
    for (const char* bad : {"", "0", "-5", "12abc", "auto:3", "Never", "1e6", "99999999999999"}) {
        try {
            (void)parseExactSwitch(bad);
            ADD_FAILURE() << "accepted '" << bad << "'";
        } catch (const InputError& e) {
            EXPECT_EQ(e.source(), "option --exact-switch") << bad;
        }
    }
    EXPECT_EQ(parseExactSwitch("never").kind, ExactSwitchKind::Never);
    EXPECT_EQ(parseExactSwitch("auto").kind, ExactSwitchKind::Auto);
    EXPECT_EQ(parseExactSwitch("5000").kind, ExactSwitchKind::Below);
    EXPECT_EQ(parseExactSwitch("5000").triangles, 5000u);
    OptionText t;
    EXPECT_EQ(parseCullideOptions(t).exactSwitch.kind, ExactSwitchKind::Never);  // the default
    t.exactSwitch = "300";
    EXPECT_EQ(parseCullideOptions(t).exactSwitch.triangles, 300u);
    t.exactSwitch = "x";
    OptionNames names;
    names.exactSwitch = "spec.json: field 'exact_switches'";
    EXPECT_NE(messageOf([&] { parseCullideOptions(t, names); }).find("spec.json: field 'exact_switches'"),
              std::string::npos);
}

// --- Numbers as typed (parse_number.h) ---

// Trap: a number past its type's limits wrapped or clamped into range (sscanf's %d took
// 4294967396 as 100, strtoull clamps 2^64 to 2^64 - 1), in the option parser as anywhere. The
// limits themselves are read exactly; one past them is out of range, with the text as typed.
TEST(Numbers, OverflowIsOutOfRangeNotWrapped) {
    EXPECT_EQ(messageOf([] { parseResolution("4294967396"); }),
              "option --resolution: 4294967396 is out of range (1 to 16384)");
    EXPECT_EQ(messageOf([] { parseResolution("640x4294967776"); }),
              "option --resolution: 4294967776 is out of range (1 to 16384)");
    constexpr uint64_t u64 = std::numeric_limits<uint64_t>::max();
    constexpr int64_t i64 = std::numeric_limits<int64_t>::max();
    EXPECT_EQ(parseNumber<uint64_t>("18446744073709551615", "S", 0, u64), u64);
    EXPECT_EQ(messageOf([&] { parseNumber<uint64_t>("18446744073709551616", "S", 0, u64); }),
              "S: 18446744073709551616 is out of range (0 to 18446744073709551615)");
    EXPECT_EQ(parseNumber<int64_t>("-9223372036854775808", "F", -i64 - 1, i64), -i64 - 1);
    EXPECT_NE(messageOf([&] { parseNumber<int64_t>("9223372036854775808", "F", 0, i64); }).find("out of range"),
              std::string::npos);
    EXPECT_NE(messageOf([] { parseNumber<int>("99999999999999999999999", "F", 0, 9); }).find("out of range"),
              std::string::npos);
    EXPECT_NE(messageOf([] { parseNumber("1e400", "T", 0.0, 59.0); }).find("out of range"), std::string::npos);
    EXPECT_NE(messageOf([] { parseExactSwitch("99999999999999999999"); }).find("out of range"), std::string::npos);
}

// Trap: a negative number for an unsigned value read as a huge one (strtoull and CLI11 take -1 as
// 2^64 - 1: a seed that wraps, `--worst -1` as "all").
TEST(Numbers, NegativeForUnsignedIsOutOfRange) {
    constexpr uint64_t u64 = std::numeric_limits<uint64_t>::max();
    EXPECT_EQ(messageOf([&] { parseNumber<uint64_t>("-1", "option --seed", 0, u64); }),
              "option --seed: -1 is out of range (0 to 18446744073709551615)");
    EXPECT_NE(messageOf([] { parseNumber<size_t>("-18446744073709551615", "W", 0, 10); }).find("out of range"),
              std::string::npos);
    EXPECT_EQ(parseNumber<unsigned>("-0", "W", 0u, 10u), 0u);  // minus zero is zero
    EXPECT_EQ(messageOf([] { checkRange(uint32_t(0), "option --leaf-size", 1u, kMaxLeafSize); }),
              "option --leaf-size: 0 is out of range (1 to 1000000)");
}

// Trap: NaN passes every range check written `x < min || x > max` (make-scene's --tilt nan then
// aborted inside a generator); an infinity is a number only where the range includes it.
TEST(Numbers, NanAndInfinityAreRefused) {
    for (const char* bad : {"nan", "NaN", "-nan", "nan(1)", "inf", "-inf", "Infinity", "+inf"})
        EXPECT_NE(messageOf([&] { parseNumber(bad, "option --tilt", 0.0, 59.0); }).find("is not a finite number"),
                  std::string::npos)
            << bad;
    constexpr double inf = std::numeric_limits<double>::infinity();
    EXPECT_EQ(parseReal("inf", "X", 0, inf), inf);
    EXPECT_NE(messageOf([&] { parseReal("nan", "X", -inf, inf); }), "");
    EXPECT_NE(messageOf([] { parseResolutionSetting("auto:nan"); }).find("finite"), std::string::npos);
    EXPECT_NE(messageOf([] { parseDirections("1 nan 0"); }).find("finite"), std::string::npos);
}

// Trap: text after the number ignored or half read (stoul("12abc") is 12, %lf reads "1.5x" as 1.5),
// spaces, hexadecimal, an exponent or a fraction where an integer is wanted. Each is "not an
// integer" / "not a number" quoting the text, cut short when it is long.
TEST(Numbers, TrailingCharactersAreRefused) {
    for (const char* bad : {"12abc", "5 ", " 5", "0x10", "1e3", "5.0", "", "-", "+", "+-1", "--1", "1,5", "٣"})
        EXPECT_NE(messageOf([&] { parseNumber(bad, "N", 0, 100000); }).find("is not an integer"), std::string::npos)
            << "'" << bad << "'";
    for (const char* bad : {"1.5x", "", ".", "e5", "1e", "+-1", "0x1p3", "1 "})
        EXPECT_NE(messageOf([&] { parseNumber(bad, "R", 0.0, 1e9); }).find("is not a number"), std::string::npos)
            << "'" << bad << "'";
    EXPECT_EQ(parseNumber("+7", "N", 0, 9), 7);
    EXPECT_EQ(parseNumber("2.5e-1", "R", 0.0, 1.0), 0.25);
    EXPECT_EQ(parseNumber(".5", "R", 0.0, 1.0), 0.5);
    const std::string huge(100000, '7');
    EXPECT_LT(messageOf([&] { parseNumber(huge + "x", "N", 0, 9); }).size(), 100u) << "the whole text quoted";
    for (const char* bad : {"500x", "x500", "12abc", "500x500x", "5 00"})
        EXPECT_NE(messageOf([&] { parseResolution(bad); }).find("cannot read"), std::string::npos) << bad;
}

// Trap: a range check before the number is read (on a wrapped value), bounds off by one, or a
// different wording per caller. The bounds are inclusive and the message names both.
TEST(Numbers, RangeIsCheckedAfterReading) {
    EXPECT_EQ(parseNumber("1", "V", 1, 16384), 1);
    EXPECT_EQ(parseNumber("16384", "V", 1, 16384), 16384);
    EXPECT_EQ(messageOf([] { parseNumber("16385", "V", 1, 16384); }), "V: 16385 is out of range (1 to 16384)");
    EXPECT_EQ(messageOf([] { parseNumber("0", "V", 1, 16384); }), "V: 0 is out of range (1 to 16384)");
    EXPECT_EQ(parseNumber("59", "T", 0.0, 59.0), 59.0);
    EXPECT_EQ(messageOf([] { parseNumber("59.5", "T", 0.0, 59.0); }), "T: 59.5 is out of range (0 to 59)");
    EXPECT_EQ(messageOf([] { parseNumber("-1e-9", "T", 0.0, 59.0); }), "T: -1e-9 is out of range (0 to 59)");
    EXPECT_EQ(messageOf([] { parseNumber("2e6", "M", 0.0, 1e6); }), "M: 2e6 is out of range (0 to 1e+06)");
    EXPECT_EQ(messageOf([] { parseDirections("10001"); }),
              "option --directions: 10001 is out of range (1 to 10000)");
    EXPECT_EQ(messageOf([] { checkThreads(-1); }), "option --threads: -1 is out of range (0 to 1024)");
}
