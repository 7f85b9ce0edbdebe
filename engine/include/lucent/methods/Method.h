// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The one interface every translucency method implements (direct, single scattering,
/// SSLPV, dipole, better dipole, directional dipole, combined, reference), so that the app, the
/// CLI, `evaluate` and the benchmarks drive any method the same way.
///
/// A Method is one configured instance of a method on one backend, made by the registry
/// (lucent/methods/Registry.h) from its name and parameters. Its lifecycle, for the live
/// preview (Gl backend, the renderer's context current):
/// @code
///   auto m = methods::create("dipole", given, {Backend::Gl, /*live=*/true});
///   m->createGl(library);
///   renderer.addMesh(mesh, m->surface());                   // the translucent-surface rule
///   m->setScene({&mesh, &volume, eta, lights, meshId});     // mesh, material, η, lights
///   renderer.setSubsurfaceProvider(m->subsurfacePass());
///   // per frame:
///   m->materialChanged(volume.takeDirtyBricks());           // dirty bricks only
///   m->cameraChanged(camera);
///   renderer.render();  if (!m->converged()) scheduleNextFrame();
///   for (const Stat& s : m->stats()) ...;                   // key/value pairs
///   m->destroyGl();
/// @endcode
/// Offline, lucent::methods::renderImage (lucent/methods/RenderImage.h) does the same until
/// converged() on a headless context, or calls renderCpu() on the Cpu backend.
/// Anchors: pbrt-v4 Integrator::Create(name, ParameterDictionary), Mitsuba 3's plugin
/// registry, Falcor's RenderPass (create / execute / renderUI / getProperties).

#include <lucent/core/Image.h>
#include <lucent/gpu/SceneRenderer.h>
#include <lucent/methods/Params.h>
#include <lucent/scene/Scene.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace lucent::methods {

/// Light types as bits (bit i = Light::Type value i).
using LightMask = unsigned;
constexpr LightMask lightBit(Light::Type type) {
    return 1u << unsigned(type);
}
constexpr LightMask ALL_LIGHTS = lightBit(Light::Type::Point) | lightBit(Light::Type::Spot) |
                                 lightBit(Light::Type::Directional) | lightBit(Light::Type::Sphere);

/// What a method can do.
struct Capabilities {
    bool gl = false;   ///< a subsurface pass for gpu::SceneRenderer (live and offline)
    bool cpu = false;  ///< a CPU renderer (offline)
    /// What Backend::Auto picks when both exist and GL is available (falling back to the other
    /// backend when it is not).
    Backend preferred = Backend::Gl;
    bool progressive = false;          ///< GL frames refine while idle until converged()
    LightMask glLights = ALL_LIGHTS;   ///< light types the GL pass handles
    LightMask cpuLights = ALL_LIGHTS;  ///< light types the CPU renderer handles (others ignored)
    /// The measuring stick (the reference path tracer): renderImage gives it every light, with
    /// no light skip (RenderOptions::lightSkipEpsilon), so nothing is ever judged against an
    /// approximation.
    bool groundTruth = false;
};

/// Named parameter values: an `evaluate` variant ("sslpv:paper") or a quality level.
struct ParamPreset {
    std::string name;  ///< "paper", "grid 16, 16 steps"
    ParamSet values;
    Backend backend = Backend::Auto;  ///< a variant may pin the backend ("dipole:cpu")
};

/// The registry's description of a method.
struct MethodInfo {
    std::string name;     ///< registry key and CLI name: "better-dipole"
    std::string title;    ///< UI label: "Better dipole"
    std::string summary;  ///< one line, with the paper: "image-space better dipole (d'Eon 2012)"
    std::string docs;     ///< page and anchor: "docs/methods/dipole.md"
    Capabilities caps;
    std::vector<ParamDescriptor> params;
    std::vector<ParamPreset> variants;  ///< `evaluate --methods name:variant`
    std::vector<ParamPreset> quality;   ///< `evaluate` quality levels, cheapest first
    /// What `evaluate` runs by default: variant names ("" = the method as is); none: not run.
    std::vector<std::string> evaluate;
};

/// Messages for the user (the CLI prints them on stderr; the app may show them).
using Log = std::function<void(const std::string&)>;

/// How an instance is made.
struct MethodContext {
    Backend backend = Backend::Gl;  ///< Gl or Cpu (Auto is resolved before creation)
    bool live = false;              ///< the app's live preview (live defaults, frame budgets)
    Log log;                        ///< notes for the user (warnings, ignored lights); may be empty
};

/// Object 0 of a scene as a live method sees it (positions in mm).
struct SceneInputs {
    const TriangleMesh* mesh = nullptr;        ///< rest pose (non-owning)
    const MaterialVolume* material = nullptr;  ///< painted volume (non-owning; must outlive)
    float eta = 1.3f;                          ///< relative index of refraction
    std::vector<Light> lights;                 ///< at most gpu::SceneRenderer::MAX_LIGHTS
    int meshId = 0;                            ///< the object's SceneRenderer mesh id
};

/// One key/value line of a method's statistics ("frames" → "12").
struct Stat {
    std::string key;
    std::string value;
};
using Stats = std::vector<Stat>;

/// Per CPU render.
struct CpuRequest {
    bool subsurfaceOnly = false;  ///< only the subsurface term (no surface reflection)
    /// Progress of long renders (fraction done in [0, 1], a short status); may be empty.
    std::function<void(double fraction, const std::string& status)> progress;
};

/// A translucency method (see the file comment).
class Method {
public:
    /// For the registry's factories (the class is abstract).
    Method(const MethodInfo& info, const MethodContext& context);
    virtual ~Method();
    Method(const Method&) = delete;
    Method& operator=(const Method&) = delete;

    [[nodiscard]] const MethodInfo& info() const { return m_info; }
    [[nodiscard]] Backend backend() const { return m_context.backend; }
    [[nodiscard]] bool isLive() const { return m_context.live; }

    //! @{ \name Parameters
    /// New values (validated against info().params; unset ones take their defaults). What a
    /// change needs (a restart, a re-propagation) is the method's business.
    /// @throw ValueError naming the parameter.
    void setParams(const ParamSet& given);
    [[nodiscard]] const Params& params() const { return m_params; }
    //! @}

    //! @{ \name GL resources (Gl backend; the renderer's context current)
    /// Compiles the method's programs. @throw GpuError with file:line on shader errors.
    virtual void createGl(const gpu::ShaderLibrary& library);
    /// Frees every GL object. Idempotent.
    virtual void destroyGl();
    //! @}

    //! @{ \name Scene (Gl backend)
    /// Mesh, material, η and lights of the object; only what changed since the last call is
    /// re-synchronised (a full material upload when the volume or η changed).
    virtual void setScene(const SceneInputs& scene);
    /// The painted bricks since the last call (MaterialVolume::takeDirtyBricks()).
    virtual void materialChanged(const std::vector<int>& dirtyBricks);
    virtual void cameraChanged(const Camera& camera);
    /// The shown mesh was re-uploaded with new positions (a deformation): what the G-buffer
    /// holds changed without a camera, light or material change.
    virtual void geometryChanged();
    //! @}

    //! @{ \name Frames
    /// Gl: the pass gpu::SceneRenderer runs each frame (nullptr: direct lighting only).
    virtual gpu::SubsurfaceProvider* subsurfacePass();
    /// The object's surface in the direct pass: the translucent-surface rule
    /// (translucentSurface(), whatever η) unless the method draws an opaque surface.
    [[nodiscard]] virtual gpu::SurfaceMaterial surface() const;
    /// Cpu: renders scene.camera's image of scene.objects[0], W/(mm²·sr), top row first.
    /// @throw ValueError for a scene the method cannot render (the message says why).
    virtual ImageRgb renderCpu(const Scene& scene, const CpuRequest& request);
    /// False while another frame would refine the image (progressive methods).
    [[nodiscard]] virtual bool converged() const;
    /// The last frame's numbers, as key/value pairs, for statistics panels and logs.
    [[nodiscard]] virtual Stats stats() const;
    //! @}

protected:
    /// Passes `message` to the context's log (if any).
    void note(const std::string& message) const;
    /// Reads the new values (called by setParams and once by the factory).
    virtual void applyParams(const Params& params) = 0;

private:
    const MethodInfo& m_info;
    MethodContext m_context;
    Params m_params;
};

/// The surface of a translucent object in the direct pass: nothing. The light that is not
/// reflected enters the medium and comes back through the subsurface term; the light that is
/// reflected leaves the smooth dielectric boundary in the mirror direction only, and every
/// light of a scene is a delta (point, spot, directional), so its reflection is a delta that no
/// camera ray meets: the exact reference has no highlight (docs/reference.md). The normalised
/// Blinn-Phong lobe of albedo ((η − 1)/(η + 1))² drawn here until 2026-12-07 added 1–7 % of
/// light the boundary does not send to the camera (docs/evaluation.md, "The surface highlight
/// removed"). So it takes no η: the boundary's Fresnel factors belong to the subsurface term.
[[nodiscard]] gpu::SurfaceMaterial translucentSurface();

}  // namespace lucent::methods
