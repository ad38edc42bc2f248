// `cullide report`, run as a user runs it: one self-contained, well-formed page, rendered by a
// browser.
#include "cli_test_util.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <tbb/info.h>

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <unistd.h>
#include <vector>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using namespace cullide::test::cli;

namespace {

bool haveMatplotlib() {
    return std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0;
}

// The report of a small mixed study (one single-object scene, one of three objects; two methods,
// two resolutions), made once for the report tests: its folder, or empty when `cullide report`
// failed (the first test to use it says how).
struct ReportRun {
    fs::path dir;
    CliRun study, report;
};
const ReportRun& smallReport() {
    static const ReportRun run = [] {
        ReportRun r;
        r.dir = freshDir("report");
        const std::string csv = quote((r.dir / "s.csv").string());
        r.study = runCli("study --scenes bunny:1500 " + quote(kData + "/scenes/two_cows_and_bunny.json") +
                         " --methods original modified --resolutions 32 64 --repeats 1 -q -o " + csv);
        r.report = runCli("report " + csv + " -o " + quote((r.dir / "page").string()));
        return r;
    }();
    return run;
}

// The elements of an HTML page, checked for balance: every element closed in order (void elements
// excepted), text without a stray '<' (the text of <style> and <script> is not markup). Returns ""
// or the first problem.
std::string checkWellFormed(const std::string& html) {
    static const std::vector<std::string> voids = {"meta", "img", "br", "hr", "link", "input", "col", "wbr"};
    std::vector<std::string> open;
    size_t i = 0;
    while ((i = html.find('<', i)) != std::string::npos) {
        const size_t end = html.find('>', i);
        if (end == std::string::npos) return "a tag without its '>' at " + std::to_string(i);
        const std::string tag = html.substr(i + 1, end - i - 1);
        i = end + 1;
        if (tag.empty() || tag[0] == '!') continue;  // <!DOCTYPE html>
        const bool closing = tag[0] == '/';
        const size_t nameStart = closing ? 1 : 0;
        size_t nameEnd = tag.find_first_of(" \t\n/", nameStart);
        if (nameEnd == std::string::npos) nameEnd = tag.size();
        std::string name = tag.substr(nameStart, nameEnd - nameStart);
        if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0])))
            return "'<' in text: <" + tag.substr(0, 20);
        if (closing) {
            if (open.empty() || open.back() != name)
                return "</" + name + "> closes <" + (open.empty() ? std::string("nothing") : open.back()) + ">";
            open.pop_back();
        } else if (std::find(voids.begin(), voids.end(), name) == voids.end() && tag.back() != '/') {
            open.push_back(name);
        }
        if (!closing && (name == "style" || name == "script")) {
            const size_t close = html.find("</" + name + ">", i);
            if (close == std::string::npos) return "<" + name + "> not closed";
            i = close;
        }
    }
    if (!open.empty()) return "<" + open.back() + "> not closed";
    return "";
}

// The values of attribute `attr` in every tag that has it. (Not std::regex: libstdc++'s recursion
// overflows the stack on a value as long as a chart's base64.)
std::vector<std::string> attributeValues(const std::string& html, const std::string& attr) {
    std::vector<std::string> out;
    const std::string key = attr + "=\"";
    for (size_t i = html.find(key); i != std::string::npos; i = html.find(key, i + 1)) {
        if (i == 0 || !std::isspace(static_cast<unsigned char>(html[i - 1]))) continue;
        const size_t start = i + key.size(), end = html.find('"', start);
        if (end == std::string::npos) break;
        out.push_back(html.substr(start, end - start));
    }
    return out;
}

size_t countOf(const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t i = text.find(what); i != std::string::npos; i = text.find(what, i + 1)) ++n;
    return n;
}

// A study CSV with every method's columns (family, time_to_pairs_ms, pairs_missed, ...): the eight
// methods of three families on a still scene and on four frames of an animated one.
const std::string kEveryMethodStudy = std::string(CULLIDE_TEST_DATA_DIR) + "/study/every_method.csv";

bool haveThreeJs() {
    return fs::exists(fs::path(CULLIDE_SOURCE_DIR) / "tools/report3d/node_modules/three/build/three.module.min.js");
}

// The attribute `attr` of the first tag that has it after `from`, or "".
std::string attributeAfter(const std::string& html, const std::string& from, const std::string& attr) {
    const size_t at = html.find(from);
    if (at == std::string::npos) return "";
    const size_t end = html.find('>', at), key = html.find(" " + attr + "=\"", at);
    if (key == std::string::npos || key > end) return "";
    const size_t start = key + attr.size() + 3;
    return html.substr(start, html.find('"', start) - start);
}

}  // namespace

// `cullide report`: one page with nothing outside it, well-formed, with a Pareto table per scene,
// the provenance (this build's commit) and the command that made the data. Traps: a chart linked
// as a file beside the page (lost when the page is mailed), a script or stylesheet from the web,
// a table for one scene only, an unescaped '<' or a quote in a path breaking the markup.
TEST(Cli, ReportIsOneSelfContainedPage) {
    if (!haveMatplotlib()) GTEST_SKIP() << "no matplotlib for /usr/bin/python3";
    const ReportRun& run = smallReport();
    ASSERT_EQ(run.study.status, 0) << run.study.output;
    ASSERT_EQ(run.report.status, 0) << run.report.output;
    const std::string html = readAll(run.dir / "page" / "report.html");
    ASSERT_FALSE(html.empty());
    EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_EQ(checkWellFormed(html), "");

    const std::vector<std::string> images = attributeValues(html, "src");
    EXPECT_GE(images.size(), 3u) << "speed against accuracy, false prunes by cause, per-call charts";
    for (const std::string& src : images) EXPECT_EQ(src.rfind("data:image/png;base64,", 0), 0u) << src.substr(0, 60);
    for (const std::string& href : attributeValues(html, "href")) EXPECT_EQ(href.rfind('#', 0), 0u) << href;
    for (const char* external : {"<script", "<link", "<iframe", "<object", "<embed", "url("})
        EXPECT_EQ(html.find(external), std::string::npos) << external;

    const std::vector<std::string> scenes = attributeValues(html, "data-scene");
    ASSERT_EQ(scenes.size(), 2u) << "one Pareto table per scene";
    EXPECT_EQ(scenes[0], "bunny:1500");
    EXPECT_EQ(scenes[1], kData + "/scenes/two_cows_and_bunny.json");
    EXPECT_EQ(countOf(html, "<table class=\"pareto\""), 2u);

    const CliRun v = runCli("--version");
    std::smatch m;
    ASSERT_TRUE(std::regex_search(v.output, m, std::regex(R"(\(commit ([^;]+);)"))) << v.output;
    EXPECT_NE(html.find("<td>" + m[1].str() + "</td>"), std::string::npos) << "the provenance names the commit";
    EXPECT_NE(html.find("<pre class=\"command\">cullide study --scenes bunny:1500 "), std::string::npos)
        << "the command that made the data";

    // Not a study: refused by name, nothing written.
    const fs::path d = freshDir("report_bad");
    { std::ofstream(d / "sweep.csv") << "sweep,method\npenetration,modified\n"; }
    CliRun bad = runCli("report " + quote((d / "sweep.csv").string()) + " -o " + quote((d / "page").string()));
    EXPECT_EQ(bad.status, 2) << bad.output;
    EXPECT_NE(bad.output.find("sweep.csv"), std::string::npos) << bad.output;
    bad = runCli("report " + quote((d / "missing.csv").string()) + " -o " + quote((d / "page").string()));
    EXPECT_EQ(bad.status, 2) << bad.output;
    EXPECT_NE(bad.output.find("missing.csv: no such file"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(d / "page" / "report.html"));
}

// The report renders in a browser: headless Chromium (Debian's `chromium`) reads the page into a
// DOM with both Pareto tables and every chart, and draws it. Required when CULLIDE_REQUIRE_CHROMIUM
// is set (tools/test.sh, where tools/setup.sh installs it); skipped otherwise without chromium.
// Trap: a page a parser accepts that a browser does not render (a broken data: URI, bad markup).
TEST(Cli, ReportRendersInChromium) {
    if (std::system("command -v chromium >/dev/null 2>&1") != 0) {
        if (std::getenv("CULLIDE_REQUIRE_CHROMIUM")) FAIL() << "no chromium (tools/setup.sh installs it)";
        GTEST_SKIP() << "no chromium on PATH (Debian: apt-get install chromium)";
    }
    if (!haveMatplotlib()) GTEST_SKIP() << "no matplotlib for /usr/bin/python3";
    const ReportRun& run = smallReport();
    ASSERT_EQ(run.report.status, 0) << run.study.output << run.report.output;
    const fs::path page = run.dir / "page" / "report.html", shot = run.dir / "shot.png";
    // A profile of its own: none written to $HOME, no lock shared with another Chromium.
    const std::string browser =
        "timeout 300 chromium --headless --no-sandbox --disable-gpu --hide-scrollbars "
        "--window-size=1200,2400 --user-data-dir=" +
        quote((run.dir / "chromium-profile").string()) + " ";
    const std::string url = quote("file://" + page.string());
    const CliRun dom = cullide::test::runCommand("( " + browser + "--dump-dom " + url + " 2>/dev/null )");
    ASSERT_EQ(dom.status, 0) << dom.output;
    EXPECT_EQ(countOf(dom.output, "<table class=\"pareto\""), 2u) << dom.output.substr(0, 2000);
    EXPECT_EQ(countOf(dom.output, "<img src=\"data:image/png;base64,"), attributeValues(readAll(page), "src").size());
    const CliRun draw = cullide::test::runCommand(browser + "--screenshot=" + quote(shot.string()) + " " + url);
    ASSERT_EQ(draw.status, 0) << draw.output;
    // A PNG of the window's size (its IHDR: width and height, big-endian, at bytes 16 and 20), and
    // more than a blank page's few kilobytes.
    const std::string png = readAll(shot);
    ASSERT_GT(png.size(), 24u) << draw.output;
    EXPECT_EQ(png.substr(1, 3), "PNG");
    auto be32 = [&](size_t at) {
        return (uint32_t(uint8_t(png[at])) << 24) | (uint32_t(uint8_t(png[at + 1])) << 16) |
            (uint32_t(uint8_t(png[at + 2])) << 8) | uint32_t(uint8_t(png[at + 3]));
    };
    EXPECT_EQ(be32(16), 1200u);
    EXPECT_EQ(be32(20), 2400u);
    EXPECT_GT(png.size(), 50000u) << "a blank page";
}

// Trap: `plot` and `report` on files that are no study output (not text, other columns, a header
// only, a cell that is no number, a row cut short, JSON of another kind) ending in a Python
// traceback (exit 1) or drawn as data (a NaN time, a cut last line), or a file without records
// "plotted" with exit 0. Each is exit status 2 with `cullide: error: FILE: CAUSE`, refused before
// anything is drawn.
TEST(Cli, PlotAndReportRefuseWhatIsNoStudy) {
    if (!haveMatplotlib()) GTEST_SKIP() << "no matplotlib for /usr/bin/python3";
    const fs::path d = freshDir("plot_bad");
    const std::string header = "index,id,scene,frame,triangles,method,time_ms,calls,pcs,colliding\n";
    const std::pair<std::string, std::string> files[] = {
        {"binary.csv", std::string("\x89PNG\r\n\x1a\n\x00\x00", 10)},
        {"other.csv", "a,b,c\n1,2,3\n"},
        {"header_only.csv", header},
        {"nan.csv", header + "0,a1,bunny:500,0,500,modified,12.5,3,40,\n1,a2,bunny:500,0,500,original,nan,1,50,\n"},
        {"short_row.csv", header + "0,a1,bunny:500,0,500\n1,a2,bunny:500,0,500,original,1.5,1,50,\n"},
        {"cut.csv", header + "0,a1,bunny:500,0,500,modified,12.5,3,4"},
        {"other.json", "{\"hello\": 1}\n"},
    };
    const std::pair<std::string, std::string> expected[] = {
        {"binary.csv", "binary.csv: binary data"},
        {"other.csv", "other.csv: not a study output: it has no column scene, method"},
        {"header_only.csv", "header_only.csv: no study records (a header only)"},
        {"nan.csv", "nan.csv: line 3: time_ms is 'nan', not a number"},
        {"short_row.csv", "short_row.csv: line 2 has 5 cells where the header (line 1) has 10"},
        {"cut.csv", "cut.csv: no study records"},
        {"other.json", "other.json: a JSON object without 'frames' or 'benchmarks'"},
    };
    for (const auto& [name, bytes] : files) std::ofstream(d / name, std::ios::binary) << bytes;
    for (size_t i = 0; i < std::size(expected); ++i) {
        const auto& [name, message] = expected[i];
        const char* command = i % 2 ? "report " : "plot ";  // one reader: half of each is enough
        const CliRun r = runCli(command + quote((d / name).string()) + " -o " + quote((d / "out").string()));
        EXPECT_EQ(r.status, 2) << command << name << ": " << r.output;
        EXPECT_NE(r.output.find("cullide: error: " + (d / message).string()), std::string::npos) << r.output;
        EXPECT_EQ(r.output.find("Traceback"), std::string::npos) << r.output;
    }
    const CliRun cut = runCli("plot " + quote((d / "cut.csv").string()) + " -o " + quote((d / "out").string()));
    EXPECT_NE(cut.output.find("cut.csv: line 2 is cut"), std::string::npos) << cut.output;
    EXPECT_FALSE(fs::exists(d / "out")) << "something was drawn";
}

// A study from before the every-method columns: one run, the columns every run has.
const char* const kOldStudy =
    "index,scene,frame,triangles,method,time_ms,calls,pcs\n"
    "0,bunny:1500,0,1500,modified,9.5,3,40\n";

// Trap: the every-method charts drawn from a study without their columns (a crash, or peers drawn
// at 0 ms), or not drawn from one with them; the image-space charts fed peer rows, whose PCS,
// calls and false prunes are empty. A study with the columns gets `methods` and `frame_times`
// beside the image-space charts; one without says each is not drawn, and still plots.
TEST(Cli, PlotDrawsEveryMethodWhereTheColumnsAre) {
    if (!haveMatplotlib()) GTEST_SKIP() << "no matplotlib for /usr/bin/python3";
    const fs::path d = freshDir("plot_methods");
    { std::ofstream(d / "old.csv") << kOldStudy; }
    const CliRun r = runCli("plot " + quote(kEveryMethodStudy) + " " + quote((d / "old.csv").string()) + " -o " +
                            quote((d / "fig").string()));
    ASSERT_EQ(r.status, 0) << r.output;
    for (const char* chart : {"methods", "frame_times", "speed_vs_accuracy", "frames"})
        EXPECT_TRUE(fs::exists(d / "fig" / (std::string(chart) + ".png"))) << chart << ": " << r.output;
    EXPECT_NE(r.output.find("methods: no time_to_pairs_ms in the study"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("frame_times: no time_to_pairs_ms in the study"), std::string::npos) << r.output;
}

// The report's 3D view: a frame's mesh, the oracle's pairs and an audit's missed and spurious
// pairs, drawn by three.js inlined into the page. Traps: a module or script fetched from the web
// (the page must work offline), three.js's second file (three.core) left unresolved so that
// nothing draws, a WebGL canvas that stays blank, an audit naming a frame or triangle the scene
// does not have accepted. Chromium draws WebGL with SwiftShader (no GPU); the view reads its
// pixels back and says how many are not background.
TEST(Cli, ReportShowsAFrameIn3D) {
    if (!haveMatplotlib()) GTEST_SKIP() << "no matplotlib for /usr/bin/python3";
    const bool required = std::getenv("CULLIDE_REQUIRE_CHROMIUM") != nullptr;
    if (!haveThreeJs()) {
        if (required) FAIL() << "no three.js in tools/report3d (tools/setup.sh installs it)";
        GTEST_SKIP() << "no three.js: run tools/setup.sh (npm ci in tools/report3d)";
    }
    const fs::path d = freshDir("report_3d");
    const std::string study = quote((d / "s.csv").string());
    { std::ofstream(d / "s.csv") << kOldStudy; }
    {
        std::ofstream(d / "audit.json") << R"({"frames": [{"frame": 0, "found": 3, "missed": [{"pair": [0, 1, 0, 2],)"
                                           R"( "class": "crossing", "cause": "shared_edge"}],)"
                                           R"( "spurious": [[0, 7, 0, 900]]}]})";
    }
    const std::string view = " --view-scene bunny:1500 --view-audit " + quote((d / "audit.json").string());
    const CliRun r = runCli("report " + study + view + " --view-method fcl -o " + quote((d / "page").string()));
    ASSERT_EQ(r.status, 0) << r.output;
    const std::string html = readAll(d / "page" / "report.html");
    EXPECT_EQ(checkWellFormed(html), "");
    for (const std::string& src : attributeValues(html, "src"))
        EXPECT_EQ(src.rfind("data:", 0), 0u) << src.substr(0, 60);
    for (const std::string& href : attributeValues(html, "href")) EXPECT_EQ(href.rfind('#', 0), 0u) << href;
    for (const char* external : {"<link", "<iframe", "\"http:", "\"https:", "import(\"http", "from\"http"})
        EXPECT_EQ(html.find(external), std::string::npos) << external;
    const std::string mapTag = "<script type=\"importmap\">";
    const size_t map = html.find(mapTag) + mapTag.size();
    ASSERT_GT(map, mapTag.size()) << "no import map";
    const nlohmann::json imports =
        nlohmann::json::parse(html.substr(map, html.find("</script>", map) - map))["imports"];
    EXPECT_EQ(imports.size(), 3u) << "three, its core and OrbitControls";
    for (const auto& [name, url] : imports.items()) EXPECT_EQ(url.get<std::string>().rfind("data:", 0), 0u) << name;
    EXPECT_EQ(attributeAfter(html, "<div class=\"view3d\"", "data-missed"), "1");
    EXPECT_EQ(attributeAfter(html, "<div class=\"view3d\"", "data-spurious"), "1");

    if (std::system("command -v chromium >/dev/null 2>&1") != 0) {
        if (required) FAIL() << "no chromium (tools/setup.sh installs it)";
        GTEST_SKIP() << "no chromium on PATH";
    }
    const CliRun dom = cullide::test::runCommand(
        "( timeout 300 chromium --headless --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader "
        "--window-size=1200,1600 --virtual-time-budget=20000 --user-data-dir=" + quote((d / "profile").string()) +
        " --dump-dom " + quote("file://" + (d / "page" / "report.html").string()) + " 2>/dev/null )");
    ASSERT_EQ(dom.status, 0) << dom.output.substr(0, 2000);
    EXPECT_EQ(attributeAfter(dom.output, "<div class=\"view3d\"", "data-view-state"), "drawn")
        << dom.output.substr(dom.output.find("view3d"), 600);
    const std::string pixels = attributeAfter(dom.output, "<div class=\"view3d\"", "data-view-pixels");
    EXPECT_GT(std::atol(pixels.c_str()), 10000) << "a blank canvas: " << pixels;

    // Refused by name before a page is written: a frame the scene lacks, an audit without the
    // frame, an audit pair naming a triangle the scene lacks.
    const std::string out = " -o " + quote((d / "bad").string());
    CliRun bad = runCli("report " + study + view + " --view-frame 3" + out);
    EXPECT_EQ(bad.status, 2) << bad.output;
    EXPECT_NE(bad.output.find("option --view-frame: scene 'bunny:1500' has 1 frame(s), no frame 3"), std::string::npos)
        << bad.output;
    { std::ofstream(d / "other_frame.json") << R"({"frames": [{"frame": 4, "missed": [], "spurious": []}]})"; }
    bad = runCli("report " + study + " --view-scene bunny:1500 --view-audit " +
                 quote((d / "other_frame.json").string()) + out);
    EXPECT_EQ(bad.status, 2) << bad.output;
    EXPECT_NE(bad.output.find("other_frame.json: the audit has no frame 0"), std::string::npos) << bad.output;
    { std::ofstream(d / "outside.json") << R"([{"frame": 0, "missed": [[0, 1, 0, 1500]], "spurious": []}])"; }
    bad = runCli("report " + study + " --view-scene bunny:1500 --view-audit " + quote((d / "outside.json").string()) +
                 out);
    EXPECT_EQ(bad.status, 2) << bad.output;
    EXPECT_NE(bad.output.find("outside.json: frame 0: missed[0]: names triangle 1500 of object 0"), std::string::npos)
        << bad.output;
    EXPECT_FALSE(fs::exists(d / "bad" / "report.html"));
}
