// The `cullide` command: one registration function per subcommand.
//
// Every subcommand reports bad input (files, scenes, options) as an InputError; main() prints it
// as "cullide: error: <file or option>: <cause>" and exits with status 2. Status 1 is reserved
// for a run that worked but found a failure it was asked to check for. Any other exception is a
// bug: "cullide: internal error: ..." and status 70, never an abort.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace cullide::cli {

// A subcommand's action, run after parsing; returns the process exit status.
using Action = std::function<int()>;

void addInfoCommand(CLI::App& app, Action& action);
void addMakeSceneCommand(CLI::App& app, Action& action);
void addPruneCommand(CLI::App& app, Action& action);
void addValidateCommand(CLI::App& app, Action& action);
void addOracleCommand(CLI::App& app, Action& action);
void addStudyCommand(CLI::App& app, Action& action);
void addPlotCommand(CLI::App& app, Action& action);

}  // namespace cullide::cli
