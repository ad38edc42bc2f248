// The Vulkan backend's memory and transfers: host-visible buffers (geometry, the view's uniform
// block, read-back), the occlusion query pool, the depth image with its view and framebuffer, and
// the one-time command buffers that clear, copy and draw (begin, barrier, submit and wait).
#include "vulkan_impl.h"

#include <algorithm>
#include <cstring>

namespace cullide::raster::vk {

uint32_t VulkanBackendImpl::memoryType(uint32_t bits, VkMemoryPropertyFlags want, VkMemoryPropertyFlags prefer,
                                       VkMemoryPropertyFlags* got) const {
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

void VulkanBackendImpl::release(Buffer& b) {
    if (b.buffer) vkDestroyBuffer(device_, b.buffer, nullptr);
    if (b.memory) vkFreeMemory(device_, b.memory, nullptr);  // unmaps
    b = Buffer{};
}

// A host-visible buffer of at least `bytes` (kept when large enough).
void VulkanBackendImpl::ensure(Buffer& b, VkDeviceSize bytes, VkBufferUsageFlags usage) {
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
    ai.memoryTypeIndex = memoryType(
        req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | (readback ? 0 : VK_MEMORY_PROPERTY_HOST_COHERENT_BIT),
        readback ? VK_MEMORY_PROPERTY_HOST_CACHED_BIT : 0, &got);
    if (readback) readbackCoherent_ = (got & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT) != 0;
    check(vkAllocateMemory(device_, &ai, nullptr, &b.memory), "vkAllocateMemory");
    check(vkBindBufferMemory(device_, b.buffer, b.memory, 0), "vkBindBufferMemory");
    check(vkMapMemory(device_, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped), "vkMapMemory");
    b.size = bytes;
}

void VulkanBackendImpl::upload(Buffer& b, const void* data, size_t bytes, VkBufferUsageFlags usage) {
    ensure(b, bytes, usage);
    if (bytes) std::memcpy(b.mapped, data, bytes);
}

// A query pool of at least n occlusion queries (grown to at least twice its size when too small).
void VulkanBackendImpl::ensureQueryPool(uint32_t n) {
    if (n <= queryCapacity_) return;
    if (queryPool_) vkDestroyQueryPool(device_, queryPool_, nullptr);
    queryPool_ = VK_NULL_HANDLE;
    queryCapacity_ = std::max(n, 2 * queryCapacity_);
    VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qi.queryType = VK_QUERY_TYPE_OCCLUSION;
    qi.queryCount = queryCapacity_;
    check(vkCreateQueryPool(device_, &qi, nullptr, &queryPool_), "vkCreateQueryPool");
}

void VulkanBackendImpl::destroyTarget() {
    if (framebuffer_) vkDestroyFramebuffer(device_, framebuffer_, nullptr);
    if (view_) vkDestroyImageView(device_, view_, nullptr);
    if (image_) vkDestroyImage(device_, image_, nullptr);
    if (imageMemory_) vkFreeMemory(device_, imageMemory_, nullptr);
    framebuffer_ = VK_NULL_HANDLE;
    view_ = VK_NULL_HANDLE;
    image_ = VK_NULL_HANDLE;
    imageMemory_ = VK_NULL_HANDLE;
}

// The depth target of a size and format: image, view and framebuffer (with the render pass and
// pipeline of the format, when it changes), cleared to the far value.
void VulkanBackendImpl::createTarget(int w, int h, const DepthFormat& format) {
    destroyTarget();
    const VkFormat vf = toVk(format);
    if (!renderPass_ || !(format == format_)) createPassAndPipeline(vf);
    createDepthImage(w, h, format, vf);
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
    clearTargetToFar();
}

// The depth image in device-local memory; BackendUnavailable naming its size and format when the
// device cannot make or back it.
void VulkanBackendImpl::createDepthImage(int w, int h, const DepthFormat& format, VkFormat vf) {
    VkImageCreateInfo ii{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ii.imageType = VK_IMAGE_TYPE_2D;
    ii.format = vf;
    ii.extent = {uint32_t(w), uint32_t(h), 1};
    ii.mipLevels = 1;
    ii.arrayLayers = 1;
    ii.samples = VK_SAMPLE_COUNT_1_BIT;
    ii.tiling = VK_IMAGE_TILING_OPTIMAL;
    ii.usage =
        VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    ii.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    ii.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    const std::string what = std::to_string(w) + "x" + std::to_string(h) + " " + format.name() + " depth image";
    if (vkCreateImage(device_, &ii, nullptr, &image_) != VK_SUCCESS) unavailable("cannot make a " + what);
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(device_, image_, &req);
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = memoryType(req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (vkAllocateMemory(device_, &ai, nullptr, &imageMemory_) != VK_SUCCESS) unavailable("cannot allocate a " + what);
    check(vkBindImageMemory(device_, image_, imageMemory_, 0), "vkBindImageMemory");
}

// As the CPU backend: a new buffer holds the far value. Leaves the image a depth attachment.
void VulkanBackendImpl::clearTargetToFar() {
    VkCommandBuffer cb = begin();
    barrier(cb, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0,
            VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
    const VkClearDepthStencilValue far{1.0f, 0};
    const VkImageSubresourceRange range{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
    vkCmdClearDepthStencilImage(cb, image_, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &far, 1, &range);
    barrier(cb, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
            VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
            VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
            VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    submit(cb);
}

// The depth aspect copied into readback_ (grown as needed), visible to the host when this returns;
// the image is a depth attachment again.
void VulkanBackendImpl::copyDepthToReadback() {
    const VkDeviceSize bytes = VkDeviceSize(width_) * VkDeviceSize(height_) * texelBytes();
    ensure(readback_, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT);
    VkCommandBuffer cb = begin();
    barrier(cb, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
            VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
            VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
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
}

void VulkanBackendImpl::barrier(VkCommandBuffer cb, VkImageLayout from, VkImageLayout to, VkPipelineStageFlags srcStage,
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

VkCommandBuffer VulkanBackendImpl::begin() {
    check(vkResetCommandBuffer(commandBuffer_, 0), "vkResetCommandBuffer");
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    check(vkBeginCommandBuffer(commandBuffer_, &bi), "vkBeginCommandBuffer");
    return commandBuffer_;
}

// Ends, submits and waits: nothing is in flight between calls.
void VulkanBackendImpl::submit(VkCommandBuffer cb) {
    check(vkEndCommandBuffer(cb), "vkEndCommandBuffer");
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cb;
    check(vkResetFences(device_, 1, &fence_), "vkResetFences");
    check(vkQueueSubmit(queue_, 1, &si, fence_), "vkQueueSubmit");
    check(vkWaitForFences(device_, 1, &fence_, VK_TRUE, UINT64_MAX), "vkWaitForFences");
}

}  // namespace cullide::raster::vk
