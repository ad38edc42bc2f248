// The study's method families (methods.h).
#include "cullide/study/methods.h"

#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/peers/peer.h"

namespace cullide::study {

const char* toString(MethodFamily f) {
    switch (f) {
        case MethodFamily::ImageSpace: return "image-space";
        case MethodFamily::Exact: return "exact";
        case MethodFamily::Peer: return "peer";
    }
    return "?";
}

MethodFamily methodFamily(const std::string& method, const std::string& source) {
    if (method == "exact") return MethodFamily::Exact;
    if (peers::isPeer(method)) return MethodFamily::Peer;
    try {
        (void)parseCullMethod(method);
        return MethodFamily::ImageSpace;
    } catch (const InputError&) {
        std::string list = "original, modified, reliable, exact";
        for (const std::string& p : peers::peerNames()) list += ", " + p;
        throw InputError(source, "unknown method '" + method + "' (expected " + list + ")");
    }
}

}  // namespace cullide::study
