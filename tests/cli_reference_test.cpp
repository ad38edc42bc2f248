// The documentation against the product: docs/cli.md against every subcommand's `--help` (the
// built `cullide`), and the README's C++ example against the consumer that the install test
// compiles and runs (tests/consumer/main.cpp).
#include "test_util.h"

#include <gtest/gtest.h>

#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

// Every subcommand, as typed after `cullide`; each has a "## cullide ..." section in docs/cli.md.
const std::vector<std::string> kCommands = {
    "info",        "make-scene",   "prune",         "oracle",     "validate", "trace record",
    "trace replay", "trace compare", "trace info", "study",      "study merge", "plot",
    "report",      "tune",        "audit",
};

std::string cliPath() { return std::string(CULLIDE_SOURCE_DIR) + "/docs/cli.md"; }

// The long options of a `--help` text: the names in its options column ("  -o,--out TEXT ...",
// "  --json TEXT ..."), not options its descriptions happen to mention. --help itself is every
// command's and is left out.
std::set<std::string> helpOptions(const std::string& help) {
    static const std::regex name(R"(^\s+(?:-[A-Za-z0-9],)?--([a-z][a-z0-9-]*))");
    std::set<std::string> options;
    std::istringstream lines(help);
    for (std::string line; std::getline(lines, line);) {
        std::smatch m;
        if (std::regex_search(line, m, name) && m[1] != "help") options.insert(m[1]);
    }
    return options;
}

// The text of docs/cli.md's section "## cullide COMMAND" (up to the next "## " heading), or ""
// when there is none.
std::string docSection(const std::string& doc, const std::string& command) {
    const std::string heading = "## cullide " + command + "\n";
    const size_t start = doc.find(heading);
    if (start == std::string::npos) return "";
    const size_t end = doc.find("\n## ", start + heading.size());
    return doc.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

// Every `--name` a section mentions.
std::set<std::string> docOptions(const std::string& section) {
    static const std::regex name(R"((^|[^A-Za-z0-9-])--([a-z][a-z0-9-]*))");
    std::set<std::string> options;
    for (std::sregex_iterator it(section.begin(), section.end(), name), end; it != end; ++it)
        if ((*it)[2] != "help") options.insert((*it)[2]);
    return options;
}

std::string helpOf(const std::string& command) {
    const auto r = cullide::test::runCommand("'" + std::string(CULLIDE_CLI_PATH) + "' " + command + " --help");
    EXPECT_EQ(r.status, 0) << "cullide " << command << " --help:\n" << r.output;
    return r.output;
}

// Trap: an option added to a command (or a command added) without a word in docs/cli.md. Every
// long option of every subcommand's --help must be named in that command's section.
TEST(CliReference, EveryOptionOfEveryCommandIsDocumented) {
    const std::string doc = cullide::test::readBytes(cliPath());
    ASSERT_FALSE(doc.empty()) << cliPath();
    for (const std::string& command : kCommands) {
        const std::string section = docSection(doc, command);
        ASSERT_FALSE(section.empty()) << "docs/cli.md has no section '## cullide " << command << "'";
        const std::set<std::string> help = helpOptions(helpOf(command));
        if (command == "prune") {  // the parser itself: prune has a dozen options, --method among them
            EXPECT_TRUE(help.count("method")) << "no options parsed from `cullide prune --help`";
        }
        const std::set<std::string> documented = docOptions(section);
        for (const std::string& o : help)
            EXPECT_TRUE(documented.count(o)) << "docs/cli.md, cullide " << command << ": --" << o
                                             << " is in --help but not documented";
    }
}

// Trap: an option renamed or removed while docs/cli.md still tells users to type it, or an
// option documented under the wrong command. Every --name a section mentions must be in that
// command's --help.
TEST(CliReference, EveryDocumentedOptionExists) {
    const std::string doc = cullide::test::readBytes(cliPath());
    ASSERT_FALSE(doc.empty()) << cliPath();
    for (const std::string& command : kCommands) {
        const std::set<std::string> help = helpOptions(helpOf(command));
        for (const std::string& o : docOptions(docSection(doc, command)))
            EXPECT_TRUE(help.count(o)) << "docs/cli.md, cullide " << command << ": --" << o
                                       << " is documented but not in --help";
    }
}

// Trap: a subcommand the tool has that the reference (and this test's list) does not know. The
// top-level --help lists the subcommands; each must be in kCommands, and trace's and study's
// own subcommands likewise.
TEST(CliReference, EverySubcommandIsListed) {
    const std::set<std::string> listed(kCommands.begin(), kCommands.end());
    static const std::regex subcommand(R"(^\s{2}([a-z][a-z-]*)\s{2,}\S)");
    for (const std::string& parent : {std::string(""), std::string("trace"), std::string("study")}) {
        const std::string help = helpOf(parent);
        const size_t at = help.find("Subcommands:");
        if (parent != "study") {
            ASSERT_NE(at, std::string::npos) << "cullide " << parent << " --help:\n" << help;
        }
        if (at == std::string::npos) continue;
        std::istringstream lines(help.substr(at));
        for (std::string line; std::getline(lines, line);) {
            std::smatch m;
            if (!std::regex_search(line, m, subcommand)) continue;
            const std::string command = parent.empty() ? m[1].str() : parent + " " + m[1].str();
            if (command == "trace" || command == "help") continue;  // trace's are listed one by one
            EXPECT_TRUE(listed.count(command)) << "cullide " << command << " is not in docs/cli.md's list";
        }
    }
}

// Trap: the README's C++ example drifting from code that compiles. Each of its lines (leading
// spaces aside) must be a line of tests/consumer/main.cpp, in the same order, and the consumer
// is built against the installed package and run by Package.InstallConsumer.
TEST(ReadmeExample, IsTheConsumersCode) {
    const std::string readme = cullide::test::readBytes(std::string(CULLIDE_SOURCE_DIR) + "/README.md");
    const std::string consumer = cullide::test::readBytes(std::string(CULLIDE_SOURCE_DIR) + "/tests/consumer/main.cpp");
    const size_t begin = readme.find("```cpp\n");
    ASSERT_NE(begin, std::string::npos) << "README.md has no ```cpp block";
    const size_t end = readme.find("```", begin + 7);
    ASSERT_NE(end, std::string::npos);
    auto trimmed = [](const std::string& s) {
        const size_t a = s.find_first_not_of(' ');
        return a == std::string::npos ? std::string() : s.substr(a);
    };
    std::vector<std::string> code;
    std::istringstream c(consumer);
    for (std::string line; std::getline(c, line);) code.push_back(trimmed(line));
    std::istringstream r(readme.substr(begin + 7, end - begin - 7));
    size_t at = 0, lines = 0;
    for (std::string line; std::getline(r, line);) {
        if (trimmed(line).empty()) continue;
        while (at < code.size() && code[at] != trimmed(line)) ++at;
        ASSERT_LT(at, code.size()) << "README.md's C++ line is not in tests/consumer/main.cpp (in order): " << line;
        ++at, ++lines;
    }
    EXPECT_GE(lines, 5u);
}

}  // namespace
