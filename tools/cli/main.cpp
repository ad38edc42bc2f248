// cullide: image-space collision and self-intersection culling, from the command line.
#include "commands.h"

#include "cullide/error.h"
#include "cullide/oracle/versions.h"
#include "cullide/provenance.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <exception>
#include <iostream>

#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

namespace cullide::cli {
namespace {
std::string gCommandLine;
}  // namespace

void setCommandLine(int argc, char** argv) {
    gCommandLine = "cullide";
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool plain = !a.empty() &&
            a.find_first_not_of(
                "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                "0123456789_-+=.,/:@%") == std::string::npos;
        gCommandLine += ' ';
        if (plain) {
            gCommandLine += a;
            continue;
        }
        // Single quotes keep everything but a single quote, which closes, is escaped, and reopens.
        gCommandLine += '\'';
        for (char c : a) {
            if (c == '\'') gCommandLine += "'\\''";
            else gCommandLine += c;
        }
        gCommandLine += '\'';
    }
}

const std::string& commandLine() {
    return gCommandLine;
}

void preferSmallFootprint() {
#if defined(__GLIBC__)
    mallopt(M_MMAP_THRESHOLD, 128 * 1024);
#endif
}

}  // namespace cullide::cli

namespace {

int run(int argc, char** argv) {
    CLI::App app{
        "cullide: image-space collision and self-intersection culling (Cullide and its "
        "self-intersection variant), with a deterministic CPU reference rasterizer"};
    app.require_subcommand(1);
    app.set_version_flag("--version",
                         std::string("cullide ") + cullide::version() + " (commit " + cullide::gitCommit() + "; " +
                             cullide::oracle::libraryVersions() + ")");

    cullide::cli::setCommandLine(argc, argv);
    cullide::cli::Action action;
    cullide::cli::addInfoCommand(app, action);
    cullide::cli::addMakeSceneCommand(app, action);
    cullide::cli::addPruneCommand(app, action);
    cullide::cli::addValidateCommand(app, action);
    cullide::cli::addOracleCommand(app, action);
    cullide::cli::addStudyCommand(app, action);
    cullide::cli::addPlotCommand(app, action);
    cullide::cli::addTraceCommand(app, action);
    cullide::cli::addReportCommand(app, action);
    cullide::cli::addTuneCommand(app, action);
    cullide::cli::addAuditCommand(app, action);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // CLI11 says only "A subcommand is required" for a misspelt command; name it.
        if (argc > 1 && argv[1][0] != '-') {
            std::string known;
            bool isCommand = false;
            for (const CLI::App* sub : app.get_subcommands({})) {
                known += (known.empty() ? "" : ", ") + sub->get_name();
                isCommand = isCommand || sub->get_name() == argv[1];
            }
            if (!isCommand) {
                std::fprintf(stderr, "cullide: error: unknown command '%s' (commands: %s)\n", argv[1], known.c_str());
                return 2;
            }
        }
        const int rc = app.exit(e);
        return rc == 0 ? 0 : 2;
    }
    try {
        return action ? action() : 0;
    } catch (const cullide::InputError& e) {
        std::fprintf(stderr, "cullide: error: %s\n", e.what());
        return 2;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "cullide: error: out of memory\n");
        return 2;
    }
}

// The last resort: anything else that escapes a command is a bug in cullide, reported as one
// with its own exit status (70, EX_SOFTWARE), never an abort.
int runGuarded(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const cullide::InputError& e) {  // from an option's check while parsing
        std::fprintf(stderr, "cullide: error: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cullide: internal error: %s\n", e.what());
    } catch (...) {
        std::fprintf(stderr, "cullide: internal error: an unknown exception\n");
    }
    return 70;
}

// Whether stdout is a pipe whose reader has gone (poll says POLLERR for a pipe without readers).
bool stdoutReaderGone() {
    struct stat st {};
    if (fstat(STDOUT_FILENO, &st) != 0 || !S_ISFIFO(st.st_mode)) return false;
    pollfd p{STDOUT_FILENO, POLLOUT, 0};
    return poll(&p, 1, 0) == 1 && (p.revents & POLLERR);
}

// Output that never arrived (a full disk, a closed file) is an error like any other: the last
// buffered bytes are written here, and a write that failed on the way sets the stream's error
// flag (its cause is lost by then when a flush, say std::endl's, already reported it). A reader
// that went away (EPIPE, where SIGPIPE is ignored; by default the signal has already ended the
// process quietly) is no error: `cullide ... | head` wanted no more.
int checkStdout(int status) {
    int err = std::fflush(stdout) == 0 ? 0 : errno;  // first: std::cout writes through stdout's buffer
    std::cout.flush();
    const bool failed = err != 0 || std::ferror(stdout) || std::cout.fail();
    if (!failed || err == EPIPE || (err == 0 && stdoutReaderGone())) return status;
    std::fprintf(stderr, "cullide: error: stdout: %s\n", err ? std::strerror(err) : "a write failed");
    return status == 70 ? status : 2;
}

}  // namespace

int main(int argc, char** argv) {
    return checkStdout(runGuarded(argc, argv));
}
