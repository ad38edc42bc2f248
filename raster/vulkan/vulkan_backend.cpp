// The Vulkan backend (see cullide/raster/vulkan_backend.h for the conventions and
// docs/vulkan-backend.md for what matches GL and the reference and what may differ).
//
// References: the Vulkan 1.3 specification (§17 queries: occlusion queries and
// VK_QUERY_CONTROL_PRECISE_BIT; §24.9 viewport transformation; §27.4 polygon rasterization;
// §28.8 depth test; §19.3 vkCmdClearAttachments, executed in rasterization order);
// docs/gl-backend.md for the GL backend this one mirrors.
#include "cullide/raster/vulkan_backend.h"

#include "depth_vert_spv.h"  // kDepthVertSpv: raster/vulkan/depth.vert, compiled at build time

#include <vulkan/vulkan.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>

namespace cullide::raster {

namespace {

const char* const kSource = "vulkan backend";
const char* const kValidationLayer = "VK_LAYER_KHRONOS_validation";

[[noreturn]] void unavailable(const std::string& why) {
    throw BackendUnavailable(why, kSource);
}

void check(VkResult r, const char* what) {
    if (r != VK_SUCCESS) unavailable(std::string(what) + " failed (VkResult " + std::to_string(int(r)) + ")");
}

std::string versionText(uint32_t v) {
    return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
        std::to_string(VK_API_VERSION_PATCH(v));
}

const char* typeText(VkPhysicalDeviceType t) {
    switch (t) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
        default: return "other";
    }
}

// Preference order: a GPU first, the CPU (lavapipe) last.
int typeRank(VkPhysicalDeviceType t) {
    switch (t) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 4;
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 3;
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return 1;
        default: return 0;
    }
}

// GL's depth functions in GL's order map to VkCompareOp in the same order.
VkCompareOp toVk(DepthFunc f) {
    static_assert(VK_COMPARE_OP_NEVER == 0 && VK_COMPARE_OP_LESS == 1 && VK_COMPARE_OP_EQUAL == 2 &&
                  VK_COMPARE_OP_LESS_OR_EQUAL == 3 && VK_COMPARE_OP_GREATER == 4 && VK_COMPARE_OP_NOT_EQUAL == 5 &&
                  VK_COMPARE_OP_GREATER_OR_EQUAL == 6 && VK_COMPARE_OP_ALWAYS == 7);
    return VkCompareOp(int(f));
}

VkFormat toVk(const DepthFormat& f) {
    if (f.kind == DepthFormat::Kind::Float32) return VK_FORMAT_D32_SFLOAT;
    return f.bits == 16 ? VK_FORMAT_D16_UNORM : VK_FORMAT_X8_D24_UNORM_PACK32;
}

// The uniform block of depth.vert (std140: dvec4 = 32 bytes).
struct ViewBlock {
    double right[4], up[4], dir[4], lo[4], extent[4], size[4];
    float scaleOffset[4];
};
static_assert(sizeof(ViewBlock) == 208);

struct Buffer {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    void* mapped = nullptr;
    VkDeviceSize size = 0;
};

class VulkanBackendImpl final : public VulkanBackend {
public:
    explicit VulkanBackendImpl(const VulkanBackendOptions& options) : options_(options) {
        if (const char* e = std::getenv("CULLIDE_VULKAN_VALIDATION"); e && *e && std::strcmp(e, "0") != 0)
            options_.validation = true;
        try {
            createInstance();
            pickDevice();
            createDevice();
            createPipeline();
        } catch (...) {
            destroy();
            throw;
        }
    }

    ~VulkanBackendImpl() override { destroy(); }

    const VulkanInfo& info() const override { return info_; }
    uint64_t validationMessages() const override { return messages_; }
    std::vector<std::string> validationLog() const override { return log_; }

    DepthFormat effectiveFormat(const DepthFormat& requested) const override {
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

    int maxViewportSide() const override { return std::max(1, maxSide_); }

    std::string describe() const override {
        std::string s = "vulkan: " + info_.device + " (" + info_.type + "), " + info_.driver + ", Vulkan " + info_.api +
            ", " + std::to_string(info_.subpixelBits) + " subpixel bits";
        if (image_) s += ", " + format_.name() + " (" + formatName(toVk(format_)) + ")";
        return s;
    }

    void setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) override {
        static_assert(sizeof(Vec3f) == 12 && sizeof(Triangle) == 12, "tightly packed positions and triangles");
        // Buffers grow as needed; nothing is in flight between calls (execute() waits).
        upload(vertices_, positions.data(), positions.size_bytes(), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
        upload(indices_, triangles.data(), triangles.size_bytes(), VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
        triangleCount_ = triangles.size();
    }

    void setView(const OrthoView& view) override {
        view.validate();
        const DepthFormat format = effectiveFormat(view.depth);
        if (!(format == view.depth) && warned_.insert(view.depth.name()).second)
            warn("vulkan backend: depth " + view.depth.name() + " is not available; using " + format.name() +
                 " (the nearest Vulkan depth format)");
        if (!image_ || view.width != width_ || view.height != height_ || !(format == format_))
            createTarget(view.width, view.height, format);

        // The exact viewport, as in the GL backend: (-P, -P, 2P, 2P) maps clip x in [-1, 1] to
        // framebuffer [-P, P] with scale P and offset 0, so x_fb = (xw / P) * P = xw exactly; P at
        // least twice the larger side where the device allows, so that clipping at +-P stays a
        // viewport away from the framebuffer.
        auto fits = [&](int q) { return 2 * q <= info_.maxViewport && -q >= viewportBoundsMin_; };
        // For a tile (OrthoView::tile) the geometry spans its whole grid, up to a grid's side away
        // from the framebuffer: P grows towards twice the grid's side, so that the device clips none of it.
        int P = 1;
        while (P < std::max(width_, height_)) P *= 2;
        const int64_t reach = 2 * int64_t(std::max(view.fullWidth(), view.fullHeight()));
        while (P < reach && fits(2 * P)) P *= 2;
        exactViewport_ = fits(P);
        P_ = P;
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
            b.scaleOffset[0] = b.scaleOffset[1] = 1.0f / float(P);
            b.scaleOffset[2] = b.scaleOffset[3] = 0.0f;
        } else {
            b.scaleOffset[0] = 2.0f / float(width_), b.scaleOffset[1] = 2.0f / float(height_);
            b.scaleOffset[2] = b.scaleOffset[3] = -1.0f;
        }
        std::memcpy(uniform_.mapped, &b, sizeof b);
        haveView_ = true;
    }

    std::vector<uint64_t> execute(const CommandList& list) override {
        if (!haveView_) throw InputError("command list", "execute() before setView()");
        if (list.queryOpen()) throw InputError("command list", "a query is still open at the end of the list");
        if (list.conservativeCount() > 0)
            throw InputError("command list",
                             "conservative commands need conservative rasterization, which this Vulkan "
                             "backend does not provide (the reliable method is CPU-only)");
        for (const Command& c : list.commands())
            if (c.op == Command::Op::Draw && uint64_t(c.first) + c.count > triangleCount_)
                throw InputError("command list",
                                 "draw of triangles [" + std::to_string(c.first) + ", " +
                                     std::to_string(uint64_t(c.first) + c.count) + ") but the geometry has " +
                                     std::to_string(triangleCount_) + " triangles");

        const uint32_t n = list.queryCount();
        if (n > queryCapacity_) {
            if (queryPool_) vkDestroyQueryPool(device_, queryPool_, nullptr);
            queryPool_ = VK_NULL_HANDLE;
            queryCapacity_ = std::max(n, 2 * queryCapacity_);
            VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
            qi.queryType = VK_QUERY_TYPE_OCCLUSION;
            qi.queryCount = queryCapacity_;
            check(vkCreateQueryPool(device_, &qi, nullptr, &queryPool_), "vkCreateQueryPool");
        }

        VkCommandBuffer cb = begin();
        if (n > 0) vkCmdResetQueryPool(cb, queryPool_, 0, n);
        VkRenderPassBeginInfo rp{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
        rp.renderPass = renderPass_;
        rp.framebuffer = framebuffer_;
        rp.renderArea = {{0, 0}, {uint32_t(width_), uint32_t(height_)}};
        vkCmdBeginRenderPass(cb, &rp, VK_SUBPASS_CONTENTS_INLINE);
        vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_);
        vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelineLayout_, 0, 1, &descriptorSet_, 0,
                                nullptr);
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
        // The persistent state (GL's, across lists) is the backend's; each list starts from it.
        setDepthCompareOp_(cb, toVk(func_));
        setDepthWriteEnable_(cb, mask_ ? VK_TRUE : VK_FALSE);

        std::vector<uint8_t> any(n, 0);
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
                case Command::Op::DrawConservative: break;  // refused above
                case Command::Op::Draw:
                    if (c.count > 0) vkCmdDrawIndexed(cb, uint32_t(uint64_t(c.count) * 3), 1, c.first * 3u, 0, 0);
                    break;
            }
        }
        vkCmdEndRenderPass(cb);
        submit(cb);

        std::vector<uint64_t> results(n, 0);
        if (n > 0) {
            check(vkGetQueryPoolResults(device_, queryPool_, 0, n, size_t(n) * sizeof(uint64_t), results.data(),
                                        sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
                  "vkGetQueryPoolResults");
            // Without the precise bit the result is only zero or non-zero.
            for (uint32_t q = 0; q < n; ++q)
                if (any[q]) results[q] = results[q] != 0 ? 1 : 0;
        }
        return results;
    }

    DepthImage readDepth() override {
        if (!haveView_) throw InputError("command list", "readDepth() before setView()");
        const VkDeviceSize bytes = VkDeviceSize(width_) * VkDeviceSize(height_) * texelBytes();
        ensure(readback_, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT);
        VkCommandBuffer cb = begin();
        barrier(cb, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                VK_ACCESS_TRANSFER_READ_BIT);
        VkBufferImageCopy region{};
        region.imageSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 0, 1};
        region.imageExtent = {uint32_t(width_), uint32_t(height_), 1};
        vkCmdCopyImageToBuffer(cb, image_, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback_.buffer, 1, &region);
        barrier(cb, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                VK_PIPELINE_STAGE_TRANSFER_BIT, 0,
                VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
        VkBufferMemoryBarrier hb{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
        hb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        hb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
        hb.srcQueueFamilyIndex = hb.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        hb.buffer = readback_.buffer;
        hb.size = VK_WHOLE_SIZE;
        vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 0, nullptr, 1, &hb, 0,
                             nullptr);
        submit(cb);
        if (!readbackCoherent_) {
            VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
            range.memory = readback_.memory;
            range.size = VK_WHOLE_SIZE;
            check(vkInvalidateMappedMemoryRanges(device_, 1, &range), "vkInvalidateMappedMemoryRanges");
        }

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

private:
    static const char* formatName(VkFormat f) {
        switch (f) {
            case VK_FORMAT_D16_UNORM: return "D16_UNORM";
            case VK_FORMAT_X8_D24_UNORM_PACK32: return "X8_D24_UNORM_PACK32";
            case VK_FORMAT_D32_SFLOAT: return "D32_SFLOAT";
            default: return "?";
        }
    }

    VkDeviceSize texelBytes() const { return format_.kind == DepthFormat::Kind::Unorm && format_.bits == 16 ? 2 : 4; }

    void warn(const std::string& msg) const {
        if (options_.warn) options_.warn(msg);
        else std::fprintf(stderr, "cullide: warning: %s\n", msg.c_str());
    }

    static VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                    VkDebugUtilsMessageTypeFlagsEXT,
                                                    const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
        auto* self = static_cast<VulkanBackendImpl*>(user);
        if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
            ++self->messages_;
            const std::string m = std::string("vulkan validation: ") + (data && data->pMessage ? data->pMessage : "?");
            if (self->log_.size() < 100) self->log_.push_back(m);
            self->warn(m);
        }
        return VK_FALSE;
    }

    void createInstance() {
        uint32_t loaderVersion = VK_API_VERSION_1_0;
        if (auto enumerate = reinterpret_cast<PFN_vkEnumerateInstanceVersion>(
                vkGetInstanceProcAddr(nullptr, "vkEnumerateInstanceVersion")))
            enumerate(&loaderVersion);
        if (loaderVersion < VK_API_VERSION_1_1)
            unavailable("the Vulkan loader offers only Vulkan " + versionText(loaderVersion) + "; 1.1 is needed");
        VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
        app.pApplicationName = "cullide";
        app.pEngineName = "cullide";
        app.apiVersion = std::min<uint32_t>(loaderVersion, VK_API_VERSION_1_3);
        apiVersion_ = app.apiVersion;

        std::vector<const char*> layers, extensions;
        VkDebugUtilsMessengerCreateInfoEXT messenger{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
        if (options_.validation) {
            uint32_t count = 0;
            vkEnumerateInstanceLayerProperties(&count, nullptr);
            std::vector<VkLayerProperties> props(count);
            vkEnumerateInstanceLayerProperties(&count, props.data());
            if (std::none_of(props.begin(), props.end(), [](const VkLayerProperties& p) {
                    return std::strcmp(p.layerName, kValidationLayer) == 0;
                }))
                unavailable(std::string("validation asked for but ") + kValidationLayer +
                            " is not installed (Debian: vulkan-validationlayers)");
            layers.push_back(kValidationLayer);
            extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
            messenger.messageSeverity =
                VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
            messenger.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
            messenger.pfnUserCallback = &onMessage;
            messenger.pUserData = this;
        }
        VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
        ci.pApplicationInfo = &app;
        ci.enabledLayerCount = uint32_t(layers.size());
        ci.ppEnabledLayerNames = layers.data();
        ci.enabledExtensionCount = uint32_t(extensions.size());
        ci.ppEnabledExtensionNames = extensions.data();
        if (options_.validation) ci.pNext = &messenger;  // also covers instance creation itself
        const VkResult r = vkCreateInstance(&ci, nullptr, &instance_);
        if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
            unavailable("no Vulkan driver (install mesa-vulkan-drivers for lavapipe, or a GPU driver)");
        check(r, "vkCreateInstance");
        if (options_.validation) {
            auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
                vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
            if (!create) unavailable("validation asked for but vkCreateDebugUtilsMessengerEXT is missing");
            check(create(instance_, &messenger, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
        }
    }

    void pickDevice() {
        uint32_t count = 0;
        check(vkEnumeratePhysicalDevices(instance_, &count, nullptr), "vkEnumeratePhysicalDevices");
        std::vector<VkPhysicalDevice> devices(count);
        check(vkEnumeratePhysicalDevices(instance_, &count, devices.data()), "vkEnumeratePhysicalDevices");
        if (devices.empty())
            unavailable("no Vulkan device (install mesa-vulkan-drivers for lavapipe, or a GPU driver)");
        std::string reasons;
        int bestRank = -1;
        for (VkPhysicalDevice d : devices) {
            VkPhysicalDeviceProperties p;
            vkGetPhysicalDeviceProperties(d, &p);
            const std::string why = unsuitable(d, p);
            if (!why.empty()) {
                reasons += std::string(reasons.empty() ? "" : "; ") + p.deviceName + ": " + why;
                continue;
            }
            if (typeRank(p.deviceType) > bestRank) {
                bestRank = typeRank(p.deviceType);
                physical_ = d;
            }
        }
        if (!physical_) unavailable("no suitable Vulkan device: " + reasons);
    }

    bool hasExtension(VkPhysicalDevice d, const char* name) const {
        uint32_t count = 0;
        vkEnumerateDeviceExtensionProperties(d, nullptr, &count, nullptr);
        std::vector<VkExtensionProperties> ext(count);
        vkEnumerateDeviceExtensionProperties(d, nullptr, &count, ext.data());
        return std::any_of(ext.begin(), ext.end(),
                           [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
    }

    bool depthAttachment(VkPhysicalDevice d, VkFormat f) const {
        VkFormatProperties fp;
        vkGetPhysicalDeviceFormatProperties(d, f, &fp);
        const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT |
            VK_FORMAT_FEATURE_TRANSFER_SRC_BIT | VK_FORMAT_FEATURE_TRANSFER_DST_BIT;
        return (fp.optimalTilingFeatures & need) == need;
    }

    // Empty when the device can run this backend, else why not.
    std::string unsuitable(VkPhysicalDevice d, const VkPhysicalDeviceProperties& p) const {
        if (!options_.deviceName.empty() && std::string(p.deviceName).find(options_.deviceName) == std::string::npos)
            return "name does not contain '" + options_.deviceName + "'";
        if (p.apiVersion < VK_API_VERSION_1_1) return "Vulkan " + versionText(p.apiVersion) + " (1.1 needed)";
        VkPhysicalDeviceFeatures f;
        vkGetPhysicalDeviceFeatures(d, &f);
        if (!f.occlusionQueryPrecise) return "no precise occlusion queries";
        if (!f.shaderFloat64) return "no 64-bit floats in shaders (shaderFloat64)";
        if (!(std::min(p.apiVersion, apiVersion_) >= VK_API_VERSION_1_3 ||
              hasExtension(d, VK_EXT_EXTENDED_DYNAMIC_STATE_EXTENSION_NAME)))
            return "no dynamic depth compare op (Vulkan 1.3 or VK_EXT_extended_dynamic_state)";
        if (graphicsQueue(d) == UINT32_MAX) return "no graphics queue";
        if (!depthAttachment(d, VK_FORMAT_D16_UNORM) && !depthAttachment(d, VK_FORMAT_X8_D24_UNORM_PACK32) &&
            !depthAttachment(d, VK_FORMAT_D32_SFLOAT))
            return "no usable depth format";
        return {};
    }

    static uint32_t graphicsQueue(VkPhysicalDevice d) {
        uint32_t count = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(d, &count, nullptr);
        std::vector<VkQueueFamilyProperties> q(count);
        vkGetPhysicalDeviceQueueFamilyProperties(d, &count, q.data());
        for (uint32_t i = 0; i < count; ++i)
            if (q[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) return i;
        return UINT32_MAX;
    }

    void createDevice() {
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(physical_, &p);
        info_.device = p.deviceName;
        info_.type = typeText(p.deviceType);
        info_.api = versionText(p.apiVersion);
        info_.subpixelBits = int(p.limits.subPixelPrecisionBits);
        info_.maxViewport = int(std::min(p.limits.maxViewportDimensions[0], p.limits.maxViewportDimensions[1]));
        viewportBoundsMin_ = p.limits.viewportBoundsRange[0];
        maxSide_ = int(std::min({uint64_t(info_.maxViewport), uint64_t(p.limits.maxFramebufferWidth),
                                 uint64_t(p.limits.maxFramebufferHeight), uint64_t(p.limits.maxImageDimension2D),
                                 uint64_t(kMaxViewportSide)}));
        info_.hasD16 = depthAttachment(physical_, VK_FORMAT_D16_UNORM);
        info_.hasD24 = depthAttachment(physical_, VK_FORMAT_X8_D24_UNORM_PACK32);
        info_.hasD32F = depthAttachment(physical_, VK_FORMAT_D32_SFLOAT);
        info_.driver = "driver " + std::to_string(p.driverVersion);
        if (p.apiVersion >= VK_API_VERSION_1_2) {
            VkPhysicalDeviceDriverProperties dp{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
            VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
            p2.pNext = &dp;
            vkGetPhysicalDeviceProperties2(physical_, &p2);
            info_.driver = std::string(dp.driverName) + ", " + dp.driverInfo;
        }
        const bool core13 = std::min(p.apiVersion, apiVersion_) >= VK_API_VERSION_1_3;

        queueFamily_ = graphicsQueue(physical_);
        const float priority = 1.0f;
        VkDeviceQueueCreateInfo qi{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
        qi.queueFamilyIndex = queueFamily_;
        qi.queueCount = 1;
        qi.pQueuePriorities = &priority;
        VkPhysicalDeviceFeatures features{};
        features.occlusionQueryPrecise = VK_TRUE;
        features.shaderFloat64 = VK_TRUE;
        VkPhysicalDeviceExtendedDynamicStateFeaturesEXT eds{
            VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_EXTENDED_DYNAMIC_STATE_FEATURES_EXT};
        eds.extendedDynamicState = VK_TRUE;
        std::vector<const char*> extensions;
        VkDeviceCreateInfo ci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
        if (!core13) {
            extensions.push_back(VK_EXT_EXTENDED_DYNAMIC_STATE_EXTENSION_NAME);
            ci.pNext = &eds;
        }
        ci.queueCreateInfoCount = 1;
        ci.pQueueCreateInfos = &qi;
        ci.enabledExtensionCount = uint32_t(extensions.size());
        ci.ppEnabledExtensionNames = extensions.data();
        ci.pEnabledFeatures = &features;
        check(vkCreateDevice(physical_, &ci, nullptr, &device_), "vkCreateDevice");
        vkGetDeviceQueue(device_, queueFamily_, 0, &queue_);
        setDepthCompareOp_ = reinterpret_cast<PFN_vkCmdSetDepthCompareOp>(
            vkGetDeviceProcAddr(device_, core13 ? "vkCmdSetDepthCompareOp" : "vkCmdSetDepthCompareOpEXT"));
        setDepthWriteEnable_ = reinterpret_cast<PFN_vkCmdSetDepthWriteEnable>(
            vkGetDeviceProcAddr(device_, core13 ? "vkCmdSetDepthWriteEnable" : "vkCmdSetDepthWriteEnableEXT"));
        if (!setDepthCompareOp_ || !setDepthWriteEnable_) unavailable("no vkCmdSetDepthCompareOp/WriteEnable");

        VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
        pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
        pi.queueFamilyIndex = queueFamily_;
        check(vkCreateCommandPool(device_, &pi, nullptr, &commandPool_), "vkCreateCommandPool");
        VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        ai.commandPool = commandPool_;
        ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
        ai.commandBufferCount = 1;
        check(vkAllocateCommandBuffers(device_, &ai, &commandBuffer_), "vkAllocateCommandBuffers");
        VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        check(vkCreateFence(device_, &fi, nullptr, &fence_), "vkCreateFence");
        ensure(uniform_, sizeof(ViewBlock), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT);
    }

    void createPipeline() {
        VkDescriptorSetLayoutBinding binding{0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT,
                                             nullptr};
        VkDescriptorSetLayoutCreateInfo li{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
        li.bindingCount = 1;
        li.pBindings = &binding;
        check(vkCreateDescriptorSetLayout(device_, &li, nullptr, &setLayout_), "vkCreateDescriptorSetLayout");
        VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1};
        VkDescriptorPoolCreateInfo dpi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        dpi.maxSets = 1;
        dpi.poolSizeCount = 1;
        dpi.pPoolSizes = &size;
        check(vkCreateDescriptorPool(device_, &dpi, nullptr, &descriptorPool_), "vkCreateDescriptorPool");
        VkDescriptorSetAllocateInfo dai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
        dai.descriptorPool = descriptorPool_;
        dai.descriptorSetCount = 1;
        dai.pSetLayouts = &setLayout_;
        check(vkAllocateDescriptorSets(device_, &dai, &descriptorSet_), "vkAllocateDescriptorSets");
        VkDescriptorBufferInfo bi{uniform_.buffer, 0, sizeof(ViewBlock)};
        VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        w.dstSet = descriptorSet_;
        w.descriptorCount = 1;
        w.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
        w.pBufferInfo = &bi;
        vkUpdateDescriptorSets(device_, 1, &w, 0, nullptr);
        VkPipelineLayoutCreateInfo pli{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
        pli.setLayoutCount = 1;
        pli.pSetLayouts = &setLayout_;
        check(vkCreatePipelineLayout(device_, &pli, nullptr, &pipelineLayout_), "vkCreatePipelineLayout");
        VkShaderModuleCreateInfo si{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
        si.codeSize = sizeof kDepthVertSpv;
        si.pCode = kDepthVertSpv;
        check(vkCreateShaderModule(device_, &si, nullptr, &shader_), "vkCreateShaderModule");
    }

    // The render pass and pipeline of a depth format (one each; remade when the format changes).
    void createRenderPass(VkFormat format) {
        if (pipeline_) vkDestroyPipeline(device_, pipeline_, nullptr);
        if (renderPass_) vkDestroyRenderPass(device_, renderPass_, nullptr);
        pipeline_ = VK_NULL_HANDLE;
        renderPass_ = VK_NULL_HANDLE;
        VkAttachmentDescription a{};
        a.format = format;
        a.samples = VK_SAMPLE_COUNT_1_BIT;
        a.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;  // state persists across execute() calls
        a.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        a.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        a.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
        a.initialLayout = a.finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
        VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
        VkSubpassDescription sub{};
        sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
        sub.pDepthStencilAttachment = &ref;
        // Earlier submissions' depth writes (draws, clears, the initial clear) before this pass.
        const VkPipelineStageFlags tests =
            VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
        VkSubpassDependency dep{};
        dep.srcSubpass = VK_SUBPASS_EXTERNAL;
        dep.dstSubpass = 0;
        dep.srcStageMask = tests | VK_PIPELINE_STAGE_TRANSFER_BIT;
        dep.srcAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
        dep.dstStageMask = tests;
        dep.dstAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
        VkRenderPassCreateInfo ri{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
        ri.attachmentCount = 1;
        ri.pAttachments = &a;
        ri.subpassCount = 1;
        ri.pSubpasses = &sub;
        ri.dependencyCount = 1;
        ri.pDependencies = &dep;
        check(vkCreateRenderPass(device_, &ri, nullptr, &renderPass_), "vkCreateRenderPass");

        VkPipelineShaderStageCreateInfo stage{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
        stage.stage = VK_SHADER_STAGE_VERTEX_BIT;
        stage.module = shader_;
        stage.pName = "main";
        VkVertexInputBindingDescription vb{0, sizeof(Vec3f), VK_VERTEX_INPUT_RATE_VERTEX};
        VkVertexInputAttributeDescription va{0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0};
        VkPipelineVertexInputStateCreateInfo vi{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
        vi.vertexBindingDescriptionCount = 1;
        vi.pVertexBindingDescriptions = &vb;
        vi.vertexAttributeDescriptionCount = 1;
        vi.pVertexAttributeDescriptions = &va;
        VkPipelineInputAssemblyStateCreateInfo ia{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
        ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
        VkPipelineViewportStateCreateInfo vs{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
        vs.viewportCount = 1;
        vs.scissorCount = 1;
        VkPipelineRasterizationStateCreateInfo rs{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
        rs.depthClampEnable = VK_FALSE;
        rs.rasterizerDiscardEnable = VK_FALSE;
        rs.polygonMode = VK_POLYGON_MODE_FILL;
        rs.cullMode = VK_CULL_MODE_NONE;
        rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
        rs.lineWidth = 1.0f;
        VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
        ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
        VkPipelineDepthStencilStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
        ds.depthTestEnable = VK_TRUE;  // with ALWAYS it still writes
        ds.depthWriteEnable = VK_TRUE;  // dynamic
        ds.depthCompareOp = VK_COMPARE_OP_LESS;  // dynamic
        const VkDynamicState dynamic[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR,
                                          VK_DYNAMIC_STATE_DEPTH_COMPARE_OP, VK_DYNAMIC_STATE_DEPTH_WRITE_ENABLE};
        VkPipelineDynamicStateCreateInfo dy{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
        dy.dynamicStateCount = 4;
        dy.pDynamicStates = dynamic;
        VkGraphicsPipelineCreateInfo gi{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
        gi.stageCount = 1;
        gi.pStages = &stage;
        gi.pVertexInputState = &vi;
        gi.pInputAssemblyState = &ia;
        gi.pViewportState = &vs;
        gi.pRasterizationState = &rs;
        gi.pMultisampleState = &ms;
        gi.pDepthStencilState = &ds;
        gi.pDynamicState = &dy;
        gi.layout = pipelineLayout_;
        gi.renderPass = renderPass_;
        gi.subpass = 0;
        check(vkCreateGraphicsPipelines(device_, VK_NULL_HANDLE, 1, &gi, nullptr, &pipeline_),
              "vkCreateGraphicsPipelines");
    }

    uint32_t memoryType(uint32_t bits, VkMemoryPropertyFlags want, VkMemoryPropertyFlags prefer,
                        VkMemoryPropertyFlags* got = nullptr) const {
        VkPhysicalDeviceMemoryProperties mp;
        vkGetPhysicalDeviceMemoryProperties(physical_, &mp);
        for (int pass = 0; pass < 2; ++pass) {
            const VkMemoryPropertyFlags need = pass == 0 ? want | prefer : want;
            for (uint32_t i = 0; i < mp.memoryTypeCount; ++i)
                if ((bits & (1u << i)) && (mp.memoryTypes[i].propertyFlags & need) == need) {
                    if (got) *got = mp.memoryTypes[i].propertyFlags;
                    return i;
                }
        }
        unavailable("no suitable memory type");
    }

    void release(Buffer& b) {
        if (b.buffer) vkDestroyBuffer(device_, b.buffer, nullptr);
        if (b.memory) vkFreeMemory(device_, b.memory, nullptr);  // unmaps
        b = Buffer{};
    }

    // A host-visible buffer of at least `bytes` (kept when large enough).
    void ensure(Buffer& b, VkDeviceSize bytes, VkBufferUsageFlags usage) {
        bytes = std::max<VkDeviceSize>(bytes, 16);
        if (b.buffer && b.size >= bytes) return;
        release(b);
        VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        bi.size = bytes;
        bi.usage = usage;
        bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
        check(vkCreateBuffer(device_, &bi, nullptr, &b.buffer), "vkCreateBuffer");
        VkMemoryRequirements req;
        vkGetBufferMemoryRequirements(device_, b.buffer, &req);
        VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        ai.allocationSize = req.size;
        VkMemoryPropertyFlags got = 0;
        // Read back: cached memory where there is some; uploads: coherent.
        const bool readback = usage == VK_BUFFER_USAGE_TRANSFER_DST_BIT;
        ai.memoryTypeIndex =
            memoryType(req.memoryTypeBits,
                       VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | (readback ? 0 : VK_MEMORY_PROPERTY_HOST_COHERENT_BIT),
                       readback ? VK_MEMORY_PROPERTY_HOST_CACHED_BIT : 0, &got);
        if (readback) readbackCoherent_ = (got & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT) != 0;
        check(vkAllocateMemory(device_, &ai, nullptr, &b.memory), "vkAllocateMemory");
        check(vkBindBufferMemory(device_, b.buffer, b.memory, 0), "vkBindBufferMemory");
        check(vkMapMemory(device_, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped), "vkMapMemory");
        b.size = bytes;
    }

    void upload(Buffer& b, const void* data, size_t bytes, VkBufferUsageFlags usage) {
        ensure(b, bytes, usage);
        if (bytes) std::memcpy(b.mapped, data, bytes);
    }

    void destroyTarget() {
        if (framebuffer_) vkDestroyFramebuffer(device_, framebuffer_, nullptr);
        if (view_) vkDestroyImageView(device_, view_, nullptr);
        if (image_) vkDestroyImage(device_, image_, nullptr);
        if (imageMemory_) vkFreeMemory(device_, imageMemory_, nullptr);
        framebuffer_ = VK_NULL_HANDLE;
        view_ = VK_NULL_HANDLE;
        image_ = VK_NULL_HANDLE;
        imageMemory_ = VK_NULL_HANDLE;
    }

    void createTarget(int w, int h, const DepthFormat& format) {
        destroyTarget();
        const VkFormat vf = toVk(format);
        if (!renderPass_ || !(format == format_)) createRenderPass(vf);
        VkImageCreateInfo ii{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
        ii.imageType = VK_IMAGE_TYPE_2D;
        ii.format = vf;
        ii.extent = {uint32_t(w), uint32_t(h), 1};
        ii.mipLevels = 1;
        ii.arrayLayers = 1;
        ii.samples = VK_SAMPLE_COUNT_1_BIT;
        ii.tiling = VK_IMAGE_TILING_OPTIMAL;
        ii.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
            VK_IMAGE_USAGE_TRANSFER_DST_BIT;
        ii.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
        ii.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        const std::string what = std::to_string(w) + "x" + std::to_string(h) + " " + format.name() + " depth image";
        if (vkCreateImage(device_, &ii, nullptr, &image_) != VK_SUCCESS) unavailable("cannot make a " + what);
        VkMemoryRequirements req;
        vkGetImageMemoryRequirements(device_, image_, &req);
        VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        ai.allocationSize = req.size;
        ai.memoryTypeIndex = memoryType(req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
        if (vkAllocateMemory(device_, &ai, nullptr, &imageMemory_) != VK_SUCCESS)
            unavailable("cannot allocate a " + what);
        check(vkBindImageMemory(device_, image_, imageMemory_, 0), "vkBindImageMemory");
        VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
        vi.image = image_;
        vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
        vi.format = vf;
        vi.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
        check(vkCreateImageView(device_, &vi, nullptr, &view_), "vkCreateImageView");
        VkFramebufferCreateInfo fi{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
        fi.renderPass = renderPass_;
        fi.attachmentCount = 1;
        fi.pAttachments = &view_;
        fi.width = uint32_t(w);
        fi.height = uint32_t(h);
        fi.layers = 1;
        check(vkCreateFramebuffer(device_, &fi, nullptr, &framebuffer_), "vkCreateFramebuffer");
        width_ = w;
        height_ = h;
        format_ = format;

        // As the CPU backend: a new buffer holds the far value.
        VkCommandBuffer cb = begin();
        barrier(cb, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                0, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
        const VkClearDepthStencilValue far{1.0f, 0};
        const VkImageSubresourceRange range{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
        vkCmdClearDepthStencilImage(cb, image_, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &far, 1, &range);
        barrier(cb, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
        submit(cb);
    }

    void barrier(VkCommandBuffer cb, VkImageLayout from, VkImageLayout to, VkPipelineStageFlags srcStage,
                 VkAccessFlags srcAccess, VkPipelineStageFlags dstStage, VkAccessFlags dstAccess) const {
        VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        b.srcAccessMask = srcAccess;
        b.dstAccessMask = dstAccess;
        b.oldLayout = from;
        b.newLayout = to;
        b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        b.image = image_;
        b.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
        vkCmdPipelineBarrier(cb, srcStage, dstStage, 0, 0, nullptr, 0, nullptr, 1, &b);
    }

    VkCommandBuffer begin() {
        check(vkResetCommandBuffer(commandBuffer_, 0), "vkResetCommandBuffer");
        VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        check(vkBeginCommandBuffer(commandBuffer_, &bi), "vkBeginCommandBuffer");
        return commandBuffer_;
    }

    // Ends, submits and waits: nothing is in flight between calls.
    void submit(VkCommandBuffer cb) {
        check(vkEndCommandBuffer(cb), "vkEndCommandBuffer");
        VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        si.commandBufferCount = 1;
        si.pCommandBuffers = &cb;
        check(vkResetFences(device_, 1, &fence_), "vkResetFences");
        check(vkQueueSubmit(queue_, 1, &si, fence_), "vkQueueSubmit");
        check(vkWaitForFences(device_, 1, &fence_, VK_TRUE, UINT64_MAX), "vkWaitForFences");
    }

    void destroy() {
        if (device_) {
            vkDeviceWaitIdle(device_);
            destroyTarget();
            release(vertices_);
            release(indices_);
            release(uniform_);
            release(readback_);
            if (queryPool_) vkDestroyQueryPool(device_, queryPool_, nullptr);
            if (pipeline_) vkDestroyPipeline(device_, pipeline_, nullptr);
            if (renderPass_) vkDestroyRenderPass(device_, renderPass_, nullptr);
            if (shader_) vkDestroyShaderModule(device_, shader_, nullptr);
            if (pipelineLayout_) vkDestroyPipelineLayout(device_, pipelineLayout_, nullptr);
            if (descriptorPool_) vkDestroyDescriptorPool(device_, descriptorPool_, nullptr);
            if (setLayout_) vkDestroyDescriptorSetLayout(device_, setLayout_, nullptr);
            if (fence_) vkDestroyFence(device_, fence_, nullptr);
            if (commandPool_) vkDestroyCommandPool(device_, commandPool_, nullptr);
            vkDestroyDevice(device_, nullptr);
            device_ = VK_NULL_HANDLE;
        }
        if (instance_) {
            if (messenger_) {
                auto destroyMessenger = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
                    vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
                if (destroyMessenger) destroyMessenger(instance_, messenger_, nullptr);
                messenger_ = VK_NULL_HANDLE;
            }
            vkDestroyInstance(instance_, nullptr);
            instance_ = VK_NULL_HANDLE;
        }
    }

    VulkanBackendOptions options_;
    VulkanInfo info_;
    uint32_t apiVersion_ = VK_API_VERSION_1_1;
    float viewportBoundsMin_ = 0;
    int maxSide_ = 0;  // the largest viewport side: viewport, framebuffer and 2D image limits
    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkPhysicalDevice physical_ = VK_NULL_HANDLE;
    VkDevice device_ = VK_NULL_HANDLE;
    uint32_t queueFamily_ = 0;
    VkQueue queue_ = VK_NULL_HANDLE;
    PFN_vkCmdSetDepthCompareOp setDepthCompareOp_ = nullptr;
    PFN_vkCmdSetDepthWriteEnable setDepthWriteEnable_ = nullptr;
    VkCommandPool commandPool_ = VK_NULL_HANDLE;
    VkCommandBuffer commandBuffer_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
    VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
    VkDescriptorPool descriptorPool_ = VK_NULL_HANDLE;
    VkDescriptorSet descriptorSet_ = VK_NULL_HANDLE;
    VkPipelineLayout pipelineLayout_ = VK_NULL_HANDLE;
    VkShaderModule shader_ = VK_NULL_HANDLE;
    VkRenderPass renderPass_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
    VkImage image_ = VK_NULL_HANDLE;
    VkDeviceMemory imageMemory_ = VK_NULL_HANDLE;
    VkImageView view_ = VK_NULL_HANDLE;
    VkFramebuffer framebuffer_ = VK_NULL_HANDLE;
    VkQueryPool queryPool_ = VK_NULL_HANDLE;
    uint32_t queryCapacity_ = 0;
    Buffer vertices_, indices_, uniform_, readback_;
    bool readbackCoherent_ = true;
    size_t triangleCount_ = 0;
    int width_ = 0, height_ = 0, P_ = 1;
    DepthFormat format_;
    DepthFunc func_ = DepthFunc::Less;
    bool mask_ = true;
    bool haveView_ = false;
    bool exactViewport_ = false;
    std::set<std::string> warned_;
    uint64_t messages_ = 0;
    std::vector<std::string> log_;
};

}  // namespace

std::unique_ptr<VulkanBackend> makeVulkanBackend(const VulkanBackendOptions& options) {
    return std::make_unique<VulkanBackendImpl>(options);
}

bool vulkanBackendAvailable(std::string* why, const VulkanBackendOptions& options) {
    return backendAvailable([&] { makeVulkanBackend(options); }, why);
}

}  // namespace cullide::raster
