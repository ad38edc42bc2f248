// `cullide plot`: charts of study results, stability sweeps, `prune --json` pass statistics and
// Google Benchmark JSON, drawn by tools/plot.py (matplotlib) with Debian's /usr/bin/python3.
#include "commands.h"

#include "cullide/error.h"
#include "cullide/resources.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace cullide::cli {
namespace {

struct PlotOptions {
    std::vector<std::string> inputs;
    std::string out = "figures";
    std::string method;
    std::string python;
};

// tools/plot.py: $CULLIDE_PLOT_SCRIPT, else under the resource root (resources.h: the source tree
// for a build-tree executable, ../share/cullide beside an installed one).
std::filesystem::path plotScript() {
    if (const char* env = std::getenv("CULLIDE_PLOT_SCRIPT")) return env;
    return resourceDir() / "tools" / "plot.py";
}

int runPlot(const PlotOptions& o) {
    std::vector<std::string> args{"-o", o.out};
    if (!o.method.empty()) args.insert(args.end(), {"--method", o.method});
    args.insert(args.end(), o.inputs.begin(), o.inputs.end());
    return runPlotScript(o.inputs, args, o.python);
}

}  // namespace

int runPlotScript(const std::vector<std::string>& inputs, const std::vector<std::string>& scriptArgs,
                  const std::string& pythonOption) {
    const std::filesystem::path script = plotScript();
    if (!std::filesystem::exists(script)) throw InputError("plot", "cannot find the plot script " + script.string());
    for (const std::string& in : inputs)
        if (!std::filesystem::exists(in)) throw InputError(in, "no such file");
    std::string python = pythonOption;
    if (python.empty()) python = std::getenv("CULLIDE_PYTHON") ? std::getenv("CULLIDE_PYTHON") : "/usr/bin/python3";
    std::vector<std::string> args{python, script.string()};
    args.insert(args.end(), scriptArgs.begin(), scriptArgs.end());
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::fflush(stdout);
    const pid_t pid = fork();
    if (pid < 0) throw InputError("plot", "cannot start " + python);
    if (pid == 0) {
        execv(argv[0], argv.data());
        std::fprintf(stderr, "cullide: error: plot: cannot run %s (set CULLIDE_PYTHON to a python3 with matplotlib)\n",
                     argv[0]);
        _exit(2);
    }
    // The script's exit status is the command's: 2 with its own `cullide: error:` line for bad input.
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    std::fprintf(stderr, "cullide: error: plot: %s ended by signal %d\n", python.c_str(),
                 WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    return 2;
}

void addPlotCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<PlotOptions>();
    CLI::App* sub = app.add_subcommand(
        "plot", "Charts (PNG and SVG) of study results, stability sweeps, prune --json or Google Benchmark JSON");
    sub->add_option("inputs", o->inputs, "study .csv/.jsonl, stability .csv, prune --json .json, cullide_bench JSON")
        ->required();
    sub->add_option("-o,--out", o->out, "Folder for the charts")->capture_default_str();
    sub->add_option("--method", o->method,
                    "Method of the per-call charts (Figures 9-11) of a study (default: modified, else the first "
                    "method with several calls)");
    sub->add_option("--python", o->python, "Python with matplotlib (default $CULLIDE_PYTHON or /usr/bin/python3)");
    sub->callback([o, &action] { action = [o] { return runPlot(*o); }; });
}

}  // namespace cullide::cli
