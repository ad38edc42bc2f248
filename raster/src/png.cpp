// Debug pictures with stb_image_write (the one translation unit that holds its implementation).
#include "cullide/raster/png.h"

#include "cullide/error.h"

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO_DEPRECATION_WARNING
#include <stb/stb_image_write.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace cullide::raster {

namespace {

void writeRaw(const std::filesystem::path& path, int width, int height, int comp, const std::vector<uint8_t>& pixels) {
    if (width <= 0 || height <= 0) throw InputError(path.string(), "cannot write an empty image");
    if (!stbi_write_png(path.string().c_str(), width, height, comp, pixels.data(), width * comp))
        throw InputError(path.string(), "cannot write the PNG file");
}

}  // namespace

void writeDepthPng(const DepthImage& image, const std::filesystem::path& path, const DepthPngOptions& options) {
    const int W = image.width, H = image.height;
    if (image.values.size() != size_t(W) * size_t(H)) throw InputError(path.string(), "depth image has the wrong size");
    double lo = 0, hi = 1;
    if (options.normalize) {
        lo = 1;
        hi = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                if (image.at(x, y) == options.background) continue;
                lo = std::min(lo, image.depth(x, y));
                hi = std::max(hi, image.depth(x, y));
            }
        if (!(lo < hi)) {  // empty or flat: plain mapping
            lo = 0;
            hi = 1;
        }
    }
    std::vector<uint8_t> px(size_t(W) * size_t(H));
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            uint8_t g = 0;
            if (image.at(x, y) != options.background) {
                const double t = std::clamp((image.depth(x, y) - lo) / (hi - lo), 0.0, 1.0);
                g = uint8_t(std::lround(255.0 * (1.0 - t)));
                if (options.normalize) g = uint8_t(std::max<int>(g, 32));  // keep drawn pixels off black
            }
            px[size_t(H - 1 - y) * size_t(W) + size_t(x)] = g;
        }
    writeRaw(path, W, H, 1, px);
}

void writeMaskPng(int width, int height, std::span<const uint8_t> mask, const std::filesystem::path& path) {
    if (width <= 0 || height <= 0 || mask.size() != size_t(width) * size_t(height))
        throw InputError(path.string(), "mask has the wrong size");
    static constexpr std::array<std::array<uint8_t, 3>, 7> palette{
        {{0, 0, 0}, {255, 255, 255}, {255, 0, 0}, {0, 200, 0}, {0, 64, 255}, {255, 220, 0}, {255, 0, 255}}};
    std::vector<uint8_t> px(size_t(width) * size_t(height) * 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const uint8_t m = mask[size_t(y) * size_t(width) + size_t(x)];
            const auto& c = palette[std::min<size_t>(m, palette.size() - 1)];
            std::copy(c.begin(), c.end(), px.begin() + (size_t(height - 1 - y) * size_t(width) + size_t(x)) * 3);
        }
    writeRaw(path, width, height, 3, px);
}

void writeRgbPng(int width, int height, std::span<const uint8_t> rgb, const std::filesystem::path& path) {
    if (width <= 0 || height <= 0 || rgb.size() != size_t(width) * size_t(height) * 3)
        throw InputError(path.string(), "RGB image has the wrong size");
    std::vector<uint8_t> flipped(rgb.size());
    const size_t row = size_t(width) * 3;
    for (int y = 0; y < height; ++y)
        std::copy_n(rgb.data() + size_t(height - 1 - y) * row, row, flipped.data() + size_t(y) * row);
    writeRaw(path, width, height, 3, flipped);
}

}  // namespace cullide::raster
