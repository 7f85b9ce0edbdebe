// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Thin move-only owners of GL objects (buffers, textures, framebuffers, vertex arrays,
/// queries). They are created and destroyed EXPLICITLY by the code that holds the context
/// (create...() / destroy()); destructors make no GL call, because the context may be gone or
/// not current (Qt: free resources on QOpenGLContext::aboutToBeDestroyed). An object still alive
/// at destruction is counted in leakedGlObjectCount() instead.
///
/// GL names are plain `unsigned` so that this header needs no GL header; enums (GL_RGBA32F...)
/// are passed as `unsigned` too.

#include <cstddef>

namespace lucent::gpu {

/// Kinds of GL object owned through GlObject.
enum class GlObjectKind { Buffer, Texture, Framebuffer, VertexArray, Query, Renderbuffer };

/// A move-only GL name with explicit destroy().
class GlObject {
public:
    GlObject() = default;
    GlObject(GlObjectKind kind, unsigned id);
    GlObject(GlObject&& other) noexcept;
    GlObject& operator=(GlObject&& other) noexcept;
    GlObject(const GlObject&) = delete;
    GlObject& operator=(const GlObject&) = delete;
    ~GlObject();

    [[nodiscard]] unsigned id() const { return m_id; }
    [[nodiscard]] bool isValid() const { return m_id != 0; }
    [[nodiscard]] GlObjectKind kind() const { return m_kind; }
    /// Deletes the GL object (its context must be current). Idempotent.
    void destroy();

    /// Creates one object of `kind` with glCreate* (DSA, GL 4.5). For textures `target` is the
    /// texture target (GL_TEXTURE_2D, ...) and for queries the query target; otherwise unused.
    static GlObject create(GlObjectKind kind, unsigned target = 0);

private:
    GlObjectKind m_kind = GlObjectKind::Buffer;
    unsigned m_id = 0;
};

/// Number of GL objects (GlObject and GlProgram) currently alive in this process.
std::size_t liveGlObjectCount();
/// Number of GL objects whose owner was destroyed without destroy() (a leak of GPU memory).
std::size_t leakedGlObjectCount();
/// Number of GL objects (GlObject and GlProgram) created so far in this process (monotonic:
/// tests use it to check that a steady-state frame or solve creates none).
std::size_t createdGlObjectCount();

/// Immutable-storage buffer helper: creates a buffer of `bytes` with `data` (may be null) and
/// glNamedBufferStorage `flags` (e.g. GL_DYNAMIC_STORAGE_BIT).
GlObject createBuffer(std::size_t bytes, const void* data, unsigned flags);
/// 2-D texture with immutable storage, linear (or nearest) filtering and clamp-to-edge.
GlObject createTexture2D(unsigned internalFormat, int width, int height, bool linear = false);
/// 2-D array texture (e.g. shadow layers) with immutable storage.
GlObject createTexture2DArray(unsigned internalFormat, int width, int height, int layers,
                              bool linear = false);
/// 3-D texture (e.g. a light volume) with immutable storage.
GlObject createTexture3D(unsigned internalFormat, int width, int height, int depth,
                         bool linear = true);

/// Work groups per dispatch dimension that every GL 4.5 implementation accepts
/// (GL_MAX_COMPUTE_WORK_GROUP_COUNT is at least this; llvmpipe's is exactly this).
constexpr unsigned MAX_DISPATCH_GROUPS = 65535;
/// glDispatchCompute of `groups` work groups along a line (× `y` along y), the line folded into
/// x and z when it is longer than MAX_DISPATCH_GROUPS (a list of every pixel of a 4K image in
/// groups of 64 is). The shader takes its group's place on the line from
/// common/dispatch.glsl's lineGroup() and skips what lies beyond its count. groups = 0: nothing.
void dispatchLine(unsigned groups, unsigned y = 1);

}  // namespace lucent::gpu
