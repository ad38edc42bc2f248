// The OpenGL backend (see cullide/raster/gl_backend.h for the conventions and docs/gl-backend.md
// for where GL and the reference can differ).
//
// References: the OpenGL 4.5/4.6 core specification (§13.8.1 viewport and glClipControl, §14.6.1
// polygon rasterization, §17.3.4 depth test, §4.2 occlusion queries, ARB_query_buffer_object);
// Cullide (Govindaraju et al., Graphics Hardware 2003) and the self-intersection variant in
// the seed paper (docs/paper.md#figure-3), whose queries this backend executes.
#include "cullide/raster/gl_backend.h"

#include "egl_context.h"

#include "../gpu/gpu_common.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <set>

namespace cullide::raster {

namespace {

// toWindow() in double, in OrthoView::toWindow's order of operations; `precise` forbids fused
// multiply-adds and reassociation. The float window coordinates are then scaled by a power of
// two (exact) into clip space, and z goes through unchanged (ZERO_TO_ONE clip control).
const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec3 position;
uniform dvec3 uRight, uUp, uDir;
uniform dvec3 uMin;     // xmin, ymin, znear
uniform dvec3 uExtent;  // xmax - xmin, ymax - ymin, zfar - znear
uniform dvec2 uSize;    // the grid: width, height (of the whole view when this is a tile)
uniform dvec2 uOrigin;  // the tile's origin in the grid (0, 0 for a whole view)
uniform vec2 uScale;    // window -> clip: 1/P (exact) or 2/W, 2/H
uniform vec2 uOffset;   // 0 (exact) or -1
void main() {
    precise double px = double(position.x), py = double(position.y), pz = double(position.z);
    precise double x = uRight.x * px + uRight.y * py + uRight.z * pz;
    precise double y = uUp.x * px + uUp.y * py + uUp.z * pz;
    precise double z = uDir.x * px + uDir.y * py + uDir.z * pz;
    precise double xw = (x - uMin.x) / uExtent.x * uSize.x - uOrigin.x;
    precise double yw = (y - uMin.y) / uExtent.y * uSize.y - uOrigin.y;
    precise double zw = (z - uMin.z) / uExtent.z;
    precise float cx = float(xw) * uScale.x + uOffset.x;
    precise float cy = float(yw) * uScale.y + uOffset.y;
    gl_Position = vec4(cx, cy, float(zw), 1.0);
}
)";

const char* kFragmentShader = R"(#version 450 core
void main() {}
)";

GLenum toGl(DepthFunc f) {
    return GLenum(GL_NEVER + int(f));
}

std::string glString(GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? reinterpret_cast<const char*>(s) : "?";
}

GLuint compile(GLenum type, const char* source) {
    const GLuint shader = glCreateShader(type);
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[2048] = {};
        glGetShaderInfoLog(shader, sizeof log, nullptr, log);
        glDeleteShader(shader);
        throw BackendUnavailable(std::string("the GL cannot compile the vertex shader (double precision needed): ") +
                                 log);
    }
    return shader;
}

// A depth renderbuffer of the given format and size; returns 0 if the framebuffer is incomplete.
bool makeDepthTarget(GLenum internalFormat, int w, int h, GLuint& fbo, GLuint& rbo) {
    glCreateRenderbuffers(1, &rbo);
    glNamedRenderbufferStorage(rbo, internalFormat, w, h);
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferRenderbuffer(fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rbo);
    glNamedFramebufferDrawBuffer(fbo, GL_NONE);
    glNamedFramebufferReadBuffer(fbo, GL_NONE);
    if (glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE && glGetError() == GL_NO_ERROR)
        return true;
    glDeleteFramebuffers(1, &fbo);
    glDeleteRenderbuffers(1, &rbo);
    fbo = rbo = 0;
    return false;
}

class GlBackendImpl final : public GlBackend {
public:
    explicit GlBackendImpl(const GlBackendOptions& options) : options_(options), context_(options) {
        context_.makeCurrent();
        GLint major = 0, minor = 0;
        glGetIntegerv(GL_MAJOR_VERSION, &major);
        glGetIntegerv(GL_MINOR_VERSION, &minor);
        if (major * 10 + minor < 45)
            throw BackendUnavailable(context_.platform() + ": OpenGL " + std::to_string(major) + "." +
                                     std::to_string(minor) + " is older than 4.5");
        info_.platform = context_.platform();
        info_.renderer = glString(GL_RENDERER);
        info_.version = glString(GL_VERSION);
        info_.vendor = glString(GL_VENDOR);
        glGetIntegerv(GL_SUBPIXEL_BITS, &info_.subpixelBits);
        GLint dims[2] = {0, 0};
        glGetIntegerv(GL_MAX_VIEWPORT_DIMS, dims);
        info_.maxViewport = std::min(dims[0], dims[1]);
        GLint renderbuffer = 0;
        glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &renderbuffer);
        maxSide_ = std::min({int(info_.maxViewport), int(renderbuffer), kMaxViewportSide});
        GLint bounds[2] = {0, 0};
        glGetIntegerv(GL_VIEWPORT_BOUNDS_RANGE, bounds);
        viewportBoundsMin_ = bounds[0];
        {
            GLuint fbo = 0, rbo = 0;
            info_.hasUnorm32 = makeDepthTarget(GL_DEPTH_COMPONENT32, 4, 4, fbo, rbo);
            if (fbo) glDeleteFramebuffers(1, &fbo);
            if (rbo) glDeleteRenderbuffers(1, &rbo);
            while (glGetError() != GL_NO_ERROR) {}
        }

        const GLuint vs = compile(GL_VERTEX_SHADER, kVertexShader), fs = compile(GL_FRAGMENT_SHADER, kFragmentShader);
        program_ = glCreateProgram();
        glAttachShader(program_, vs);
        glAttachShader(program_, fs);
        glLinkProgram(program_);
        glDeleteShader(vs);
        glDeleteShader(fs);
        GLint ok = 0;
        glGetProgramiv(program_, GL_LINK_STATUS, &ok);
        if (!ok) throw BackendUnavailable("the GL cannot link the shader program");
        for (const char* name : {"uRight", "uUp", "uDir", "uMin", "uExtent", "uSize", "uScale", "uOffset", "uOrigin"})
            uniforms_.push_back(glGetUniformLocation(program_, name));

        glCreateVertexArrays(1, &vao_);
        glCreateBuffers(1, &vbo_);
        glCreateBuffers(1, &ebo_);
        glCreateBuffers(1, &queryBuffer_);
        glEnableVertexArrayAttrib(vao_, 0);
        glVertexArrayAttribFormat(vao_, 0, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao_, 0, 0);

        // Fixed state: depth test on (with ALWAYS it still writes), no culling, no clamping.
        glEnable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glDisable(GL_DEPTH_CLAMP);
        glDisable(GL_MULTISAMPLE);
        glEnable(GL_SCISSOR_TEST);
        glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
        glDepthRange(0.0, 1.0);
        glDepthFunc(GL_LESS);
        glDepthMask(GL_TRUE);
        glUseProgram(program_);
        glBindVertexArray(vao_);
        checkError("context setup");
    }

    ~GlBackendImpl() override {
        try {
            context_.makeCurrent();
        } catch (...) {
            return;  // the context goes with its objects
        }
        glDeleteProgram(program_);
        glDeleteVertexArrays(1, &vao_);
        GLuint buffers[3] = {vbo_, ebo_, queryBuffer_};
        glDeleteBuffers(3, buffers);
        if (fbo_) glDeleteFramebuffers(1, &fbo_);
        if (rbo_) glDeleteRenderbuffers(1, &rbo_);
        for (auto& pool : queryPool_)
            if (!pool.empty()) glDeleteQueries(GLsizei(pool.size()), pool.data());
    }

    const GlInfo& info() const override { return info_; }

    DepthFormat effectiveFormat(const DepthFormat& requested) const override {
        if (requested.kind == DepthFormat::Kind::Float32) return DepthFormat::float32();
        int best = 16;
        for (int candidate : {24, 32}) {
            if (candidate == 32 && !info_.hasUnorm32) continue;
            if (std::abs(candidate - requested.bits) <= std::abs(best - requested.bits)) best = candidate;
        }
        return DepthFormat::unorm(best);
    }

    int depthBits() const override { return depthBits_; }

    int maxViewportSide() const override { return std::max(1, maxSide_); }

    std::string describe() const override {
        std::string s = "gl: " + info_.renderer + ", " + info_.version + ", " + info_.platform + ", " +
            std::to_string(info_.subpixelBits) + " subpixel bits";
        if (depthBits_ > 0) s += ", " + format_.name() + " (" + std::to_string(depthBits_) + " depth bits)";
        return s;
    }

    void setGeometry(std::span<const Vec3f> positions, std::span<const Triangle> triangles) override {
        context_.makeCurrent();
        static_assert(sizeof(Vec3f) == 12 && sizeof(Triangle) == 12, "tightly packed positions and triangles");
        // Storage is re-specified each frame (glNamedBufferData orphans the old store).
        glNamedBufferData(vbo_, GLsizeiptr(positions.size_bytes()), positions.data(), GL_STATIC_DRAW);
        glNamedBufferData(ebo_, GLsizeiptr(triangles.size_bytes()), triangles.data(), GL_STATIC_DRAW);
        glVertexArrayVertexBuffer(vao_, 0, vbo_, 0, sizeof(Vec3f));
        glVertexArrayElementBuffer(vao_, ebo_);
        triangleCount_ = triangles.size();
        checkError("setGeometry");
    }

    void setView(const OrthoView& view) override {
        view.validate();
        context_.makeCurrent();
        const DepthFormat format = effectiveFormat(view.depth);
        gpu::warnFormatOnce(warned_, view.depth, format, "gl backend", "GL", options_.warn);
        if (!fbo_ || view.width != width_ || view.height != height_ || !(format == format_)) {
            if (fbo_) glDeleteFramebuffers(1, &fbo_);
            if (rbo_) glDeleteRenderbuffers(1, &rbo_);
            const GLenum internal = format.kind == DepthFormat::Kind::Float32 ? GL_DEPTH_COMPONENT32F
                : format.bits == 16                                           ? GL_DEPTH_COMPONENT16
                : format.bits == 24                                           ? GL_DEPTH_COMPONENT24
                                                                              : GL_DEPTH_COMPONENT32;
            if (!makeDepthTarget(internal, view.width, view.height, fbo_, rbo_))
                throw BackendUnavailable("cannot make a " + std::to_string(view.width) + "x" +
                                         std::to_string(view.height) + " " + format.name() + " depth framebuffer");
            glGetNamedRenderbufferParameteriv(rbo_, GL_RENDERBUFFER_DEPTH_SIZE, &depthBits_);
            width_ = view.width;
            height_ = view.height;
            format_ = format;
            glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
            glScissor(0, 0, width_, height_);
            // As the CPU backend: a new buffer holds the far value.
            glDepthMask(GL_TRUE);
            glClearDepth(1.0);
            glClear(GL_DEPTH_BUFFER_BIT);
            glDepthMask(mask_ ? GL_TRUE : GL_FALSE);
        }
        // The exact viewport (gpu_common.h).
        const gpu::ViewportSize viewport =
            gpu::exactViewport(width_, height_, view, info_.maxViewport, viewportBoundsMin_);
        const int P = viewport.P;
        const bool exact = viewport.exact;
        if (exact) {
            glViewport(-P, -P, 2 * P, 2 * P);
            glProgramUniform2f(program_, uniforms_[6], 1.0f / float(P), 1.0f / float(P));
            glProgramUniform2f(program_, uniforms_[7], 0.0f, 0.0f);
        } else {
            glViewport(0, 0, width_, height_);
            glProgramUniform2f(program_, uniforms_[6], 2.0f / float(width_), 2.0f / float(height_));
            glProgramUniform2f(program_, uniforms_[7], -1.0f, -1.0f);
        }
        exactViewport_ = exact;
        glProgramUniform3d(program_, uniforms_[0], view.right.x(), view.right.y(), view.right.z());
        glProgramUniform3d(program_, uniforms_[1], view.up.x(), view.up.y(), view.up.z());
        glProgramUniform3d(program_, uniforms_[2], view.dir.x(), view.dir.y(), view.dir.z());
        glProgramUniform3d(program_, uniforms_[3], view.xmin, view.ymin, view.znear);
        glProgramUniform3d(program_, uniforms_[4], view.xmax - view.xmin, view.ymax - view.ymin,
                           view.zfar - view.znear);
        glProgramUniform2d(program_, uniforms_[5], double(view.fullWidth()), double(view.fullHeight()));
        glProgramUniform2d(program_, uniforms_[8], double(view.originX), double(view.originY));
        haveView_ = true;
        checkError("setView");
    }

    std::vector<uint64_t> execute(const CommandList& list) override {
        gpu::checkCommandList(list, haveView_, triangleCount_, "GL");
        context_.makeCurrent();
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
        glUseProgram(program_);
        glBindVertexArray(vao_);

        const uint32_t n = list.queryCount();
        std::vector<GLuint> ids(n);
        size_t used[2] = {0, 0};
        uint32_t next = 0;
        GLenum activeTarget = 0;
        for (const Command& c : list.commands()) {
            switch (c.op) {
                case Command::Op::Clear:
                    // glClear honours the depth mask; the reference's clear does not.
                    if (!mask_) glDepthMask(GL_TRUE);
                    glClearDepth(c.clearDepth);
                    glClear(GL_DEPTH_BUFFER_BIT);
                    if (!mask_) glDepthMask(GL_FALSE);
                    break;
                case Command::Op::SetDepthFunc: glDepthFunc(toGl(c.func)); break;
                case Command::Op::SetDepthMask:
                    mask_ = c.mask;
                    glDepthMask(c.mask ? GL_TRUE : GL_FALSE);
                    break;
                case Command::Op::BeginQuery: {
                    const int k = c.queryKind == QueryKind::SamplesPassed ? 0 : 1;
                    activeTarget = k == 0 ? GL_SAMPLES_PASSED : GL_ANY_SAMPLES_PASSED;
                    std::vector<GLuint>& pool = queryPool_[k];
                    if (used[k] == pool.size()) {
                        const size_t grow = std::max<size_t>(64, pool.size());
                        pool.resize(pool.size() + grow);
                        glCreateQueries(activeTarget, GLsizei(grow), pool.data() + pool.size() - grow);
                    }
                    ids[next++] = pool[used[k]++];
                    glBeginQuery(activeTarget, ids[next - 1]);
                    break;
                }
                case Command::Op::EndQuery: glEndQuery(activeTarget); break;
                case Command::Op::ClearIntervals:
                case Command::Op::DrawConservative: break;  // refused by checkCommandList
                case Command::Op::Draw:
                    if (c.count > 0)
                        glDrawElements(GL_TRIANGLES, GLsizei(uint64_t(c.count) * 3), GL_UNSIGNED_INT,
                                       reinterpret_cast<const void*>(uintptr_t(c.first) * sizeof(Triangle)));
                    break;
            }
        }
        std::vector<uint64_t> results(n, 0);
        if (n > 0) {
            // Every result goes into one buffer on the GL side; one read brings them all back.
            const GLsizeiptr bytes = GLsizeiptr(n) * GLsizeiptr(sizeof(uint64_t));
            if (bytes > queryBufferBytes_) {
                glNamedBufferData(queryBuffer_, bytes, nullptr, GL_STREAM_READ);
                queryBufferBytes_ = bytes;
            }
            for (uint32_t q = 0; q < n; ++q)
                glGetQueryBufferObjectui64v(ids[q], queryBuffer_, GL_QUERY_RESULT,
                                            GLintptr(q) * GLintptr(sizeof(uint64_t)));
            glGetNamedBufferSubData(queryBuffer_, 0, bytes, results.data());
        }
        checkError("execute");
        return results;
    }

    DepthImage readDepth() override {
        if (!haveView_) throw InputError("command list", "readDepth() before setView()");
        context_.makeCurrent();
        DepthImage img;
        img.width = width_;
        img.height = height_;
        img.format = format_;
        img.values.resize(size_t(width_) * size_t(height_));
        glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
        glPixelStorei(GL_PACK_ALIGNMENT, 4);
        const bool isFloat = format_.kind == DepthFormat::Kind::Float32;
        glReadPixels(0, 0, width_, height_, GL_DEPTH_COMPONENT, isFloat ? GL_FLOAT : GL_UNSIGNED_INT,
                     img.values.data());
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
        if (!isFloat && format_.bits < 32) {
            // GL returns k scaled to 32 bits, v = k * (2^32 - 1) / (2^n - 1); back to k, exactly.
            const uint64_t m = (uint64_t(1) << format_.bits) - 1, full = 0xFFFFFFFFull;
            for (uint32_t& v : img.values) v = uint32_t((uint64_t(v) * m * 2 + full) / (2 * full));
        }
        checkError("readDepth");
        return img;
    }

private:
    void checkError(const char* where) const {
        const GLenum e = glGetError();
        if (e != GL_NO_ERROR) {
            char buf[96];
            std::snprintf(buf, sizeof buf, "GL error 0x%04x in %s", unsigned(e), where);
            throw BackendUnavailable(buf);
        }
    }

    GlBackendOptions options_;
    gl::EglContext context_;
    GlInfo info_;
    GLint viewportBoundsMin_ = 0;
    int maxSide_ = 0;  // the largest viewport side: GL_MAX_VIEWPORT_DIMS, GL_MAX_RENDERBUFFER_SIZE
    GLuint program_ = 0, vao_ = 0, vbo_ = 0, ebo_ = 0, queryBuffer_ = 0, fbo_ = 0, rbo_ = 0;
    std::vector<GLint> uniforms_;
    std::vector<GLuint> queryPool_[2];  // SAMPLES_PASSED, ANY_SAMPLES_PASSED
    GLsizeiptr queryBufferBytes_ = 0;
    size_t triangleCount_ = 0;
    int width_ = 0, height_ = 0;
    GLint depthBits_ = 0;
    DepthFormat format_;
    bool mask_ = true;
    bool haveView_ = false;
    bool exactViewport_ = false;
    std::set<std::string> warned_;
};

}  // namespace

std::unique_ptr<GlBackend> makeGlBackend(const GlBackendOptions& options) {
    return std::make_unique<GlBackendImpl>(options);
}

bool glBackendAvailable(std::string* why, const GlBackendOptions& options) {
    return backendAvailable([&] { makeGlBackend(options); }, why);
}

}  // namespace cullide::raster
