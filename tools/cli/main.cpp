// cullide: image-space collision and self-intersection culling, from the command line.
#include "commands.h"

#include "cullide/error.h"
#include "cullide/oracle/versions.h"

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
    CLI::App app{"cullide: image-space collision and self-intersection culling (Cullide and its "
                 "self-intersection variant), with a deterministic CPU reference rasterizer"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("cullide 0.1.0 (") + cullide::oracle::libraryVersions() + ")");

    cullide::cli::Action action;
    cullide::cli::addInfoCommand(app, action);
    cullide::cli::addMakeSceneCommand(app, action);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
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
