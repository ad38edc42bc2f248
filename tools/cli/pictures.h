// Pictures of the PCS (the paper's Figure 12): the whole scene from one fixed view, shaded by
// depth, with the visible parts of PCS triangles in green.
#pragma once

#include "cullide/cullide.h"
#include "cullide/scene.h"

#include <filesystem>
#include <memory>
#include <span>

namespace cullide::cli {

class PcsPictures {
public:
    // Renders with its own CPU backend (the culling backend's state is left alone), looking
    // along `direction`, the view fitted to the whole scene.
    PcsPictures(const Scene& scene, const Vec3d& direction, int width, int height);
    ~PcsPictures();

    // Writes one PNG: pixels whose front-most surface is a PCS triangle are green.
    void write(std::span<const PcsTriangle> pcs, const std::filesystem::path& path);

private:
    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace cullide::cli
