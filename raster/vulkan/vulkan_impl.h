// The Vulkan backend's implementation class, private to raster/vulkan/. Its member functions live
// in four files, one job each:
//   vulkan_context.cpp    the instance, the device chosen and created, the command buffer and
//                         fence, teardown, validation messages;
//   vulkan_resources.cpp  memory: host-visible buffers, the depth image and its framebuffer,
//                         query pools, one-time command buffers (begin, barrier, submit);
//   vulkan_pipeline.cpp   the descriptor set, pipeline layout and shader module, and per depth
//                         format the render pass and graphics pipeline;
//   vulkan_backend.cpp    the DepthBackend interface: views, command lists, read-back.
// See cullide/raster/vulkan_backend.h for the conventions and docs/vulkan-backend.md for what
// matches GL and the reference and what may differ.
#pragma once

#include "cullide/raster/vulkan_backend.h"

#include <vulkan/vulkan.h>

#include <algorithm>
#include <set>
#include <span>
#include <string>
#include <vector>

namespace cullide::raster::vk {

inline constexpr const char* kSource = "vulkan backend";

[[noreturn]] inline void unavailable(const std::string& why) {
    throw BackendUnavailable(why, kSource);
}

inline void check(VkResult r, const char* what) {
    if (r != VK_SUCCESS) unavailable(std::string(what) + " failed (VkResult " + std::to_string(int(r)) + ")");
}

inline VkFormat toVk(const DepthFormat& f) {
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
    explicit VulkanBackendImpl(const VulkanBackendOptions& options);
    ~VulkanBackendImpl() override;

    // vulkan_backend.cpp: the interface.
    const VulkanInfo& info() const override { return info_; }
    uint64_t validationMessages() const override { return messages_; }
    std::vector<std::string> validationLog() const override { return log_; }
    DepthFormat effectiveFormat(const DepthFormat& requested) const override;
    int maxViewportSide() const override { return std::max(1, maxSide_); }
    std::string describe() const override;
    void setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) override;
    void setView(const OrthoView& view) override;
    std::vector<uint64_t> execute(const CommandList& list) override;
    DepthImage readDepth() override;

private:
    // vulkan_backend.cpp: the steps of setView(), execute() and readDepth().
    void writeViewBlock(const OrthoView& view);
    void beginPass(VkCommandBuffer cb);
    void record(VkCommandBuffer cb, const CommandList& list, std::vector<uint8_t>& any);
    std::vector<uint64_t> queryResults(uint32_t n, const std::vector<uint8_t>& any);
    VkDeviceSize texelBytes() const { return format_.kind == DepthFormat::Kind::Unorm && format_.bits == 16 ? 2 : 4; }

    // vulkan_context.cpp
    void warn(const std::string& msg) const;
    static VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                    VkDebugUtilsMessageTypeFlagsEXT,
                                                    const VkDebugUtilsMessengerCallbackDataEXT* data, void* user);
    void createInstance();
    void requireValidationLayer() const;
    void createMessenger(const VkDebugUtilsMessengerCreateInfoEXT& messenger);
    void pickDevice();
    std::string unsuitable(VkPhysicalDevice d, const VkPhysicalDeviceProperties& p) const;
    void createDevice();
    void readDeviceInfo(const VkPhysicalDeviceProperties& p);
    void createLogicalDevice(bool core13);
    void createCommandObjects();
    void destroy();

    // vulkan_resources.cpp
    uint32_t memoryType(uint32_t bits, VkMemoryPropertyFlags want, VkMemoryPropertyFlags prefer,
                        VkMemoryPropertyFlags* got = nullptr) const;
    void release(Buffer& b);
    void ensure(Buffer& b, VkDeviceSize bytes, VkBufferUsageFlags usage);
    void upload(Buffer& b, const void* data, size_t bytes, VkBufferUsageFlags usage);
    void ensureQueryPool(uint32_t n);
    void destroyTarget();
    void createTarget(int w, int h, const DepthFormat& format);
    void createDepthImage(int w, int h, const DepthFormat& format, VkFormat vf);
    void clearTargetToFar();
    void copyDepthToReadback();
    void barrier(VkCommandBuffer cb, VkImageLayout from, VkImageLayout to, VkPipelineStageFlags srcStage,
                 VkAccessFlags srcAccess, VkPipelineStageFlags dstStage, VkAccessFlags dstAccess) const;
    VkCommandBuffer begin();
    void submit(VkCommandBuffer cb);

    // vulkan_pipeline.cpp
    void createLayoutAndShader();
    void createPassAndPipeline(VkFormat format);
    void createRenderPass(VkFormat format);
    void createGraphicsPipeline();

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

}  // namespace cullide::raster::vk
