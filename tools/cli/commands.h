// The `cullide` command: one registration function per subcommand.
//
// Every subcommand reports bad input (files, scenes, options) as an InputError; main() prints it
// as "cullide: error: <file or option>: <cause>" and exits with status 2. Status 1 is reserved
// for a run that worked but found a failure it was asked to check for. Any other exception is a
// bug: "cullide: internal error: ..." and status 70, never an abort.
#pragma once

#include "common.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace cullide::cli {

// A subcommand's action, run after parsing; returns the process exit status.
using Action = std::function<int()>;

// For the commands whose peak memory is a promise (oracle, trace record and replay): a fixed
// glibc mmap threshold of 128 KiB. glibc otherwise raises the threshold to the size of each large
// block freed (up to 32 MB), so that later large buffers come from the heap, where freed ones
// stay resident: oracle on a 1M-triangle bunny peaks at 165 MB instead of 140, trace record of a
// 270k bunny of 9 frames (pipeline and interval evaluator take turns) at 85 MB instead of 64.
// The price is a fresh mapping, and its page faults, for every large block: not for commands that
// allocate and free large buffers over and over (study: 120k page faults instead of 16k, 20-40%
// of its time; prune of 9 frames: 25% more CPU), which keep glibc's default.
void preferSmallFootprint();

// The command line this process runs, as a POSIX shell reads it back: argv[0] as "cullide" (its
// basename: no machine path in the outputs), each other argument quoted where the shell would
// split or expand it. main() sets it before parsing; `study` records it in each record ("command").
void setCommandLine(int argc, char** argv);
const std::string& commandLine();

// Runs tools/plot.py (the plot command's script: $CULLIDE_PLOT_SCRIPT or the resource root's) with
// `scriptArgs` under `python` (empty: $CULLIDE_PYTHON, else /usr/bin/python3); returns its exit
// status. InputError when the script or one of `inputs` does not exist, before anything runs.
int runPlotScript(const std::vector<std::string>& inputs, const std::vector<std::string>& scriptArgs,
                  const std::string& python);

void addInfoCommand(CLI::App& app, Action& action);
void addMakeSceneCommand(CLI::App& app, Action& action);
void addPruneCommand(CLI::App& app, Action& action);
void addValidateCommand(CLI::App& app, Action& action);
void addOracleCommand(CLI::App& app, Action& action);
void addStudyCommand(CLI::App& app, Action& action);
void addPlotCommand(CLI::App& app, Action& action);
void addTraceCommand(CLI::App& app, Action& action);
void addReportCommand(CLI::App& app, Action& action);
void addTuneCommand(CLI::App& app, Action& action);
void addAuditCommand(CLI::App& app, Action& action);

}  // namespace cullide::cli
