// Benchmarks of whole `cullide` commands, run as the user runs them: the command-line tool is
// started as a child process, so that its peak memory is its own (getrusage of the child, the
// figure `/usr/bin/time -f %M` prints) and nothing of this process's heap counts.
//
//   BM_PeakMemory/<command>: peak resident memory of `cullide prune` (0) or `cullide oracle` (1)
//     on the generated bunny of 1M triangles (`make-scene bunny --triangles 1000000`,
//     999,424 triangles after simplification), default options. Counters: peak_MB (10^6 bytes),
//     B_per_tri, x_v010 (the 0.1.0 reference build's recorded peak over this run's,
//     bench/baseline.json) and goal_B_per_tri (150).
//   BM_StudyPaper: `cullide study --preset paper -q` (the paper's experiments: 28 runs of the
//     deformed bunny and the two cows, median of 3 each, oracle and causes included), wall time;
//     x_v010 is the 0.1.0 reference build's recorded time (bench/baseline.json) over this run's.
//
// Each runs once per invocation (Iterations(1)): a 1M-triangle prune or the preset take seconds,
// and a second run would measure the same thing. Filter them out (--benchmark_filter=-BM_Peak...)
// for a quick run of the kernels.
#include "bench_util.h"

#include <benchmark/benchmark.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;

struct ChildRun {
    int status = -1;
    long maxRssKiB = 0;  // the child's peak resident set, KiB (ru_maxrss)
    double seconds = 0;
};

// Runs the cullide command-line tool with `args`, stdout to /dev/null (stderr kept, for errors).
ChildRun runCli(const std::vector<std::string>& args) {
    std::vector<std::string> all{CULLIDE_CLI};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    const auto start = std::chrono::steady_clock::now();
    pid_t pid = 0;
    const int err = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ChildRun r;
    if (err != 0) return r;
    rusage usage{};
    wait4(pid, &r.status, 0, &usage);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    r.maxRssKiB = usage.ru_maxrss;
    return r;
}

bool succeeded(const ChildRun& r) {
    return WIFEXITED(r.status) && WEXITSTATUS(r.status) == 0;
}

// A scratch folder for the generated scenes and outputs, removed at exit.
const fs::path& scratchDir() {
    static const fs::path dir = [] {
        std::string tmpl = (fs::temp_directory_path() / "cullide-bench-XXXXXX").string();
        if (!mkdtemp(tmpl.data())) throw std::runtime_error("cannot make a scratch folder in " + tmpl);
        return fs::path(tmpl);
    }();
    static const struct Remove {
        ~Remove() {
            std::error_code ec;
            fs::remove_all(scratchDir(), ec);
        }
    } remove;
    return dir;
}

// The 1M bunny scene, generated once by the tool itself (`cullide make-scene bunny --triangles 1000000`).
const fs::path& bunny1M() {
    static const fs::path scene = [] {
        const fs::path out = scratchDir() / "bunny1m.json";
        if (!succeeded(runCli({"make-scene", "bunny", "--triangles", "1000000", "-o", out.string()})))
            return fs::path();
        return out;
    }();
    return scene;
}

constexpr double kGoalBytesPerTriangle = 150;
constexpr size_t kBunny1MTriangles = 999'424;

void BM_PeakMemory(benchmark::State& state) {
    const fs::path& scene = bunny1M();
    if (scene.empty()) {
        state.SkipWithError("make-scene failed");
        return;
    }
    const char* command = state.range(0) == 0 ? "prune" : "oracle";
    ChildRun r;
    for (auto _ : state) {
        r = runCli({command, scene.string()});
        state.SetIterationTime(r.seconds);
    }
    if (!succeeded(r)) {
        state.SkipWithError((std::string("cullide ") + command + " failed").c_str());
        return;
    }
    const double bytes = double(r.maxRssKiB) * 1024.0;
    state.counters["peak_MB"] = bytes / 1e6;
    state.counters["B_per_tri"] = bytes / double(kBunny1MTriangles);
    state.counters["goal_B_per_tri"] = kGoalBytesPerTriangle;
    // The 0.1.0 reference build's recorded peak (bench/baseline.json) over this run's.
    const double oldKiB = baselineFigure("BM_PeakMemory/command:" + std::to_string(state.range(0)));
    if (oldKiB > 0) state.counters["x_v010"] = oldKiB / double(r.maxRssKiB);
}
BENCHMARK(BM_PeakMemory)
    ->ArgName("command")
    ->DenseRange(0, 1)
    ->Iterations(1)
    ->UseManualTime()
    ->Unit(benchmark::kSecond);

void BM_StudyPaper(benchmark::State& state) {
    const fs::path out = scratchDir() / "paper.csv";
    ChildRun r;
    for (auto _ : state) {
        fs::remove(out);
        fs::remove(fs::path(out).replace_extension(".jsonl"));
        r = runCli({"study", "--preset", "paper", "-q", "-o", out.string()});
        state.SetIterationTime(r.seconds);
    }
    if (!succeeded(r)) {
        state.SkipWithError("cullide study --preset paper failed");
        return;
    }
    // The 0.1.0 reference build's recorded time (bench/baseline.json) over this run's.
    const double oldSeconds = baselineFigure("BM_StudyPaper");
    if (oldSeconds > 0) state.counters["x_v010"] = oldSeconds / r.seconds;
    state.counters["peak_MB"] = double(r.maxRssKiB) * 1024.0 / 1e6;
}
BENCHMARK(BM_StudyPaper)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

}  // namespace
