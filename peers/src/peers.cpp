#include "cullide/peers/peer.h"

#include "cullide/error.h"
#include "peer_makers.h"

#include <algorithm>

namespace cullide::peers {

const std::vector<std::string>& peerNames() {
    static const std::vector<std::string> names{"fcl", "embree", "bullet", "cgal"};
    return names;
}

bool isPeer(const std::string& name) {
    const auto& names = peerNames();
    return std::find(names.begin(), names.end(), name) != names.end();
}

std::unique_ptr<Peer> makePeer(const std::string& name, const PeerOptions& options) {
    if (name == "fcl") return detail::makeFclPeer(options);
    if (name == "embree") return detail::makeEmbreePeer(options);
    if (name == "bullet") return detail::makeBulletPeer(options);
    if (name == "cgal") return detail::makeCgalPeer(options);
    std::string known;
    for (const std::string& n : peerNames()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("peer", "unknown peer '" + name + "' (" + known + ")");
}

}  // namespace cullide::peers
