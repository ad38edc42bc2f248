// The benchmarks' main: Google Benchmark's own, plus cullide's provenance in the report's context
// (the "context" object of --benchmark_format=json, the header of the console output), so that a
// timing names the build and the CPU it came from. Google Benchmark adds the date, host name and
// CPU count itself; the thread count is each benchmark's own argument.
#include "cullide/provenance.h"

#include <benchmark/benchmark.h>

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    const cullide::Provenance p = cullide::provenance(0, {}, false);
    benchmark::AddCustomContext("cullide_version", p.cullideVersion);
    benchmark::AddCustomContext("git_commit", p.gitCommit);
    benchmark::AddCustomContext("compiler", p.compiler);
    benchmark::AddCustomContext("cpu_model", p.cpuModel);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
