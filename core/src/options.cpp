// Option text -> CullideOptions (options.h).
#include "cullide/options.h"

#include "cullide/error.h"
#include "cullide/parse_number.h"

#include <algorithm>
#include <cctype>
#include <limits>
#include <sstream>
#include <tuple>

namespace cullide {

namespace {

// Runs `parse`, re-throwing its InputError under `name` with the same cause: the pieces parsed
// elsewhere (method, depth format, hierarchy kind) name their own default source.
template <typename Parse>
auto named(const std::string& name, Parse&& parse) {
    try {
        return parse();
    } catch (const InputError& e) {
        const std::string what = e.what();
        const size_t prefix = e.source().size() + 2;  // "source: "
        throw InputError(name, what.size() >= prefix ? what.substr(prefix) : what);
    }
}

bool allDigits(std::string_view text) {
    return !text.empty() && std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
}

}  // namespace

std::pair<int, int> parseResolution(const std::string& text, const std::string& name) {
    const size_t x = text.find_first_of("xX");
    const std::string_view w = std::string_view(text).substr(0, x);
    const std::string_view h = x == std::string::npos ? w : std::string_view(text).substr(x + 1);
    if (!allDigits(w) || !allDigits(h))
        throw InputError(name, "cannot read '" + text + "' (expected N or WxH, e.g. 500 or 640x480)");
    return {parseNumber(w, name, 1, kMaxViewportSide), parseNumber(h, name, 1, kMaxViewportSide)};
}

ResolutionSetting parseResolutionSetting(const std::string& text, const std::string& name) {
    ResolutionSetting r;
    if (text.rfind("auto", 0) != 0) {
        std::tie(r.width, r.height) = parseResolution(text, name);
        return r;
    }
    r.autoCoverage = kDefaultAutoCoverage;
    if (text == "auto") return r;
    if (text.size() < 5 || text[4] != ':')
        throw InputError(name, "cannot read '" + text + "' (expected auto or auto:K with a number K, e.g. auto:2)");
    const double value = parseReal(std::string_view(text).substr(5), name, 0, kMaxAutoCoverage);
    if (value == 0) throw InputError(name, "'" + text + "': K must be more than 0");
    r.autoCoverage = value;
    return r;
}

DirectionMode parseDirectionMode(const std::string& text) {
    if (text == "pca") return DirectionMode::Pca;
    if (text == "coherent" || text.rfind("coherent:", 0) == 0) return DirectionMode::Coherent;
    return DirectionMode::Fixed;
}

std::vector<Vec3d> parseDirections(const std::string& text, const std::string& name) {
    if (text == "axes" || text == "pca" || text == "coherent") return axisDirections();
    if (text.rfind("coherent:", 0) == 0) {
        const std::string list = text.substr(9);
        if (list.empty() || list == "pca" || list.rfind("coherent", 0) == 0)
            throw InputError(name,
                             "'" + text +
                                 "': coherent takes a fixed list (coherent:axes, coherent:N or "
                                 "coherent:x,-y,z)");
        return parseDirections(list, name);
    }
    if (allDigits(text)) return spreadDirections(parseNumber<uint32_t>(text, name, 1, kMaxSpreadDirections));
    std::vector<Vec3d> dirs;
    const char separator = text.find(';') != std::string::npos ? ';' : ',';
    std::stringstream items(text);
    std::string item;
    while (std::getline(items, item, separator)) {
        item.erase(0, item.find_first_not_of(' '));
        item.erase(item.find_last_not_of(' ') + 1);
        Vec3d d;
        if (item == "x" || item == "+x") d = Vec3d(1, 0, 0);
        else if (item == "-x") d = Vec3d(-1, 0, 0);
        else if (item == "y" || item == "+y") d = Vec3d(0, 1, 0);
        else if (item == "-y") d = Vec3d(0, -1, 0);
        else if (item == "z" || item == "+z") d = Vec3d(0, 0, 1);
        else if (item == "-z") d = Vec3d(0, 0, -1);
        else {
            std::stringstream words(item);
            std::vector<std::string> xyz;
            for (std::string w; words >> w;) xyz.push_back(w);
            if (xyz.size() != 3)
                throw InputError(name,
                                 "cannot read direction '" + item +
                                     "' (expected axes, a count, or a list like x,-y,z or '1 0 0;0 1 1')");
            constexpr double big = std::numeric_limits<double>::max();
            for (int k = 0; k < 3; ++k) d[k] = parseReal(xyz[size_t(k)], name, -big, big);
        }
        if (!d.allFinite() || d.norm() == 0) throw InputError(name, "direction '" + item + "' is zero or not finite");
        dirs.push_back(d.normalized());
    }
    if (dirs.empty()) throw InputError(name, "no directions given");
    return dirs;
}

ExactSwitch parseExactSwitch(const std::string& text, const std::string& name) {
    ExactSwitch s;
    if (text == "never") return s;
    if (text == "auto") {
        s.kind = ExactSwitchKind::Auto;
        return s;
    }
    if (!allDigits(text))
        throw InputError(name, "cannot read '" + text + "' (expected never, auto or a triangle count N)");
    s.kind = ExactSwitchKind::Below;
    s.triangles = size_t(parseNumber<unsigned long long>(text, name, 1, 1'000'000'000'000ull));
    return s;
}

CullideOptions parseCullideOptions(const OptionText& text, const OptionNames& names) {
    CullideOptions o;
    o.method = named(names.method, [&] { return parseCullMethod(text.method); });
    const ResolutionSetting resolution = parseResolutionSetting(text.resolution, names.resolution);
    o.width = resolution.width, o.height = resolution.height, o.autoCoverage = resolution.autoCoverage;
    o.depth = named(names.depth, [&] { return DepthFormat::parse(text.depth); });
    o.directions = parseDirections(text.directions, names.directions);
    o.directionMode = parseDirectionMode(text.directions);
    o.hierarchy.kind = named(names.hierarchy, [&] { return parseHierarchyKind(text.hierarchy); });
    o.views = named(names.views, [&] { return parseViewMode(text.views); });
    o.hierarchy.leafSize = checkRange(text.leafSize, names.leafSize, 1u, kMaxLeafSize);
    o.hierarchy.branching = checkRange(text.branching, names.branching, kMinBranching, kMaxBranching);
    o.hierarchy.seed = text.seed;
    o.exactSwitch = parseExactSwitch(text.exactSwitch, names.exactSwitch);
    o.validate();  // nothing left to refuse: the checks above cover it
    return o;
}

// A depth format by name (declared with DepthFormat, depth_backend.h).
DepthFormat DepthFormat::parse(const std::string& text) {
    std::string t;
    for (char c : text) t.push_back(char(std::tolower(static_cast<unsigned char>(c))));
    if (t == "float" || t == "f32" || t == "d32f" || t == "float32") return float32();
    std::string digits = t;
    if (digits.rfind("unorm", 0) == 0) digits = digits.substr(5);
    else if (digits.rfind("d", 0) == 0) digits = digits.substr(1);
    if (!allDigits(digits) || digits.size() > 2)
        throw InputError("depth format", "'" + text + "' is not a depth format (use 8..32, d24, unorm16, float, d32f)");
    return unorm(parseNumber(std::string_view(digits), "depth format", 0, 99));
}

int checkThreads(long long threads, const std::string& name) {
    return int(checkRange(threads, name, 0LL, (long long)kMaxThreads));
}

DepthFunc parseDepthFunc(const std::string& text, const std::string& name) {
    static const char* names[] = {"never", "less", "equal", "lequal", "greater", "notequal", "gequal", "always"};
    for (int i = 0; i < 8; ++i)
        if (text == names[i]) return DepthFunc(i);
    throw InputError(name,
                     "'" + text + "' is not one of never, less, equal, lequal, greater, notequal, gequal, always");
}

QueryKind parseQueryKind(const std::string& text, const std::string& name) {
    if (text == "samples") return QueryKind::SamplesPassed;
    if (text == "any") return QueryKind::AnySamplesPassed;
    throw InputError(name, "'" + text + "' is not 'samples' or 'any'");
}

}  // namespace cullide
