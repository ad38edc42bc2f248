// `cullide report`: one self-contained HTML page of a study (charts embedded, the Pareto-optimal
// configurations of each scene, provenance, the command that produced the data), written by
// tools/plot.py --report (matplotlib) with Debian's /usr/bin/python3, as `cullide plot` runs it.
#include "commands.h"

namespace cullide::cli {
namespace {

struct ReportOptions {
    std::vector<std::string> inputs;
    std::string out = "report";
    std::string method;
    std::string python;
};

}  // namespace

void addReportCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<ReportOptions>();
    CLI::App* sub = app.add_subcommand(
        "report", "One self-contained HTML page of study results: charts, Pareto tables, provenance, command");
    sub->add_option("inputs", o->inputs, "Study outputs (.csv or .jsonl; the .jsonl beside a .csv is read)")
        ->required();
    sub->add_option("-o,--out", o->out, "Folder for report.html")->capture_default_str();
    sub->add_option("--method", o->method, "Method of the per-call charts (Figures 9-11), as plot --method");
    sub->add_option("--python", o->python, "Python with matplotlib (default $CULLIDE_PYTHON or /usr/bin/python3)");
    sub->callback([o, &action] {
        action = [o] {
            std::vector<std::string> args{"--report", "-o", o->out};
            if (!o->method.empty()) args.insert(args.end(), {"--method", o->method});
            args.insert(args.end(), o->inputs.begin(), o->inputs.end());
            return runPlotScript(o->inputs, args, o->python);
        };
    });
}

}  // namespace cullide::cli
