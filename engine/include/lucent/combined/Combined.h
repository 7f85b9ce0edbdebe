// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Combined subsurface mode: the image-space dipole for the *local* part of the
/// transport (x_i within the split radius r_s of x_o) plus SSLPV for what travels further
/// (Mertens et al. 2005 §7.1: the two are "perfectly complementary"; Børlum et al.
/// 2011, Børlum et al. 2011). Two splits (docs/methods/combined.md):
///
///  - SplitMode::Kernel (default): SSLPV's own estimate of its local part is replaced by the
///    dipole's,
///      L(x_o) = L_sslpv + F_t(ω_o)/π ∫_{|x_i−x_o|≤r_s} R_d(r) E(x_i) dA − min(L̂, f·L_sslpv),
///      L̂ = F_t(ω_o)/π ∫_{|x_i−x_o|≤r_s} R_lpv(r) E(x_i) dA,
///    R_lpv the radial surface kernel of SSLPV itself (a point-injection solve on a homogeneous
///    half-space with the same options, SslpvSurfaceKernel), E the Fresnel-transmitted
///    irradiance the dipole gathers, f the kernel's near share of ∫ R_lpv E dA
///    (localSslpvFraction): SSLPV's local part is never taken larger than the near share of
///    SSLPV's own radiance. Exact bookkeeping for uniform irradiance on a flat surface. With
///    SSLPV's diffusion mode L̂ is carried to the albedo its read-out sees at x_o
///    (localScaleToSurfaceMaterial): one kernel, the surface cells' mean, for a painted body.
///  - SplitMode::Steps: L(x_o) = L_dipole,r≤r_s(x_o) + L_sslpv,n>k(x_o), k = max(k₀,
///    round(r_s/Δx)): SSLPV skips its first k propagation steps (SslpvOptions::
///    skipAccumulateSteps, §4). Light from beyond k·Δx needs more than k steps, so nothing
///    far is dropped, but SSLPV light of near sources that arrives late is counted twice
///    (20–40 % of the total on thick slabs, docs/methods/combined.md).
///
/// Where the dipole's tail beyond r_s (within the object's extent) is negligible, SSLPV is left
/// out (applyFarSkip, CombinedSettings::autoSkipSslpv).
///
///     combined::CombinedSettings cs;  cs.splitRadius = 4.f;     // mm
///     combined::CombinedResult r = combined::renderCombined(scene, cs);
///     writeExr(r.radiance, "combined.exr");                     // W/(mm²·sr), subsurface only
///
/// Units: mm, mm⁻¹, radiance W/(mm²·sr).

#include <lucent/core/Image.h>
#include <lucent/dipole/ImageSpace.h>
#include <lucent/scene/Scene.h>
#include <lucent/sslpv/SslpvRenderer.h>

#include <limits>
#include <vector>

namespace lucent {
class MaterialVolume;
struct TriangleMesh;
namespace sslpv {
class ExactReflectanceRatio;
}
}  // namespace lucent

namespace lucent::combined {

/// Which split (see the file comment).
enum class SplitMode {
    Kernel,  ///< SSLPV minus its own local kernel, plus the windowed dipole (default)
    Steps,   ///< windowed dipole plus SSLPV without its first k propagation steps
};

/// How the transport is split between the two methods.
struct SplitPlan {
    SplitMode mode = SplitMode::Kernel;
    float cellSize = 0.f;     ///< SSLPV cell edge Δx, mm
    float splitRadius = 0.f;  ///< r_s, mm (+∞: dipole only)
    int skipSteps = 0;        ///< k: SSLPV accumulates from step k + 1 on
    bool dipoleOn = false;    ///< r_s > 0: the dipole term is evaluated
    bool sslpvOn = false;     ///< the SSLPV term is evaluated (Steps: k < maxSteps)
    /// The dipole's far share F(r_s, D) of the material (dipoleFarShare, largest over the
    /// object's voxels and channels); 1 until applyFarSkip() has seen the scene.
    double farShare = 1.0;
    /// applyFarSkip() turned SSLPV off: the far share is within the tolerance.
    bool sslpvSkipped = false;
    /// dipole::GatherSettings::maxRadius for this plan (0 = unlimited when r_s = +∞).
    [[nodiscard]] float dipoleMaxRadius() const;
};

/// Default split radius in SSLPV cells (r_s = DEFAULT_SPLIT_CELLS·Δx when
/// CombinedSettings::splitRadius < 0); chosen from the evaluation in docs/methods/combined.md.
constexpr float DEFAULT_SPLIT_CELLS = 4.f;

/// Largest split radius of SplitMode::Kernel, in SSLPV cells (the kernel's half-space solve
/// grows with it).
constexpr float MAX_KERNEL_SPLIT_CELLS = 24.f;

/// The plan for a split radius. @param splitRadius r_s in mm: ≥ 0 or +∞, < 0 picks
/// DEFAULT_SPLIT_CELLS·Δx (Kernel mode: at most MAX_KERNEL_SPLIT_CELLS·Δx; +∞ and larger radii
/// are clamped to it). @param cellSize Δx > 0 (mm). @param baseSkip k₀ ≥ 0 (SSLPV's own skip).
/// @param maxSteps SSLPV propagation steps. @throw ValueError for NaN or Δx ≤ 0.
SplitPlan planSplit(float splitRadius, float cellSize, int baseSkip, int maxSteps,
                    SplitMode mode = SplitMode::Kernel);

/// Default tolerance of the automatic SSLPV skip (CombinedSettings::farTolerance): the share of
/// the dipole's reflectance within the object's reach that may lie beyond r_s when SSLPV is left
/// out.
constexpr float DEFAULT_FAR_TOLERANCE = 1e-3f;

/// The far share of one homogeneous material: the part of the dipole's diffuse reflectance
/// within the object's reach that the split leaves to SSLPV,
///   F(r_s, D) = ∫_{r_s}^{max(r_s, D)} R_d 2πr dr / ∫_0^{max(r_s, D)} R_d 2πr dr
/// (DipoleProfile::reflectanceBeyond, closed form), largest of the RGB channels. D bounds the
/// distance between any two surface points of the object (objectExtent), so light cannot
/// travel further than D between entering and leaving: F = 0 when r_s ≥ D (the window covers
/// the object), and F ≤ e^{−σ_tr (r_s − z_v)}-small when r_s is a few diffusion lengths
/// 1/σ_tr. Bound: for any x_o the transport from |x_i − x_o| > r_s is
///   F_t/π ∫_{r_s<r≤D} R_d E dA ≤ F · (F_t/π · E_max · ∫_{r≤D} R_d dA),
/// i.e. at most F times the radiance of the brightest irradiance spread uniformly over the
/// object's reach (flat-surface measure dA = 2πr dr, the one the image-space gather integrates
/// on; normalising by the reach, not the whole plane, keeps optically thin objects, D ≪ 1/σt′,
/// from skipping). 0 for a black material.
/// @param model Dipole or BetterDipole (the image-space gather's models); @param splitRadius,
/// extent in mm (≥ 0; +∞ allowed). @throw ValueError for NaN radii or an invalid medium.
double dipoleFarShare(dipole::Model model, const MaterialSample& material, float eta,
                      float splitRadius, float extent);

/// dipoleFarShare over every distinct inside voxel of `volume` (the largest: a painted volume
/// may hold its most translucent material anywhere). @throw ValueError if no voxel is inside.
double volumeFarShare(dipole::Model model, const MaterialVolume& volume, float eta,
                      float splitRadius, float extent);

/// D for dipoleFarShare: the diagonal of the mesh's bounding box (mm), which bounds the
/// distance between any two of its points; 0 for an empty mesh.
float objectExtent(const TriangleMesh& mesh);

/// The automatic SSLPV skip (docs/methods/combined.md, "Automatic skip"): records farShare and
/// turns SSLPV off when the dipole is on and farShare ≤ tolerance; the dipole keeps its window
/// r_s, so the image is the windowed dipole and the change is at most the bound of
/// dipoleFarShare. A plan without the dipole (r_s = 0) or with SSLPV already off is unchanged
/// apart from farShare. @param tolerance ≥ 0 (0: only when the window covers the object).
void applyFarSkip(SplitPlan& plan, double farShare, float tolerance);

/// SSLPV's radial surface kernel for one homogeneous material, in the units of a dipole profile
/// R_d(r) (mm⁻², per unit Fresnel-transmitted irradiance): a unit flux is injected at normal
/// incidence into one boundary cell of a half-space (a thick slab of the material, sinks
/// around it) and solved with the renderer's options; the exitant radiance of the surface cells
/// (calibrated exit scale, without T(ω_o)) times Δx² is G(i, j). Cells are grouped into rings
/// by their distance from the source cell (ring 0: the source cell; ring b: distances in
/// [b − ½, b + ½) cells) and ring b becomes an annulus of the same total area (outer radius
/// Δx·√(cells so far/π)), over which R_lpv is constant: R_lpv = π Σ_ring G /(T(0)·area). So
/// ∫_0^{ρ_b} R_lpv 2πr dr = π Σ_{rings ≤ b} G / T(0) exactly.
struct SslpvSurfaceKernel {
    float cellSize = 0.f;          ///< Δx, mm
    std::vector<float> ringOuter;  ///< ρ_b, mm (increasing)
    std::vector<Rgb> ringValue;    ///< R_lpv on ring b, mm⁻²
    /// R_lpv(r), 0 beyond the last ring. @param r mm ≥ 0.
    [[nodiscard]] Rgb evaluate(float r) const;
    /// ∫_0^R R_lpv(r) 2πr dr (piecewise exact), dimensionless.
    [[nodiscard]] Rgb integral(float R) const;
};

/// SSLPV's response to a point injection on a homogeneous half-space: a thick slab of
/// `material` (cells [1, n−2]³ of an n³ grid of edge Δx, sinks around it), 2×2 texels of ¼ W
/// each into the top cell (n/2, n/2), arriving from outside at cosine `incidenceCos` to the
/// normal (1: normal incidence; the beam tilts towards +x), solved with `options` at index η.
/// Returns G(i, j) for |i|, |j| ≤ half, row-major (j slowest): the exitant radiance of the top
/// cell (n/2 + i, n/2 + j), read at its face centre along +z (calibrated exit scale, without
/// T(ω_o)), times Δx², per watt injected (before Fresnel). By superposition Σ_ij G is L_o/E of a
/// laterally infinite slab under uniform irradiance E at that incidence. @param n grid cells per
/// axis, [8, 128]; @param half ≤ (n − 3)/2; @param incidenceCos ∈ (0, 1].
/// @throw ValueError for invalid arguments.
std::vector<Rgb> sslpvHalfSpaceResponse(const MaterialSample& material, float eta,
                                        const sslpv::SslpvOptions& options, float cellSize, int n,
                                        int half, float incidenceCos = 1.f);

/// Solves the half-space for `material` (reduced σt, σs′, g, mm⁻¹) with `options` (mode,
/// order, steps, skip, attenuation as the renderer uses them) at cell size Δx and index η,
/// lit at the outside cosine `incidenceCos` (meanIncidenceCosine), covering radii up to
/// `radius` (mm); R_lpv is per unit of the irradiance transmitted at that incidence
/// (T(incidenceCos)). The rings average the response over azimuth, so an oblique beam's lean
/// along its direction is not kept, only how much of its light leaves at each distance.
/// @throw ValueError for an invalid material, Δx ≤ 0 or incidenceCos ∉ (0, 1].
SslpvSurfaceKernel computeSslpvSurfaceKernel(const MaterialSample& material, float eta,
                                             const sslpv::SslpvOptions& options, float cellSize,
                                             float radius, float incidenceCos = 1.f);

/// Step of meanIncidenceCosine's answer: the kernel is solved again only when the mean moves
/// by a step (a light dragged in the app re-solves it a few times, not every frame).
constexpr float KERNEL_INCIDENCE_STEP = 0.05f;

/// The cosine at which the object's surface receives its light, on average: over the mesh's
/// triangles facing each light (unshadowed, at the centroid), Σ A·E_t·cos θ_i / Σ A·E_t, E_t
/// the Fresnel-transmitted irradiance (luminance, dipole::lightIrradiance) and θ_i the angle
/// between the face's normal (its winding's, outward as the vertex normals every method reads
/// are computed) and the direction to the light; rounded to KERNEL_INCIDENCE_STEP,
/// within [KERNEL_INCIDENCE_STEP, 1]. The Kernel split solves SSLPV's local kernel lit at this
/// cosine, because SSLPV's own light is injected at the true incidence and an oblique beam
/// scatters first nearer the surface (more of it leaves near where it entered: a high-albedo
/// half-space reflects more at oblique incidence). 1 (normal incidence) when no face is lit.
/// Positions and normals in the lights' space (mm).
float meanIncidenceCosine(const TriangleMesh& mesh, const std::vector<Light>& lights, float eta);

/// Mean reduced material over the inside voxels of `volume`. @throw ValueError if no voxel is
/// inside.
MaterialSample meanInsideMaterial(const MaterialVolume& volume);

/// The inside voxels with an outside voxel (or the grid's exterior) within k = max(1,
/// round(depthMm / voxel size)) voxels along every axis, a (2k+1)³ box: the volume's surface
/// layer about `depthMm` deep, the first voxel layer at least, in x-fastest order. The kernel's
/// material is their mean (surfaceMaterial): the kernel stands for the SSLPV part's response to
/// light that enters and leaves near x_o, which on the grid is set by what its surface cells
/// hold, so with depthMm = one SSLPV cell a painted layer or coat counts as what it is there,
/// not diluted by the core (docs/methods/combined.md, "Painted volumes: the kernel of the
/// surface cells"). @throw ValueError for a volume without inside voxels or a depth that is not
/// finite.
std::vector<Coord> surfaceShell(const MaterialVolume& volume, float depthMm);

/// Mean reduced material (σt′, σs′ ≤ σt′, g) over `shell` (surfaceShell's voxels).
/// @throw ValueError if `shell` is empty.
MaterialSample surfaceMaterial(const MaterialVolume& volume, const std::vector<Coord>& shell);

/// SSLPV's local part at every covered pixel, L̂(x_o) = F_t(η, ω_o)/π ∫_{r ≤ r_s} R_lpv(r) E dA,
/// by `samples` stratified uniform disc samples on the tangent plane (Hammersley with a
/// per-pixel Cranley–Patterson shift from pixelShift()); a sample counts where it projects onto
/// a covered pixel, E and r = its tangent-plane distance. W/(mm²·sr).
/// @throw ValueError for invalid buffers, r_s ≤ 0 or samples ∉ [1, 4096].
ImageRgb localSslpvEstimate(const dipole::SurfaceBuffers& buffers, const SslpvSurfaceKernel& kernel,
                            float splitRadius, float eta, int samples, uint32_t seed);

/// The kernel's near fraction at every covered pixel,
///   f(x_o) = ∫_{r ≤ r_s} R_lpv E dA / ∫_{r ≤ ρ_last} R_lpv E dA ∈ [0, 1] (per channel; 0 where
/// both vanish), ρ_last the kernel's outer radius; both integrals by `samples` stratified
/// uniform samples (the disc as in localSslpvEstimate, the annulus (r_s, ρ_last] with the same
/// per-pixel shifts). The Kernel split subtracts min(L̂, f·L_sslpv): the flat half-space
/// kernel's absolute value overstates what SSLPV deposits on a voxelised curved object (at
/// η = 1 more than SSLPV's whole radiance, docs/methods/combined.md), its share f does not.
/// @throw ValueError as localSslpvEstimate.
ImageRgb localSslpvFraction(const dipole::SurfaceBuffers& buffers, const SslpvSurfaceKernel& kernel,
                            float splitRadius, int samples, uint32_t seed);

/// Jensen et al. 2001's classical dipole's near share: the part of its total diffuse reflectance
/// that leaves within `radius` (mm) of where the light entered,
///   N(r) = 1 − (z_r e^{−σ_tr d_r}/d_r + z_v e^{−σ_tr d_v}/d_v) / (e^{−σ_tr z_r} + e^{−σ_tr z_v}),
/// d = √(r² + z²), z_r = 1/σt′, z_v = z_r + 4AD, D = 1/(3σt′), σ_tr = σt′ √(3(1 − α′)), i.e.
/// 1 − DipoleProfile::reflectanceBeyond(r) / totalReflectance() of the Dipole model (R_d of
/// Jensen et al. 2001 integrated over the plane in closed form, Mertens et al. 2005 Eq. 6–7,
/// beyond r and in all), in float
/// and line for line as the GLSL copy in shaders/combined_add.comp. @param sigmaT reduced σt′
/// (mm⁻¹); @param albedo α′ ∈ [0, 1]; @param boundaryA A = (1 + F_dr)/(1 − F_dr). 0 where σt′
/// ≤ 0 or the total underflows.
float dipoleNearShare(float sigmaT, float albedo, float boundaryA, float radius);

/// What localScaleToSurfaceMaterial needs of the kernel's material, once per kernel.
struct KernelSurfaceTerms {
    Rgb exactTotal{0.f};      ///< R_exact(α′_k), ExactReflectanceRatio::exactTotal per channel
    Rgb nearShare{0.f};       ///< dipoleNearShare(σt′_k, α′_k, A, r_s) per channel
    float boundaryA = 1.f;    ///< A = (1 + F_dr)/(1 − F_dr) of η (Jensen et al. 2001)
    float splitRadius = 0.f;  ///< r_s, mm
};

/// The kernel's terms for its material at η and r_s. @throw ValueError if η ∉ [1, 3].
KernelSurfaceTerms kernelSurfaceTerms(const MaterialSample& kernelMaterial, float eta,
                                      float splitRadius, const sslpv::ExactReflectanceRatio& table);

/// The mean material of the surface around pixel (x, y): σt′ and σs′ averaged over the pixels
/// holding material (σt′ ≠ 0) at LUCENT_COMBINED_DISC_MEAN_SAMPLES Hammersley points of the disc r
/// ≤ radius on the tangent plane at x_o (uniform in area, r = radius √u;
/// shaders/shared/CombinedShared.h), the same points on every pixel, line for line as the GLSL copy
/// in shaders/combined_add.comp. Zero if (x, y) is uncovered or no point holds material. The light
/// L̂ integrates enters within r_s and crosses this material on its way to x_o, not x_o's alone: on
/// marble veined finer than r_s the point's material overstated how far the light spreads
/// (docs/methods/combined.md, "The kernel at the painted surface").
MaterialSample discMeanMaterial(const dipole::SurfaceBuffers& buffers, int x, int y, float radius);

/// The factor that carries L̂ from the kernel's material to the painted surface at x_o, per
/// channel:
///   s = R_exact(α′(x_o)) / R_exact(α′_k) · N(σ̄t′, σ̄s′/σ̄t′) / N(σt′_k, α′_k),
/// R_exact the exact half-space's total (ExactReflectanceRatio::exactTotal), N the classical
/// dipole's near share within r_s (dipoleNearShare) and σ̄ the material of the disc r ≤ r_s
/// around x_o (discMeanMaterial). SSLPV's diffusion part normalises every surface cell to
/// R_exact at that cell's albedo, so on a half-space of the cell's material its local part is
/// the kernel's times the first ratio; without it a vein darker than the surface's mean had the
/// mean's local part subtracted (too much) and the marble around it the mean's (too little).
/// L̂ is the part within r_s, and a translucent surface (jade: a mean free path of several mm)
/// keeps less of its total there than a denser kernel: the second ratio carries that share
/// (docs/methods/combined.md, "The kernel at the painted surface").
/// @param readoutAlbedo α′ the SSLPV read-out sees at x_o (SslpvSolver::readoutAlbedo); a
/// channel at 0 (no cell read there, or a propagation mode, which holds no albedo) keeps the
/// factor 1, as does a kernel whose total vanishes. @param discMean discMeanMaterial at x_o; a
/// channel with σ̄t′ = 0, or a kernel without a near share, keeps the first ratio alone.
Rgb localScaleToSurfaceMaterial(const Rgb& readoutAlbedo, const MaterialSample& discMean,
                                const KernelSurfaceTerms& kernel,
                                const sslpv::ExactReflectanceRatio& table);

/// Per-pixel shift pair in [0, 1)² of localSslpvEstimate (PCG hash of x, y, seed; the GLSL
/// copy in shaders/combined_add.comp is bit-identical).
Point2f pixelShift(int x, int y, uint32_t seed);

/// SSLPV cell size Δx (mm) of `volume` resampled to gridResolution³ (resampleForPropagation).
/// @throw ValueError if gridResolution ∉ [1, volume resolution].
float sslpvCellSize(const MaterialVolume& volume, int gridResolution);

/// Settings of the CPU combined renderer.
struct CombinedSettings {
    /// r_s in mm; < 0: DEFAULT_SPLIT_CELLS·Δx; 0: SSLPV only; +∞: dipole only (Steps mode).
    float splitRadius = -1.f;
    SplitMode mode = SplitMode::Kernel;
    int localSamples = 32;  ///< Kernel mode: disc samples of localSslpvEstimate, [1, 4096]
    /// The automatic SSLPV skip (applyFarSkip): SSLPV is not run when the dipole's far share
    /// dipoleFarShare(r_s, objectExtent) ≤ farTolerance. Off: SSLPV runs whenever the plan
    /// says so (the reference the skip is tested and measured against).
    bool autoSkipSslpv = true;
    float farTolerance = DEFAULT_FAR_TOLERANCE;  ///< ≥ 0, see DEFAULT_FAR_TOLERANCE
    /// The dipole part's light-view irradiance images (dipole::LightViewSettings). Off by
    /// default: the local-part subtraction sees the camera image only, so light-view irradiance
    /// gathered by the dipole would be counted twice (docs/methods/combined.md).
    bool dipoleLightViews = false;
    /// Dipole gather (model, samples, seed...). eta is taken from the scene, maxRadius from
    /// the split.
    dipole::GatherSettings dipole;
    /// SSLPV (grid, steps, order, mode; calibrated by default as in the CLI). The subsurface
    /// term alone is used; skipAccumulateSteps is k₀ and is raised to k by the split.
    sslpv::SslpvRenderOptions sslpv = defaultSslpvOptions();

    /// Calibrated mode (the CLI's SSLPV default), subsurface term only.
    static sslpv::SslpvRenderOptions defaultSslpvOptions();
};

/// The combined image and its two parts (all subsurface radiance, W/(mm²·sr)).
struct CombinedResult {
    ImageRgb radiance;  ///< dipole + sslpv
    ImageRgb dipole;    ///< the windowed dipole term (black when the plan disables it)
    ImageRgb sslpv;     ///< the SSLPV term (Steps: late steps only; black when disabled)
    ImageRgb local;  ///< Kernel mode: SSLPV's local part that was subtracted, min(L̂, f·L_sslpv)
    SplitPlan plan;
};

/// CPU combined render of scene.objects[0]: CPU irradiance pass + image-space gather
/// (dipole::renderImageSpaceDipole with maxRadius = r_s) and the CPU SslpvRenderer; Kernel mode
/// subtracts min(s·localSslpvEstimate(), localSslpvFraction() · L_sslpv), s =
/// localScaleToSurfaceMaterial at the albedo SSLPV's read-out sees there on a painted volume (1
/// on a homogeneous one; camera's surface buffers; `local` holds it; the sum clamped at 0 per
/// channel),
/// Steps mode skips k propagation steps. @throw ValueError for a scene without
/// object/material or bad settings (message names the field).
CombinedResult renderCombined(const Scene& scene, const CombinedSettings& settings);

}  // namespace lucent::combined
