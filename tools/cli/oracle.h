// `cullide prune --check` and `--exact`: a PCS against the exact oracle (oracle.cpp).
#pragma once

#include "cullide/cullide.h"
#include "cullide/oracle/oracle.h"

#include <nlohmann/json.hpp>

#include <span>

namespace cullide::cli {

struct PcsCheck {
    nlohmann::ordered_json json;  // {"check": {...}} and/or {"exact": {...}}
    bool guaranteeBroken = false;  // a false prune of a pair the method promises to keep
};

// Prints one line per requested measure and returns them as JSON. --check: false prunes by class
// (triangles and pairs), false positives, efficiency; a false prune breaks the method's promise
// when the method promises to keep its pair (promisesToKeep, cullide.h). --exact: the exact
// stage's pairs among the PCS (`exact`, from the Pruner), the final intersecting pairs of the
// pipeline, by class.
PcsCheck checkPcs(const Scene& scene, std::span<const PcsTriangle> pcs, const CullideOptions& options, bool check,
                  const oracle::Truth* exact);

}  // namespace cullide::cli
