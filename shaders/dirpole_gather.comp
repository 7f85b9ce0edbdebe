#version 450 core
// SPDX-License-Identifier: MIT
// Gather pass of dipole::DirpoleSubsurfaceProvider (the dirpole thesis §4.1 step 2, "render to cubemap"):
// for every cube-face fragment x_o (normal n_o) and light, k new disc samples around x_o in the
// light's view add to a running sum (one layer per face)
//   C^f(x_o) += Σ_i E⊥(x_i) T₁₂(ω_i) S_d(x_i, ω₁₂; x_o) ΔA⊥_i          (the dirpole thesis §4.1, C^f)
// where x_i, n_i are the light G-buffer texel the sample falls in, ω₁₂ the refracted light
// direction (Snell), T₁₂ = 1 − F_r (Fresnel), S_d the Frisvad et al. 2014 directional dipole
// and ΔA⊥_i = 1/(k·p(r)) the light-plane area a sample stands for: the disc is importance-
// sampled with the better dipole's exact sampler per channel (Mertens et al. 2005 §4; multi-sample balance
// heuristic over the channels, as the CPU DirectionalDipoleRenderer) instead of the dirpole thesis's
// uniform disc, because S_d falls off over a few diffusion lengths while a uniform disc must
// reach the far tail. Point/spot lights: the flux crossing the disc plane (normal along the ray
// to x′_o) is I(ω)cosθ_p/ρ_p² per unit plane area (inverse-square law), which the same
// perspective G-buffer texel receives.
// Seed 001 §4.3.1 (G-buffer shrink): the disc is centred at x′_o = x_o − ε_g(n_o − ω_l(ω_l·n_o)),
// with ε_g at most one mean free path 1/σt′ (deeper than the dipole's real source, S_d of a
// dense medium vanishes; DirectionalPipeline.cpp shrinkWithin).
// Sub-texel sources: a sample's x_i is where the light ray through it crosses the tangent plane
// of the light G-buffer texel it lands in, not the texel's stored centre. Where the profile is
// narrower than a light texel (dense media, metre-sized objects) the centre is many diffusion
// lengths from x_o and S_d read 0 (stability matrix, docs/benchmarks.md); on the plane the
// error is second order in the texel size. (x_o's own plane for samples in x′_o's texel was
// tried and rejected: S_d's real-source term is not bounded by the sampler's pdf as r → 0, and
// the estimate blew up to 35× at σt′ = 10⁴ mm⁻¹.)
// Progressive, per texel: the texel's accumulator holds Σ over its N samples of the one-sample
// estimate and N (a); a frame adds k_t = min(u_k, u_target − N) samples n = N … N + k_t − 1 of a
// per-texel rotated R2 sequence, so the sum after N samples does not depend on how they were
// spread over frames. Sample n uses channel c_n = channels[(n + o_t) mod m] (o_t a per-texel
// hash, m the channels with a profile): every channel is chosen with probability 1/m, and the
// one-sample balance heuristic (Veach 1997 §9.2.4) weights f/p by p_c/Σ_c p_c with p = Σ_c p_c/m
// per unit light-plane area, i.e. each sample is f·m/Σ_c p_c(r) (the CPU pipeline's n_c/k =
// 1/m up to the rounding of k/m).
// Convergence statistics: atomic max of |C̄_after − C̄_before| and of C̄_after over the sampled
// texels, and their count.
#include "common/hash.glsl"
#include "common/lighting.glsl"
#include "dipole_fresnel.glsl"
#include "shared/DirpoleShared.h"
#include "dipole_profiles.glsl"
#include "dirpole_common.glsl"
#include "common/dispatch.glsl"

layout(local_size_x = 64) in;  // one invocation per listed texel

layout(binding = 0) uniform sampler2DArray u_facePosition;   // xyz mm, a covered
layout(binding = 1) uniform sampler2DArray u_faceNormal;     // outward unit normal
layout(binding = 2) uniform sampler2DArray u_lightPosition;  // one layer per light
layout(binding = 3) uniform sampler2DArray u_lightNormal;

layout(binding = 4) uniform sampler2DArray u_matT;          // σt rgb at x_o (prepare pass)
layout(binding = 5) uniform sampler2DArray u_matS;          // σs′ rgb at x_o

layout(rgba32f, binding = 0) uniform image2DArray u_accum;  // rgb Σ C (W/(mm²·sr)), a = N

// The texels to sample (dirpole_compact.comp, packTexel words).
layout(std430, binding = 5) readonly buffer WorkList { uint b_texels[]; };
uniform uint u_listed;  // entries in b_texels

layout(location = 0) uniform mat4 u_lightClipFromWorld[LUCENT_MAX_LIGHTS];
uniform int u_lightCount;
uniform int u_lightMapSize;
uniform float u_eta;
uniform vec3 u_boundary;  // F_dr, C1(η), C2(η) for the sampler (better dipole)
uniform vec3 u_moments;   // C1(η), C2(η), C1(1/η) for the directional dipole
uniform uint u_k;       // samples per texel and light of this frame (at most)
uniform uint u_target;  // texels sample up to this count
uniform float u_shrink;   // ε_g (mm), 0 when the fix is off
uniform uint u_seed;
// Energy-normalised S_d (DirpoleSettings::energyNormalised): lucent::DirpoleEnergyTable::scale
// sampled at nodes uniform in s = √(1 − α′), interpolated linearly in s.
const int ENERGY_NODES = LUCENT_DIRPOLE_ENERGY_NODES;
uniform int u_energyNormalised;
uniform float u_energyScale[ENERGY_NODES];

// The exact target's incidence correction k(α′, μ₀) (lucent::dipole::DirpoleIncidenceTable):
// row-major [albedo node][cosine node], cosines uniform over [u_incidenceMinCosine, 1].
layout(std430, binding = LUCENT_DIRPOLE_BINDING_INCIDENCE_TABLE) readonly buffer
    DirpoleIncidenceValues {
    float b_incidence[];
};
uniform int u_incidenceCorrection;
uniform float u_incidenceMinCosine;

float incidenceCorrection(float alphaP, float mu0) {
    const int A = LUCENT_DIRPOLE_INCIDENCE_ALBEDO_NODES, C = LUCENT_DIRPOLE_INCIDENCE_COSINE_NODES;
    float s = sqrt(clamp(1.0 - alphaP, 0.0, 1.0)) * float(A - 1);
    int i = min(int(s), A - 2);
    float fs = s - float(i);
    float u = clamp((mu0 - u_incidenceMinCosine) / (1.0 - u_incidenceMinCosine), 0.0, 1.0) *
              float(C - 1);
    int j = min(int(u), C - 2);
    float fu = u - float(j);
    float lo = mix(b_incidence[i * C + j], b_incidence[i * C + j + 1], fu);
    float hi = mix(b_incidence[(i + 1) * C + j], b_incidence[(i + 1) * C + j + 1], fu);
    return mix(lo, hi, fs);
}

float energyScale(float alphaP) {
    float s = sqrt(clamp(1.0 - alphaP, 0.0, 1.0)) * float(ENERGY_NODES - 1);
    int i = min(int(s), ENERGY_NODES - 2);
    float t = s - float(i);
    return (1.0 - t) * u_energyScale[i] + t * u_energyScale[i + 1];
}

const float PI = 3.14159265358979;

// R2 sequence (Roberts 2018; lucent::r2Sequence) in 32-bit fixed point, so sample indices in
// the millions keep full precision: frac(offset + n·(1/φ₂, 1/φ₂²)).
vec2 r2(uint n, uvec2 offset) {
    return vec2(toUnit(offset.x + n * 3242174890u), toUnit(offset.y + n * 2447445414u));
}

// C^f contribution of one light at x_o (W/(mm²·sr)).
// Samples n = first … first + count − 1.
vec3 gatherLight(int l, vec3 xo, vec3 no, Dirpole dd[3], Profile prof[3], int channels[3],
                 int channelCount, uint first, uint count, uvec2 offset, uint texelSeed,
                 float shrink, vec3 alphaP) {
    GpuLight light = lights[l];
    bool directional = int(light.positionType.w) == LUCENT_LIGHT_DIRECTIONAL;
    vec3 wl, unusedE;
    float unusedD;
    lightIncidence(light, xo, wl, unusedE, unusedD);  // ω_l: unit, toward the light
    vec3 xs = xo - shrink * (no - wl * dot(wl, no));  // the dirpole thesis §4.3.1
    // Disc plane through x′_o, perpendicular to the light ray (Duff et al. 2017 basis).
    vec3 pn = directional ? -wl : normalize(xs - light.positionType.xyz);
    float sgn = pn.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sgn + pn.z);
    float b = pn.x * pn.y * a;
    vec3 fs = vec3(1.0 + sgn * pn.x * pn.x * a, sgn * b, -sgn * pn.x);
    vec3 ft = vec3(b, sgn + pn.y * pn.y * a, -pn.y);
    mat4 clipFromWorld = u_lightClipFromWorld[l];
    vec3 sum = vec3(0.0);
    uint rotation = pcgHash(texelSeed + 2u) % uint(channelCount);
    for (uint n = first; n < first + count; ++n) {
        vec2 u = r2(n, offset);
        float uSrc = toUnit(pcgHash(texelSeed ^ pcgHash(n + uint(l) * 0x68E31DA4u)));
        Profile p = prof[channels[(n + rotation) % uint(channelCount)]];
        float r = sampleSourceRadius(p.sigma, uSrc < p.pReal ? p.zr : p.zv, u.x);
        float phi = 2.0 * PI * u.y;
        // One-sample balance heuristic over the channels' samplers: weight/pdf = m/Σ_c p_c(r).
        float denom = 0.0;
        for (int j = 0; j < channelCount; ++j) denom += pdfArea(prof[channels[j]], r);
        denom /= float(channelCount);
        if (!(denom > 0.0)) continue;
        vec3 pp = xs + r * (cos(phi) * fs + sin(phi) * ft);
        // The light G-buffer texel the ray through pp lands in: x_i, n_i.
        vec4 clip = clipFromWorld * vec4(pp, 1.0);
        if (!(clip.w > 0.0)) continue;
        vec2 uv = (clip.xy / clip.w) * 0.5 + 0.5;
        if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0)))) continue;
        ivec3 texel = ivec3(ivec2(uv * float(u_lightMapSize)), l);
        vec4 xiCover = texelFetch(u_lightPosition, texel, 0);
        if (xiCover.w == 0.0) continue;
        vec3 xi = xiCover.xyz;
        vec3 ni = texelFetch(u_lightNormal, texel, 0).xyz;
        // The ray through pp on a tangent plane (file comment); not at grazing incidence,
        // where the plane would carry x_i far outside the texel.
        vec3 rayDir = directional ? pn : normalize(pp - light.positionType.xyz);
        float dn = dot(rayDir, ni);
        if (dn < -0.25) xi = pp + (dot(xi - pp, ni) / dn) * rayDir;
        vec3 wi, E, wp, Ep;
        float dist;
        lightIncidence(light, xi, wi, E, dist);
        float cosI = dot(ni, wi);
        if (cosI <= 0.0) continue;
        // Flux per unit disc area: E⊥ at pp times cos θ_p (1 for a directional light).
        lightIncidence(light, pp, wp, Ep, dist);
        float cosP = directional ? 1.0 : max(0.0, dot(-wp, pn));
        // Refracted direction of travel ω₁₂ (Snell, relative index 1/η from outside).
        vec3 wt = -wi;
        float sin2T = (1.0 - cosI * cosI) / (u_eta * u_eta);
        float cosT = sqrt(max(0.0, 1.0 - sin2T));
        vec3 w12 = normalize(wt / u_eta + (cosI / u_eta - cosT) * ni);
        float t12 = 1.0 - dipoleFresnelReflectance(cosI, u_eta);
        vec3 w = Ep * (cosP * t12 / denom);
        if (u_incidenceCorrection != 0)
            for (int c = 0; c < 3; ++c) w[c] *= incidenceCorrection(alphaP[c], cosT);
        for (int c = 0; c < 3; ++c) sum[c] += w[c] * dirpoleSd(dd[c], xi, ni, w12, xo, no);
    }
    return sum;
}

shared uint s_maxChange;
shared uint s_maxMean;
shared uint s_sampled;

void main() {
    if (gl_LocalInvocationIndex == 0u) {
        s_maxChange = 0u;
        s_maxMean = 0u;
        s_sampled = 0u;
    }
    barrier();
    uint index = lineGroup() * 64u + gl_LocalInvocationIndex;  // gpu::dispatchLine
    bool listed = index < u_listed;
    uint entry = listed ? b_texels[index] : 0u;
    ivec3 id = unpackTexel(entry);
    vec4 pos = listed ? texelFetch(u_facePosition, id, 0) : vec4(0.0);
    vec4 acc = listed ? imageLoad(u_accum, id) : vec4(0.0);
    uint before = uint(acc.a);
    if (listed && before < u_target) {  // covered and behind (the list): always written
        uint k = min(u_k, u_target - before);
        vec3 xo = pos.xyz;
        vec3 no = texelFetch(u_faceNormal, id, 0).xyz;
        vec3 sigT = texelFetch(u_matT, id, 0).rgb;  // 0 without material: black
        vec3 sigS = texelFetch(u_matS, id, 0).rgb;
        Dirpole dd[3];
        Profile prof[3];
        int channels[3];
        int channelCount = 0;
        vec3 alphaP = vec3(0.0);
        for (int c = 0; c < 3; ++c) {
            float sa = max(sigT[c] - sigS[c], 0.0);
            alphaP[c] = sigS[c] > 0.0 ? sigS[c] / (sa + sigS[c]) : 0.0;
            dd[c] = makeDirpole(sa, sigS[c], u_moments);
            if (u_energyNormalised != 0 && sigS[c] > 0.0)
                dd[c].norm *= energyScale(sigS[c] / (sa + sigS[c]));
            prof[c] = makeProfile(1, sa, sigS[c], u_boundary);
            if (prof[c].zr > 0.0 && !dd[c].zero) channels[channelCount++] = c;
        }
        vec3 C = vec3(0.0);
        if (channelCount > 0) {
            uint texelSeed = pcgHash(uint(id.x) + pcgHash(uint(id.y) + pcgHash(uint(id.z) +
                                                                               pcgHash(u_seed))));
            uvec2 offset = uvec2(pcgHash(texelSeed), pcgHash(texelSeed + 1u));
            float densest = max(sigT.r, max(sigT.g, sigT.b));
            float shrink = densest > 0.0 ? min(u_shrink, 1.0 / densest) : u_shrink;
            for (int l = 0; l < u_lightCount; ++l)
                C += gatherLight(l, xo, no, dd, prof, channels, channelCount, before, k, offset,
                                 texelSeed, shrink, alphaP);
        }
        vec3 oldMean = before > 0u ? acc.rgb / float(before) : vec3(0.0);
        vec3 sum = acc.rgb + C;
        uint after = before + k;
        vec3 mean = sum / float(after);
        imageStore(u_accum, id, vec4(sum, float(after)));
        if (before > 0u) {
            vec3 d = abs(mean - oldMean);
            atomicMax(s_maxChange, floatBitsToUint(max(d.r, max(d.g, d.b))));
        }
        atomicMax(s_maxMean, floatBitsToUint(max(mean.r, max(mean.g, mean.b))));
        atomicAdd(s_sampled, 1u);
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && s_sampled > 0u) {
        atomicMax(b_maxChange, s_maxChange);
        atomicMax(b_maxMean, s_maxMean);
        atomicAdd(b_sampled, s_sampled);
    }
}
