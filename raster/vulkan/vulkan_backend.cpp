// The Vulkan backend's DepthBackend interface: geometry, views, command lists and read-back (see
// cullide/raster/vulkan_backend.h for the conventions and docs/vulkan-backend.md for what matches
// GL and the reference and what may differ). vulkan_impl.h lists the files behind it.
//
// References: the Vulkan 1.3 specification (§17 queries: occlusion queries and
// VK_QUERY_CONTROL_PRECISE_BIT; §24.9 viewport transformation; §27.4 polygon rasterization;
// §28.8 depth test; §19.3 vkCmdClearAttachments, executed in rasterization order);
// docs/gl-backend.md for the GL backend this one mirrors.
#include "vulkan_impl.h"

#include "../gpu/gpu_common.h"

#include <cstdlib>
#include <cstring>

namespace cullide::raster {

namespace vk {

namespace {

// GL's depth functions in GL's order map to VkCompareOp in the same order.
VkCompareOp toVk(DepthFunc f) {
    static_assert(VK_COMPARE_OP_NEVER == 0 && VK_COMPARE_OP_LESS == 1 && VK_COMPARE_OP_EQUAL == 2 &&
                  VK_COMPARE_OP_LESS_OR_EQUAL == 3 && VK_COMPARE_OP_GREATER == 4 && VK_COMPARE_OP_NOT_EQUAL == 5 &&
                  VK_COMPARE_OP_GREATER_OR_EQUAL == 6 && VK_COMPARE_OP_ALWAYS == 7);
    return VkCompareOp(int(f));
}

const char* formatName(VkFormat f) {
    switch (f) {
        case VK_FORMAT_D16_UNORM: return "D16_UNORM";
        case VK_FORMAT_X8_D24_UNORM_PACK32: return "X8_D24_UNORM_PACK32";
        case VK_FORMAT_D32_SFLOAT: return "D32_SFLOAT";
        default: return "?";
    }
}

}  // namespace

DepthFormat VulkanBackendImpl::effectiveFormat(const DepthFormat& requested) const {
    if (requested.kind == DepthFormat::Kind::Float32 && info_.hasD32F) return DepthFormat::float32();
    // Unorm (or float without D32_SFLOAT): the nearest unorm bit count, ties to the larger.
    const int want = requested.kind == DepthFormat::Kind::Float32 ? 32 : requested.bits;
    int best = 0;
    for (int candidate : {16, 24}) {
        if ((candidate == 16 && !info_.hasD16) || (candidate == 24 && !info_.hasD24)) continue;
        if (best == 0 || std::abs(candidate - want) <= std::abs(best - want)) best = candidate;
    }
    if (best == 0) return DepthFormat::float32();  // only D32_SFLOAT (checked at creation)
    return DepthFormat::unorm(best);
}

std::string VulkanBackendImpl::describe() const {
    std::string s = "vulkan: " + info_.device + " (" + info_.type + "), " + info_.driver + ", Vulkan " + info_.api +
        ", " + std::to_string(info_.subpixelBits) + " subpixel bits";
    if (image_) s += ", " + format_.name() + " (" + formatName(toVk(format_)) + ")";
    return s;
}

void VulkanBackendImpl::setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) {
    static_assert(sizeof(Vec3f) == 12 && sizeof(Triangle) == 12, "tightly packed positions and triangles");
    // Buffers grow as needed; nothing is in flight between calls (execute() waits).
    upload(vertices_, positions.data(), positions.size_bytes(), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
    upload(indices_, triangles.data(), triangles.size_bytes(), VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
    triangleCount_ = triangles.size();
}

void VulkanBackendImpl::setView(const OrthoView& view) {
    view.validate();
    const DepthFormat format = effectiveFormat(view.depth);
    gpu::warnFormatOnce(warned_, view.depth, format, "vulkan backend", "Vulkan", options_.warn);
    if (!image_ || view.width != width_ || view.height != height_ || !(format == format_))
        createTarget(view.width, view.height, format);
    // The exact viewport, as in the GL backend (gpu_common.h).
    const gpu::ViewportSize viewport = gpu::exactViewport(width_, height_, view, info_.maxViewport, viewportBoundsMin_);
    exactViewport_ = viewport.exact;
    P_ = viewport.P;
    writeViewBlock(view);
    haveView_ = true;
}

// The view and the window -> clip scale into the uniform block depth.vert reads.
void VulkanBackendImpl::writeViewBlock(const OrthoView& view) {
    ViewBlock b{};
    auto put = [](double* d, double x, double y, double z) { d[0] = x, d[1] = y, d[2] = z, d[3] = 0; };
    put(b.right, view.right.x(), view.right.y(), view.right.z());
    put(b.up, view.up.x(), view.up.y(), view.up.z());
    put(b.dir, view.dir.x(), view.dir.y(), view.dir.z());
    put(b.lo, view.xmin, view.ymin, view.znear);
    put(b.extent, view.xmax - view.xmin, view.ymax - view.ymin, view.zfar - view.znear);
    put(b.size, double(view.fullWidth()), double(view.fullHeight()), double(view.originX));
    b.size[3] = double(view.originY);
    if (exactViewport_) {
        b.scaleOffset[0] = b.scaleOffset[1] = 1.0f / float(P_);
        b.scaleOffset[2] = b.scaleOffset[3] = 0.0f;
    } else {
        b.scaleOffset[0] = 2.0f / float(width_), b.scaleOffset[1] = 2.0f / float(height_);
        b.scaleOffset[2] = b.scaleOffset[3] = -1.0f;
    }
    std::memcpy(uniform_.mapped, &b, sizeof b);
}

// One render pass, one submission: the list's commands one to one, then its query results.
std::vector<uint64_t> VulkanBackendImpl::execute(const CommandList& list) {
    gpu::checkCommandList(list, haveView_, triangleCount_, "Vulkan");
    const uint32_t n = list.queryCount();
    ensureQueryPool(n);
    VkCommandBuffer cb = begin();
    if (n > 0) vkCmdResetQueryPool(cb, queryPool_, 0, n);
    beginPass(cb);
    std::vector<uint8_t> any(n, 0);
    record(cb, list, any);
    vkCmdEndRenderPass(cb);
    submit(cb);
    return queryResults(n, any);
}

// The render pass begun on the target, the pipeline, geometry, viewport and scissor bound, and the
// persistent depth state (GL's, across lists: the backend's) set: each list starts from it.
void VulkanBackendImpl::beginPass(VkCommandBuffer cb) {
    VkRenderPassBeginInfo rp{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rp.renderPass = renderPass_;
    rp.framebuffer = framebuffer_;
    rp.renderArea = {{0, 0}, {uint32_t(width_), uint32_t(height_)}};
    vkCmdBeginRenderPass(cb, &rp, VK_SUBPASS_CONTENTS_INLINE);
    vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_);
    vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelineLayout_, 0, 1, &descriptorSet_, 0, nullptr);
    if (vertices_.buffer) {
        const VkDeviceSize offset = 0;
        vkCmdBindVertexBuffers(cb, 0, 1, &vertices_.buffer, &offset);
        vkCmdBindIndexBuffer(cb, indices_.buffer, 0, VK_INDEX_TYPE_UINT32);
    }
    VkViewport vp{};
    if (exactViewport_) vp = {float(-P_), float(-P_), float(2 * P_), float(2 * P_), 0.0f, 1.0f};
    else vp = {0.0f, 0.0f, float(width_), float(height_), 0.0f, 1.0f};
    vkCmdSetViewport(cb, 0, 1, &vp);
    const VkRect2D scissor{{0, 0}, {uint32_t(width_), uint32_t(height_)}};
    vkCmdSetScissor(cb, 0, 1, &scissor);
    setDepthCompareOp_(cb, toVk(func_));
    setDepthWriteEnable_(cb, mask_ ? VK_TRUE : VK_FALSE);
}

// The commands into the render pass; any[q] marks the any-samples queries.
void VulkanBackendImpl::record(VkCommandBuffer cb, const CommandList& list, std::vector<uint8_t>& any) {
    const VkRect2D scissor{{0, 0}, {uint32_t(width_), uint32_t(height_)}};
    uint32_t next = 0;
    for (const Command& c : list.commands()) {
        switch (c.op) {
            case Command::Op::Clear: {
                // In rasterization order with the draws, regardless of the write mask.
                VkClearAttachment a{};
                a.aspectMask = VK_IMAGE_ASPECT_DEPTH_BIT;
                a.clearValue.depthStencil = {float(c.clearDepth), 0};
                const VkClearRect r{scissor, 0, 1};
                vkCmdClearAttachments(cb, 1, &a, 1, &r);
                break;
            }
            case Command::Op::SetDepthFunc:
                func_ = c.func;
                setDepthCompareOp_(cb, toVk(c.func));
                break;
            case Command::Op::SetDepthMask:
                mask_ = c.mask;
                setDepthWriteEnable_(cb, c.mask ? VK_TRUE : VK_FALSE);
                break;
            case Command::Op::BeginQuery: {
                const bool exact = c.queryKind == QueryKind::SamplesPassed;
                any[next] = exact ? 0 : 1;
                vkCmdBeginQuery(cb, queryPool_, next, exact ? VK_QUERY_CONTROL_PRECISE_BIT : 0);
                break;
            }
            case Command::Op::EndQuery: vkCmdEndQuery(cb, queryPool_, next++); break;
            case Command::Op::ClearIntervals:
            case Command::Op::DrawConservative: break;  // refused by checkCommandList
            case Command::Op::Draw:
                if (c.count > 0) vkCmdDrawIndexed(cb, uint32_t(uint64_t(c.count) * 3), 1, c.first * 3u, 0, 0);
                break;
        }
    }
}

// The n results, 64-bit, waited for; any-samples queries as 0 or 1.
std::vector<uint64_t> VulkanBackendImpl::queryResults(uint32_t n, const std::vector<uint8_t>& any) {
    std::vector<uint64_t> results(n, 0);
    if (n == 0) return results;
    check(vkGetQueryPoolResults(device_, queryPool_, 0, n, size_t(n) * sizeof(uint64_t), results.data(),
                                sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
          "vkGetQueryPoolResults");
    // Without the precise bit the result is only zero or non-zero.
    for (uint32_t q = 0; q < n; ++q)
        if (any[q]) results[q] = results[q] != 0 ? 1 : 0;
    return results;
}

DepthImage VulkanBackendImpl::readDepth() {
    if (!haveView_) throw InputError("command list", "readDepth() before setView()");
    copyDepthToReadback();
    DepthImage img;
    img.width = width_;
    img.height = height_;
    img.format = format_;
    img.values.resize(size_t(width_) * size_t(height_));
    // Framebuffer row y is GL window row y (positive viewport height), so no flip.
    if (texelBytes() == 2) {
        const auto* src = static_cast<const uint16_t*>(readback_.mapped);
        for (size_t i = 0; i < img.values.size(); ++i) img.values[i] = src[i];
    } else {
        std::memcpy(img.values.data(), readback_.mapped, img.values.size() * 4);
        // X8_D24: the top 8 bits are undefined.
        if (format_.kind == DepthFormat::Kind::Unorm)
            for (uint32_t& v : img.values) v &= 0xFFFFFFu;
    }
    return img;
}

}  // namespace vk

std::unique_ptr<VulkanBackend> makeVulkanBackend(const VulkanBackendOptions& options) {
    return std::make_unique<vk::VulkanBackendImpl>(options);
}

bool vulkanBackendAvailable(std::string* why, const VulkanBackendOptions& options) {
    return backendAvailable([&] { makeVulkanBackend(options); }, why);
}

}  // namespace cullide::raster
