// The Vulkan backend's only shader (no fragment stage): OrthoView::toWindow() in double, in its
// order of operations (`precise`: no fused multiply-add, no reassociation), rounded to float and
// scaled by 1/P (a power of two, exact) into clip space; z goes through unchanged (depth range
// 0..1). Same arithmetic as the GL backend's vertex shader (raster/gl/gl_backend.cpp).
// Compiled to SPIR-V at build time by glslangValidator (raster/CMakeLists.txt).
#version 450
#extension GL_ARB_gpu_shader_fp64 : enable

layout(location = 0) in vec3 position;
layout(set = 0, binding = 0, std140) uniform View {
    dvec4 right, up, dir;
    dvec4 lo;      // xmin, ymin, znear
    dvec4 extent;  // xmax - xmin, ymax - ymin, zfar - znear
    dvec4 size;    // x, y: the grid (the whole view's width, height); z, w: the tile's origin in it
    vec4 scaleOffset;  // window -> clip: (1/P, 1/P, 0, 0) (exact) or (2/W, 2/H, -1, -1)
} v;

void main() {
    precise double px = double(position.x), py = double(position.y), pz = double(position.z);
    precise double x = v.right.x * px + v.right.y * py + v.right.z * pz;
    precise double y = v.up.x * px + v.up.y * py + v.up.z * pz;
    precise double z = v.dir.x * px + v.dir.y * py + v.dir.z * pz;
    precise double xw = (x - v.lo.x) / v.extent.x * v.size.x - v.size.z;
    precise double yw = (y - v.lo.y) / v.extent.y * v.size.y - v.size.w;
    precise double zw = (z - v.lo.z) / v.extent.z;
    precise float cx = float(xw) * v.scaleOffset.x + v.scaleOffset.z;
    precise float cy = float(yw) * v.scaleOffset.y + v.scaleOffset.w;
    gl_Position = vec4(cx, cy, float(zw), 1.0);
}
