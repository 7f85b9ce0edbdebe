// SPDX-License-Identifier: MIT
/// @file
/// @brief CPU SSLPV: injection, propagation (the hot loop) and the radiance estimate.

#include <lucent/core/Fresnel.h>
#include <lucent/sslpv/SslpvSolver.h>

#include <lucent/dipole/Profiles.h>
#include <shared/SslpvShared.h>

#include <lucent/core/Error.h>
#include <lucent/core/Parallel.h>
#include <lucent/core/Timer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

namespace lucent::sslpv {
namespace {

/// A texel that carries light into the object: front-facing (light hits the surface from
/// outside), some flux, finite position and flux (skipped texels are counted, not injected).
bool isInjectable(const SslpvInjectionSample& smp) {
    const float cosI = -glm::dot(smp.direction, smp.normal);
    return cosI > 0.f && (smp.flux.x > 0.f || smp.flux.y > 0.f || smp.flux.z > 0.f) &&
           lucent::isFinite(smp.position) && lucent::isFinite(smp.flux);
}

constexpr double TWO_SQRT_PI = 3.544907701811032;  // ∫ y00 dω = 2√π: flux of c00 = 1
constexpr float Y00 = 0.282094791773878f;          // 1/(2√π)
constexpr float K1 = 0.488602511902920f;           // √(3/(4π))

constexpr int bandOf(int i) {
    return i == 0 ? 0 : (i < 4 ? 1 : 2);
}

/// e^x for x ≤ 0 without libm, so the per-cell factor loops vectorise: x·log₂e = n + f with
/// n rounded to nearest (|f| ≤ ½), 2^f = e^{f ln 2} by its degree-6 Taylor polynomial
/// (remainder ≤ 0.347⁷/7! ≈ 1.2·10⁻⁷ relative), 2^n from the exponent bits; x below
/// −87 (2⁻¹²⁶) returns ≈ 1.2·10⁻³⁸ instead of a subnormal.
__attribute__((always_inline)) inline float expNonPositive(float x) {
    float t = (x < 0.f ? x : 0.f) * 1.44269504f;
    t = t > -126.f ? t : -126.f;
    // Round to nearest for t ≤ 0 by truncating t − ½ (conversions vectorise, and unlike the
    // magic-number trick this survives the file's -fassociative-math).
    const int32_t ni = int32_t(t - 0.5f);
    const float y = (t - float(ni)) * 0.693147181f;
    const float p =
        1.f +
        y * (1.f + y * (0.5f + y * (1.f / 6.f + y * (1.f / 24.f + y * (1.f / 120.f + y / 720.f)))));
    const int32_t bits = (ni + 127) << 23;
    float scale;
    std::memcpy(&scale, &bits, sizeof(scale));
    return p * scale;
}

/// How the per-step attenuation exponent β is formed from one cell's σt, σs′ (mm⁻¹) and Δx:
/// β = linear·(σt − scatterLoss·σs′)·Δx + transport·√(3(σt − σs′)σt)·Δx
///     + diffusion·3(σt − σs′)σt·Δx² + perStep·(σt − σs′)/σt + perStepTransport·σ_tr/σt.
/// Paper mode: linear = 1, diffusion = 0, scatterLoss 0 (extinction, §3.2.1) or 1 (absorption).
/// Calibrated mode: scatterLoss = 1 and the fitted weights (SslpvCalibration; the second term
/// is (σ_tr·Δx)², σ_tr = √(3σa σt′), Jensen et al. 2001 Eq. 5).
struct AttenuationModel {
    float scatterLoss = 0.f;
    float linear = 1.f;
    float transport = 0.f;  ///< weight of σ_tr·Δx = √(3σaσt)·Δx
    float diffusion = 0.f;
    float perStep = 0.f;           ///< weight of 1 − α′ = σa/σt (cell-size independent)
    float perStepTransport = 0.f;  ///< weight of σ_tr/σt = √(3(1 − α′)) (likewise)
};

// The two hot kernels below are compiled for x86-64-v4, v3 and baseline, one picked at load
// time by an ifunc resolver. ThreadSanitizer instruments that resolver, which the dynamic
// loader runs before TSan's runtime is initialised (a segfault at start-up, GCC 12): the
// `tsan` preset compiles the baseline only.
#if defined(__SANITIZE_THREAD__)
#define LUCENT_ISA_CLONES
#else
#define LUCENT_ISA_CLONES \
    __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif

AttenuationModel attenuationModel(const SslpvOptions& o) {
    if (o.mode == SslpvMode::Calibrated)
        return {1.f,
                o.calibration.linear,
                o.calibration.transport,
                o.calibration.diffusion,
                o.calibration.perStep,
                o.calibration.perStepTransport};
    return {o.attenuation == SslpvAttenuation::Extinction ? 0.f : 1.f, 1.f, 0.f, 0.f, 0.f, 0.f};
}

/// Per-cell factors of one row (§3.2.1 and Eq. 3): f_l = a·((1 − s′) + s′ g^l) with
/// a = exp(−β) (AttenuationModel), s′ = 1 − exp(−σs′ Δx). Cloned like the propagation kernel
/// so the polynomial exp vectorises (16 cells per AVX-512 instruction).
LUCENT_ISA_CLONES void foldFactorRow(const float* __restrict st, const float* __restrict ssIn,
                                     const float* __restrict gg, float* __restrict f0,
                                     float* __restrict f1, float* __restrict f2, int n, float dx,
                                     AttenuationModel model) {
    const float scatterLoss = model.scatterLoss;  // σatt = σt − scatterLoss·σs′
    const float lin = model.linear * dx;
    const float quad = model.diffusion * dx * dx;
    const float tr = model.transport * dx;
    for (int x = 0; x < n; ++x) {
        const float ss = ssIn[x] < st[x] ? ssIn[x] : st[x];
        const float sFrac = 1.f - expNonPositive(-ss * dx);
        const float tr2 = 3.f * (st[x] - ss) * st[x];  // σ_tr² (Jensen et al. 2001, Eq. 5)
        const float absorbing = st[x] > 0.f ? (st[x] - ss) / st[x] : 0.f;  // 1 − α′
        const float a = expNonPositive((scatterLoss * ss - st[x]) * lin - tr * std::sqrt(tr2) -
                                       quad * tr2 - model.perStep * absorbing -
                                       model.perStepTransport * std::sqrt(3.f * absorbing));
        const float keep = 1.f - sFrac;
        f0[x] = a;
        f1[x] = a * (keep + sFrac * gg[x]);
        f2[x] = a * (keep + sFrac * gg[x] * gg[x]);
    }
}

/// One non-zero entry of a propagation matrix, as a shifted read of a source plane.
struct Term {
    int srcCoeff;
    std::ptrdiff_t offset;  ///< padded linear offset of the source cell from the destination
    float weight;
};

/// Order-1 weights of one neighbour along axis a (dipole coefficient k): the only non-zero
/// entries of M_o by symmetry (§4).
struct L1Weights {
    std::ptrdiff_t offset = 0;
    int k = 3, a = 1, b = 2;  ///< k: the axis' coefficient; a, b: the other two dipole ones
    float w00 = 0.f, w0k = 0.f, wk0 = 0.f, wkk = 0.f, waa = 0.f, wbb = 0.f;
};

/// Everything one propagation step needs; raw pointers into the solver's arrays.
struct StepCtx {
    int coeffs = 4;
    const std::vector<Term>* terms = nullptr;  ///< [coeffs]
    const float* src[3][SSLPV_MAX_COEFFS] = {};
    float* dst[3][SSLPV_MAX_COEFFS] = {};
    float* acc[3][SSLPV_MAX_COEFFS] = {};   ///< null: do not accumulate this step
    float* exit[3][SSLPV_MAX_COEFFS] = {};  ///< null: no sinks
    bool assignAcc = false;                 ///< first accumulated step: acc = c, not +=
    bool assignExit = false;                ///< first step: exit = leave, not +=
    const float* mask = nullptr;            ///< null: no sinks
    const float* factor[3][3] = {};         ///< null: homogeneous (use homFactor)
    bool perCellFactors = false;  ///< absorbed = Σc − Σc·a (no separate 1 − a planes)
    float homFactor[3][3] = {};
    float homAbsorb[3] = {};
    CoordBox box;
    int padded = 0;
    bool l1 = false;  ///< order 1 with the symmetric sparsity: use l1w instead of terms
    L1Weights l1w[6];
    /// Per-brick stop threshold on |coefficient| (SslpvOptions::brickStopEpsilon); 0: off.
    float dark = 0.f;
};

/// Sums of one z-slice: [channel] × {remaining, exitant, absorbed, dropped}; bricks computed
/// and lit after the step; cells computed.
struct SliceSums {
    double v[3][4] = {};
    int activeBricks = 0;
    int litBricks = 0;
    int64_t cells = 0;
};

constexpr int VEC = 8;  ///< floats per GCC vector below (AVX2 register; two SSE ones otherwise)
typedef float Vec16 __attribute__((vector_size(2 * VEC * sizeof(float))));
typedef int32_t Vec16i __attribute__((vector_size(2 * VEC * sizeof(int32_t))));

// Unaligned 16-float load/store as macros: helper functions returning vectors would be
// compiled for the baseline ABI outside the cloned kernel (GCC -Wpsabi).
#define LUCENT_LOAD16(ptr)                        \
    ({                                            \
        Vec16 v_;                                 \
        __builtin_memcpy(&v_, (ptr), sizeof(v_)); \
        v_;                                       \
    })
#define LUCENT_STORE16(ptr, val)                  \
    do {                                          \
        const Vec16 s_ = (val);                   \
        __builtin_memcpy((ptr), &s_, sizeof(s_)); \
    } while (false)

// The propagation kernel for one z-slice. Compiled for x86-64-v4 (AVX-512), v3 (AVX2+FMA)
// and baseline, picked at load time. Rows are processed in blocks of 32 x-consecutive cells:
// first the gather of §4, c_d,i = Σ_o Σ_j M_o[i][j] c_{d+o,j}, for every output coefficient
// into a small block buffer, then per coefficient the post-processing (sinks, accumulation,
// the next step's folded factors, energy sums). Order 1 uses the matrices' sparsity (§4: a
// neighbour along axis a couples only c00 with its own dipole coefficient, the other two are
// scaled): 24 shifted loads and 36 FMAs per 32 cells instead of 36 loads; order 2 walks the
// generic term list over 4 independent accumulator pairs to hide the FMA latency.
//
// One call computes the run of `len` cells starting at (xStart, y, z) and writes into nz[x]
// (x relative to xStart, len entries) the cell's flags over its new propagation values: bit
// NZ_ANY when one is non-zero, bit NZ_BRIGHT when one exceeds ctx.dark in magnitude (with
// ctx.dark = 0: when one is non-zero), from which the caller derives the bricks lit after
// this step.
constexpr int32_t NZ_ANY = 1;
constexpr int32_t NZ_BRIGHT = 2;

LUCENT_ISA_CLONES void processRun(const StepCtx& ctx, int z, int y, int xStart, int len,
                                  SliceSums& sums, int32_t* nz) {
    const size_t p = size_t(ctx.padded);
    // |value| > ctx.dark compared on the bits: non-negative floats order as their bit patterns
    // (a NaN counts as bright).
    int32_t darkBits;
    __builtin_memcpy(&darkBits, &ctx.dark, sizeof(darkBits));
    constexpr int BLOCK = 4 * VEC;  // 32 cells
    alignas(64) float out[SSLPV_MAX_COEFFS][BLOCK];
    {
        const size_t base = (size_t(z + 1) * p + size_t(y + 1)) * p + size_t(xStart + 1);
        for (int ch = 0; ch < 3; ++ch) {
            Vec16 remV = {}, absV = {}, exitV = {};
            float remS = 0.f, absS = 0.f, exitS = 0.f;
            for (int x0 = 0; x0 < len; x0 += BLOCK) {
                // ---- gather
                if (ctx.l1) {
                    const float* s[4];
                    for (int j = 0; j < 4; ++j)
                        s[j] = ctx.src[ch][j] + base + x0;
                    Vec16 o[4][2] = {};
                    // Neighbour NB along the axis whose dipole coefficient is K (A, B: the
                    // other two); literal indices keep o[][] and s[] in registers.
#define LUCENT_NEIGHBOUR(NB, K, A, B)                                                 \
    do {                                                                              \
        const L1Weights& w = ctx.l1w[NB];                                             \
        for (int h = 0; h < 2; ++h) {                                                 \
            const std::ptrdiff_t at = w.offset + h * 2 * VEC;                         \
            const Vec16 s0 = LUCENT_LOAD16(s[0] + at), sk = LUCENT_LOAD16(s[K] + at); \
            o[0][h] += w.w00 * s0 + w.w0k * sk;                                       \
            o[K][h] += w.wk0 * s0 + w.wkk * sk;                                       \
            o[A][h] += w.waa * LUCENT_LOAD16(s[A] + at);                              \
            o[B][h] += w.wbb * LUCENT_LOAD16(s[B] + at);                              \
        }                                                                             \
    } while (false)
                    LUCENT_NEIGHBOUR(0, 3, 1, 2);  // +x
                    LUCENT_NEIGHBOUR(1, 3, 1, 2);  // −x
                    LUCENT_NEIGHBOUR(2, 1, 2, 3);  // +y
                    LUCENT_NEIGHBOUR(3, 1, 2, 3);  // −y
                    LUCENT_NEIGHBOUR(4, 2, 1, 3);  // +z
                    LUCENT_NEIGHBOUR(5, 2, 1, 3);  // −z
#undef LUCENT_NEIGHBOUR
                    for (int i = 0; i < 4; ++i) {
                        LUCENT_STORE16(out[i], o[i][0]);
                        LUCENT_STORE16(out[i] + 2 * VEC, o[i][1]);
                    }
                } else {
                    for (int i = 0; i < ctx.coeffs; ++i) {
                        const std::vector<Term>& terms = ctx.terms[i];
                        const int nt = int(terms.size());
                        Vec16 a[4][2] = {};
                        for (int t = 0; t < nt; t += 4) {
                            for (int u = 0; u < 4; ++u) {
                                const Term& tm = terms[t + u];
                                const float* q = ctx.src[ch][tm.srcCoeff] + base + tm.offset + x0;
                                a[u][0] += tm.weight * LUCENT_LOAD16(q);
                                a[u][1] += tm.weight * LUCENT_LOAD16(q + 2 * VEC);
                            }
                        }
                        LUCENT_STORE16(out[i], (a[0][0] + a[1][0]) + (a[2][0] + a[3][0]));
                        LUCENT_STORE16(out[i] + 2 * VEC, (a[0][1] + a[1][1]) + (a[2][1] + a[3][1]));
                    }
                }
                // ---- post-processing per coefficient
                // 16-cell halves done with vectors: both for a full block, else as many as fit.
                const int halves = x0 + BLOCK <= len ? 2 : (len - x0) / (2 * VEC);
                Vec16i nzv[2] = {};  // NZ_ANY | NZ_BRIGHT over the coefficients
                const size_t bx = base + size_t(x0);
                const float* msk = ctx.mask ? ctx.mask + bx : nullptr;
                for (int i = 0; i < ctx.coeffs; ++i) {
                    const int band = bandOf(i);
                    const float* fac = ctx.factor[ch][band] ? ctx.factor[ch][band] + bx : nullptr;
                    const float homF = ctx.homFactor[ch][band];
                    float* ex = ctx.exit[ch][i] ? ctx.exit[ch][i] + bx : nullptr;
                    float* ac = ctx.acc[ch][i] ? ctx.acc[ch][i] + bx : nullptr;
                    float* ds = ctx.dst[ch][i] + bx;
                    const bool sum = i == 0;
                    {
                        for (int h = 0; h < halves; ++h) {
                            const int x = h * 2 * VEC;
                            Vec16 o = LUCENT_LOAD16(out[i] + x);
                            // Sinks: flux reaching a cell outside the object leaves it.
                            if (msk) {
                                const Vec16 m = LUCENT_LOAD16(msk + x);
                                const Vec16 leave = o * (1.f - m);
                                LUCENT_STORE16(
                                    ex + x, ctx.assignExit ? leave : LUCENT_LOAD16(ex + x) + leave);
                                if (sum)
                                    exitV += leave;
                                o *= m;
                            }
                            if (ac)
                                LUCENT_STORE16(ac + x,
                                               ctx.assignAcc ? o : LUCENT_LOAD16(ac + x) + o);
                            // The next step's per-source factors: Beer attenuation (§3.2.1)
                            // times the scattering reweighting of band l (Eq. 3).
                            const Vec16 d = fac ? o * LUCENT_LOAD16(fac + x) : o * homF;
                            LUCENT_STORE16(ds + x, d);
                            Vec16i magnitude;  // |d|'s bits: ordered as |d| is
                            __builtin_memcpy(&magnitude, &d, sizeof(magnitude));
                            magnitude &= 0x7fffffff;
                            nzv[h] |= ((d != 0.f) & NZ_ANY) | ((magnitude > darkBits) & NZ_BRIGHT);
                            if (sum) {
                                remV += d;
                                absV += o;
                            }
                        }
                        if (i + 1 == ctx.coeffs)
                            for (int h = 0; h < halves; ++h) {
                                Vec16i m = nzv[h];
                                if (ch > 0) {
                                    Vec16i prev;
                                    __builtin_memcpy(&prev, nz + x0 + h * 2 * VEC, sizeof(prev));
                                    m |= prev;
                                }
                                __builtin_memcpy(nz + x0 + h * 2 * VEC, &m, sizeof(m));
                            }
                    }
                    // Row tail (fewer than 16 cells left): scalar, same operations.
                    const int blockLen = std::min(len - x0, BLOCK);
                    for (int x = halves * 2 * VEC; x < blockLen; ++x) {
                        float v = out[i][x];
                        if (msk) {
                            const float leave = v * (1.f - msk[x]);
                            ex[x] = ctx.assignExit ? leave : ex[x] + leave;
                            if (sum)
                                exitS += leave;
                            v *= msk[x];
                        }
                        if (ac)
                            ac[x] = ctx.assignAcc ? v : ac[x] + v;
                        const float d = v * (fac ? fac[x] : homF);
                        ds[x] = d;
                        nz[x0 + x] = (ch > 0 || i > 0 ? nz[x0 + x] : 0) | (d != 0.f ? NZ_ANY : 0) |
                                     (std::abs(d) > ctx.dark ? NZ_BRIGHT : 0);
                        if (sum) {
                            remS += d;
                            absS += v;
                        }
                    }
                }
            }
            for (int k = 0; k < 2 * VEC; ++k) {
                remS += remV[k];
                absS += absV[k];
                exitS += exitV[k];
            }
            sums.v[ch][0] += remS;
            sums.v[ch][1] += exitS;
            // Absorbed this step: Σ c00 (1 − a) — with per-cell factors as Σ c00 − Σ c00·a,
            // the latter being the remaining sum (band-0 factor = a).
            sums.v[ch][2] += ctx.perCellFactors ? absS - remS : absS * ctx.homAbsorb[ch];
        }
    }
}

#undef LUCENT_LOAD16
#undef LUCENT_STORE16

}  // namespace

// ---------------------------------------------------------------------------------------------
// SslpvGrid

SslpvGrid::SslpvGrid(int resolution, int order)
    : m_res(resolution), m_order(order), m_coeffs(shCount(order)) {
    LUCENT_CHECK(resolution >= 1 && resolution <= 1022, "SSLPV grid: resolution ", resolution,
                 " outside [1, 1022]");
    LUCENT_CHECK(order == 1 || order == 2, "SSLPV grid: SH order must be 1 or 2, got ", order);
    const size_t p = size_t(resolution + 2);
    m_planeSize = p * p * p;
    // Slack after the last plane: the vector kernel reads whole 32-float blocks past a row end.
    m_data.assign(m_planeSize * CHANNELS * m_coeffs + 64, 0.f);
}

void SslpvGrid::clear() {
    std::fill(m_data.begin(), m_data.end(), 0.f);
}

Rgb SslpvGrid::flux() const {
    Rgb r(0.f);
    if (m_data.empty())
        return r;
    for (int ch = 0; ch < CHANNELS; ++ch) {
        const float* c = plane(ch, 0);
        double s = 0.0;
        for (size_t k = 0; k < m_planeSize; ++k)
            s += c[k];
        r[ch] = float(s * TWO_SQRT_PI);
    }
    return r;
}

float SslpvGrid::maxAbs() const {
    float m = 0.f;
    for (float v : m_data) {
        if (std::isnan(v))
            return v;
        m = std::max(m, std::abs(v));
    }
    return m;
}

bool SslpvGrid::isFinite() const {
    return std::all_of(m_data.begin(), m_data.end(), [](float v) { return std::isfinite(v); });
}

// ---------------------------------------------------------------------------------------------
// SslpvSolver

SslpvSolver::SslpvSolver(const SslpvOptions& options) {
    setOptions(options);
}

SslpvCalibration defaultSslpvCalibration() {
    // Fitted by `lucent-cli bench sslpv-fit` (order 1) and `... --sh 2` (gain of order 2)
    // against the classical dipole's thick-slab reflectance, α′ ∈ [0.3, 0.99],
    // Δx·σt ∈ {0.5, 1, 2, 4}, η = 1.3 (docs/methods/sslpv.md, "Calibrated mode": the per-case
    // β* table shows the matching per-step absorption is nearly independent of Δx, so only the
    // per-step terms are used; the residual table is there too).
    SslpvCalibration c;
    c.linear = 0.f;
    c.transport = 0.f;
    c.diffusion = 0.f;
    c.perStep = 0.4795f;
    c.perStepTransport = 0.1388f;
    c.gain[0] = 0.9792f;
    c.gain[1] = 1.0681f;
    return c;
}

void SslpvSolver::setOptions(const SslpvOptions& o) {
    LUCENT_CHECK(o.order == 1 || o.order == 2, "SSLPV option 'order' must be 1 or 2, got ",
                 o.order);
    LUCENT_CHECK(o.maxSteps >= 0 && o.maxSteps <= 4096,
                 "SSLPV option 'maxSteps' must be in [0, 4096], got ", o.maxSteps);
    LUCENT_CHECK(o.skipAccumulateSteps >= 0,
                 "SSLPV option 'skipAccumulateSteps' must be >= 0, got ", o.skipAccumulateSteps);
    const SslpvCalibration& cal = o.calibration;
    for (const float w :
         {cal.linear, cal.transport, cal.diffusion, cal.perStep, cal.perStepTransport})
        LUCENT_CHECK(std::isfinite(w) && w >= 0.f,
                     "SSLPV option 'calibration': linear, transport, diffusion, perStep and "
                     "perStepTransport must be finite and >= 0, got ",
                     cal.linear, ", ", cal.transport, ", ", cal.diffusion, ", ", cal.perStep, ", ",
                     cal.perStepTransport);
    LUCENT_CHECK(std::isfinite(cal.gain[0]) && cal.gain[0] > 0.f && std::isfinite(cal.gain[1]) &&
                     cal.gain[1] > 0.f,
                 "SSLPV option 'calibration.gain' must be finite and > 0, got ", cal.gain[0], ", ",
                 cal.gain[1]);
    LUCENT_CHECK(o.mode == SslpvMode::Paper || o.mode == SslpvMode::Calibrated ||
                     o.mode == SslpvMode::Diffusion,
                 "SSLPV option 'mode' is not Paper, Calibrated or Diffusion");
    LUCENT_CHECK(std::isfinite(o.stopEpsilon) && o.stopEpsilon >= 0.f && o.stopEpsilon <= 1.f,
                 "SSLPV option 'stopEpsilon' must be in [0, 1], got ", o.stopEpsilon);
    LUCENT_CHECK(
        std::isfinite(o.brickStopEpsilon) && o.brickStopEpsilon >= 0.f && o.brickStopEpsilon <= 1.f,
        "SSLPV option 'brickStopEpsilon' must be in [0, 1], got ", o.brickStopEpsilon);
    // Order and sinks change where light is injected, the entry depths what mode Diffusion's
    // walk keeps; everything changes propagation.
    if (o.order != m_opt.order || o.removeExitant != m_opt.removeExitant || o.mode != m_opt.mode ||
        o.diffusionEntryDepth != m_opt.diffusionEntryDepth)
        m_injectionDirty = true;
    m_opt = o;
    m_materialDirty = true;
    m_factorsDirty = true;
    m_refoldAll = true;
    ++m_readableVersion;
    m_exitTable = nullptr;  // the next diffusion solve sets it (its grid holds the albedo)
}

namespace {

void validateCell(const CoarseMaterial& m, size_t k, int c) {
    const float st = m.sigma_t[c][k], ss = m.sigma_s[c][k], g = m.g[c][k];
    if (!(std::isfinite(st) && st >= 0.f) || !(std::isfinite(ss) && ss >= 0.f) ||
        !(std::isfinite(g) && std::abs(g) <= 1.f)) {
        LUCENT_THROW(ValueError, "SSLPV material: cell ", k, " channel ", c, " has sigma_t=", st,
                     " sigma_s=", ss, " g=", g,
                     " (need finite sigma_t, sigma_s >= 0 mm^-1 and |g| <= 1)");
    }
}

}  // namespace

void SslpvSolver::markMaterialCellsDirty(const std::vector<int>& cells) {
    LUCENT_CHECK(m_hasMaterial, "SSLPV: markMaterialCellsDirty() called before setMaterial()");
    const int n = m_material.spec.resolution;
    const size_t count = m_material.spec.voxelCount();
    for (const int k : cells) {
        LUCENT_CHECK(k >= 0 && size_t(k) < count, "SSLPV: markMaterialCellsDirty: cell ", k,
                     " outside [0, ", count, ")");
        for (int c = 0; c < 3; ++c)
            validateCell(m_material, size_t(k), c);
    }
    m_materialDirty = true;
    if (!m_factorsDirty) {
        m_factorsDirty = true;
        m_refoldAll = false;
        m_refoldRows.clear();
    }
    if (!m_refoldAll)
        for (const int k : cells)
            m_refoldRows.push_back(k / n);
}

void SslpvSolver::validateMaterial(const CoarseMaterial& m) const {
    const GridSpec& s = m.spec;
    LUCENT_CHECK(s.resolution >= 1 && s.resolution <= 1022, "SSLPV material: spec.resolution ",
                 s.resolution, " outside [1, 1022]");
    LUCENT_CHECK(std::isfinite(s.voxelSize) && s.voxelSize > 0.f,
                 "SSLPV material: spec.voxelSize must be finite and > 0 mm, got ", s.voxelSize);
    LUCENT_CHECK(lucent::isFinite(s.origin), "SSLPV material: spec.origin is not finite");
    const size_t n = s.voxelCount();
    const char* names[3] = {"sigma_t", "sigma_s", "g"};
    for (int c = 0; c < 3; ++c) {
        const std::vector<float>* arrays[3] = {&m.sigma_t[c], &m.sigma_s[c], &m.g[c]};
        for (int a = 0; a < 3; ++a) {
            LUCENT_CHECK(arrays[a]->size() == n, "SSLPV material: ", names[a], "[", c, "] has ",
                         arrays[a]->size(), " values, expected ", n);
        }
        for (size_t k = 0; k < n; ++k)
            validateCell(m, k, c);
    }
    LUCENT_CHECK(m.insideFraction.size() == n, "SSLPV material: insideFraction has ",
                 m.insideFraction.size(), " values, expected ", n);
}

void SslpvSolver::setMaterial(const CoarseMaterial& material, float eta) {
    setMaterial(CoarseMaterial(material), eta);
}

void SslpvSolver::setMaterial(CoarseMaterial&& material, float eta) {
    validateMaterial(material);
    LUCENT_CHECK(std::isfinite(eta) && eta >= 1.f && eta <= 3.f,
                 "SSLPV: eta must be in [1, 3], got ", eta);
    const bool regrid = !m_hasMaterial || !(material.spec == m_material.spec);
    const bool insideChanged = regrid || material.insideFraction != m_material.insideFraction;
    m_material = std::move(material);
    if (regrid || insideChanged || eta != m_eta)
        m_injectionDirty = true;
    if (regrid || insideChanged)
        ++m_readableVersion;
    m_eta = eta;
    m_hasMaterial = true;
    m_materialDirty = true;
    m_factorsDirty = true;
    m_refoldAll = true;
}

void SslpvSolver::setInjectionSamples(std::vector<SslpvInjectionSample> samples) {
    m_samples = std::move(samples);
    m_injectionDirty = true;
}

bool SslpvSolver::isReadable(const Coord& c) const {
    if (!isInside(c))
        return false;
    return m_opt.mode != SslpvMode::Diffusion ||
           m_diffusion.isBoundary(m_material.spec.linearIndex(c));
}

float SslpvSolver::readoutAlpha(const Coord& c) const {
    if (isReadable(c))
        return 1.f;
    const GridSpec& s = m_material.spec;
    if (!m_hasMaterial || !s.contains(c))
        return 0.f;
    return std::min(m_material.insideFraction[s.linearIndex(c)], 0.5f);
}

bool SslpvSolver::isInside(const Coord& c) const {
    const GridSpec& s = m_material.spec;
    return m_hasMaterial && s.contains(c) && m_material.insideFraction[s.linearIndex(c)] >= 0.5f;
}

void SslpvSolver::rebuildFactors() {
    const GridSpec& s = m_material.spec;
    const int n = s.resolution;
    const float dx = s.voxelSize;
    const size_t plane = size_t(n + 2) * (n + 2) * (n + 2);
    auto padded = [&](int x, int y, int z) {
        return (size_t(z + 1) * (n + 2) + size_t(y + 1)) * (n + 2) + size_t(x + 1);
    };

    // Per-cell factors for every channel and band (§3.2.1 and Eq. 3). The paper's σs′ is a
    // dimensionless per-step fraction; ours is mm⁻¹, converted per cell as the probability of
    // scattering over one cell width, s′ = 1 − exp(−σs′·Δx) (docs/methods/sslpv.md).
    const AttenuationModel model = attenuationModel(m_opt);
    auto cellFactors = [&](size_t k, int c, float f[3], float& absorb) {  // homogeneous path
        const float st = m_material.sigma_t[c][k];
        const float ss = std::min(m_material.sigma_s[c][k], st);
        const float g = m_material.g[c][k];
        const float sFrac = 1.f - expNonPositive(-ss * dx);
        const float tr2 = 3.f * (st - ss) * st;  // σ_tr² (Jensen et al. 2001, Eq. 5)
        const float absorbing = st > 0.f ? (st - ss) / st : 0.f;  // 1 − α′
        const float a = expNonPositive(-(st - model.scatterLoss * ss) * model.linear * dx -
                                       model.transport * dx * std::sqrt(tr2) -
                                       model.diffusion * dx * dx * tr2 - model.perStep * absorbing -
                                       model.perStepTransport * std::sqrt(3.f * absorbing));
        f[0] = a;  // band 0: Eq. 3 leaves c00 unchanged
        f[1] = a * ((1.f - sFrac) + sFrac * g);
        f[2] = a * ((1.f - sFrac) + sFrac * g * g);
        absorb = 1.f - a;
    };

    // After markMaterialCellsDirty alone the inside cells, so the sinks, the active box and the
    // cells that hold light, are as they were, and of a heterogeneous material only the named
    // rows need refolding (the same row calls as a full refold: bit-identical factors).
    const bool rowsOnly = !m_refoldAll && !m_homogeneous && m_factor[0][0].size() == plane;
    m_refoldAll = false;
    std::vector<int> rows;
    if (rowsOnly) {
        rows.swap(m_refoldRows);
        std::sort(rows.begin(), rows.end());
        rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    }
    m_refoldRows.clear();

    if (!rowsOnly) {
        // Sinks: a cell keeps min(1, 2f) of the light that enters it, f its insideFraction, and the
        // rest leaves the object. Inside cells (f ≥ ½) keep everything, as with a binary mask; a
        // cell the surface cuts with f < ½ is a partial sink, so the lattice's boundary follows
        // the surface within a cell instead of the voxel staircase (a binary mask leaks through
        // every stair riser: a slab tilted 20–45° against the grid read 14–18 % darker than one
        // aligned with it, and the stair pattern shows as contour bands).
        m_mask.assign(m_opt.removeExitant ? plane : 0, 0.f);
        m_lightCells = 0;
        Bounds3f insideBox;
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    const float f = m_material.insideFraction[s.linearIndex({x, y, z})];
                    if (!(f > 0.f))
                        continue;
                    ++m_lightCells;
                    if (m_opt.removeExitant)
                        m_mask[padded(x, y, z)] = std::min(1.f, 2.f * f);
                    insideBox.expand(Point3f(float(x), float(y), float(z)));
                }
        if (m_opt.removeExitant) {
            // Light can only exist in cells with f > 0 and the sink cells one step away.
            if (insideBox.isEmpty()) {
                m_active = CoordBox{};
            } else {
                m_active.lo = glm::max(Coord(insideBox.lo) - Coord(1), Coord(0));
                m_active.hi = glm::min(Coord(insideBox.hi) + Coord(1), Coord(n - 1));
            }
        } else {
            m_active.lo = Coord(0);
            m_active.hi = Coord(n - 1);
        }
    }

    // Homogeneous fast path: every cell that can carry light to a neighbour has the same
    // factors (inside cells with sinks, all cells without).
    bool hom = true;
    size_t ref = SIZE_MAX;
    for (size_t k = 0; k < s.voxelCount() && hom; ++k) {
        if (m_opt.removeExitant && m_material.insideFraction[k] < 0.5f)
            continue;
        if (ref == SIZE_MAX) {
            ref = k;
            continue;
        }
        for (int c = 0; c < 3; ++c)
            if (m_material.sigma_t[c][k] != m_material.sigma_t[c][ref] ||
                m_material.sigma_s[c][k] != m_material.sigma_s[c][ref] ||
                m_material.g[c][k] != m_material.g[c][ref])
                hom = false;
    }
    m_homogeneous = hom;
    if (hom) {
        m_stats.refoldedRows = 0;
        for (int c = 0; c < 3; ++c) {
            if (ref == SIZE_MAX) {
                m_homFactor[c][0] = m_homFactor[c][1] = m_homFactor[c][2] = 1.f;
                m_homAbsorb[c] = 0.f;
            } else {
                cellFactors(ref, c, m_homFactor[c], m_homAbsorb[c]);
            }
            for (auto& f : m_factor[c])
                f.clear();
        }
        return;
    }
    // Every interior value is rewritten below; the zero border is set once per grid size.
    for (int c = 0; c < 3; ++c) {
        for (auto& f : m_factor[c])
            if (f.size() != plane)
                f.assign(plane, 0.f);
    }
    const auto foldRow = [&](int y, int z) {
        // Row loops over contiguous arrays with the branch-free exp: they vectorise.
        for (int c = 0; c < 3; ++c) {
            const size_t k = s.linearIndex({0, y, z});
            const size_t pk = padded(0, y, z);
            const float* __restrict st = &m_material.sigma_t[c][k];
            const float* __restrict ssIn = &m_material.sigma_s[c][k];
            const float* __restrict gg = &m_material.g[c][k];
            float* __restrict f0 = &m_factor[c][0][pk];
            float* __restrict f1 = &m_factor[c][1][pk];
            float* __restrict f2 = &m_factor[c][2][pk];
            foldFactorRow(st, ssIn, gg, f0, f1, f2, n, dx, model);
        }
    };
    m_stats.refoldedRows = rowsOnly ? int64_t(rows.size()) : int64_t(n) * n;
    if (rowsOnly) {
        parallelFor(
            0, int64_t(rows.size()),
            [&](int64_t r0, int64_t r1) {
                for (int64_t r = r0; r < r1; ++r)
                    foldRow(rows[size_t(r)] % n, rows[size_t(r)] / n);
            },
            /*grain=*/16);
        return;
    }
    parallelFor(
        0, n,
        [&](int64_t z0, int64_t z1) {
            for (int z = int(z0); z < int(z1); ++z)
                for (int y = 0; y < n; ++y)
                    foldRow(y, z);
        },
        /*grain=*/1);
}

Rgb SslpvSolver::interactingFraction(const Point3f& entry, const Vector3f& wt,
                                     const Coord& injectionCell, BeamSegment* chord,
                                     const CoarseMaterial* sigmaT) const {
    // Optical depth τ of the refracted beam's chord, by midpoint samples every half cell from
    // the entry point until the beam leaves the medium (the object's inside cells with sinks,
    // the whole grid without) or every channel is opaque. A concave object's re-entry is not
    // followed: light leaving the object is refracted out there, not carried on.
    const GridSpec& s = m_material.spec;
    const CoarseMaterial& optics = sigmaT ? *sigmaT : m_material;
    const float step = 0.5f * s.voxelSize;
    constexpr float OPAQUE_DEPTH = 20.f;  // e^−20 = 2·10⁻⁹: below float resolution of 1 − e^−τ
    const int maxSamples = 4 * s.resolution;  // a half-cell step crosses the grid in ≤ 2√3·N
    auto isMedium = [&](const Coord& c) {
        return m_opt.removeExitant ? isInside(c) : s.contains(c);
    };
    Rgb tau(0.f);
    bool entered = false;
    int walked = 0;  // samples taken (the chord ends at the last one)
    for (int k = 0; k < maxSamples; ++k) {
        walked = k + 1;
        const Coord c = s.cellOf(entry + (float(k) + 0.5f) * step * wt);
        if (!isMedium(c)) {
            // Before the medium (the entry point lies on the mesh, the voxelised surface is a
            // staircase around it) keep looking for up to two cells; after it, the beam is out.
            if (entered || k >= 4)
                break;
            continue;
        }
        entered = true;
        const size_t i = s.linearIndex(c);
        for (int ch = 0; ch < 3; ++ch)
            tau[ch] += optics.sigma_t[ch][i] * step;
        if (tau.x > OPAQUE_DEPTH && tau.y > OPAQUE_DEPTH && tau.z > OPAQUE_DEPTH)
            break;
    }
    const auto toGrid = [&](const Point3f& p) { return (p - s.origin) / s.voxelSize; };
    if (chord)
        *chord = {toGrid(entry), toGrid(entry + (float(walked) + 0.5f) * step * wt)};
    if (!entered) {
        // The staircase missed the beam: one cell of the injection cell's material.
        const size_t i = s.linearIndex(injectionCell);
        for (int ch = 0; ch < 3; ++ch)
            tau[ch] = optics.sigma_t[ch][i] * s.voxelSize;
        if (chord)
            *chord = {Vector3f(injectionCell) + 0.5f, Vector3f(injectionCell) + 0.5f};
    }
    Rgb f;
    for (int ch = 0; ch < 3; ++ch)
        f[ch] = -std::expm1(-tau[ch]);
    return f;
}

void SslpvSolver::inject() {
    const Timer timer;
    const GridSpec& s = m_material.spec;
    const int count = shCount(m_opt.order);
    if (m_injection.resolution() != s.resolution || m_injection.order() != m_opt.order)
        m_injection = SslpvGrid(s.resolution, m_opt.order);
    else
        m_injection.clear();
    int used = 0, skipped = 0;
    const int bricksX = (s.resolution + SSLPV_BRICK_X - 1) / SSLPV_BRICK_X;
    const int bricksY = (s.resolution + SSLPV_BRICK_Y - 1) / SSLPV_BRICK_Y;
    m_injBrickLit.assign(size_t(s.resolution) * bricksX * bricksY, 0);
    // What an incremental re-injection needs (reinjectChangedChords): each texel's cell,
    // deposit and chord, and the material they were computed with.
    m_injectionCell.assign(m_samples.size(), UINT32_MAX);
    m_injectionFraction.assign(m_samples.size(), Rgb(0.f));
    m_beamSegments.assign(m_samples.size(), BeamSegment{});
    m_sourceMaterial = m_material;
    m_incrementalInjections = 0;
    m_stats.rewalkedTexels = 0;
    const float h = s.voxelSize;
    for (size_t j = 0; j < m_samples.size(); ++j) {
        const SslpvInjectionSample& smp = m_samples[j];
        if (!isInjectable(smp)) {
            ++skipped;
            continue;
        }
        const float cosI = -glm::dot(smp.direction, smp.normal);
        // The texel's cell (§3.1): taken half a cell inside along −n so the virtual point light
        // lands in a boundary cell of the object; with sinks it must be an inside cell.
        Coord cell(-1);
        for (float depth : {0.5f, 1.0f, 0.0f, 1.5f}) {
            const Coord c = s.cellOf(smp.position - depth * h * smp.normal);
            if (!s.contains(c))
                continue;
            if (m_opt.removeExitant && !isInside(c))
                continue;
            cell = c;
            break;
        }
        if (cell.x < 0) {
            ++skipped;
            continue;
        }
        // Eq. 1: I_p(ω) = (1/π) T(ω_p, ω_t) Φ_p max(0, ω_t·ω), T exact dielectric Fresnel
        // transmittance, ω_t from Snell's law; projected on SH with the clamped-cosine zonal
        // coefficients √π/2, √(π/3), √(5π)/8 (the SSLPV project page errata).
        const float T = 1.f - fresnelDielectric(cosI, m_eta);
        const Vector3f wt = refractInto(smp.direction, smp.normal, m_eta);
        const Rgb interacting = interactingFraction(smp.position, wt, cell, &m_beamSegments[j]);
        const ShCoeffs<2> lobe = clampedCosineLobe<2>(wt);
        const size_t idx = m_injection.index(cell);
        m_injBrickLit[(size_t(cell.z) * bricksY + size_t(cell.y / SSLPV_BRICK_Y)) * bricksX +
                      size_t(cell.x / SSLPV_BRICK_X)] = 1;
        for (int ch = 0; ch < 3; ++ch) {
            const float k = T * interacting[ch] * smp.flux[ch] * INV_PI;
            for (int i = 0; i < count; ++i)
                m_injection.plane(ch, i)[idx] += k * lobe.c[i];
        }
        m_injectionCell[j] = uint32_t(s.linearIndex(cell));
        m_injectionFraction[j] = interacting;
        ++used;
    }
    m_stats.injectedTexels = used;
    m_stats.skippedTexels = skipped;
    m_stats.injectMs = timer.elapsedMs();
}

struct SslpvSolver::StepKernel {
    std::vector<Term> terms[SSLPV_MAX_COEFFS];
    StepCtx ctx;
};

void SslpvSolver::propagate() {
    const Timer timer;
    const GridSpec& s = m_material.spec;
    const int n = s.resolution;
    const int count = shCount(m_opt.order);
    LUCENT_CHECK(n + 2 <= 1024, "SSLPV: resolution ", n, " too large for the row kernel");
    // Cells outside the active box stay zero (at most rewritten with zeros by a widened SIMD
    // run), so the grids are cleared only when they are new or the box moved; inside it the
    // first write assigns.
    const bool boxMoved = m_active.lo != m_lastActive.lo || m_active.hi != m_lastActive.hi;
    bool cleared = boxMoved;
    for (SslpvGrid* g : {&m_accum, &m_exitant, &m_prop[0], &m_prop[1]}) {
        if (g->resolution() != n || g->order() != m_opt.order) {
            *g = SslpvGrid(n, m_opt.order);
            cleared = true;
        } else if (boxMoved) {
            g->clear();
        }
    }
    // Which bricks of each grid may hold non-zero values (persist across solves, like the
    // grids). prop[0] is rewritten below from the injection, so its bricks are the injected ones.
    static_assert(SSLPV_BRICK_Z == 1, "the step loop below works on one-slice bricks");
    const int bricksX = (n + SSLPV_BRICK_X - 1) / SSLPV_BRICK_X;
    const int bricksY = (n + SSLPV_BRICK_Y - 1) / SSLPV_BRICK_Y;
    const size_t brickTotal = size_t(n) * bricksX * bricksY;
    for (std::vector<uint8_t>* f : {&m_brickLit[1], &m_accBrickLit, &m_exitBrickLit})
        if (cleared || f->size() != brickTotal)
            f->assign(brickTotal, 0);
    m_lastActive = m_active;
    m_run = PropagationRun{};

    // Step 0: the injected lights become the first sources, with their cells' factors folded in.
    // Only bricks holding injected light are computed; bricks of m_prop[0] lit by the previous
    // solve are cleared, so m_prop[0]'s bricks are exactly the injected ones afterwards.
    m_run.injected = m_injection.flux();
    {
        if (cleared || m_brickLit[0].size() != brickTotal)
            m_brickLit[0].assign(brickTotal, 0);
        double ab[3] = {}, rem[3] = {};
        for (int z = 0; z < n; ++z)
            for (int by = 0; by < bricksY; ++by)
                for (int bx = 0; bx < bricksX; ++bx) {
                    const size_t t = (size_t(z) * bricksY + size_t(by)) * bricksX + size_t(bx);
                    const bool lit = m_injBrickLit[t] != 0;
                    if (!lit && !m_brickLit[0][t])
                        continue;
                    m_brickLit[0][t] = uint8_t(lit);
                    const int xa = bx * SSLPV_BRICK_X, xb = std::min(xa + SSLPV_BRICK_X, n);
                    const int ya = by * SSLPV_BRICK_Y, yb = std::min(ya + SSLPV_BRICK_Y, n);
                    for (int y = ya; y < yb; ++y) {
                        const size_t k0 = m_injection.index({xa, y, z});
                        for (int ch = 0; ch < 3; ++ch) {
                            for (int i = 0; i < count; ++i) {
                                const float* in = m_injection.plane(ch, i) + k0;
                                float* out = m_prop[0].plane(ch, i) + k0;
                                const int band = bandOf(i);
                                const float* f =
                                    m_homogeneous ? nullptr : m_factor[ch][band].data() + k0;
                                for (int x = 0; x < xb - xa; ++x)
                                    out[x] = lit ? in[x] * (f ? f[x] : m_homFactor[ch][band]) : 0.f;
                            }
                            if (!lit)
                                continue;
                            const float* c0 = m_injection.plane(ch, 0) + k0;
                            const float* p0 = m_prop[0].plane(ch, 0) + k0;
                            const float* f0 = m_homogeneous ? nullptr : m_factor[ch][0].data() + k0;
                            for (int x = 0; x < xb - xa; ++x) {
                                ab[ch] += double(c0[x]) * (f0 ? 1.f - f0[x] : m_homAbsorb[ch]);
                                rem[ch] += double(p0[x]);
                            }
                        }
                    }
                }
        for (int ch = 0; ch < 3; ++ch) {
            m_run.absorbed[ch] = float(ab[ch] * TWO_SQRT_PI);
            m_run.remaining[ch] = float(rem[ch] * TWO_SQRT_PI);
        }
    }
    m_cur = 0;
    m_stats.activeBricksPerStep.clear();
    m_stats.cellsComputed = 0;

    StepKernel kernel;
    prepareStepKernel(kernel);
    runSteps(kernel, m_opt.maxSteps);
    m_stats.propagateMs = timer.elapsedMs();
}

bool SslpvSolver::propagationInFlight() const {
    return m_opt.mode != SslpvMode::Diffusion && m_hasMaterial && !isDirty() && m_run.inFlight;
}

const SslpvStats& SslpvSolver::continuePropagation(int steps) {
    LUCENT_CHECK(steps >= 1, "SSLPV: continuePropagation(", steps, "): need at least one step");
    LUCENT_CHECK(propagationInFlight(),
                 "SSLPV: continuePropagation() with no propagation in flight (call solve() first)");
    const Timer timer;
    m_stats.reinjected = m_stats.repropagated = false;
    m_stats.refoldedRows = 0;
    StepKernel kernel;
    prepareStepKernel(kernel);
    runSteps(kernel, m_run.steps + steps);
    m_stats.repropagated = true;
    m_stats.propagateMs = timer.elapsedMs();
    return m_stats;
}

void SslpvSolver::prepareStepKernel(StepKernel& kernel) const {
    const int n = m_material.spec.resolution;
    const int count = shCount(m_opt.order);
    StepCtx& ctx = kernel.ctx;
    // Term lists of the gather: c_d,i += Σ_o Σ_j M_o[i][j] c_{d+o, j} (§4).
    const auto& mats = propagationMatrices(m_opt.order);
    const std::ptrdiff_t p = n + 2;
    const std::ptrdiff_t offs[6] = {1, -1, p, -p, p * p, -p * p};
    auto& terms = kernel.terms;
    for (int i = 0; i < count; ++i)
        for (int o = 0; o < 6; ++o)
            for (int j = 0; j < count; ++j) {
                const float w = mats[o].at(i, j);
                // Entries that vanish by symmetry come out of the quadrature at ~1e−17.
                if (std::abs(w) > 1e-7f)
                    terms[i].push_back({j, offs[o], w});
            }
    // Pad every list to a multiple of 4 (the kernel's unroll) with zero-weight reads of the
    // destination cell itself, which is always inside the allocation.
    for (int i = 0; i < count; ++i)
        while (terms[i].size() % 4 != 0)
            terms[i].push_back({0, 0, 0.f});

    ctx.coeffs = count;
    if (m_opt.order == 1) {
        // Check the sparsity the specialised gather relies on; otherwise use the term list.
        const int axisCoeff[3] = {3, 1, 2};
        ctx.l1 = true;
        for (int o = 0; o < 6; ++o) {
            const int axis = o / 2, k = axisCoeff[axis];
            L1Weights& w = ctx.l1w[o];
            w.offset = offs[o];
            w.k = k;
            w.a = k == 1 ? 2 : 1;
            w.b = k == 3 ? 2 : 3;
            w.w00 = mats[o].at(0, 0);
            w.w0k = mats[o].at(0, k);
            w.wk0 = mats[o].at(k, 0);
            w.wkk = mats[o].at(k, k);
            w.waa = mats[o].at(w.a, w.a);
            w.wbb = mats[o].at(w.b, w.b);
            for (int i = 0; i < 4; ++i)
                for (int j = 0; j < 4; ++j) {
                    const bool used = (i == j) || (i == 0 && j == k) || (i == k && j == 0);
                    if (!used && std::abs(mats[o].at(i, j)) > 1e-7f)
                        ctx.l1 = false;
                }
        }
    }
    ctx.terms = terms;
    ctx.box = m_active;
    // Per-brick stop: ε times the injected band-0 coefficient per cell that can hold light.
    const Rgb injectedFlux = m_injection.flux();
    if (m_opt.brickStopEpsilon > 0.f)
        ctx.dark = m_opt.brickStopEpsilon *
                   std::max({injectedFlux.x, injectedFlux.y, injectedFlux.z}) /
                   (TWO_SQRT_PI * float(std::max<int64_t>(m_lightCells, 1)));
    ctx.padded = int(p);
    ctx.mask = m_opt.removeExitant ? m_mask.data() : nullptr;
    for (int ch = 0; ch < 3; ++ch) {
        for (int l = 0; l < 3; ++l) {
            ctx.factor[ch][l] = m_homogeneous ? nullptr : m_factor[ch][l].data();
            ctx.perCellFactors = !m_homogeneous;
            ctx.homFactor[ch][l] = m_homFactor[ch][l];
        }
        ctx.homAbsorb[ch] = m_homAbsorb[ch];
    }
}

void SslpvSolver::runSteps(StepKernel& kernel, int stepLimit) {
    const int n = m_material.spec.resolution;
    const int count = shCount(m_opt.order);
    const int bricksX = (n + SSLPV_BRICK_X - 1) / SSLPV_BRICK_X;
    const int bricksY = (n + SSLPV_BRICK_Y - 1) / SSLPV_BRICK_Y;
    StepCtx& ctx = kernel.ctx;
    const bool brickStop = m_opt.brickStopEpsilon > 0.f;
    PropagationRun& run = m_run;
    const Rgb injected = run.injected;
    Rgb &absorbed = run.absorbed, &exitant = run.exitant, &remaining = run.remaining,
        &dropped = run.dropped;
    int& steps = run.steps;
    bool &accWritten = run.accWritten, &exitWritten = run.exitWritten, &anyLit = run.anyLit;
    const bool empty = m_active.isEmpty();
    auto converged = [&] {
        if (m_opt.stopEpsilon <= 0.f)
            return false;
        for (int ch = 0; ch < 3; ++ch)
            if (remaining[ch] > m_opt.stopEpsilon * injected[ch])
                return false;
        return true;
    };
    std::vector<SliceSums> sums(size_t(std::max(n, 1)));
    const CoordBox box = m_active;
    const bool dense = !m_opt.skipEmptySlices;
    const int bx0 = box.lo.x / SSLPV_BRICK_X, bx1 = box.hi.x / SSLPV_BRICK_X;
    const int by0 = box.lo.y / SSLPV_BRICK_Y, by1 = box.hi.y / SSLPV_BRICK_Y;
    m_stats.brickCount = empty ? 0 : (bx1 - bx0 + 1) * (by1 - by0 + 1) * (box.hi.z - box.lo.z + 1);
    struct Run {
        int xs, xe;  // inclusive cell range in x
    };
    // Zeroes cells [xs, xe] × [ya, yb] of slice z, for every segment, in every plane of g.
    auto zeroSegments = [&](SslpvGrid& g, const Run* seg, int segs, int ya, int yb, int z) {
        for (int ch = 0; ch < 3; ++ch)
            for (int i = 0; i < count; ++i)
                for (int y = ya; y <= yb; ++y)
                    for (int r = 0; r < segs; ++r)
                        std::memset(g.plane(ch, i) + g.index({seg[r].xs, y, z}), 0,
                                    size_t(seg[r].xe - seg[r].xs + 1) * sizeof(float));
    };
    // Appends [xs, xe] to a sorted segment list, merging with the last one when adjacent.
    auto append = [](Run* seg, int& segs, int xs, int xe) {
        if (segs > 0 && seg[segs - 1].xe + 1 == xs)
            seg[segs - 1].xe = xe;
        else
            seg[segs++] = {xs, xe};
    };
    const Timer stepTimer;
    while (!empty && anyLit && steps < stepLimit && !converged()) {
        const int next = 1 - m_cur;
        const bool accumulate = steps + 1 > m_opt.skipAccumulateSteps;
        ctx.assignAcc = accumulate && !accWritten;
        ctx.assignExit = !exitWritten;
        accWritten = accWritten || accumulate;
        exitWritten = exitWritten || m_opt.removeExitant;
        for (int ch = 0; ch < 3; ++ch)
            for (int i = 0; i < count; ++i) {
                ctx.src[ch][i] = m_prop[m_cur].plane(ch, i);
                ctx.dst[ch][i] = m_prop[next].plane(ch, i);
                ctx.acc[ch][i] = accumulate ? m_accum.plane(ch, i) : nullptr;
                ctx.exit[ch][i] = m_opt.removeExitant ? m_exitant.plane(ch, i) : nullptr;
            }
        std::fill(sums.begin(), sums.end(), SliceSums{});
        const uint8_t* srcLit = m_brickLit[m_cur].data();
        uint8_t* dstLit = m_brickLit[next].data();
        uint8_t* accLit = m_accBrickLit.data();
        uint8_t* exitLit = m_exitBrickLit.data();
        parallelFor(
            box.lo.z, box.hi.z + 1,
            [&](int64_t zb, int64_t ze) {
                constexpr int MAX_RUNS = 1024 / SSLPV_BRICK_X + 1;
                Run runs[MAX_RUNS], clearDst[MAX_RUNS], clearAcc[MAX_RUNS], clearExit[MAX_RUNS];
                uint8_t brickNz[1024 / SSLPV_BRICK_X + 1];
                alignas(64) int32_t nz[1024 + 64];
                for (int z = int(zb); z < int(ze); ++z) {
                    SliceSums& sl = sums[size_t(z)];
                    const size_t zBase = size_t(z) * bricksY * bricksX;
                    for (int by = by0; by <= by1; ++by) {
                        const size_t rowBase = zBase + size_t(by) * bricksX;
                        // Active bricks of this brick row: lit, or next to a lit brick (face
                        // neighbours; the stencil reaches no further). The others get exactly
                        // zero; they are only cleared where an earlier write may remain.
                        int nr = 0, nDst = 0, nAcc = 0, nExit = 0;
                        for (int bx = bx0; bx <= bx1; ++bx) {
                            const size_t t = rowBase + size_t(bx);
                            const bool active =
                                dense || srcLit[t] || (bx > 0 && srcLit[t - 1]) ||
                                (bx + 1 < bricksX && srcLit[t + 1]) ||
                                (by > 0 && srcLit[t - size_t(bricksX)]) ||
                                (by + 1 < bricksY && srcLit[t + size_t(bricksX)]) ||
                                (z > 0 && srcLit[t - size_t(bricksX) * bricksY]) ||
                                (z + 1 < n && srcLit[t + size_t(bricksX) * bricksY]);
                            const int xs = std::max(bx * SSLPV_BRICK_X, box.lo.x);
                            const int xe =
                                std::min(bx * SSLPV_BRICK_X + SSLPV_BRICK_X - 1, box.hi.x);
                            if (active) {
                                ++sl.activeBricks;
                                append(runs, nr, xs, xe);
                                continue;
                            }
                            if (dstLit[t]) {
                                append(clearDst, nDst, xs, xe);
                                dstLit[t] = 0;
                            }
                            if (ctx.assignAcc && accLit[t]) {
                                append(clearAcc, nAcc, xs, xe);
                                accLit[t] = 0;
                            }
                            if (ctx.assignExit && ctx.exit[0][0] && exitLit[t]) {
                                append(clearExit, nExit, xs, xe);
                                exitLit[t] = 0;
                            }
                        }
                        const int ya = std::max(by * SSLPV_BRICK_Y, box.lo.y);
                        const int yb = std::min(by * SSLPV_BRICK_Y + SSLPV_BRICK_Y - 1, box.hi.y);
                        if (nDst > 0)
                            zeroSegments(m_prop[next], clearDst, nDst, ya, yb, z);
                        if (nAcc > 0)
                            zeroSegments(m_accum, clearAcc, nAcc, ya, yb, z);
                        if (nExit > 0)
                            zeroSegments(m_exitant, clearExit, nExit, ya, yb, z);
                        if (nr == 0)
                            continue;
                        // Widen each run to whole 32-cell SIMD blocks where the grid allows,
                        // merging runs that meet, so the kernel rarely takes its scalar tail:
                        // inactive cells computed this way come out exactly zero, and so do
                        // cells outside the box (only sink cells, which hold no light, border
                        // it), so writing them keeps every grid as the dense solve has it.
                        int nm = 0;
                        for (int r = 0; r < nr; ++r) {
                            Run cur = runs[r];
                            if (nm > 0 && cur.xs <= runs[nm - 1].xe + 1) {
                                cur.xs = runs[nm - 1].xs;
                                cur.xe = std::max(cur.xe, runs[nm - 1].xe);
                                --nm;
                            }
                            const int minStart = nm > 0 ? runs[nm - 1].xe + 1 : 0;
                            const int want = (cur.xe - cur.xs + 1 + 31) / 32 * 32;
                            if (cur.xs + want - 1 <= n - 1) {
                                cur.xe = cur.xs + want - 1;
                            } else {
                                cur.xe = n - 1;
                                cur.xs = std::max(minStart, n - want);
                            }
                            runs[nm++] = cur;
                        }
                        // Later raw runs may now lie inside a widened one: merge once more.
                        nr = 0;
                        for (int r = 0; r < nm; ++r) {
                            if (nr > 0 && runs[r].xs <= runs[nr - 1].xe + 1)
                                runs[nr - 1].xe = std::max(runs[nr - 1].xe, runs[r].xe);
                            else
                                runs[nr++] = runs[r];
                        }
                        const int bxa = runs[0].xs / SSLPV_BRICK_X;
                        const int bxb = runs[nr - 1].xe / SSLPV_BRICK_X;
                        std::fill(brickNz + bxa, brickNz + bxb + 1, uint8_t(0));
                        for (int y = ya; y <= yb; ++y)
                            for (int r = 0; r < nr; ++r) {
                                const int len = runs[r].xe - runs[r].xs + 1;
                                processRun(ctx, z, y, runs[r].xs, len, sl, nz);
                                sl.cells += len;
                                const int xs = runs[r].xs, xe = runs[r].xe;
                                for (int bx = xs / SSLPV_BRICK_X; bx <= xe / SSLPV_BRICK_X; ++bx) {
                                    const int a = std::max(bx * SSLPV_BRICK_X, xs) - xs;
                                    const int b =
                                        std::min(bx * SSLPV_BRICK_X + SSLPV_BRICK_X - 1, xe) - xs;
                                    int32_t any = 0;
                                    for (int x = a; x <= b; ++x)
                                        any |= nz[x];
                                    brickNz[bx] |= uint8_t(any & (NZ_ANY | NZ_BRIGHT));
                                }
                            }
                        // Bricks the runs touched: fully rewritten when active, zero or
                        // rewritten with exact zeros otherwise, so their new flag is exact.
                        // With the per-brick stop, a wholly rewritten brick whose values are
                        // all below ctx.dark is set to zero (its light counted as dropped) and
                        // is dark: a dark brick holds exact zeros, as without the stop.
                        for (int r = 0; r < nr; ++r)
                            for (int bx = runs[r].xs / SSLPV_BRICK_X;
                                 bx <= runs[r].xe / SSLPV_BRICK_X; ++bx) {
                                const size_t t = rowBase + size_t(bx);
                                const int xa = std::max(bx * SSLPV_BRICK_X, box.lo.x);
                                const int xb =
                                    std::min(bx * SSLPV_BRICK_X + SSLPV_BRICK_X - 1, box.hi.x);
                                const bool whole = xa >= runs[r].xs && xb <= runs[r].xe;
                                const uint8_t bits = brickNz[bx];
                                uint8_t lit = uint8_t((bits & NZ_ANY) != 0);
                                if (brickStop && whole) {
                                    lit = uint8_t((bits & NZ_BRIGHT) != 0);
                                    if ((bits & NZ_ANY) && !lit) {
                                        for (int ch = 0; ch < 3; ++ch) {
                                            double faint = 0.0;
                                            for (int y = ya; y <= yb; ++y) {
                                                const float* c0 = m_prop[next].plane(ch, 0) +
                                                                  m_prop[next].index({xa, y, z});
                                                for (int x = 0; x <= xb - xa; ++x)
                                                    faint += double(c0[x]);
                                            }
                                            sl.v[ch][3] += faint;
                                            sl.v[ch][0] -= faint;  // no longer remaining
                                        }
                                        const Run brick{xa, xb};
                                        zeroSegments(m_prop[next], &brick, 1, ya, yb, z);
                                    }
                                }
                                dstLit[t] = whole ? lit : uint8_t(dstLit[t] | lit);
                                sl.litBricks += dstLit[t];
                                accLit[t] |= uint8_t(accumulate);
                                exitLit[t] |= uint8_t(ctx.exit[0][0] != nullptr);
                            }
                    }
                }
            },
            /*grain=*/1);
        Rgb rem(0.f);
        int active = 0, lit = 0;
        for (const SliceSums& sl : sums) {
            for (int ch = 0; ch < 3; ++ch) {
                rem[ch] += float(sl.v[ch][0] * TWO_SQRT_PI);
                exitant[ch] += float(sl.v[ch][1] * TWO_SQRT_PI);
                absorbed[ch] += float(sl.v[ch][2] * TWO_SQRT_PI);
                dropped[ch] += float(sl.v[ch][3] * TWO_SQRT_PI);
            }
            active += sl.activeBricks;
            lit += sl.litBricks;
            m_stats.cellsComputed += sl.cells;
        }
        m_stats.activeBricksPerStep.push_back(active);
        anyLit = !brickStop || lit > 0;  // all dark: the rest of the steps would add nothing
        remaining = rem;
        m_cur = next;
        ++steps;
    }
    m_stats.stepsMs = stepTimer.elapsedMs();
    run.inFlight = !empty && anyLit && !converged();
    if (!accWritten) {
        m_accum.clear();
        std::fill(m_accBrickLit.begin(), m_accBrickLit.end(), uint8_t(0));
    }
    if (!exitWritten) {
        m_exitant.clear();
        std::fill(m_exitBrickLit.begin(), m_exitBrickLit.end(), uint8_t(0));
    }
    m_stats.stepsUsed = steps;
    m_stats.injected = injected;
    m_stats.remaining = remaining;
    m_stats.exitant = exitant;
    m_stats.absorbed = absorbed;
    m_stats.dropped = dropped;
}

const SslpvStats& SslpvSolver::solve() {
    LUCENT_CHECK(m_hasMaterial, "SSLPV: solve() called before setMaterial()");
    m_stats.reinjected = m_stats.repropagated = false;
    m_stats.refoldedRows = 0;
    if (m_opt.mode == SslpvMode::Diffusion) {
        // The source depends on σt′ along each beam, so a material change re-injects too.
        if (m_injectionDirty || m_materialDirty) {
            // A stroke changes σ in a few cells: only the beams through them are walked again
            // (reinjectChangedDiffusionSources), the same sources as a full walk to rounding.
            if (m_injectionDirty || !m_opt.incrementalInjection ||
                !reinjectChangedDiffusionSources())
                injectDiffusionSources();
            m_injectionDirty = false;
            m_stats.reinjected = true;
            if (m_factorsDirty)
                m_diffusion.setMaterial(m_material, m_eta);
            m_factorsDirty = false;
            diffuse();
            m_materialDirty = false;
            m_stats.repropagated = true;
        }
        return m_stats;
    }
    if (m_materialDirty && !m_injectionDirty) {
        // Each beam's deposit holds its chord's interacting fraction, so σt along a beam is part
        // of the injection: a stroke injects the beams through the cells it changed again.
        if (!m_opt.incrementalInjection || !reinjectChangedChords())
            m_injectionDirty = true;
        else if (m_stats.rewalkedTexels > 0)
            m_stats.reinjected = true;
    }
    if (m_injectionDirty) {
        inject();
        m_injectionDirty = false;
        m_materialDirty = true;  // new sources: propagation must rerun
        m_stats.reinjected = true;
    }
    if (m_materialDirty) {
        if (m_factorsDirty)
            rebuildFactors();
        m_factorsDirty = false;
        propagate();
        m_materialDirty = false;
        m_stats.repropagated = true;
    }
    return m_stats;
}

std::vector<float> SslpvSolver::foldedFactorPlane(int channel, int band) const {
    LUCENT_CHECK(channel >= 0 && channel < 3 && band >= 0 && band < 3, "SSLPV: foldedFactorPlane(",
                 channel, ", ", band, ") out of range");
    const int n = m_material.spec.resolution;
    const size_t plane = size_t(n + 2) * (n + 2) * (n + 2);
    if (!m_homogeneous && m_factor[channel][band].size() == plane)
        return m_factor[channel][band];
    return std::vector<float>(plane, m_homFactor[channel][band]);
}

std::vector<float> SslpvSolver::sinkMaskPlane() const {
    const int n = m_material.spec.resolution;
    const size_t plane = size_t(n + 2) * (n + 2) * (n + 2);
    if (m_opt.removeExitant && m_mask.size() == plane)
        return m_mask;
    return std::vector<float>(plane, 1.f);
}

float SslpvSolver::exitScale() const {
    // Radiance scaling at refraction, L_o = T·L_i/η² (docs/reference.md; Veach 1997 §5.2): the
    // paper's Eq. 4 leaves it out, which made Paper mode η² too bright (1.69× at η = 1.3).
    const float refraction = 1.f / (m_eta * m_eta);
    if (m_opt.mode != SslpvMode::Calibrated)
        return refraction;
    // Calibrated: times the fitted normalisation of the Eq. 7 estimate.
    return m_opt.calibration.gain[m_opt.order - 1] * refraction;
}

bool SslpvSolver::interpolateCoefficients(const Point3f& p, const Normal3f& n,
                                          float (&c)[3][SSLPV_MAX_COEFFS]) const {
    for (auto& row : c)
        std::fill(row, row + SSLPV_MAX_COEFFS, 0.f);
    if (!m_hasMaterial || m_accum.resolution() == 0)
        return false;
    const GridSpec& s = m_material.spec;
    const float h = s.voxelSize;
    const int count = m_accum.coeffCount();
    bool found = false;
    for (float depth : {0.5f, 1.0f, 1.5f}) {
        // Trilinear over the eight nearest cell centres, inside cells only (renormalised).
        const Vector3f u = (p - depth * h * n - s.origin) / h - Vector3f(0.5f);
        const Coord i0(glm::floor(u));
        const Vector3f f = u - Vector3f(i0);
        float wsum = 0.f;
        for (int corner = 0; corner < 8; ++corner) {
            const Coord o(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            const Coord cell = i0 + o;
            if (!isReadable(cell))
                continue;
            const float w =
                (o.x ? f.x : 1.f - f.x) * (o.y ? f.y : 1.f - f.y) * (o.z ? f.z : 1.f - f.z);
            if (w <= 0.f)
                continue;
            wsum += w;
            for (int ch = 0; ch < 3; ++ch)
                for (int i = 0; i < count; ++i)
                    c[ch][i] += w * m_accum.at(cell, ch, i);
        }
        if (wsum > 1e-4f) {
            for (auto& row : c)
                for (int i = 0; i < count; ++i)
                    row[i] /= wsum;
            found = true;
            break;
        }
        for (auto& row : c)
            std::fill(row, row + SSLPV_MAX_COEFFS, 0.f);
    }
    return found || thinPartCoefficients(p, n, c);
}

bool SslpvSolver::thinPartCoefficients(const Point3f& p, const Normal3f& n,
                                       float (&c)[3][SSLPV_MAX_COEFFS]) const {
    // A part thinner than half a cell (a rim, a fin) has no cell with insideFraction ≥ ½, so
    // it is absent from the grid and the depths above find nothing: it rendered black (11.8 %
    // of the covered pixels of the back-lit thin-thick suite case at 32³; docs/methods/
    // sslpv.md, "Parts thinner than half a cell"). Read it from the readable cells within
    // LUCENT_SSLPV_THIN_PART_REACH cells of the depth-½ point (Gaussian weights of distance in
    // cells), scaled by 2f, f the largest inside fraction (capped at ½) of the eight cells
    // around that point: the part's own cells (a layer t cells thick crossing a cell fills
    // about t of it; trilinear weights would mix in the empty cells beside it and fall as t²).
    // The light a layer thin against a mean free path sends out grows with its thickness, and
    // at f = ½, where the cell joins the grid and is read itself, the scale is 1. The albedo
    // slot of mode Diffusion is a material value, not light: averaged, not scaled.
    const GridSpec& s = m_material.spec;
    const float h = s.voxelSize;
    const int count = m_accum.coeffCount();
    const Vector3f u = (p - 0.5f * h * n - s.origin) / h - Vector3f(0.5f);
    const Coord i0(glm::floor(u));
    float fraction = 0.f;
    for (int corner = 0; corner < 8; ++corner)
        fraction = std::max(
            fraction,
            std::min(readoutAlpha(i0 + Coord(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1)),
                     0.5f));
    if (!(fraction > 0.f))
        return false;
    const Coord centre(glm::floor(u + Vector3f(0.5f)));
    float wsum = 0.f;
    constexpr int R = LUCENT_SSLPV_THIN_PART_REACH;
    for (int dz = -R; dz <= R; ++dz)
        for (int dy = -R; dy <= R; ++dy)
            for (int dx = -R; dx <= R; ++dx) {
                const Coord cell = centre + Coord(dx, dy, dz);
                if (!isReadable(cell))
                    continue;
                const Vector3f d = u - Vector3f(cell);
                const float w = std::exp(-glm::dot(d, d));
                wsum += w;
                for (int ch = 0; ch < 3; ++ch)
                    for (int i = 0; i < count; ++i)
                        c[ch][i] += w * m_accum.at(cell, ch, i);
            }
    if (!(wsum > 1e-6f))
        return false;
    const bool diffusion = m_opt.mode == SslpvMode::Diffusion;
    for (auto& row : c)
        for (int i = 0; i < count; ++i) {
            const bool albedo = diffusion && i == LUCENT_SSLPV_DIFFUSION_ALBEDO_COEFF;
            row[i] *= (albedo ? 1.f : 2.f * fraction) / wsum;
        }
    return true;
}

Rgb SslpvSolver::radianceFromCoefficients(const float (&c)[3][SSLPV_MAX_COEFFS],
                                          const Normal3f& n) const {
    // Eq. 7 with the rotation of Eq. 6 (zyz Euler angles of n): c10^(n) = n·(c11, c1−1, c10);
    // hemisphere integrals ∫₀^{π/2} y_l0 sin θ dθ = 1/(2√π), ½√(3/4π), 0 (band 2: (3cos²−1)
    // integrates to zero), so L_i = (2/A)(c00/(2√π) + ½√(3/4π) c10^(n)), A = Δx² (§4). Mode
    // Diffusion has band 0 only (its band-1 slot holds the albedo, shared/SslpvShared.h).
    const float h = m_material.spec.voxelSize;
    const float invA = 1.f / (h * h);
    const bool band1 = m_opt.mode != SslpvMode::Diffusion;
    Rgb L(0.f);
    for (int ch = 0; ch < 3; ++ch) {
        const float c10n = band1 ? n.x * c[ch][3] + n.y * c[ch][1] + n.z * c[ch][2] : 0.f;
        L[ch] = std::max(0.f, 2.f * invA * (Y00 * c[ch][0] + 0.5f * K1 * c10n));
    }
    return L;
}

Rgb SslpvSolver::radiance(const Point3f& p, const Normal3f& n) const {
    float c[3][SSLPV_MAX_COEFFS];
    if (!interpolateCoefficients(p, n, c))
        return Rgb(0.f);
    return radianceFromCoefficients(c, n);
}

Rgb SslpvSolver::readoutAlbedo(const Point3f& p, const Normal3f& n) const {
    float c[3][SSLPV_MAX_COEFFS];
    if (m_opt.mode != SslpvMode::Diffusion || !interpolateCoefficients(p, n, c))
        return Rgb(0.f);
    return {c[0][LUCENT_SSLPV_DIFFUSION_ALBEDO_COEFF], c[1][LUCENT_SSLPV_DIFFUSION_ALBEDO_COEFF],
            c[2][LUCENT_SSLPV_DIFFUSION_ALBEDO_COEFF]};
}

Rgb SslpvSolver::exitantRadiance(const Point3f& p, const Normal3f& n, float cosOut,
                                 const Vector3f& wo) const {
    float c[3][SSLPV_MAX_COEFFS];
    if (!(cosOut > 0.f) || !interpolateCoefficients(p, n, c))
        return Rgb(0.f);
    Rgb L = (exitScale() * (1.f - fresnelDielectric(std::min(cosOut, 1.f), m_eta))) *
            radianceFromCoefficients(c, n);
    if (m_exitTable) {
        // The exact half-space's exit-angle distribution at the albedo the read-out sees
        // (DirpoleExitTable: c = L_exact(t)/L_diffuse(t), flux-weighted mean 1 over the
        // hemisphere, so it moves light between directions and keeps the total).
        for (int ch = 0; ch < 3; ++ch) {
            const float albedo = c[ch][LUCENT_SSLPV_DIFFUSION_ALBEDO_COEFF];
            if (albedo > 0.f)
                L[ch] *= float(m_exitTable->correction(double(albedo), double(cosOut)));
        }
    }
    if (m_opt.mode == SslpvMode::Diffusion && m_surfaceFluxReadout) {
        // P1 just inside the boundary: L(ω) = (φ + 3J·ω)/4π with φ = 2A·J_n (Robin), so along
        // the refracted direction ω (tangential part ω_t = (wo − cos θ_o n)/η, Snell; cosine μ)
        // L = J_n(2A + 3μ)/4π · (1 + 3 J_t·ω_t/(J_n(2A + 3μ))). The exit table above stands for
        // the first factor's angular shape; this is the second. Odd in ω_t, it moves light
        // between azimuths and keeps the exitance. A flux larger than the fluence has no
        // radiance field (|J| ≤ φ, the bound flux limiters enforce), so J_t is limited to
        // √(φ_b² − J_n²) = J_n√(4A² − 1): a steep gradient (a shadow's edge on a coarse grid)
        // cannot make the term exceed what any radiance could carry.
        const Vector3f wt = (wo - cosOut * Vector3f(n)) / m_eta;
        const float mu = std::sqrt(std::max(0.f, 1.f - glm::dot(wt, wt)));
        const float twoA = float(2.0 * m_diffusion.boundaryConstant());
        const float limit = std::sqrt(std::max(0.f, twoA * twoA - 1.f));
        for (int ch = 0; ch < 3; ++ch) {
            const float jn = c[ch][0];
            if (!(jn > 0.f))
                continue;
            Vector3f jt(c[ch][LUCENT_SSLPV_DIFFUSION_FLUX_COEFF],
                        c[ch][LUCENT_SSLPV_DIFFUSION_FLUX_COEFF + 1],
                        c[ch][LUCENT_SSLPV_DIFFUSION_FLUX_COEFF + 2]);
            const float size = glm::length(jt);
            if (size > limit * jn)
                jt *= limit * jn / size;
            L[ch] *= std::max(0.f, 1.f + 3.f * glm::dot(jt, wt) / (jn * (twoA + 3.f * mu)));
        }
    }
    return L;
}

namespace {

/// One cell's share of a beam's first-scattering source (W per channel); in the cell where the
/// beam entered the medium also the mean depth of that first scattering under the surface (mm
/// per channel; GridDiffusion::solve places it there), 0 elsewhere.
struct BeamDeposit {
    uint32_t cell;
    bool entry;
    float q[3];
    float depth[3];
};

/// What walking one beam gave: whether it met the medium, its power bookkeeping (W, in double)
/// and the straight segment it covered in grid units (the cells it can have deposited in lie
/// along it).
struct BeamWalk {
    bool entered = false;
    double injected[3] = {}, firstAbsorbed[3] = {};
    Vector3f from{0.f}, to{0.f};
};

/// Walks texel `smp`'s refracted beam through `m` (Amanatides & Woo 1987) and hands each inside
/// cell's deposit to `deposit`, scaled by `sign` (−1: take a walk back out of the source). Each
/// cell gets the exact integral of the first-scattering source over the chord it holds:
/// α′·T·(1 − e^(−σt′ℓ)), T the transmittance so far. The chord in cells before the medium (the
/// voxel staircase around x_p: cells the surface cuts with less than half inside, up to two
/// cells) is medium too: it joins the first inside cell's chord, whose control volume reaches
/// the surface (the Robin condition's δ counts it). After the medium, the beam is out. The entry
/// cell's deposit also carries the mean depth of its first scattering: along the chord [0, ℓ]
/// from the surface, density ∝ e^(−σt′s), s̄ = ℓ(1/τ − 1/(e^τ − 1)), τ = σt′ℓ, times the
/// refracted direction's cosine to the normal.
template <class Deposit>
BeamWalk walkDiffusionBeam(const SslpvInjectionSample& smp, float eta, const CoarseMaterial& m,
                           float sign, Deposit&& deposit) {
    constexpr float OPAQUE = 2.0611536e-9f;  // e^−20: nothing of the beam is left to scatter
    const GridSpec& s = m.spec;
    const float h = s.voxelSize;
    const int maxSteps = 3 * s.resolution + 3;  // a ray crosses at most 3N cells of the grid
    const float cosI = -glm::dot(smp.direction, smp.normal);
    const Rgb beam = (1.f - fresnelDielectric(cosI, eta)) * smp.flux;
    const Vector3f wt = refractInto(smp.direction, smp.normal, eta);
    const float cosT = std::max(0.f, -glm::dot(wt, smp.normal));
    const Vector3f u = (smp.position - s.origin) / h;  // grid units
    Coord c(glm::floor(u));
    Vector3f tMax, tDelta;
    Coord stepDir;
    for (int a = 0; a < 3; ++a) {
        if (wt[a] > 0.f) {
            stepDir[a] = 1;
            tDelta[a] = h / wt[a];
            tMax[a] = (float(c[a] + 1) - u[a]) * tDelta[a];
        } else if (wt[a] < 0.f) {
            stepDir[a] = -1;
            tDelta[a] = -h / wt[a];
            tMax[a] = (u[a] - float(c[a])) * tDelta[a];
        } else {
            stepDir[a] = 0;
            tDelta[a] = tMax[a] = INF;
        }
    }
    const auto inside = [&](const Coord& q) {
        return s.contains(q) && m.insideFraction[s.linearIndex(q)] >= 0.5f;
    };
    BeamWalk w;
    Rgb transmitted(1.f);
    float t = 0.f, pending = 0.f;
    for (int k = 0; k < maxSteps; ++k) {
        const int axis = tMax.x < tMax.y ? (tMax.x < tMax.z ? 0 : 2) : (tMax.y < tMax.z ? 1 : 2);
        const float tNext = tMax[axis];
        const float len = tNext - t + pending;
        if (inside(c)) {
            pending = 0.f;
            const size_t i = s.linearIndex(c);
            BeamDeposit d{uint32_t(i), !w.entered, {}, {}};
            w.entered = true;
            for (int ch = 0; ch < 3; ++ch) {
                const float st = m.sigma_t[ch][i];
                const float tau = st * len;
                const float interacting = transmitted[ch] * -std::expm1(-tau);  // one exp per cell
                if (d.entry) {
                    // s̄/ℓ = 1/τ − 1/(e^τ − 1) = ½ − τ/12 + O(τ³) near 0.
                    const float meanOverChord =
                        tau > 1e-3f ? 1.f / tau - 1.f / std::expm1(tau) : 0.5f - tau / 12.f;
                    d.depth[ch] = meanOverChord * len * cosT;
                }
                transmitted[ch] -= interacting;
                const float albedo = st > 0.f ? std::min(1.f, m.sigma_s[ch][i] / st) : 0.f;
                const float power = beam[ch] * interacting;
                d.q[ch] = sign * albedo * power;
                w.injected[ch] += double(sign) * double(power);
                w.firstAbsorbed[ch] += double(sign) * double((1.f - albedo) * power);
            }
            deposit(d);
            if (transmitted.x < OPAQUE && transmitted.y < OPAQUE && transmitted.z < OPAQUE) {
                t = tNext;
                break;
            }
        } else if (w.entered || t > 2.f * h) {
            break;
        } else {
            pending = len;
        }
        t = tNext;
        c[axis] += stepDir[axis];
        tMax[axis] += tDelta[axis];
        if (!s.contains(c))
            break;
    }
    w.from = u;
    w.to = u + (std::isfinite(t) ? t : 0.f) / h * wt;
    return w;
}

/// One range of beams walked on one thread: its deposits in walk order and its power (W, in
/// double).
struct BeamPart {
    std::vector<BeamDeposit> deposits;
    double injected[3] = {}, firstAbsorbed[3] = {};
    int used = 0, skipped = 0;
    void count(const BeamWalk& w) {
        for (int ch = 0; ch < 3; ++ch) {
            injected[ch] += w.injected[ch];
            firstAbsorbed[ch] += w.firstAbsorbed[ch];
        }
    }
};

/// Runs walk(part, i) for i in [0, count) in parallel over ranges of `perPart`, each range into
/// its own part; applyBeamParts then sums the parts in order, so every cell adds its deposits
/// in the order a serial walk would: the same bits on any thread count.
template <class Walk>
std::vector<BeamPart> walkInParts(int64_t count, int64_t perPart, Walk&& walk) {
    std::vector<BeamPart> parts(size_t((count + perPart - 1) / perPart));
    parallelFor(0, int64_t(parts.size()), [&](int64_t p0, int64_t p1) {
        for (int64_t p = p0; p < p1; ++p) {
            const int64_t end = std::min(count, (p + 1) * perPart);
            for (int64_t i = p * perPart; i < end; ++i)
                walk(parts[size_t(p)], i);
        }
    });
    return parts;
}

/// Adds the parts' deposits to `source` (the entry cells' also to its entry parts, where it has
/// them) and their power to the totals, in part order. Taking a
/// beam's share away (an incremental update) can leave a rounding residue below 0: clamped
/// (a no-op for a full walk, whose deposits are all ≥ 0).
void applyBeamParts(const std::vector<BeamPart>& parts, GridDiffusionSource& source,
                    std::array<double, 3>& injected, std::array<double, 3>& firstAbsorbed) {
    for (const BeamPart& part : parts) {
        for (const BeamDeposit& d : part.deposits)
            for (size_t ch = 0; ch < 3; ++ch) {
                float& q = source.power[ch][d.cell];
                q = std::max(0.f, q + d.q[ch]);
                if (d.entry && !source.entry[ch].empty()) {
                    float& entry = source.entry[ch][d.cell];
                    float& moment = source.entryDepth[ch][d.cell];
                    entry = std::max(0.f, entry + d.q[ch]);
                    moment = std::max(0.f, moment + d.q[ch] * d.depth[ch]);
                }
            }
        for (int ch = 0; ch < 3; ++ch) {
            injected[size_t(ch)] += part.injected[ch];
            firstAbsorbed[size_t(ch)] += part.firstAbsorbed[ch];
        }
    }
}

/// Whether the segment [a, b] (grid units) meets the box [lo, hi] (slab test).
bool segmentMeetsBox(const Vector3f& a, const Vector3f& b, const Vector3f& lo, const Vector3f& hi) {
    float t0 = 0.f, t1 = 1.f;
    for (int k = 0; k < 3; ++k) {
        const float d = b[k] - a[k];
        if (std::abs(d) < 1e-12f) {
            if (a[k] < lo[k] || a[k] > hi[k])
                return false;
            continue;
        }
        float ta = (lo[k] - a[k]) / d, tb = (hi[k] - a[k]) / d;
        if (ta > tb)
            std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1)
            return false;
    }
    return true;
}

/// The cells whose σt (and σs′ when `withScattering`) differ between two materials of one
/// spec, and the box of their centres in grid units with a cell of margin for rounding (a
/// cell's centre is at its index + ½: [lo − 1, hi + 2]).
struct ChangedCells {
    std::vector<uint32_t> cells;
    Vector3f boxLo{0.f}, boxHi{0.f};
};
ChangedCells changedCells(const CoarseMaterial& now, const CoarseMaterial& was,
                          bool withScattering) {
    const GridSpec& s = now.spec;
    const int n = s.resolution;
    ChangedCells out;
    Coord lo(n), hi(-1);
    for (size_t k = 0; k < s.voxelCount(); ++k) {
        bool differs = false;
        for (int ch = 0; ch < 3 && !differs; ++ch)
            differs = now.sigma_t[ch][k] != was.sigma_t[ch][k] ||
                      (withScattering && now.sigma_s[ch][k] != was.sigma_s[ch][k]);
        if (!differs)
            continue;
        out.cells.push_back(uint32_t(k));
        const Coord c(int(k % size_t(n)), int((k / size_t(n)) % size_t(n)),
                      int(k / (size_t(n) * size_t(n))));
        lo = glm::min(lo, c);
        hi = glm::max(hi, c);
    }
    out.boxLo = Vector3f(lo) - Vector3f(1.f);
    out.boxHi = Vector3f(hi) + Vector3f(2.f);
    return out;
}

}  // namespace

void SslpvSolver::injectDiffusionSources() {
    const Timer timer;
    const GridSpec& s = m_material.spec;
    const size_t count = s.voxelCount();
    // The entry parts only when the solve places them (diffusionEntryDepth; applyBeamParts
    // skips empty ones): otherwise two grids per channel written for nothing.
    const size_t entryCount = m_opt.diffusionEntryDepth ? count : 0;
    for (int ch = 0; ch < 3; ++ch) {
        m_diffusionSource.power[ch].assign(count, 0.f);
        m_diffusionSource.entry[ch].assign(entryCount, 0.f);
        m_diffusionSource.entryDepth[ch].assign(entryCount, 0.f);
    }
    m_beamSegments.assign(m_samples.size(), {});
    m_beamEntered.assign(m_samples.size(), 0);

    // The beams are walked in parallel over contiguous texel ranges, each range recording its
    // deposits in walk order; the ranges are then applied in texel order (walkInParts): the
    // source is bit-identical on any thread count.
    constexpr int64_t TEXELS_PER_PART = 1024;
    const std::vector<BeamPart> parts =
        walkInParts(int64_t(m_samples.size()), TEXELS_PER_PART, [&](BeamPart& part, int64_t j) {
            const SslpvInjectionSample& smp = m_samples[size_t(j)];
            if (!isInjectable(smp)) {
                ++part.skipped;
                return;
            }
            const BeamWalk w =
                walkDiffusionBeam(smp, m_eta, m_material, 1.f,
                                  [&](const BeamDeposit& d) { part.deposits.push_back(d); });
            part.count(w);
            m_beamSegments[size_t(j)] = {w.from, w.to};
            m_beamEntered[size_t(j)] = w.entered ? 1 : 0;
            if (w.entered)
                ++part.used;
            else
                ++part.skipped;
        });
    m_sourceInjected = {};
    m_sourceFirstAbsorbed = {};
    applyBeamParts(parts, m_diffusionSource, m_sourceInjected, m_sourceFirstAbsorbed);
    int used = 0, skipped = 0;
    for (const BeamPart& part : parts) {
        used += part.used;
        skipped += part.skipped;
    }
    m_sourceMaterial = m_material;
    m_incrementalInjections = 0;
    m_stats.injectedTexels = used;
    m_stats.skippedTexels = skipped;
    m_stats.rewalkedTexels = 0;
    for (int ch = 0; ch < 3; ++ch) {
        m_stats.injected[ch] = float(m_sourceInjected[size_t(ch)]);
        m_stats.absorbed[ch] = float(m_sourceFirstAbsorbed[size_t(ch)]);  // diffuse() adds
    }
    m_stats.injectMs = timer.elapsedMs();
}

bool SslpvSolver::reinjectChangedDiffusionSources() {
    const Timer timer;
    const CoarseMaterial& now = m_material;
    const CoarseMaterial& was = m_sourceMaterial;
    // A walk depends on the inside cells (where beams enter and stop) and on σt′, σs′ along
    // them; a new shape, grid or η re-walks everything (m_injectionDirty). The drift of adding
    // and taking away in float is bounded by a full walk every MAX_INCREMENTAL updates.
    constexpr int MAX_INCREMENTAL = 64;
    if (m_incrementalInjections >= MAX_INCREMENTAL || !(was.spec == now.spec) ||
        was.insideFraction != now.insideFraction || m_beamSegments.size() != m_samples.size())
        return false;
    const GridSpec& s = now.spec;
    const ChangedCells diff = changedCells(now, was, /*withScattering=*/true);
    const std::vector<uint32_t>& changed = diff.cells;
    // A stroke over much of the object gains nothing from the bookkeeping.
    if (changed.size() > s.voxelCount() / 8)
        return false;
    m_stats.rewalkedTexels = 0;
    if (!changed.empty()) {
        // The beams whose walked segment meets the changed cells' box.
        std::vector<uint32_t> affected;
        for (size_t j = 0; j < m_samples.size(); ++j)
            if (m_beamEntered[j] && segmentMeetsBox(m_beamSegments[j].from, m_beamSegments[j].to,
                                                    diff.boxLo, diff.boxHi))
                affected.push_back(uint32_t(j));
        // Each affected beam is walked through the old material with its deposits taken away
        // and through the new one with them added, in parallel over ranges of the list and
        // applied in its (texel) order: deterministic on any thread count.
        constexpr int64_t BEAMS_PER_PART = 256;
        const std::vector<BeamPart> parts =
            walkInParts(int64_t(affected.size()), BEAMS_PER_PART, [&](BeamPart& part, int64_t b) {
                const size_t j = affected[size_t(b)];
                const auto keep = [&](const BeamDeposit& d) { part.deposits.push_back(d); };
                part.count(walkDiffusionBeam(m_samples[j], m_eta, was, -1.f, keep));
                const BeamWalk after = walkDiffusionBeam(m_samples[j], m_eta, now, 1.f, keep);
                part.count(after);
                m_beamSegments[j] = {after.from, after.to};
            });
        applyBeamParts(parts, m_diffusionSource, m_sourceInjected, m_sourceFirstAbsorbed);
        for (const uint32_t k : changed)
            for (int ch = 0; ch < 3; ++ch) {
                m_sourceMaterial.sigma_t[ch][k] = now.sigma_t[ch][k];
                m_sourceMaterial.sigma_s[ch][k] = now.sigma_s[ch][k];
            }
        m_stats.rewalkedTexels = int(affected.size());
        ++m_incrementalInjections;
    }
    for (int ch = 0; ch < 3; ++ch) {
        m_stats.injected[ch] = float(m_sourceInjected[size_t(ch)]);
        m_stats.absorbed[ch] = float(m_sourceFirstAbsorbed[size_t(ch)]);
    }
    m_stats.injectMs = timer.elapsedMs();
    return true;
}

void SslpvSolver::diffuse() {
    const Timer timer;
    const GridSpec& s = m_material.spec;
    GridDiffusionOptions o;
    o.maxIterations = m_opt.maxSteps;
    o.tolerance = m_opt.stopEpsilon;
    const GridDiffusionStats& ds = m_diffusion.solve(m_diffusionSource, o);
    // The read-out (radiance(), the GL shader) returns L_i = 2/(Δx²)·Y00·c00 and multiplies it
    // by T(ω_o)/η² (exitScale). A Fresnel-weighted diffuse exit of the exitance J,
    // L_o = T(ω_o)·J/(π(1 − F_dr(η))), has ∫ L_o cos θ_o dω_o = J, so c00 = η²·J·Δx²/(2·Y00·π(1 −
    // F_dr(η))) per cell; the higher coefficients are 0.
    const int n = s.resolution;
    // Order 2's nine slots whatever the solver's order: band 0 the light, slot 1 the albedo,
    // slots 2–4 the surface flux (shared/SslpvShared.h).
    if (m_accum.resolution() != n || m_accum.order() != LUCENT_SSLPV_DIFFUSION_ORDER)
        m_accum = SslpvGrid(n, LUCENT_SSLPV_DIFFUSION_ORDER);
    else
        m_accum.clear();
    const float exitNorm =
        float(double(m_eta) * m_eta / (PI * (1.0 - diffuseFresnelReflectance(double(m_eta)))));
    const float toC00 = exitNorm * s.voxelSize * s.voxelSize / (2.f * Y00);
    if (m_opt.diffusionExactTotal && (!m_exactRatio || m_exactRatio->eta() != double(m_eta)))
        m_exactRatio = exactReflectanceRatio(double(m_eta));
    const bool slab = m_opt.diffusionExactTotal && m_opt.diffusionSlabTotal;
    if (slab && (!m_slabRatio || m_slabRatio->eta() != double(m_eta)))
        m_slabRatio = exactSlabRatio(double(m_eta));
    m_exitTable =
        m_opt.diffusionExitTable ? dipole::DirpoleExitTable::shared(double(m_eta)) : nullptr;
    m_surfaceFluxReadout = m_opt.diffusionSurfaceFlux;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const Coord c(x, y, z);
                const size_t k = s.linearIndex(c);
                if (!m_diffusion.isBoundary(k))
                    continue;  // only boundary cells are read (isReadable)
                const std::array<Vector3f, 3> surfaceFlux = m_diffusion.surfaceFlux(k);
                for (int ch = 0; ch < 3; ++ch) {
                    const float st = m_material.sigma_t[ch][k];
                    const float albedo =
                        st > 0.f ? std::clamp(m_material.sigma_s[ch][k] / st, 0.f, 1.f) : 0.f;
                    float scale = toC00;
                    if (slab)
                        scale *= (*m_slabRatio)(albedo, st * m_diffusion.chordLength(k));
                    else if (m_opt.diffusionExactTotal)
                        scale *= (*m_exactRatio)(albedo);
                    const size_t at = m_accum.index(c);
                    m_accum.plane(ch, 0)[at] = scale * m_diffusion.exitance(k, ch);
                    m_accum.plane(ch, LUCENT_SSLPV_DIFFUSION_ALBEDO_COEFF)[at] = albedo;
                    // The flux along the surface, in the band-0 slot's units (the same scale),
                    // so the read-out's P1 term sees the ratio J_t/J the model has.
                    const Vector3f flux = scale * surfaceFlux[size_t(ch)];
                    for (int a = 0; a < 3; ++a)
                        m_accum.plane(ch, LUCENT_SSLPV_DIFFUSION_FLUX_COEFF + a)[at] = flux[a];
                }
            }
    m_stats.stepsUsed = std::max({ds.iterations[0], ds.iterations[1], ds.iterations[2]});
    m_stats.activeBricksPerStep.clear();
    m_stats.cellsComputed = int64_t(ds.cells) * m_stats.stepsUsed;
    for (int ch = 0; ch < 3; ++ch) {
        m_stats.absorbed[ch] += float(ds.absorbed[size_t(ch)]);
        m_stats.exitant[ch] = float(ds.exitant[size_t(ch)]);
        m_stats.remaining[ch] = float(ds.residual[size_t(ch)] * ds.source[size_t(ch)]);
    }
    m_stats.stepsMs = ds.ms;
    m_stats.propagateMs = timer.elapsedMs();
}

bool SslpvSolver::reinjectChangedChords() {
    const Timer timer;
    const CoarseMaterial& now = m_material;
    const CoarseMaterial& was = m_sourceMaterial;
    // A chord depends on the inside cells (where it runs) and on σt along it; a new shape, grid
    // or η injects everything again (m_injectionDirty). The drift of replacing deposits in float
    // is bounded by a full injection every MAX_INCREMENTAL updates.
    constexpr int MAX_INCREMENTAL = 64;
    if (m_incrementalInjections >= MAX_INCREMENTAL || !(was.spec == now.spec) ||
        was.insideFraction != now.insideFraction || m_injectionCell.size() != m_samples.size())
        return false;
    const GridSpec& s = now.spec;
    const ChangedCells diff = changedCells(now, was, /*withScattering=*/false);
    if (diff.cells.size() > s.voxelCount() / 8)
        return false;  // a stroke over much of the object gains nothing from the bookkeeping
    m_stats.rewalkedTexels = 0;
    if (diff.cells.empty())
        return true;  // σs′ or g only: the injection stands
    const int count = shCount(m_opt.order);
    int rewalked = 0;
    for (size_t j = 0; j < m_samples.size(); ++j) {
        const uint32_t k = m_injectionCell[j];
        if (k == UINT32_MAX ||
            !segmentMeetsBox(m_beamSegments[j].from, m_beamSegments[j].to, diff.boxLo, diff.boxHi))
            continue;
        // inject()'s deposit with the new σt along the chord; its difference from the old one
        // replaces that in the injection grid.
        const SslpvInjectionSample& smp = m_samples[j];
        const float cosI = -glm::dot(smp.direction, smp.normal);
        const float T = 1.f - fresnelDielectric(cosI, m_eta);
        const Vector3f wt = refractInto(smp.direction, smp.normal, m_eta);
        const Coord cell(int(k % size_t(s.resolution)),
                         int((k / size_t(s.resolution)) % size_t(s.resolution)),
                         int(k / (size_t(s.resolution) * size_t(s.resolution))));
        const Rgb before = m_injectionFraction[j];
        const Rgb after = interactingFraction(smp.position, wt, cell, &m_beamSegments[j]);
        m_injectionFraction[j] = after;
        const ShCoeffs<2> lobe = clampedCosineLobe<2>(wt);
        const size_t idx = m_injection.index(cell);
        for (int ch = 0; ch < 3; ++ch) {
            const float delta = T * (after[ch] - before[ch]) * smp.flux[ch] * INV_PI;
            for (int i = 0; i < count; ++i)
                m_injection.plane(ch, i)[idx] += delta * lobe.c[i];
        }
        ++rewalked;
    }
    for (const uint32_t k : diff.cells)
        for (int ch = 0; ch < 3; ++ch)
            m_sourceMaterial.sigma_t[ch][k] = now.sigma_t[ch][k];
    m_stats.rewalkedTexels = rewalked;
    ++m_incrementalInjections;
    m_stats.injectMs = timer.elapsedMs();
    return true;
}

}  // namespace lucent::sslpv
