// SPDX-License-Identifier: MIT
/// @file
/// @brief GL object owners: explicit creation/destruction, leak accounting.

#include <lucent/core/Error.h>
#include <lucent/gpu/GlResources.h>

#include "GlObjectCount.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <atomic>
#include <utility>

namespace lucent::gpu {

namespace {
std::atomic<std::size_t> s_live{0};
std::atomic<std::size_t> s_leaked{0};
std::atomic<std::size_t> s_created{0};
}  // namespace

namespace detail {
void countCreated() {
    ++s_live;
    ++s_created;
}
void countDestroyed() {
    --s_live;
}
void countLeaked() {
    --s_live;
    ++s_leaked;
}
}  // namespace detail

std::size_t liveGlObjectCount() {
    return s_live.load();
}
std::size_t leakedGlObjectCount() {
    return s_leaked.load();
}
std::size_t createdGlObjectCount() {
    return s_created.load();
}

GlObject::GlObject(GlObjectKind kind, unsigned id) : m_kind(kind), m_id(id) {
    if (m_id)
        detail::countCreated();
}

GlObject::GlObject(GlObject&& other) noexcept
    : m_kind(other.m_kind), m_id(std::exchange(other.m_id, 0u)) {}

GlObject& GlObject::operator=(GlObject&& other) noexcept {
    if (this != &other) {
        if (m_id)
            detail::countLeaked();  // overwritten without destroy(): the GL name is lost
        m_kind = other.m_kind;
        m_id = std::exchange(other.m_id, 0u);
    }
    return *this;
}

GlObject::~GlObject() {
    // No GL call here: the context may be gone or not current (see the header).
    if (m_id)
        detail::countLeaked();
}

void GlObject::destroy() {
    if (!m_id)
        return;
    GLuint id = m_id;
    switch (m_kind) {
        case GlObjectKind::Buffer:
            glDeleteBuffers(1, &id);
            break;
        case GlObjectKind::Texture:
            glDeleteTextures(1, &id);
            break;
        case GlObjectKind::Framebuffer:
            glDeleteFramebuffers(1, &id);
            break;
        case GlObjectKind::VertexArray:
            glDeleteVertexArrays(1, &id);
            break;
        case GlObjectKind::Query:
            glDeleteQueries(1, &id);
            break;
        case GlObjectKind::Renderbuffer:
            glDeleteRenderbuffers(1, &id);
            break;
    }
    m_id = 0;
    detail::countDestroyed();
}

GlObject GlObject::create(GlObjectKind kind, unsigned target) {
    GLuint id = 0;
    switch (kind) {
        case GlObjectKind::Buffer:
            glCreateBuffers(1, &id);
            break;
        case GlObjectKind::Texture:
            glCreateTextures(target, 1, &id);
            break;
        case GlObjectKind::Framebuffer:
            glCreateFramebuffers(1, &id);
            break;
        case GlObjectKind::VertexArray:
            glCreateVertexArrays(1, &id);
            break;
        case GlObjectKind::Query:
            glCreateQueries(target, 1, &id);
            break;
        case GlObjectKind::Renderbuffer:
            glCreateRenderbuffers(1, &id);
            break;
    }
    if (!id)
        LUCENT_THROW(GpuError, "OpenGL object creation failed (is a 4.5 context current?)");
    return GlObject(kind, id);
}

GlObject createBuffer(std::size_t bytes, const void* data, unsigned flags) {
    LUCENT_CHECK(bytes > 0, "createBuffer: size must be > 0 bytes");
    GlObject b = GlObject::create(GlObjectKind::Buffer);
    glNamedBufferStorage(b.id(), GLsizeiptr(bytes), data, flags);
    return b;
}

namespace {
void setSampling(GLuint tex, bool linear) {
    const GLint filter = linear ? GL_LINEAR : GL_NEAREST;
    glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, filter);
    glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, filter);
    glTextureParameteri(tex, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(tex, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTextureParameteri(tex, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
}
}  // namespace

GlObject createTexture2D(unsigned internalFormat, int width, int height, bool linear) {
    LUCENT_CHECK(width > 0 && height > 0, "createTexture2D: size ", width, "x", height,
                 " must be positive");
    GlObject t = GlObject::create(GlObjectKind::Texture, GL_TEXTURE_2D);
    glTextureStorage2D(t.id(), 1, internalFormat, width, height);
    setSampling(t.id(), linear);
    return t;
}

GlObject createTexture2DArray(unsigned internalFormat, int width, int height, int layers,
                              bool linear) {
    LUCENT_CHECK(width > 0 && height > 0 && layers > 0, "createTexture2DArray: size ", width, "x",
                 height, "x", layers, " must be positive");
    GlObject t = GlObject::create(GlObjectKind::Texture, GL_TEXTURE_2D_ARRAY);
    glTextureStorage3D(t.id(), 1, internalFormat, width, height, layers);
    setSampling(t.id(), linear);
    return t;
}

GlObject createTexture3D(unsigned internalFormat, int width, int height, int depth, bool linear) {
    LUCENT_CHECK(width > 0 && height > 0 && depth > 0, "createTexture3D: size ", width, "x", height,
                 "x", depth, " must be positive");
    GlObject t = GlObject::create(GlObjectKind::Texture, GL_TEXTURE_3D);
    glTextureStorage3D(t.id(), 1, internalFormat, width, height, depth);
    setSampling(t.id(), linear);
    return t;
}

void dispatchLine(unsigned groups, unsigned y) {
    if (groups == 0 || y == 0)
        return;
    const unsigned x = std::min(groups, MAX_DISPATCH_GROUPS);
    glDispatchCompute(x, y, (groups + x - 1) / x);
}

}  // namespace lucent::gpu
