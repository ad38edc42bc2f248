// Provenance of results (provenance.h). gitCommit() is in the generated git_commit.cpp.
#include "cullide/provenance.h"

#include <tbb/info.h>

#include <cstdio>
#include <ctime>
#include <fstream>
#include <utility>

#ifndef CULLIDE_VERSION
#error "CULLIDE_VERSION is set by core/CMakeLists.txt from project(VERSION)"
#endif

namespace cullide {
namespace {

#define CULLIDE_STR2(x) #x
#define CULLIDE_STR(x) CULLIDE_STR2(x)

// Clang defines __GNUC__ too (as 4.2.1), so it is asked first.
const char* compilerName() {
#if defined(__clang__)
    return "Clang " CULLIDE_STR(__clang_major__) "." CULLIDE_STR(__clang_minor__) "." CULLIDE_STR(__clang_patchlevel__);
#elif defined(__GNUC__)
    return "GCC " CULLIDE_STR(__GNUC__) "." CULLIDE_STR(__GNUC_MINOR__) "." CULLIDE_STR(__GNUC_PATCHLEVEL__);
#else
    return "unknown";
#endif
}

// The first "model name" of /proc/cpuinfo (x86; other machines may have none: "unknown").
std::string readCpuModel() {
    std::ifstream f("/proc/cpuinfo");
    for (std::string line; std::getline(f, line);) {
        if (line.rfind("model name", 0) != 0) continue;
        const size_t colon = line.find(':');
        if (colon == std::string::npos) continue;
        const size_t begin = line.find_first_not_of(" \t", colon + 1);
        if (begin == std::string::npos) continue;
        const size_t end = line.find_last_not_of(" \t\r");
        return line.substr(begin, end + 1 - begin);
    }
    return "unknown";
}

const std::string& cpuModel() {
    static const std::string model = readCpuModel();  // read once per process: a study writes many records
    return model;
}

std::string utcNow() {
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buf;
}

}  // namespace

const char* version() {
    return CULLIDE_VERSION;
}

Provenance provenance(int threads, std::vector<std::string> drivers, bool withDate) {
    Provenance p;
    p.cullideVersion = version();
    p.gitCommit = gitCommit();
    p.compiler = compilerName();
    p.cpuModel = cpuModel();
    p.threads = threads > 0 ? threads : tbb::info::default_concurrency();
    if (withDate) p.date = utcNow();
    p.drivers = std::move(drivers);
    return p;
}

nlohmann::ordered_json toJson(const Provenance& p) {
    nlohmann::ordered_json j = {{"cullide_version", p.cullideVersion},
                                {"git_commit", p.gitCommit},
                                {"compiler", p.compiler},
                                {"cpu_model", p.cpuModel},
                                {"threads", p.threads}};
    if (!p.date.empty()) j["date"] = p.date;
    if (!p.drivers.empty()) j["drivers"] = p.drivers;
    return j;
}

}  // namespace cullide
