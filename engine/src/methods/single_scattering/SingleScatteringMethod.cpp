// SPDX-License-Identifier: MIT
/// @file
/// @brief `single-scattering`: the single-scattering term of the radiative transfer equation,
/// ray-marched per covered G-buffer pixel along the refracted view ray through the painted
/// volume (shaders/preview_single_scatter.comp: Chandrasekhar 1960; pbrt-v3 §15.1, eq. 15.1
/// restricted to one scattering event; reduced medium, Wyman et al. 1989). GL only. The volume
/// lives in two RGBA32F 3-D textures (σt, σs′; texels are voxels) re-uploaded brick by brick.

#include <lucent/core/Error.h>
#include <lucent/gpu/Shader.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/methods/Registry.h>

#include <epoxy/gl.h>

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lucent::methods {

namespace {

/// Settings of the pass (the method's parameters).
struct SingleScatteringSettings {
    int steps = 24;       ///< view-ray march steps, [1, 512]
    int lightSteps = 6;   ///< shadow-ray march steps per view step, [1, 128]
    float ambient = 0.f;  ///< uniform ambient irradiance, W/mm²
    bool smoothVoxels =
        false;  ///< trilinear σ filtering (display only; the lookup rule is nearest)
};

/// The compute pass and its two volume textures.
class SingleScatterPass final : public gpu::SubsurfaceProvider {
public:
    void create(const gpu::ShaderLibrary& lib) {
        m_program = gpu::GlProgram::compute(lib, "preview_single_scatter.comp", {"LOCAL_SIZE=8"});
    }
    void destroy() {
        m_program.destroy();
        glDeleteTextures(1, &m_texSigmaT);
        glDeleteTextures(1, &m_texSigmaS);
        m_texSigmaT = m_texSigmaS = 0;
        m_resolution = 0;
    }

    /// Uploads the whole volume (full) or the given bricks. @return bricks uploaded.
    int sync(const MaterialVolume& vol, bool full, const std::vector<int>& dirty) {
        const int res = vol.resolution();
        constexpr int B = MaterialVolume::BRICK, BV = MaterialVolume::BRICK_VOXELS;
        std::vector<int> bricks = dirty;
        if (full || res != m_resolution || m_texSigmaT == 0) {
            glDeleteTextures(1, &m_texSigmaT);
            glDeleteTextures(1, &m_texSigmaS);
            for (GLuint* tex : {&m_texSigmaT, &m_texSigmaS}) {
                glCreateTextures(GL_TEXTURE_3D, 1, tex);
                glTextureStorage3D(*tex, 1, GL_RGBA32F, res, res, res);
                for (GLenum w : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
                    glTextureParameteri(*tex, w, GL_CLAMP_TO_BORDER);
                const float zero[4] = {0.f, 0.f, 0.f, 0.f};  // outside the grid: vacuum
                glTextureParameterfv(*tex, GL_TEXTURE_BORDER_COLOR, zero);
            }
            m_resolution = res;
            bricks.clear();
            for (int b = 0; b < vol.brickCount(); ++b)
                bricks.push_back(b);
        }
        std::vector<float> st(size_t(BV) * 4), ss(size_t(BV) * 4), cst, css;
        for (int b : bricks) {
            const float* d = vol.brickData(b);
            for (int v = 0; v < BV; ++v)
                for (int c = 0; c < 3; ++c) {
                    st[size_t(v) * 4 + size_t(c)] =
                        d[size_t(MaterialVolume::component(Channel::SigmaT, c)) * BV + size_t(v)];
                    ss[size_t(v) * 4 + size_t(c)] =
                        d[size_t(MaterialVolume::component(Channel::SigmaS, c)) * BV + size_t(v)];
                }
            const Coord o = vol.brickOrigin(b);
            const Coord size = glm::min(Coord(B), Coord(res) - o);
            const float* pt = st.data();
            const float* ps = ss.data();
            if (size != Coord(B)) {  // partial brick at the grid's far edge: compact the rows
                cst.clear();
                css.clear();
                for (int z = 0; z < size.z; ++z)
                    for (int y = 0; y < size.y; ++y)
                        for (int x = 0; x < size.x; ++x) {
                            const size_t v = size_t(MaterialVolume::voxelInBrick(x, y, z)) * 4;
                            cst.insert(cst.end(), st.begin() + long(v), st.begin() + long(v) + 4);
                            css.insert(css.end(), ss.begin() + long(v), ss.begin() + long(v) + 4);
                        }
                pt = cst.data();
                ps = css.data();
            }
            glTextureSubImage3D(m_texSigmaT, 0, o.x, o.y, o.z, size.x, size.y, size.z, GL_RGBA,
                                GL_FLOAT, pt);
            glTextureSubImage3D(m_texSigmaS, 0, o.x, o.y, o.z, size.x, size.y, size.z, GL_RGBA,
                                GL_FLOAT, ps);
        }
        return int(bricks.size());
    }

    /// Per-frame inputs.
    void setFrame(const SceneInputs& scene, const GridSpec& spec,
                  const SingleScatteringSettings& s) {
        m_scene = &scene;
        m_spec = spec;
        m_settings = s;
    }

    void renderSubsurface(const gpu::GBufferView& g, unsigned target) override {
        const GLuint p = m_program.id();
        glUseProgram(p);
        const auto loc = [&](const char* n) { return glGetUniformLocation(p, n); };
        glUniform2i(loc("u_size"), g.width, g.height);
        glUniform3fv(loc("u_eye"), 1, glm::value_ptr(g.cameraPosition));
        glUniform1i(loc("u_steps"), std::clamp(m_settings.steps, 1, 512));
        glUniform1i(loc("u_lightSteps"), std::clamp(m_settings.lightSteps, 1, 128));
        glUniform1f(loc("u_eta"), m_scene->eta);
        glUniform3f(loc("u_ambient"), m_settings.ambient, m_settings.ambient, m_settings.ambient);
        glUniform1i(loc("u_meshId"), m_scene->meshId + 1);  // the object's pixels only
        const int lightCount = std::min<int>(int(m_scene->lights.size()), 8);
        glUniform1i(loc("u_lightCount"), lightCount);
        char name[48];
        for (int i = 0; i < lightCount; ++i) {
            const Light& l = m_scene->lights[size_t(i)];
            const auto uni = [&](const char* base) {
                std::snprintf(name, sizeof name, "%s[%d]", base, i);
                return loc(name);
            };
            Rgb intensity = l.intensity;
            // Sphere light of radiance L, radius R: intensity L·πR² W/sr seen from afar.
            if (l.type == Light::Type::Sphere)
                intensity *= PI * l.radius * l.radius;
            const int type = l.type == Light::Type::Sphere ? 0 : int(l.type);
            glUniform1i(uni("u_lightType"), type);
            glUniform3f(uni("u_lightPos"), l.position.x, l.position.y, l.position.z);
            glUniform3f(uni("u_lightDir"), l.direction.x, l.direction.y, l.direction.z);
            glUniform3f(uni("u_lightI"), intensity.r, intensity.g, intensity.b);
            glUniform2f(uni("u_spotCos"), std::cos(glm::radians(l.spotOuterDeg)),
                        std::cos(glm::radians(l.spotInnerDeg)));
        }
        glUniform3f(loc("u_gridOrigin"), m_spec.origin.x, m_spec.origin.y, m_spec.origin.z);
        glUniform1f(loc("u_gridSize"), m_spec.voxelSize * float(m_spec.resolution));
        glUniform1f(loc("u_voxelSize"), m_spec.voxelSize);
        const GLint filter = m_settings.smoothVoxels ? GL_LINEAR : GL_NEAREST;
        for (GLuint tex : {m_texSigmaT, m_texSigmaS}) {
            glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, filter);
            glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, filter);
        }
        glBindTextureUnit(0, g.positionTexture);
        glBindTextureUnit(1, g.normalTexture);
        glBindTextureUnit(2, m_texSigmaT);
        glBindTextureUnit(3, m_texSigmaS);
        glBindImageTexture(0, target, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glDispatchCompute(GLuint((g.width + 7) / 8), GLuint((g.height + 7) / 8), 1);
        glUseProgram(0);
    }

private:
    gpu::GlProgram m_program;
    GLuint m_texSigmaT = 0, m_texSigmaS = 0;
    int m_resolution = 0;
    const SceneInputs* m_scene = nullptr;
    GridSpec m_spec;
    SingleScatteringSettings m_settings;
};

class SingleScatteringMethod final : public Method {
public:
    using Method::Method;

    void createGl(const gpu::ShaderLibrary& library) override {
        m_pass.create(library);
        m_synced = false;
    }
    void destroyGl() override {
        m_pass.destroy();
        m_synced = false;
    }

    void setScene(const SceneInputs& scene) override {
        LUCENT_CHECK(scene.material != nullptr,
                     "single-scattering: the object needs a material volume");
        if (scene.material != m_scene.material)
            m_synced = false;
        m_scene = scene;
        if (!m_synced) {
            m_lastBricks = m_pass.sync(*m_scene.material, /*full=*/true, {});
            m_synced = true;
        }
        m_pass.setFrame(m_scene, m_scene.material->spec(), m_settings);
    }
    void materialChanged(const std::vector<int>& dirtyBricks) override {
        if (!m_scene.material || dirtyBricks.empty())
            return;
        m_lastBricks = m_pass.sync(*m_scene.material, /*full=*/false, dirtyBricks);
    }

    gpu::SubsurfaceProvider* subsurfacePass() override { return &m_pass; }

    [[nodiscard]] Stats stats() const override {
        return {{"bricks uploaded", std::to_string(m_lastBricks)}};
    }

private:
    void applyParams(const Params& p) override {
        m_settings.steps = p.getInt("steps");
        m_settings.lightSteps = p.getInt("light-steps");
        m_settings.ambient = p.getFloat("ambient");
        m_settings.smoothVoxels = p.getBool("smooth-voxels");
        if (m_scene.material)
            m_pass.setFrame(m_scene, m_scene.material->spec(), m_settings);
    }

    SingleScatterPass m_pass;
    SingleScatteringSettings m_settings;
    SceneInputs m_scene;
    bool m_synced = false;
    int m_lastBricks = 0;
};

}  // namespace

MethodEntry singleScatteringMethod() {
    MethodEntry e;
    MethodInfo& i = e.info;
    i.name = "single-scattering";
    i.title = "Single scattering";
    i.summary = "ray-marched single scattering of the painted volume (GL)";
    i.docs = "docs/methods/single-scattering.md";
    i.caps.gl = true;
    i.params = {
        {"steps", ParamType::Int, "view-ray march steps", 1, 512, {}, "24"},
        {"light-steps", ParamType::Int, "shadow-ray march steps per view step", 1, 128, {}, "6"},
        {"ambient", ParamType::Float, "uniform ambient irradiance, W/mm^2", 0, 1e6, {}, "0"},
        {"smooth-voxels",
         ParamType::Bool,
         "trilinear filtering of sigma (display only; the engine's lookup rule is nearest)",
         0,
         0,
         {},
         "off"},
    };
    // `evaluate` levels: the view-ray step count sets the cost and the quadrature error.
    for (int steps : {12, 24, 48})
        i.quality.push_back({std::to_string(steps) + " steps",
                             ParamSet::fromAssignments({"steps=" + std::to_string(steps)}),
                             Backend::Auto});
    e.create = [](const MethodInfo& info, const MethodContext& context) {
        return std::unique_ptr<Method>(new SingleScatteringMethod(info, context));
    };
    return e;
}

}  // namespace lucent::methods
