// Study specs from JSON (study.h): every field checked here, before anything runs, so that a bad
// spec is an InputError naming the field (exit status 2), never an exception from deep inside.
#include "cullide/study/study.h"

#include "cullide/study/methods.h"

#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/hierarchy.h"
#include "cullide/json_read.h"
#include "cullide/options.h"
#include "cullide/parse_number.h"
#include "cullide/raster/backends.h"

#include <algorithm>
#include <string>

namespace cullide::study {
namespace {

using Json = nlohmann::json;

// Reads the fields of one spec; every error names the file and the field.
class FieldReader {
public:
    explicit FieldReader(const std::string& source) : source_(source) {}

    [[noreturn]] void fail(const std::string& key, const std::string& cause) const {
        throw InputError(source_, "field '" + key + "': " + cause);
    }

    // A list field's items: a list (not empty), or one value standing for a list of one.
    std::vector<Json> items(const Json& v, const std::string& key) const {
        if (!v.is_array()) return {v};
        if (v.empty()) fail(key, "an empty list (give at least one value, or leave the field out)");
        return {v.begin(), v.end()};
    }

    // A single-valued field: a value, or a list of exactly one.
    const Json& single(const Json& v, const std::string& key) const {
        if (!v.is_array()) return v;
        if (v.size() != 1) fail(key, "expected one value, not a list of " + std::to_string(v.size()));
        return v[0];
    }

    // A JSON integer in [lo, hi] (2.5, "3", true and integers beyond the range are refused).
    int64_t integer(const Json& v, const std::string& key, int64_t lo, int64_t hi) const {
        const std::string range = "expected an integer from " + std::to_string(lo) + " to " + std::to_string(hi);
        if (!v.is_number_integer()) fail(key, range + ", not " + v.dump());
        if (v.is_number_unsigned() ? v.get<uint64_t>() > uint64_t(hi) : v.get<int64_t>() < lo || v.get<int64_t>() > hi)
            fail(key, range + ", not " + v.dump());
        return v.is_number_unsigned() ? int64_t(v.get<uint64_t>()) : v.get<int64_t>();
    }

    // A JSON number in [lo, hi] (NaN cannot be written in JSON; "0.1" and true are refused).
    double real(const Json& v, const std::string& key, double lo, double hi) const {
        if (!v.is_number() || v.get<double>() < lo || v.get<double>() > hi)
            fail(key, "expected a number from " + numberText(lo) + " to " + numberText(hi) + ", not " + v.dump());
        return v.get<double>();
    }

    std::string text(const Json& v, const std::string& key) const {
        if (!v.is_string() || v.get<std::string>().empty()) fail(key, "expected a non-empty string, not " + v.dump());
        return v.get<std::string>();
    }

    // A string, or an integer in [lo, hi] written as its decimal text (resolutions, depths,
    // directions accept both).
    std::string textOrInteger(const Json& v, const std::string& key, int64_t lo, int64_t hi) const {
        return v.is_number() ? std::to_string(integer(v, key, lo, hi)) : text(v, key);
    }

    // Runs a core parser on a value, its InputError restated as the field's: the same cause that
    // `prune` gives for the same value (options.h).
    template <typename Parse>
    void check(const std::string& key, const std::string& value, Parse parse) const {
        try {
            (void)parse(value);
        } catch (const InputError& e) {
            const std::string what = e.what();
            fail(key, what.substr(std::min(what.size(), e.source().size() + 2)));  // the parser's own cause
        }
    }

    // A list of strings (with integers in [lo, hi] as their text when hi > 0), each checked by
    // `parse`.
    template <typename Parse>
    std::vector<std::string> texts(const Json& v, const std::string& key, Parse parse, int64_t lo = 0,
                                   int64_t hi = 0) const {
        std::vector<std::string> out;
        for (const Json& x : items(v, key)) out.push_back(hi > 0 ? textOrInteger(x, key, lo, hi) : text(x, key));
        for (const std::string& t : out) check(key, t, parse);
        return out;
    }

    // A list of integers in [lo, hi].
    template <typename T>
    std::vector<T> integers(const Json& v, const std::string& key, int64_t lo, int64_t hi) const {
        std::vector<T> out;
        for (const Json& x : items(v, key)) out.push_back(T(integer(x, key, lo, hi)));
        return out;
    }

private:
    std::string source_;
};

}  // namespace

Spec parseSpec(const nlohmann::json& j, const std::string& source) {
    if (!j.is_object()) throw InputError(source, "a study spec is a JSON object");
    const FieldReader r(source);
    Spec s;
    s.names = specOptionNames(source);
    s.source = source;
    for (const auto& [key, v] : j.items()) {
        if (key == "scenes") {
            s.scenes = r.texts(v, key, [](const std::string&) { return 0; });  // checked when expanded
        } else if (key == "methods") {
            s.methods = r.texts(v, key, [](const std::string& m) { return methodFamily(m, "method"); });
        } else if (key == "resolutions") {
            s.resolutions = r.texts(
                v, key, [](const std::string& t) { return parseResolutionSetting(t); }, 1, kMaxViewportSide);
        } else if (key == "depths") {
            s.depths = r.texts(v, key, DepthFormat::parse, 8, 32);
        } else if (key == "directions") {
            s.directions = r.texts(
                v, key, [](const std::string& t) { return parseDirections(t); }, 1, 10000);
        } else if (key == "views") {
            s.views = r.texts(v, key, parseViewMode);
        } else if (key == "hierarchies") {
            s.hierarchies = r.texts(v, key, parseHierarchyKind);
        } else if (key == "leaf_sizes") {
            s.leafSizes = r.integers<uint32_t>(v, key, 1, kMaxLeafSize);
        } else if (key == "exact_switches") {
            s.exactSwitches = r.texts(
                v, key, [](const std::string& t) { return parseExactSwitch(t); }, 1, 1'000'000'000'000);
        } else if (key == "backends") {
            s.backends = r.texts(v, key, [](const std::string& b) {
                if (!raster::isBackendName(b)) throw InputError("backend", "'" + b + "': " + raster::backendNameList());
                return 0;
            });
        } else if (key == "threads") {
            s.threads = r.integers<int>(v, key, 0, kMaxThreads);
        } else if (key == "branching") {
            s.branching = uint32_t(r.integer(r.single(v, key), key, kMinBranching, kMaxBranching));
        } else if (key == "seed") {
            const Json& x = r.single(v, key);
            if (!x.is_number_unsigned()) r.fail(key, "expected an integer from 0 to 2^64 - 1, not " + x.dump());
            s.seed = x.get<uint64_t>();
        } else if (key == "repeats") {
            s.repeats = int(r.integer(r.single(v, key), key, 1, 1000));
        } else if (key == "near_distance") {
            s.nearDistance = r.real(r.single(v, key), key, 0, kMaxNearDistance);
        } else if (key == "tolerance") {
            s.tolerance = r.real(r.single(v, key), key, 0, kMaxTolerance);
        } else if (key == "oracle") {
            if (!v.is_boolean()) r.fail(key, "true or false, not " + v.dump());
            s.oracle = v.get<bool>();
        } else {
            throw InputError(source,
                             "unknown field '" + key +
                                 "' (fields: scenes, methods, resolutions, depths, directions, views, hierarchies, "
                                 "leaf_sizes, exact_switches, backends, threads, branching, seed, repeats, near_distance, tolerance, "
                                 "oracle)");
        }
    }
    return s;
}

Spec loadSpec(const std::string& path) {
    // 1 MiB: a spec lists a few values per axis; its size is no bound on its runs (expand's is).
    constexpr JsonLimits kSpecJson{.kind = "a study spec", .maxBytes = uint64_t(1) << 20};
    return parseSpec(readJsonFile(path, kSpecJson), path);
}

}  // namespace cullide::study
