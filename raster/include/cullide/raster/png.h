// Debug pictures: depth buffers and coverage masks as PNG (stb_image_write).
//
// Conventions
//   - Images are written top row first, so a GL buffer (row 0 at the bottom) looks upright.
//   - Writers throw InputError(path, cause) when the file cannot be written; nothing else throws.
#pragma once

#include "cullide/depth_backend.h"

#include <cstdint>
#include <filesystem>
#include <span>

namespace cullide::raster {

struct DepthPngOptions {
    // Stretch the grey ramp to the [min, max] depth of the pixels that differ from `background`
    // (the clear value, normally the far plane), so that shallow scenes stay visible; background
    // pixels are drawn black. Without it, depth d maps to grey 255*(1-d) (near is bright).
    bool normalize = true;
    uint32_t background = 0xFFFFFFFFu;  // stored value treated as background; default: none
};

// Writes `image` as an 8-bit grey PNG, near bright, far dark.
void writeDepthPng(const DepthImage& image, const std::filesystem::path& path, const DepthPngOptions& options = {});

// Writes a width x height mask (row 0 at the bottom, one byte per pixel) as an RGB PNG with a
// fixed palette: 0 black, 1 white, 2 red, 3 green, 4 blue, 5 yellow, anything else magenta.
// Meant for coverage counts (0 = hole, 1 = covered once, 2 = covered twice) and diffs.
void writeMaskPng(int width, int height, std::span<const uint8_t> mask, const std::filesystem::path& path);

// Writes a width x height RGB image (row 0 at the bottom, 3 bytes per pixel) as PNG.
void writeRgbPng(int width, int height, std::span<const uint8_t> rgb, const std::filesystem::path& path);

}  // namespace cullide::raster
