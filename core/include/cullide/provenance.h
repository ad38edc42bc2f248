// Where a result came from: the `provenance` object that every JSON output of cullide carries
// (prune --json, oracle --json, info --json, each study record, the benchmarks' context), so
// that a number can be traced to the build, the machine and the run that produced it.
//
//   "provenance": {"cullide_version": "0.2.0", "git_commit": "<40 hex>[-dirty]" | "unknown",
//                  "compiler": "GCC 12.2.0", "cpu_model": "...", "threads": 16,
//                  "date": "2026-11-22T15:04:05Z", "drivers": ["..."]}
//
// The date (UTC, ISO 8601, seconds) is left out where outputs must be byte-reproducible (traces);
// drivers are the GL/Vulkan backends' descriptions, left out for the CPU backend.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace cullide {

// The project version ("0.2.0", from CMake's project(VERSION)).
const char* version();
// The git commit the build was made from ("unknown" outside a git checkout), with "-dirty" when
// the work tree had changes at build time. Regenerated on every build (core/cmake/git_commit.cmake).
const char* gitCommit();

struct Provenance {
    std::string cullideVersion, gitCommit, compiler, cpuModel, date;
    int threads = 0;
    std::vector<std::string> drivers;
};

// threads: the worker threads used (0: TBB's default concurrency, what a task arena without a
// limit gets); drivers: backend descriptions (GL/Vulkan driver strings), may be empty;
// withDate=false leaves date empty (traces must be byte-reproducible).
Provenance provenance(int threads, std::vector<std::string> drivers = {}, bool withDate = true);

// Keys, in this order: cullide_version, git_commit, compiler, cpu_model, threads, date (omitted
// when empty), drivers (omitted when empty).
nlohmann::ordered_json toJson(const Provenance& p);

}  // namespace cullide
