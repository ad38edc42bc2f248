// The provenance object of every JSON output (core provenance.h): its fields, formats and keys.
#include "cullide/provenance.h"

#include <gtest/gtest.h>

#include <tbb/info.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <regex>
#include <string>

namespace {

using namespace cullide;

const std::regex kDate(R"(\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}Z)");

// Seconds since the epoch of a "YYYY-MM-DDTHH:MM:SSZ" date read as UTC.
std::time_t parseUtc(const std::string& s) {
    std::tm tm{};
    EXPECT_EQ(std::sscanf(s.c_str(), "%d-%d-%dT%d:%d:%dZ", &tm.tm_year, &tm.tm_mon, &tm.tm_mday, &tm.tm_hour,
                          &tm.tm_min, &tm.tm_sec),
              6)
        << s;
    tm.tm_year -= 1900, tm.tm_mon -= 1;
    return timegm(&tm);
}

// Trap: an empty field (a compiler the macros miss, a /proc/cpuinfo line cut at the colon) or a
// thread count passed through as given instead of the one used.
TEST(Provenance, EveryFieldIsFilledIn) {
    const Provenance p = provenance(3);
    EXPECT_FALSE(p.cullideVersion.empty());
    EXPECT_FALSE(p.gitCommit.empty());
    EXPECT_TRUE(p.compiler.rfind("GCC ", 0) == 0 || p.compiler.rfind("Clang ", 0) == 0) << p.compiler;
    EXPECT_TRUE(std::regex_match(p.compiler, std::regex(R"((GCC|Clang) \d+\.\d+\.\d+)"))) << p.compiler;
    EXPECT_FALSE(p.cpuModel.empty());
    EXPECT_NE(p.cpuModel.front(), ' ');
    EXPECT_NE(p.cpuModel.back(), ' ');
    EXPECT_EQ(p.threads, 3);
    EXPECT_TRUE(p.drivers.empty());
    EXPECT_TRUE(std::regex_match(p.date, kDate)) << p.date;
}

// Trap: threads 0 ("all cores") written as 0, which says nothing about the machine.
TEST(Provenance, ZeroThreadsIsTbbsDefaultConcurrency) {
    const Provenance p = provenance(0);
    EXPECT_EQ(p.threads, tbb::info::default_concurrency());
    EXPECT_GT(p.threads, 0);
}

// Trap: the date in local time (strftime of localtime) still matches the format; under a time
// zone hours away from UTC it is hours off the clock.
TEST(Provenance, DateIsUtcNow) {
    const char* old = std::getenv("TZ");
    const std::string saved = old ? old : "";
    setenv("TZ", "EST+5", 1), tzset();  // POSIX rule: needs no zoneinfo files
    const std::time_t before = std::time(nullptr);
    const Provenance p = provenance(1);
    const std::time_t after = std::time(nullptr);
    old ? setenv("TZ", saved.c_str(), 1) : unsetenv("TZ");
    tzset();
    ASSERT_TRUE(std::regex_match(p.date, kDate)) << p.date;
    const std::time_t t = parseUtc(p.date);
    EXPECT_GE(t, before) << p.date;
    EXPECT_LE(t, after) << p.date;
}

// Trap: a date left in a trace makes two recordings of the same run differ in their bytes; and
// keys in another order (or an empty "drivers": []) change every output that embeds them.
TEST(Provenance, JsonKeysInOrderDateAndDriversOnlyWhenSet) {
    const nlohmann::ordered_json j = toJson(provenance(2, {}, false));
    std::string keys;
    for (const auto& [k, v] : j.items()) keys += k + ",";
    EXPECT_EQ(keys, "cullide_version,git_commit,compiler,cpu_model,threads,");
    EXPECT_EQ(j.at("threads").get<int>(), 2);
    EXPECT_EQ(j.dump(), toJson(provenance(2, {}, false)).dump()) << "without the date, the same bytes";

    const nlohmann::ordered_json g = toJson(provenance(1, {"GL 4.6 Mesa 22.3.6 (llvmpipe)"}));
    keys.clear();
    for (const auto& [k, v] : g.items()) keys += k + ",";
    EXPECT_EQ(keys, "cullide_version,git_commit,compiler,cpu_model,threads,date,drivers,");
    EXPECT_EQ(g.at("drivers"), nlohmann::ordered_json::array({"GL 4.6 Mesa 22.3.6 (llvmpipe)"}));
}

// Trap: a commit frozen at configure time, abbreviated, or with git's stderr in it; outside a
// checkout it must say "unknown", never an empty string or the commit of an enclosing checkout.
TEST(Provenance, GitCommitIsFullHashOrUnknown) {
    const std::string c = gitCommit();
    EXPECT_TRUE(std::regex_match(c, std::regex("[0-9a-f]{40}(-dirty)?|unknown"))) << c;
    EXPECT_EQ(provenance(1).gitCommit, c);
}

// Trap: a second hard-coded version string that drifts from CMake's project(VERSION).
TEST(Provenance, VersionIsTheCMakeProjectVersion) {
    EXPECT_STREQ(version(), CULLIDE_EXPECTED_VERSION);
    EXPECT_EQ(provenance(1).cullideVersion, CULLIDE_EXPECTED_VERSION);
}

}  // namespace
