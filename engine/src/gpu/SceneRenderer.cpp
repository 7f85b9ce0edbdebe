// SPDX-License-Identifier: MIT
/// @file
/// @brief Deferred direct-lighting renderer: shadow maps, G-buffer, subsurface hook, shading,
/// tone mapping, readback.

#include <lucent/core/Error.h>
#include <lucent/gpu/SceneRenderer.h>
#include <shared/LightingShared.h>

#include <epoxy/gl.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace lucent::gpu {

namespace sh = shared;

Mat4f cameraViewFromWorld(const Camera& camera) {
    return glm::lookAt(camera.position, camera.target, camera.up);
}

Mat4f cameraClipFromView(const Camera& camera) {
    const float aspect = float(camera.width) / float(camera.height);
    if (camera.orthographic) {
        const float h = 0.5f * camera.orthoHeight;
        return glm::ortho(-h * aspect, h * aspect, -h, h, camera.nearPlane, camera.farPlane);
    }
    return glm::perspective(glm::radians(camera.fovYDeg), aspect, camera.nearPlane,
                            camera.farPlane);
}

namespace {

constexpr int MAX_SHADOW_LAYERS = SceneRenderer::MAX_LIGHTS * 6;

struct MeshGpu {
    GlObject vao;
    GlObject positions;
    GlObject normals;
    GlObject indices;
    size_t vertexCount = 0;
    size_t indexCount = 0;
    Bounds3f bounds;
    SurfaceMaterial material;
    uint64_t revision = 0;  ///< GBufferView::MeshGeometry::revision

    void destroy() {
        vao.destroy();
        positions.destroy();
        normals.destroy();
        indices.destroy();
    }
};

void validateMesh(const TriangleMesh& mesh) {
    LUCENT_CHECK(!mesh.isEmpty() && !mesh.positions.empty(), "SceneRenderer: the mesh is empty");
    LUCENT_CHECK(mesh.normals.size() == mesh.positions.size(), "SceneRenderer: the mesh has ",
                 mesh.normals.size(), " normals for ", mesh.positions.size(),
                 " vertices (call computeVertexNormals)");
    const size_t n = mesh.positions.size();
    for (size_t i = 0; i < n; ++i) {
        LUCENT_CHECK(isFinite(mesh.positions[i]), "SceneRenderer: vertex ", i,
                     " has a non-finite position");
        // Unit normals are expected; zero or NaN ones would turn the shading into NaN.
        LUCENT_CHECK(
            isFinite(mesh.normals[i]) && glm::dot(mesh.normals[i], mesh.normals[i]) > 1e-12f,
            "SceneRenderer: vertex ", i, " has a zero or non-finite normal");
    }
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (uint32_t i : mesh.triangles[t])
            LUCENT_CHECK(i < n, "SceneRenderer: triangle ", t, " uses vertex ", i, " of ", n);
}

void validateSurface(const SurfaceMaterial& s) {
    auto inUnit = [](const Rgb& c) {
        return isFinite(c) && glm::all(glm::greaterThanEqual(c, Rgb(0.f))) &&
               glm::all(glm::lessThanEqual(c, Rgb(1.f)));
    };
    LUCENT_CHECK(inUnit(s.diffuseAlbedo), "SurfaceMaterial.diffuseAlbedo must be in [0,1]");
    LUCENT_CHECK(inUnit(s.specularAlbedo), "SurfaceMaterial.specularAlbedo must be in [0,1]");
    LUCENT_CHECK(std::isfinite(s.shininess) && s.shininess >= 1.f,
                 "SurfaceMaterial.shininess must be >= 1, got ", s.shininess);
}

/// Fixed-function state every pass of the renderer relies on, whatever a provider (which runs
/// between the G-buffer and the shade pass) or the host (Qt's paint engine) left: no scissor (it
/// also limits glClear*), no culling (the full-screen triangle is drawn whatever the winding
/// convention), no blending, stencil or rasteriser discard, filled polygons, all colour channels
/// written, and GL's default depth convention (the shaders map clip z in [−1, 1] to [0, 1]).
/// Each pass then enables what it needs (depth test, polygon offset).
void setPassRasterState() {
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_RASTERIZER_DISCARD);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glDisable(GL_STENCIL_TEST);
    glDisable(GL_DEPTH_CLAMP);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_FRAMEBUFFER_SRGB);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthRange(0.0, 1.0);
    glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
}

}  // namespace

struct SceneRenderer::Impl {
    bool created = false;
    GlProgram gbufferProgram;
    GlProgram shadowProgram;
    GlProgram shadeProgram;
    GlProgram shadeReuseProgram;  ///< direct_shade.frag with REUSE_DIRECT
    GlProgram tonemapProgram;
    GlObject emptyVao;

    std::vector<MeshGpu> meshes;
    uint64_t meshUploads = 0;  ///< source of MeshGpu::revision
    std::vector<Light> lights;
    Camera camera;
    DirectSettings settings;
    SubsurfaceProvider* provider = nullptr;

    int width = 0;
    int height = 0;
    GlObject gPosition, gNormal, gDepth, gFbo;
    GlObject subsurface, subsurfaceFbo;
    GlObject radiance, radianceFbo;
    GlObject direct, directFbo;  ///< the cached direct term; directFbo draws radiance + direct
    GlObject display, displayFbo;
    bool displayValid = false;
    bool haveFrame = false;

    GlObject shadowMaps;
    GlObject shadowFbo;
    int shadowLayersAllocated = 0;
    int shadowSizeAllocated = 0;
    bool shadowsDirty = true;
    bool gbufferDirty = true;  ///< camera, meshes or target size changed
    bool directDirty = true;   ///< lights, surfaces or shading settings changed
    PassReuseCounters counters;

    GlObject frameUbo, lightSsbo, layerSsbo, surfaceSsbo;
    int surfaceCapacity = 0;

    GpuProfiler profiler;
    Mat4f viewFromWorld{1.f};
    Mat4f clipFromWorld{1.f};

    void requireCreated(const char* what) const {
        LUCENT_CHECK(created, "SceneRenderer::", what, " before create()");
    }

    Bounds3f sceneBounds() const {
        Bounds3f b;
        for (const MeshGpu& m : meshes)
            b.expand(m.bounds);
        return b;
    }

    void uploadMesh(MeshGpu& g, const TriangleMesh& mesh) {
        const size_t vbytes = mesh.positions.size() * sizeof(Point3f);
        const size_t ibytes = mesh.triangles.size() * sizeof(mesh.triangles[0]);
        const bool reuse = g.vao.isValid() && g.vertexCount == mesh.positions.size() &&
                           g.indexCount == mesh.triangles.size() * 3;
        if (reuse) {
            glNamedBufferSubData(g.positions.id(), 0, GLsizeiptr(vbytes), mesh.positions.data());
            glNamedBufferSubData(g.normals.id(), 0, GLsizeiptr(vbytes), mesh.normals.data());
            glNamedBufferSubData(g.indices.id(), 0, GLsizeiptr(ibytes), mesh.triangles.data());
        } else {
            g.destroy();
            g.positions = createBuffer(vbytes, mesh.positions.data(), GL_DYNAMIC_STORAGE_BIT);
            g.normals = createBuffer(vbytes, mesh.normals.data(), GL_DYNAMIC_STORAGE_BIT);
            g.indices = createBuffer(ibytes, mesh.triangles.data(), GL_DYNAMIC_STORAGE_BIT);
            g.vao = GlObject::create(GlObjectKind::VertexArray);
            const GLuint vao = g.vao.id();
            glVertexArrayVertexBuffer(vao, 0, g.positions.id(), 0, sizeof(Point3f));
            glVertexArrayVertexBuffer(vao, 1, g.normals.id(), 0, sizeof(Normal3f));
            for (GLuint a = 0; a < 2; ++a) {
                glEnableVertexArrayAttrib(vao, a);
                glVertexArrayAttribFormat(vao, a, 3, GL_FLOAT, GL_FALSE, 0);
                glVertexArrayAttribBinding(vao, a, a);
            }
            glVertexArrayElementBuffer(vao, g.indices.id());
        }
        g.vertexCount = mesh.positions.size();
        g.indexCount = mesh.triangles.size() * 3;
        g.bounds = mesh.bounds();
        g.revision = ++meshUploads;
        shadowsDirty = gbufferDirty = true;
    }

    void uploadSurfaces() {
        if (meshes.empty())
            return;
        if (int(meshes.size()) > surfaceCapacity) {
            surfaceSsbo.destroy();
            surfaceCapacity = std::max<int>(int(meshes.size()), 2 * surfaceCapacity);
            surfaceSsbo = createBuffer(size_t(surfaceCapacity) * sizeof(sh::GpuSurface), nullptr,
                                       GL_DYNAMIC_STORAGE_BIT);
        }
        std::vector<sh::GpuSurface> data(meshes.size());
        for (size_t i = 0; i < meshes.size(); ++i) {
            const SurfaceMaterial& m = meshes[i].material;
            data[i].diffuse = glm::vec4(m.diffuseAlbedo, 0.f);
            data[i].specularShininess = glm::vec4(m.specularAlbedo, m.shininess);
        }
        glNamedBufferSubData(surfaceSsbo.id(), 0, GLsizeiptr(data.size() * sizeof(data[0])),
                             data.data());
        directDirty = true;
    }

    void ensureTargets() {
        if (width == camera.width && height == camera.height && gFbo.isValid())
            return;
        destroyTargets();
        checkTargetLimits(camera.width, camera.height);
        while (glGetError() != GL_NO_ERROR)  // judge only the allocations below
            ;
        width = camera.width;
        height = camera.height;
        gPosition = createTexture2D(GL_RGBA32F, width, height);
        gNormal = createTexture2D(GL_RGBA32F, width, height);
        gDepth = createTexture2D(GL_DEPTH_COMPONENT32F, width, height);
        gFbo = GlObject::create(GlObjectKind::Framebuffer);
        glNamedFramebufferTexture(gFbo.id(), GL_COLOR_ATTACHMENT0, gPosition.id(), 0);
        glNamedFramebufferTexture(gFbo.id(), GL_COLOR_ATTACHMENT1, gNormal.id(), 0);
        glNamedFramebufferTexture(gFbo.id(), GL_DEPTH_ATTACHMENT, gDepth.id(), 0);
        const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
        glNamedFramebufferDrawBuffers(gFbo.id(), 2, bufs);
        subsurface = createTexture2D(GL_RGBA32F, width, height);
        // Cleared through a framebuffer: glClearTexImage maps the texture on some drivers
        // (llvmpipe), which stalls until all queued work has run.
        subsurfaceFbo = GlObject::create(GlObjectKind::Framebuffer);
        glNamedFramebufferTexture(subsurfaceFbo.id(), GL_COLOR_ATTACHMENT0, subsurface.id(), 0);
        radiance = createTexture2D(GL_RGBA32F, width, height, /*linear=*/true);
        radianceFbo = GlObject::create(GlObjectKind::Framebuffer);
        glNamedFramebufferTexture(radianceFbo.id(), GL_COLOR_ATTACHMENT0, radiance.id(), 0);
        // The direct term is read while radianceFbo is drawn (reuse) and written through
        // directFbo (recompute): never attached to the framebuffer it is sampled under.
        direct = createTexture2D(GL_RGBA32F, width, height);
        directFbo = GlObject::create(GlObjectKind::Framebuffer);
        glNamedFramebufferTexture(directFbo.id(), GL_COLOR_ATTACHMENT0, radiance.id(), 0);
        glNamedFramebufferTexture(directFbo.id(), GL_COLOR_ATTACHMENT1, direct.id(), 0);
        const GLenum directBufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
        glNamedFramebufferDrawBuffers(directFbo.id(), 2, directBufs);
        display = createTexture2D(GL_RGBA32F, width, height);
        displayFbo = GlObject::create(GlObjectKind::Framebuffer);
        glNamedFramebufferTexture(displayFbo.id(), GL_COLOR_ATTACHMENT0, display.id(), 0);
        bool complete = glGetError() != GL_OUT_OF_MEMORY;
        for (GLuint fbo :
             {gFbo.id(), subsurfaceFbo.id(), radianceFbo.id(), directFbo.id(), displayFbo.id()})
            complete = complete && glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) ==
                                       GL_FRAMEBUFFER_COMPLETE;
        if (!complete) {
            const int w = width, h = height;
            destroyTargets();
            throw GpuError(targetsMessage(w, h, "the device could not allocate them"));
        }
        haveFrame = false;
        gbufferDirty = directDirty = true;
    }

    /// Bytes of the per-pixel render targets: six RGBA32F images and a 32-bit depth buffer.
    static double targetBytes(int w, int h) { return double(w) * double(h) * (6.0 * 16.0 + 4.0); }

    /// Why a w×h frame cannot be rendered on this device, in words a user can act on.
    static std::string targetsMessage(int w, int h, const std::string& reason) {
        const auto* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
        const std::string renderer = name ? name : "unknown";
        std::ostringstream os;
        os << "cannot render " << w << "x" << h << " on '" << renderer << "': " << reason
           << " (six RGBA32F images and a depth buffer, " << std::fixed << std::setprecision(1)
           << targetBytes(w, h) / double(1u << 30) << " GiB)";
        if (renderer.find("llvmpipe") != std::string::npos)
            os << "; llvmpipe allows 1 GiB per texture, so at most 8192x8192";
        os << ". Render smaller (--width/--height) or on a GPU with more memory";
        return os.str();
    }

    /// The device's size limits, checked before allocating (a texture over them would only
    /// show up later as an incomplete framebuffer).
    static void checkTargetLimits(int w, int h) {
        GLint maxTexture = 0, maxFbWidth = 0, maxFbHeight = 0;
        glGetIntegerv(GL_MAX_TEXTURE_SIZE, &maxTexture);
        glGetIntegerv(GL_MAX_FRAMEBUFFER_WIDTH, &maxFbWidth);
        glGetIntegerv(GL_MAX_FRAMEBUFFER_HEIGHT, &maxFbHeight);
        const int maxW = std::min(maxTexture, maxFbWidth), maxH = std::min(maxTexture, maxFbHeight);
        if (maxW > 0 && maxH > 0 && (w > maxW || h > maxH))
            throw GpuError(targetsMessage(
                w, h, detail::concat("the device allows at most ", maxW, "x", maxH, " pixels")));
    }

    void destroyTargets() {
        for (GlObject* o : {&gPosition, &gNormal, &gDepth, &gFbo, &subsurface, &subsurfaceFbo,
                            &radiance, &radianceFbo, &direct, &directFbo, &display, &displayFbo})
            o->destroy();
        width = height = 0;
    }

    int shadowLayersNeeded() const {
        int n = 0;
        for (const Light& l : lights)
            n += (l.type == Light::Type::Point || l.type == Light::Type::Sphere) ? 6 : 1;
        return std::max(n, 1);
    }

    void ensureShadowMaps() {
        const int size = settings.shadows ? settings.shadowMapSize : 1;
        const int layers = settings.shadows ? shadowLayersNeeded() : 1;
        if (shadowMaps.isValid() && size == shadowSizeAllocated && layers == shadowLayersAllocated)
            return;
        shadowMaps.destroy();
        shadowMaps = createTexture2DArray(GL_DEPTH_COMPONENT32F, size, size, layers,
                                          /*linear=*/true);
        glTextureParameteri(shadowMaps.id(), GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
        glTextureParameteri(shadowMaps.id(), GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
        if (!shadowFbo.isValid()) {
            shadowFbo = GlObject::create(GlObjectKind::Framebuffer);
            glNamedFramebufferDrawBuffer(shadowFbo.id(), GL_NONE);
            glNamedFramebufferReadBuffer(shadowFbo.id(), GL_NONE);
        }
        const float one = 1.f;
        glClearTexImage(shadowMaps.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, &one);
        shadowSizeAllocated = size;
        shadowLayersAllocated = layers;
        shadowsDirty = true;
    }

    /// Builds GpuLight entries and the shadow layers of every light.
    void buildLights(std::vector<sh::GpuLight>& gl, std::vector<sh::GpuShadowLayer>& layers) const {
        const Bounds3f b = sceneBounds();
        const Point3f c = b.isEmpty() ? Point3f(0.f) : b.center();
        const float r = b.isEmpty() ? 1.f : std::max(0.5f * glm::length(b.extent()), 1e-3f);
        const float size = float(std::max(shadowSizeAllocated, 1));
        for (const Light& l : lights) {
            sh::GpuLight g{};
            Rgb intensity = l.intensity;
            int type = LUCENT_LIGHT_POINT;
            if (l.type == Light::Type::Spot)
                type = LUCENT_LIGHT_SPOT;
            if (l.type == Light::Type::Directional)
                type = LUCENT_LIGHT_DIRECTIONAL;
            // A sphere light of uniform radiance L and radius r seen from outside has intensity
            // I = L·πr² in every direction (projected area πr² times L); direct lighting treats
            // it as that point light at its centre.
            if (l.type == Light::Type::Sphere)
                intensity = l.intensity * (PI * l.radius * l.radius);
            const Vector3f dir = glm::normalize(l.direction);
            const float outer = std::clamp(l.spotOuterDeg, 0.1f, 89.9f);
            const float inner = std::clamp(l.spotInnerDeg, 0.f, outer);
            const float cosOuter = std::cos(glm::radians(outer));
            const float cosInner = std::max(std::cos(glm::radians(inner)), cosOuter + 1e-6f);
            g.positionType = glm::vec4(l.position, float(type));
            g.directionCosOuter = glm::vec4(dir, cosOuter);
            g.intensityCosInner = glm::vec4(intensity, cosInner);
            g.shadow = glm::ivec4(-1, 0, 0, 0);
            if (settings.shadows && !b.isEmpty()) {
                g.shadow = glm::ivec4(int(layers.size()), type == LUCENT_LIGHT_POINT ? 6 : 1, 0, 0);
                if (type == LUCENT_LIGHT_DIRECTIONAL) {
                    // Orthographic box fitted to the bounding sphere of the scene (centre c,
                    // radius r), looking along the light direction.
                    const Vector3f up =
                        std::abs(dir.y) < 0.99f ? Vector3f(0, 1, 0) : Vector3f(1, 0, 0);
                    const Mat4f view = glm::lookAt(c - dir * (2.f * r), c, up);
                    const Mat4f proj = glm::ortho(-r, r, -r, r, 0.5f * r, 3.5f * r);
                    layers.push_back({proj * view, glm::vec4(1.f, 2.f * r / size, 0.f, 0.f)});
                } else {
                    // Near/far from the distance to the farthest point of the bounding sphere.
                    const float far = (glm::length(c - l.position) + r) * 1.01f;
                    const float near = std::max(far * 1e-4f, 1e-3f);
                    if (type == LUCENT_LIGHT_SPOT) {
                        const float fov = std::min(2.f * outer + 2.f, 170.f);
                        const Vector3f up =
                            std::abs(dir.y) < 0.99f ? Vector3f(0, 1, 0) : Vector3f(1, 0, 0);
                        const Mat4f view = glm::lookAt(l.position, l.position + dir, up);
                        const Mat4f proj = glm::perspective(glm::radians(fov), 1.f, near, far);
                        const float texel = 2.f * std::tan(glm::radians(0.5f * fov)) / size;
                        layers.push_back({proj * view, glm::vec4(0.f, texel, 0.f, 0.f)});
                    } else {
                        // Cube faces +x −x +y −y +z −z, 90° each (matches common/shadow.glsl).
                        static const Vector3f AXES[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                                         {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
                        const Mat4f proj = glm::perspective(glm::radians(90.f), 1.f, near, far);
                        for (const Vector3f& a : AXES) {
                            const Vector3f up =
                                std::abs(a.y) > 0.5f ? Vector3f(0, 0, 1) : Vector3f(0, 1, 0);
                            const Mat4f view = glm::lookAt(l.position, l.position + a, up);
                            layers.push_back({proj * view, glm::vec4(0.f, 2.f / size, 0.f, 0.f)});
                        }
                    }
                }
            }
            gl.push_back(g);
        }
    }

    void drawMeshes(bool withIds) {
        for (size_t i = 0; i < meshes.size(); ++i) {
            const MeshGpu& m = meshes[i];
            if (withIds)
                glUniform1i(0, int(i));
            glBindVertexArray(m.vao.id());
            glDrawElements(GL_TRIANGLES, GLsizei(m.indexCount), GL_UNSIGNED_INT, nullptr);
        }
    }

    /// @return true when the maps were re-rendered.
    bool renderShadows(const std::vector<sh::GpuShadowLayer>& layers) {
        if (!settings.shadows || layers.empty())
            return false;
        if (!shadowsDirty) {  // always reused while unchanged (reuseUnchangedPasses or not)
            ++counters.shadowsReused;
            return false;
        }
        ++counters.shadowsRendered;
        glBindFramebuffer(GL_FRAMEBUFFER, shadowFbo.id());
        glViewport(0, 0, shadowSizeAllocated, shadowSizeAllocated);
        setPassRasterState();
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glDepthMask(GL_TRUE);
        // Slope-scaled depth bias against self-shadowing acne.
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset(2.f, 4.f);
        glUseProgram(shadowProgram.id());
        for (size_t i = 0; i < layers.size(); ++i) {
            glNamedFramebufferTextureLayer(shadowFbo.id(), GL_DEPTH_ATTACHMENT, shadowMaps.id(), 0,
                                           GLint(i));
            glClear(GL_DEPTH_BUFFER_BIT);
            glUniformMatrix4fv(0, 1, GL_FALSE, &layers[i].clipFromWorld[0][0]);
            drawMeshes(false);
        }
        glDisable(GL_POLYGON_OFFSET_FILL);
        // The maps are sampled by the shade pass: leave them attached to no framebuffer (no
        // attachment survives a reallocation of the array either).
        glNamedFramebufferTexture(shadowFbo.id(), GL_DEPTH_ATTACHMENT, 0, 0);
        shadowsDirty = false;
        return true;
    }

    void renderFrame(unsigned tonemapFbo, int tonemapWidth, int tonemapHeight);
    [[nodiscard]] GBufferView gbufferView() const;

    void tonemapInto(GLuint fbo, int w, int h) {
        glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        glViewport(0, 0, w, h);
        setPassRasterState();
        glDisable(GL_DEPTH_TEST);
        glUseProgram(tonemapProgram.id());
        glBindBufferBase(GL_UNIFORM_BUFFER, LUCENT_BINDING_FRAME, frameUbo.id());
        glBindTextureUnit(0, radiance.id());
        glBindVertexArray(emptyVao.id());
        glDrawArrays(GL_TRIANGLES, 0, 3);
        // Leave no renderer object bound (a Qt paint engine may run after us in this context).
        glBindVertexArray(0);
        glUseProgram(0);
    }
};

SceneRenderer::SceneRenderer() : m(std::make_unique<Impl>()) {}
SceneRenderer::~SceneRenderer() = default;

void SceneRenderer::create(const ShaderLibrary& library) {
    if (m->created)
        return;
    try {
        createPrograms(library);
    } catch (...) {
        destroy();  // free what was created before the failure
        throw;
    }
    m->created = true;
}

void SceneRenderer::createPrograms(const ShaderLibrary& library) {
    m->gbufferProgram = GlProgram::graphics(library, "mesh_gbuffer.vert", "mesh_gbuffer.frag");
    m->shadowProgram = GlProgram::graphics(library, "shadow_depth.vert", "shadow_depth.frag");
    m->shadeProgram = GlProgram::graphics(library, "post_fullscreen.vert", "direct_shade.frag");
    m->shadeReuseProgram =
        GlProgram::graphics(library, "post_fullscreen.vert", "direct_shade.frag", {"REUSE_DIRECT"});
    m->tonemapProgram = GlProgram::graphics(library, "post_fullscreen.vert", "post_tonemap.frag");
    m->emptyVao = GlObject::create(GlObjectKind::VertexArray);
    m->frameUbo = createBuffer(sizeof(sh::FrameUniforms), nullptr, GL_DYNAMIC_STORAGE_BIT);
    m->lightSsbo = createBuffer(MAX_LIGHTS * sizeof(sh::GpuLight), nullptr, GL_DYNAMIC_STORAGE_BIT);
    m->layerSsbo = createBuffer(MAX_SHADOW_LAYERS * sizeof(sh::GpuShadowLayer), nullptr,
                                GL_DYNAMIC_STORAGE_BIT);
}

void SceneRenderer::destroy() {
    for (MeshGpu& g : m->meshes)
        g.destroy();
    m->meshes.clear();
    m->destroyTargets();
    for (GlProgram* p : {&m->gbufferProgram, &m->shadowProgram, &m->shadeProgram,
                         &m->shadeReuseProgram, &m->tonemapProgram})
        p->destroy();
    for (GlObject* o : {&m->emptyVao, &m->shadowMaps, &m->shadowFbo, &m->frameUbo, &m->lightSsbo,
                        &m->layerSsbo, &m->surfaceSsbo})
        o->destroy();
    m->surfaceCapacity = 0;
    m->shadowLayersAllocated = m->shadowSizeAllocated = 0;
    m->counters = {};
    m->shadowsDirty = m->gbufferDirty = m->directDirty = true;
    m->profiler.destroy();
    m->created = false;
    m->haveFrame = false;
}

bool SceneRenderer::isCreated() const {
    return m->created;
}

int SceneRenderer::addMesh(const TriangleMesh& mesh, const SurfaceMaterial& material) {
    m->requireCreated("addMesh");
    validateMesh(mesh);
    validateSurface(material);
    MeshGpu g;
    g.material = material;
    m->uploadMesh(g, mesh);
    m->meshes.push_back(std::move(g));
    m->uploadSurfaces();
    return int(m->meshes.size() - 1);
}

void SceneRenderer::updateMesh(int id, const TriangleMesh& mesh) {
    m->requireCreated("updateMesh");
    LUCENT_CHECK(id >= 0 && id < int(m->meshes.size()),
                 "SceneRenderer::updateMesh: unknown mesh id ", id);
    validateMesh(mesh);
    m->uploadMesh(m->meshes[size_t(id)], mesh);
}

void SceneRenderer::setSurfaceMaterial(int id, const SurfaceMaterial& material) {
    m->requireCreated("setSurfaceMaterial");
    LUCENT_CHECK(id >= 0 && id < int(m->meshes.size()),
                 "SceneRenderer::setSurfaceMaterial: unknown mesh id ", id);
    validateSurface(material);
    m->meshes[size_t(id)].material = material;
    m->uploadSurfaces();
}

int SceneRenderer::meshCount() const {
    return int(m->meshes.size());
}

void SceneRenderer::clearMeshes() {
    for (MeshGpu& g : m->meshes)
        g.destroy();
    m->meshes.clear();
    m->shadowsDirty = m->gbufferDirty = true;
}

void SceneRenderer::setLights(const std::vector<Light>& lights) {
    LUCENT_CHECK(int(lights.size()) <= MAX_LIGHTS, "SceneRenderer: ", lights.size(),
                 " lights exceed the maximum of ", MAX_LIGHTS);
    for (size_t i = 0; i < lights.size(); ++i) {
        const Light& l = lights[i];
        LUCENT_CHECK(isFinite(l.position) && isFinite(l.direction) && isFinite(l.intensity) &&
                         std::isfinite(l.radius) && std::isfinite(l.spotInnerDeg) &&
                         std::isfinite(l.spotOuterDeg),
                     "lights[", i, "]: non-finite value");
        LUCENT_CHECK(glm::all(glm::greaterThanEqual(l.intensity, Rgb(0.f))), "lights[", i,
                     "].intensity must be >= 0");
        if (l.type == Light::Type::Spot || l.type == Light::Type::Directional)
            LUCENT_CHECK(glm::length(l.direction) > 1e-6f, "lights[", i,
                         "].direction must be non-zero");
    }
    m->lights = lights;
    m->shadowsDirty = m->directDirty = true;
}

void SceneRenderer::setCamera(const Camera& c) {
    LUCENT_CHECK(c.width >= 1 && c.width <= 16384 && c.height >= 1 && c.height <= 16384,
                 "camera size ", c.width, "x", c.height, " is outside [1, 16384]");
    LUCENT_CHECK(isFinite(c.position) && isFinite(c.target) && isFinite(c.up) &&
                     glm::length(c.target - c.position) > 0.f &&
                     glm::length(glm::cross(c.target - c.position, c.up)) > 0.f,
                 "camera: position, target and up must be finite, distinct and not collinear");
    LUCENT_CHECK(c.nearPlane > 0.f && c.farPlane > c.nearPlane, "camera: need 0 < near < far, got ",
                 c.nearPlane, ", ", c.farPlane);
    LUCENT_CHECK(c.orthographic ? c.orthoHeight > 0.f : (c.fovYDeg > 0.f && c.fovYDeg < 180.f),
                 "camera: orthoHeight must be > 0 / fovYDeg in (0, 180)");
    const Camera& o = m->camera;
    const bool same = o.position == c.position && o.target == c.target && o.up == c.up &&
                      o.orthographic == c.orthographic && o.fovYDeg == c.fovYDeg &&
                      o.orthoHeight == c.orthoHeight && o.width == c.width &&
                      o.height == c.height && o.nearPlane == c.nearPlane &&
                      o.farPlane == c.farPlane;
    if (!same)
        m->gbufferDirty = true;  // the view vector of the direct term follows via the G-buffer
    m->camera = c;
}

void SceneRenderer::setSettings(const DirectSettings& s) {
    LUCENT_CHECK(s.shadowMapSize >= 16 && s.shadowMapSize <= 8192, "DirectSettings.shadowMapSize ",
                 s.shadowMapSize, " is outside [16, 8192]");
    LUCENT_CHECK(
        isFinite(s.background) && std::isfinite(s.toneMap.exposure) && s.toneMap.exposure >= 0.f,
        "DirectSettings: background and exposure must be finite (exposure >= 0)");
    const DirectSettings& o = m->settings;
    if (s.shadows != o.shadows || s.shadowMapSize != o.shadowMapSize)
        m->shadowsDirty = true;
    if (s.shadows != o.shadows || s.specular != o.specular ||
        s.subsurfaceOnly != o.subsurfaceOnly || s.background != o.background)
        m->directDirty = true;
    m->settings = s;
}

const DirectSettings& SceneRenderer::settings() const {
    return m->settings;
}

void SceneRenderer::setSubsurfaceProvider(SubsurfaceProvider* provider) {
    m->provider = provider;
}

const PassReuseCounters& SceneRenderer::reuseCounters() const {
    return m->counters;
}

void SceneRenderer::invalidatePasses() {
    m->shadowsDirty = m->gbufferDirty = m->directDirty = true;
}

void SceneRenderer::render() {
    m->requireCreated("render");
    m->ensureTargets();
    m->renderFrame(m->displayFbo.id(), m->width, m->height);
    m->displayValid = true;
}

void SceneRenderer::renderToFramebuffer(unsigned framebuffer, int width, int height) {
    m->requireCreated("renderToFramebuffer");
    LUCENT_CHECK(width > 0 && height > 0, "renderToFramebuffer: size ", width, "x", height,
                 " must be positive");
    m->ensureTargets();
    m->renderFrame(framebuffer, width, height);
    m->displayValid = false;
}

void SceneRenderer::Impl::renderFrame(unsigned tonemapFbo, int tonemapWidth, int tonemapHeight) {
    Impl& r = *this;
    r.ensureShadowMaps();
    // A provider or pass that throws cancels the frame: the next frame starts cleanly.
    GpuProfiler::FrameScope frame(r.profiler);

    // Per-frame uniforms and light buffers.
    r.viewFromWorld = cameraViewFromWorld(r.camera);
    r.clipFromWorld = cameraClipFromView(r.camera) * r.viewFromWorld;
    std::vector<sh::GpuLight> lights;
    std::vector<sh::GpuShadowLayer> layers;
    r.buildLights(lights, layers);
    sh::FrameUniforms fu{};
    fu.clipFromWorld = r.clipFromWorld;
    fu.viewFromWorld = r.viewFromWorld;
    fu.cameraPosition = glm::vec4(r.camera.position, r.camera.orthographic ? 1.f : 0.f);
    fu.cameraForward = glm::vec4(glm::normalize(r.camera.target - r.camera.position), 0.f);
    fu.background = glm::vec4(r.settings.background, 0.f);
    fu.flags = glm::ivec4(int(lights.size()), r.settings.shadows ? 1 : 0,
                          r.settings.specular ? 1 : 0, r.settings.subsurfaceOnly ? 1 : 0);
    fu.toneMap =
        glm::vec4(r.settings.toneMap.exposure, float(int(r.settings.toneMap.curve)), 0.f, 0.f);
    static_assert(int(ToneMap::Curve::Clamp) == LUCENT_TONEMAP_CLAMP &&
                  int(ToneMap::Curve::Reinhard) == LUCENT_TONEMAP_REINHARD &&
                  int(ToneMap::Curve::Aces) == LUCENT_TONEMAP_ACES);
    glNamedBufferSubData(r.frameUbo.id(), 0, sizeof(fu), &fu);
    if (!lights.empty())
        glNamedBufferSubData(r.lightSsbo.id(), 0, GLsizeiptr(lights.size() * sizeof(lights[0])),
                             lights.data());
    if (!layers.empty())
        glNamedBufferSubData(r.layerSsbo.id(), 0, GLsizeiptr(layers.size() * sizeof(layers[0])),
                             layers.data());

    const bool reuse = r.settings.reuseUnchangedPasses;
    bool shadowsRendered = false;
    {
        auto s = r.profiler.scope("shadows");
        shadowsRendered = r.renderShadows(layers);
    }
    const bool renderGbuffer = r.gbufferDirty || !reuse;
    // The direct term depends on the G-buffer, the shadow maps, the lights, the surfaces and
    // the shading settings; a material edit (new subsurface term) changes none of them.
    const bool renderDirect = renderGbuffer || shadowsRendered || r.directDirty || !reuse;
    ++r.counters.frames;
    ++(renderGbuffer ? r.counters.gbufferRendered : r.counters.gbufferReused);
    ++(renderDirect ? r.counters.directRendered : r.counters.directReused);
    if (renderGbuffer) {
        auto s = r.profiler.scope("gbuffer");
        glBindFramebuffer(GL_FRAMEBUFFER, r.gFbo.id());
        glViewport(0, 0, r.width, r.height);
        setPassRasterState();  // before the clears: a scissor left enabled would limit them
        const float zero[4] = {0.f, 0.f, 0.f, 0.f};
        const float one = 1.f;
        glClearNamedFramebufferfv(r.gFbo.id(), GL_COLOR, 0, zero);
        glClearNamedFramebufferfv(r.gFbo.id(), GL_COLOR, 1, zero);
        glClearNamedFramebufferfv(r.gFbo.id(), GL_DEPTH, 0, &one);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glDepthMask(GL_TRUE);
        glUseProgram(r.gbufferProgram.id());
        glBindBufferBase(GL_UNIFORM_BUFFER, LUCENT_BINDING_FRAME, r.frameUbo.id());
        r.drawMeshes(true);
        r.gbufferDirty = false;
    } else {
        auto s = r.profiler.scope("gbuffer");  // reused: an empty scope keeps the pass list
    }
    {
        auto s = r.profiler.scope("subsurface");
        setPassRasterState();  // the clear below honours the scissor test and the colour mask
        const float zero[4] = {0.f, 0.f, 0.f, 0.f};
        glClearNamedFramebufferfv(r.subsurfaceFbo.id(), GL_COLOR, 0, zero);
        if (r.provider) {
            r.provider->renderSubsurface(gbufferView(), r.subsurface.id());
            glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                            GL_FRAMEBUFFER_BARRIER_BIT);
        }
    }
    {
        auto s = r.profiler.scope("shade");
        glBindFramebuffer(GL_FRAMEBUFFER, renderDirect ? r.directFbo.id() : r.radianceFbo.id());
        glViewport(0, 0, r.width, r.height);
        setPassRasterState();  // the provider ran just before and may leave any state
        glDisable(GL_DEPTH_TEST);
        glUseProgram(renderDirect ? r.shadeProgram.id() : r.shadeReuseProgram.id());
        glBindBufferBase(GL_UNIFORM_BUFFER, LUCENT_BINDING_FRAME, r.frameUbo.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, LUCENT_BINDING_LIGHTS, r.lightSsbo.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, LUCENT_BINDING_SHADOW_LAYERS, r.layerSsbo.id());
        if (r.surfaceSsbo.isValid())
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, LUCENT_BINDING_SURFACES, r.surfaceSsbo.id());
        glBindTextureUnit(0, r.gPosition.id());
        glBindTextureUnit(1, r.gNormal.id());
        glBindTextureUnit(2, r.subsurface.id());
        glBindTextureUnit(3, r.shadowMaps.id());
        glBindTextureUnit(4, renderDirect ? 0 : r.direct.id());
        glBindVertexArray(r.emptyVao.id());
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glBindTextureUnit(4, 0);
        r.directDirty = false;
    }
    {
        auto s = r.profiler.scope("tonemap");
        r.tonemapInto(tonemapFbo, tonemapWidth, tonemapHeight);
    }
    frame.end();
    r.haveFrame = true;
}

namespace {
ImageRgb readTexture(GLuint tex, int w, int h) {
    ImageRgb img(w, h);
    // Read in strips of at most 64 MiB: one read of a large frame (16384² RGBA32F = 4 GiB) would
    // overflow the GLsizei byte count and double the host memory.
    const size_t rowBytes = size_t(w) * 4 * sizeof(float);
    const int stripRows = int(std::clamp<size_t>((size_t(64) << 20) / rowBytes, 1, size_t(h)));
    std::vector<float> rgba(size_t(w) * size_t(stripRows) * 4);
    // Default pack state, whatever another pass (or Qt) left: client memory, tight rows.
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glPixelStorei(GL_PACK_ROW_LENGTH, 0);
    glPixelStorei(GL_PACK_SKIP_ROWS, 0);
    glPixelStorei(GL_PACK_SKIP_PIXELS, 0);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    for (int y0 = 0; y0 < h; y0 += stripRows) {
        const int rows = std::min(stripRows, h - y0);
        glGetTextureSubImage(tex, 0, 0, y0, 0, w, rows, 1, GL_RGBA, GL_FLOAT,
                             GLsizei(size_t(rows) * rowBytes), rgba.data());
        for (int r = 0; r < rows; ++r) {
            const float* row = rgba.data() + size_t(r) * size_t(w) * 4;
            const int y = h - 1 - (y0 + r);  // GL rows bottom-up
            for (int x = 0; x < w; ++x)
                img.at(x, y) = Rgb(row[4 * x], row[4 * x + 1], row[4 * x + 2]);
        }
    }
    return img;
}
}  // namespace

ImageRgb SceneRenderer::readRadiance() const {
    LUCENT_CHECK(m->haveFrame, "SceneRenderer::readRadiance before render()");
    return readTexture(m->radiance.id(), m->width, m->height);
}

ImageRgb SceneRenderer::readDisplay() const {
    LUCENT_CHECK(m->haveFrame, "SceneRenderer::readDisplay before render()");
    if (!m->displayValid) {
        m->tonemapInto(m->displayFbo.id(), m->width, m->height);
        m->displayValid = true;
    }
    return readTexture(m->display.id(), m->width, m->height);
}

GBufferView SceneRenderer::Impl::gbufferView() const {
    GBufferView v;
    v.width = width;
    v.height = height;
    v.positionTexture = gPosition.id();
    v.normalTexture = gNormal.id();
    v.depthTexture = gDepth.id();
    v.viewFromWorld = viewFromWorld;
    v.clipFromWorld = clipFromWorld;
    v.cameraPosition = camera.position;
    v.lightBuffer = lightSsbo.id();
    v.shadowLayerBuffer = layerSsbo.id();
    v.shadowMapTexture = shadowMaps.id();
    v.lightCount = int(lights.size());
    v.shadows = settings.shadows;
    for (const MeshGpu& g : meshes)
        v.meshes.push_back({g.vao.id(), int(g.indexCount), g.bounds, g.revision});
    return v;
}

GBufferView SceneRenderer::gbuffer() const {
    return m->gbufferView();
}

unsigned SceneRenderer::radianceTexture() const {
    return m->radiance.id();
}

GpuProfiler& SceneRenderer::profiler() {
    return m->profiler;
}

}  // namespace lucent::gpu
