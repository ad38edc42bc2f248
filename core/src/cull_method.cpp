// The words of the enums (CullMethod, ViewMode, DirectionMode), each method's promise
// (promisesToKeep) and the validation of CullideOptions. See cullide.h.
#include "cullide/cullide.h"

#include "cullide/error.h"

#include <string>

namespace cullide {

const char* toString(CullMethod m) {
    switch (m) {
        case CullMethod::Original: return "original";
        case CullMethod::Modified: return "modified";
        case CullMethod::Reliable: return "reliable";
    }
    return "?";
}

CullMethod parseCullMethod(const std::string& text) {
    if (text == "original") return CullMethod::Original;
    if (text == "modified") return CullMethod::Modified;
    if (text == "reliable") return CullMethod::Reliable;
    throw InputError("option --method", "unknown method '" + text + "' (expected original, modified or reliable)");
}

const char* toString(ViewMode m) {
    switch (m) {
        case ViewMode::Fit: return "fit";
        case ViewMode::Clustered: return "clustered";
    }
    return "?";
}

ViewMode parseViewMode(const std::string& text) {
    if (text == "fit") return ViewMode::Fit;
    if (text == "clustered") return ViewMode::Clustered;
    throw InputError("option --views", "unknown view mode '" + text + "' (expected fit or clustered)");
}

bool promisesToKeep(CullMethod method, bool crossing, bool sameObject) {
    switch (method) {
        case CullMethod::Original: return !sameObject;
        case CullMethod::Modified: return crossing;
        case CullMethod::Reliable: return true;
    }
    return true;
}

const char* toString(DirectionMode m) {
    switch (m) {
        case DirectionMode::Fixed: return "fixed";
        case DirectionMode::Pca: return "pca";
        case DirectionMode::Coherent: return "coherent";
    }
    return "?";
}

void CullideOptions::validate() const {
    if (directions.empty()) throw InputError("option --directions", "no directions given");
    for (const Vec3d& d : directions)
        if (!d.allFinite() || d.norm() == 0)
            throw InputError("option --directions", "a direction is zero or not finite");
    if (width < 1 || width > kMaxViewportSide || height < 1 || height > kMaxViewportSide)
        throw InputError("option --resolution",
                         "the viewport must be 1 to " + std::to_string(kMaxViewportSide) + " pixels per side, not " +
                             std::to_string(width) + "x" + std::to_string(height));
    if (autoCoverage != 0 && !(autoCoverage > 0 && autoCoverage <= kMaxAutoCoverage))
        throw InputError("option --resolution",
                         "the adaptive resolution's K must be more than 0 and at most " +
                             std::to_string(int(kMaxAutoCoverage)) + " pixels");
    if (autoCoverage != 0 && autoBudget < int64_t(width) * height)
        throw InputError("option --resolution",
                         "the adaptive resolution's pixel budget (" + std::to_string(autoBudget) +
                             ") is smaller than the base viewport");
    if (hierarchy.leafSize < 1) throw InputError("option --leaf-size", "the leaf size must be at least 1");
    if (hierarchy.branching < 2) throw InputError("option --branching", "the branching must be at least 2");
    if (exactSwitch.kind == ExactSwitchKind::Below && exactSwitch.triangles < 1)
        throw InputError("option --exact-switch", "the switch's triangle count must be at least 1");
}

}  // namespace cullide
