// replaced by the rasterizer
