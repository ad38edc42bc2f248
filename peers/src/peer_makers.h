// The four adapters' constructors (private): peers.cpp chooses among them by name.
#pragma once

#include "cullide/peers/peer.h"

#include <memory>

namespace cullide::peers::detail {

std::unique_ptr<Peer> makeFclPeer(const PeerOptions& options);
std::unique_ptr<Peer> makeEmbreePeer(const PeerOptions& options);
std::unique_ptr<Peer> makeBulletPeer(const PeerOptions& options);
std::unique_ptr<Peer> makeCgalPeer(const PeerOptions& options);

}  // namespace cullide::peers::detail
