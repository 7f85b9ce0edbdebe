#version 450 core
// SPDX-License-Identifier: MIT
// Progressive image-space dipole gather of dipole::DipoleSubsurfaceProvider (Mertens et al.
// 2005, Mertens et al. 2005 §4–6): the estimator of dipole_gather.comp / engine/src/dipole/ImageSpace.cpp
// (importance samples of R_d(r)·r per channel + uniform disc samples, multi-sample balance
// heuristic §6.1, Eq. 9 Jacobian, interleaved Cranley–Patterson shifts), reading the renderer's
// G-buffer and the irradiance pass's images (GL rows, bottom first; the interleave cell and the
// pixel projection use top-first rows like the CPU gather, so frame 0 equals gatherImageSpace()).
// Each frame adds one estimate B_f (a new shift table) to a running sum; the output is the mean:
//   L = F_t(η, ω_o) · (Σ_f B_f / N) / π   (Eq. 3), W/(mm²·sr).
// Frames after the first add a per-pixel hashed offset to the cell's shifts (u_pixelShifts):
// with the table alone, pixels k apart use the same samples in every frame, so their errors stay
// equal however many frames are averaged and the converged image keeps a k×k-periodic error
// pattern (the "waffle" of issue 17, docs/methods/dipole.md §3c).
// Convergence statistics: atomic max of |B̄_N − B̄_{N−1}| and of B̄_N over pixels and channels.
// Light views (Mertens et al. 2005 §7.1): the camera and the gathered light views split the pixel's sample
// budget (viewSamples) and are combined by the balance heuristic with sample counts in
// surface-area measure (dipole_lightview.glsl; docs/methods/dipole.md §3d); maxRadius > 0
// truncates the camera's samplers to the local window, a light view's are truncated to the disc
// A′ (r′ ≤ R′, Mertens et al. 2005 §5: the issue-6 firefly fix, as ImageSpace.cpp).
// MULTI_VIEW 0 (a second program of the provider, used when no light view is gathered): the
// camera gather alone, without the code of the view combination: on llvmpipe that code slowed
// even the camera-only loop ≈ 2× (23 → 12 ms per frame on the back-lit scene at 256×192; a
// branch on the view count did not avoid it, the cause was not isolated further).
#ifndef MULTI_VIEW
#define MULTI_VIEW 1
#endif
#include "common/dispatch.glsl"
#include "common/hash.glsl"
#include "dipole_profiles.glsl"
#include "dipole_fresnel.glsl"
#include "dipole_lightview.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2D u_position;    // xyz mm, a coverage
layout(binding = 1) uniform sampler2D u_normal;      // unit normal facing the camera
layout(binding = 2) uniform sampler2D u_irradiance;  // E (W/mm²)
layout(binding = 3) uniform sampler2D u_sigmaT;      // σt (mm⁻¹)
layout(binding = 4) uniform sampler2D u_sigmaS;      // rgb σs′ (mm⁻¹), a disc radius R′ (mm)

layout(rgba32f, binding = 0) uniform image2D u_accum;            // rgb Σ_f B_f (W/mm²), a frames
layout(rgba32f, binding = 1) writeonly uniform image2D u_target;  // renderer's subsurface term

layout(std430, binding = 0) readonly buffer ShiftBlock { vec4 b_shift[]; };  // 2 per cell
layout(std430, binding = 1) buffer StatsBlock { uint b_maxChange; uint b_maxMean; };

// Light views (Mertens et al. 2005 §7.1), one array layer per light; b_views lists the gathered ones.
layout(binding = 5) uniform sampler2DArray u_lvPosition;    // xyz mm, a covered
layout(binding = 6) uniform sampler2DArray u_lvNormal;      // outward unit normal
layout(binding = 7) uniform sampler2DArray u_lvIrradiance;  // E (W/mm²), all lights, shadowed
struct LightView {
    mat4 clipFromWorld;
    vec4 eyeOrtho;  // xyz centre of projection (mm); w 1 orthographic
    vec4 viewDir;   // xyz unit direction the view looks; w its layer of the u_lv* arrays
};
layout(std430, binding = 2) readonly buffer LightViewBlock { LightView b_views[]; };
// The catch-up list of dipole_material_update.comp (its counts, then x | y << 16 per pixel).
layout(std430, binding = 4) readonly buffer UpdateBlock { uvec4 b_updateCounts; uint b_list[]; };

uniform mat4 u_clipFromWorld;
uniform vec3 u_eye;
uniform vec3 u_viewDir;
uniform int u_ortho;
uniform ivec2 u_size;
uniform int u_model;  // 0 dipole, 1 better dipole
uniform vec3 u_boundary;  // F_dr, C1, C2
uniform float u_eta;
uniform int u_nImp;
uniform int u_nUni;
uniform int u_jacobian;
uniform float u_maxJacobian;
uniform int u_interleave;
// 1: this frame's shifts are the cell's plus a hash of (pixel, u_frameSeed), mod 1 — an
// independent uniform Cranley–Patterson rotation per pixel; 0 (frame 0, previews): the table
// alone, exactly the CPU gather's samples.
uniform int u_pixelShifts;
uniform uint u_frameSeed;
uniform float u_maxRadius;  // mm; > 0: only r ≤ u_maxRadius (ProviderSettings::maxRadius)
uniform int u_lightViews;     // light views gathered (entries of b_views), 0: camera only
uniform int u_lightViewSize;  // texels per side of each light view
uniform int u_gather;  // 1: add one frame of samples; 0: only resolve the stored mean
// 0: the accumulation restarts (every gathered pixel's sum is overwritten); else each pixel's
// frame count is its own, in u_accum's alpha (material-only restarts reset single pixels).
uniform int u_framesBefore;
// Frame parts (interactive accumulations, docs/methods/dipole.md §3c): a frame's samples are
// added over u_parts provider frames; work-group row y belongs to part y mod u_parts. The gather
// program is dispatched over part u_part's rows only; the RESOLVE_ONLY program over every pixel.
// Every pixel gets exactly the samples of a one-part frame. RESOLVE_ONLY 1 (a third program): no
// gather code at all — llvmpipe runs the straight-line code of a branch under its execution mask
// even when no lane takes it, so a resolve inside the gather program cost nearly a gather
// (≈ 200 ms at 640×360).
uniform int u_parts;
uniform int u_part;
// Catch-up after a material-only restart: u_listCount > 0 dispatches one invocation per listed
// pixel (64 per work group, in list order) instead of the image's rows; a listed pixel with
// fewer than u_level frames gathers one more. A list, not a branch, because of the execution
// mask above: only the listed pixels pay for the gather.
uniform int u_listCount;
uniform int u_level;
// With u_listCount > 0: a preview of the listed pixels that have no frame yet (a paint stroke's
// frame, ProviderSettings::previewSamples camera-only samples): stored with alpha −1, shown by
// the resolve, never added to a sum (the first catch-up frame overwrites it).
uniform int u_listPreview;
#ifndef RESOLVE_ONLY
#define RESOLVE_ONLY 0
#endif

const float PI = 3.14159265358979;

// Views (dipole_lightview.glsl): 0 the camera (G-buffer + the irradiance pass's E), 1.. the
// light views gathered (Mertens et al. 2005 §7.1; layers of the u_lv* arrays, descriptors in b_views).
mat4 viewClip(int v) { return v == 0 ? u_clipFromWorld : b_views[v - 1].clipFromWorld; }
bool viewOrtho(int v) { return v == 0 ? u_ortho != 0 : b_views[v - 1].eyeOrtho.w > 0.5; }
vec3 viewEye(int v) { return v == 0 ? u_eye : b_views[v - 1].eyeOrtho.xyz; }
vec3 viewDirection(int v) { return v == 0 ? u_viewDir : b_views[v - 1].viewDir.xyz; }
ivec2 viewSize(int v) { return v == 0 ? u_size : ivec2(u_lightViewSize); }
int viewLayer(int v) { return int(b_views[v - 1].viewDir.w + 0.5); }
vec4 viewPosition(int v, ivec2 pix) {
    return v == 0 ? texelFetch(u_position, pix, 0)
                  : texelFetch(u_lvPosition, ivec3(pix, viewLayer(v)), 0);
}
vec3 viewNormal(int v, ivec2 pix) {
    return v == 0 ? texelFetch(u_normal, pix, 0).xyz
                  : texelFetch(u_lvNormal, ivec3(pix, viewLayer(v)), 0).xyz;
}
vec3 viewIrradiance(int v, ivec2 pix) {
    return v == 0 ? texelFetch(u_irradiance, pix, 0).rgb
                  : texelFetch(u_lvIrradiance, ivec3(pix, viewLayer(v)), 0).rgb;
}

vec3 towardEye(vec3 p) { return towardEyeOf(0, p); }

float radicalInverse2(uint i) { return float(bitfieldReverse(i)) * 2.3283064365386963e-10; }
vec2 hammersley(uint i, uint n) { return vec2((float(i) + 0.5) / float(n), radicalInverse2(i)); }
float halton3(uint i) {
    float f = 1.0, r = 0.0;
    while (i > 0u) {
        f /= 3.0;
        r += f * float(i % 3u);
        i /= 3u;
    }
    return r;
}

// The pixel's sampling techniques (set by setUpTechniques). Channel arrays are indexed by
// constants only where it matters (llvmpipe lowers dynamic indices of private arrays to
// per-lane selects).
Profile g_prof[3];
vec3 g_masses[3];    // window u_maxRadius (the camera's techniques)
vec3 g_lvMasses[3];  // window g_R, the disc A′ (the light views' techniques, see below)
int g_channels[3];  // the valid channels, in order
int g_slot[3];      // channel → its round-robin slot in g_channels (−1: invalid)
int g_channelCount;
float g_R, g_pUniform;

// Sets the globals above for pixel xy (its material and disc radius); false: no valid channel.
// Defined before every function that reads them: Mesa's GLSL compiler warns "used
// uninitialized" for a global read textually before any assignment, and the GL debug log
// reports that warning as an error on every compile that misses the shader cache.
bool setUpTechniques(ivec2 xy) {
    vec4 sigS4 = texelFetch(u_sigmaS, xy, 0);
    vec3 sigT = texelFetch(u_sigmaT, xy, 0).rgb, sigS = sigS4.rgb;
    g_channelCount = 0;
    g_R = sigS4.a;  // min(R′, maxRadius), from the irradiance pass
    for (int c = 0; c < 3; ++c) {
        g_prof[c] = makeProfile(u_model, max(sigT[c] - sigS[c], 0.0), sigS[c], u_boundary);
        g_masses[c] = windowMasses(g_prof[c], u_maxRadius);
        g_slot[c] = -1;
        g_lvMasses[c] = vec3(1.0);
        if (g_prof[c].zr > 0.0) {
            g_slot[c] = g_channelCount;
            g_channels[g_channelCount++] = c;
        }
    }
    g_pUniform = g_R > 0.0 ? 1.0 / (PI * g_R * g_R) : 0.0;
#if MULTI_VIEW
    for (int c = 0; c < 3; ++c) g_lvMasses[c] = windowMasses(g_prof[c], g_R);
#endif
    return g_channelCount > 0;
}

// View v's share of the pixel's budget (dipole::viewSamples, docs/methods/dipole.md §3d): the
// nImp + nUni samples (importance first) go to view g mod views; a view left with none draws one
// importance sample. Returns (importance, uniform).
ivec2 viewSamples(int nImp, int nUni, int views, int v) {
    int imp = nImp > v ? (nImp - v - 1) / views + 1 : 0;
    int total = nImp + nUni > v ? (nImp + nUni - v - 1) / views + 1 : 0;
    return total == 0 ? ivec2(1, 0) : ivec2(imp, total - imp);
}

// Multi-sample balance heuristic over the techniques of view v with `counts` samples
// (Veach 1997 Eq. 9.13; Mertens et al. 2005 §6.1): Σ_t n_t p_t at tangent-plane radius r′, the importance
// samples assigned to the valid channels round robin. The camera's samplers have the window
// u_maxRadius; a light view's are conditioned on the disc A′ (r′ ≤ g_R, Mertens et al. 2005 §5), as in
// ImageSpace.cpp (docs/methods/dipole.md §3d "Light views sample the disc A′").
float techniquePdf(int v, ivec2 counts, float rPlane) {
    float sum = rPlane <= g_R ? float(counts.y) * g_pUniform : 0.0;
    for (int c = 0; c < 3; ++c) {
        int s = g_slot[c];
        int n = s >= 0 && counts.x > s ? (counts.x - s - 1) / g_channelCount + 1 : 0;
        if (n > 0)
            sum += float(n) * (v == 0 ? pdfWindowed(g_prof[c], g_masses[c], u_maxRadius, rPlane)
                                      : pdfWindowed(g_prof[c], g_lvMasses[c], g_R, rPlane));
    }
    return sum;
}

// One estimate of B(x_o) (Eq. 4, W/mm²) at pixel xy with the shifts of its interleave cell.
vec3 gatherExitance(ivec2 xy, vec3 xo, vec3 no) {
    float sgn = no.z >= 0.0 ? 1.0 : -1.0;  // Duff et al. 2017 basis (lucent::Frame)
    float a = -1.0 / (sgn + no.z);
    float bb = no.x * no.y * a;
    vec3 fs = vec3(1.0 + sgn * no.x * no.x * a, sgn * bb, -sgn * no.x);
    vec3 ft = vec3(bb, sgn + no.y * no.y * a, -no.y);

    if (!setUpTechniques(xy)) return vec3(0.0);
    int k = u_interleave;
    int cell = ((u_size.y - 1 - xy.y) % k) * k + (xy.x % k);
    vec4 s0 = b_shift[2 * cell], s1 = b_shift[2 * cell + 1];
    if (u_pixelShifts != 0) {
        // A uniform offset added mod 1 (the fract() below) makes each pixel's shift uniform and
        // independent of every other pixel's, so each frame stays an unbiased RQMC estimate.
        uint h = pcgHash(uint(xy.x) + pcgHash(uint(xy.y) + pcgHash(u_frameSeed)));
        s0 += vec4(toUnit(pcgHash(h)), toUnit(pcgHash(h + 1u)), toUnit(pcgHash(h + 2u)),
                   toUnit(pcgHash(h + 3u)));
        s1.x += toUnit(pcgHash(h + 4u));
    }
    bool jac = u_jacobian != 0;

    vec3 B = vec3(0.0);
    int views = MULTI_VIEW != 0 ? 1 + u_lightViews : 1;
    int nUni = g_R > 0.0 ? u_nUni : 0;
    for (int v = 0; v < views; ++v) {
        // View v's share of the budget: its own points, rotated by v times the golden ratio.
        ivec2 counts = viewSamples(u_nImp, nUni, views, v);
        float rot = float(v) * 0.61803398875;
        for (int i = 0; i < counts.x + counts.y; ++i) {
            float rPlane, phi;
            if (i < counts.x) {
                vec2 h = hammersley(uint(i), uint(counts.x));
                float uSrc = fract(halton3(uint(i)) + s0.x + rot);
                float uR = fract(h.x + s0.y + rot), uPhi = fract(h.y + s0.z + rot);
                int c = g_channels[i % g_channelCount];
                rPlane = v == 0 ? sampleWindowed(g_prof[c], g_masses[c], u_maxRadius, uSrc, uR)
                                : sampleWindowed(g_prof[c], g_lvMasses[c], g_R, uSrc, uR);
                phi = 2.0 * PI * uPhi;
            } else {
                int j = i - counts.x;
                vec2 h = hammersley(uint(j), uint(counts.y));
                rPlane = g_R * sqrt(fract(h.x + s0.w + rot));
                phi = 2.0 * PI * fract(h.y + s1.x + rot);
            }
            vec3 pPlane = xo + rPlane * (cos(phi) * fs + sin(phi) * ft);
            ViewHit hit;
            if (!lookUp(v, pPlane, hit)) continue;
            // x_o's own camera pixel: its tangent plane holds pPlane, so the eye ray meets it at
            // pPlane (r = r') at any angle; lookUp's grazing fallback gave r = 0 (issue-6 edge
            // outlier; as ImageSpace.cpp, docs/methods/dipole.md §3).
            if (v == 0 && hit.pix == xy) {
                hit.p = pPlane;
                hit.n = no;
            }
            vec3 E = viewIrradiance(v, hit.pix);
            if (E == vec3(0.0)) continue;  // unlit sample: contributes exactly 0
            float r = length(hit.p - xo);
            if (u_maxRadius > 0.0 && r > u_maxRadius) continue;  // outside the local window
            float J = areaJacobian(v, hit.p, hit.n, pPlane, no, jac, u_maxJacobian);
            if (!(J > 0.0)) continue;
            float own = techniquePdf(v, counts, rPlane);
            if (!(own > 0.0)) continue;
            // Balance heuristic across the views' techniques in surface-area measure (Mertens et al. 2005
            // §7.1): w = 1/Σ_j q_j, q_j = Σ_t n_jt p_t(r′_j)/J_j over the views j in which hit.p
            // is visible (q_v = own/J); one view: J/Σ_t n_t p_t. The MULTI_VIEW 0 program has
            // no code for the other views (see the top of the file).
            float sum = own / J;
#if MULTI_VIEW
            float fp = pixelFootprint(v, hit.p);
            for (int m = 1; m < views; ++m) {
                int j = (v + m) % views;
                vec3 pj;
                if (!visibleIn(j, hit.p, fp) || !tangentPlanePoint(j, hit.p, xo, no, pj)) continue;
                float Jj = areaJacobian(j, hit.p, hit.n, pj, no, jac, u_maxJacobian);
                ivec2 countsJ = viewSamples(u_nImp, nUni, views, j);
                if (Jj > 0.0) sum += techniquePdf(j, countsJ, length(pj - xo)) / Jj;
            }
#endif
            float w = 1.0 / sum;
            for (int c = 0; c < 3; ++c) B[c] += rd(g_prof[c], r) * E[c] * w;
        }
    }
    return B;
}

shared uint s_maxChange;
shared uint s_maxMean;

void main() {
    if (gl_LocalInvocationIndex == 0u) {
        s_maxChange = 0u;
        s_maxMean = 0u;
    }
    barrier();
    ivec2 group = ivec2(gl_WorkGroupID.xy);
    ivec2 xy = group * 8 + ivec2(gl_LocalInvocationID.xy);
    bool inside = xy.x < u_size.x && xy.y < u_size.y;
#if RESOLVE_ONLY
    const bool gatherHere = false, listed = false;
#else
    bool listed = u_listCount > 0;
    if (listed) {
        uint i = lineGroup() * 64u + gl_LocalInvocationIndex;  // gpu::dispatchLine
        inside = i < uint(u_listCount);
        uint code = inside ? b_list[i] : 0u;
        xy = ivec2(code & 0xffffu, code >> 16);
    } else if (u_parts > 1) {
        group.y = u_part + u_parts * group.y;  // the rows of part u_part only
        xy = group * 8 + ivec2(gl_LocalInvocationID.xy);
        inside = xy.x < u_size.x && xy.y < u_size.y;
    }
    bool gatherHere = u_gather != 0;
#endif
    vec4 pos = inside ? texelFetch(u_position, xy, 0) : vec4(0.0);
    if (inside && pos.w == 0.0) imageStore(u_target, xy, vec4(0.0));
    if (inside && pos.w != 0.0) {
        vec3 xo = pos.xyz;
        vec3 no = normalize(texelFetch(u_normal, xy, 0).xyz);
        vec4 acc = imageLoad(u_accum, xy);
        int frames = acc.a > 0.0 ? int(acc.a + 0.5) : 0;
#if !RESOLVE_ONLY
        if (u_framesBefore == 0 && !listed) frames = 0;
        if (listed) gatherHere = gatherHere && (u_listPreview != 0 ? frames == 0 : frames < u_level);
#endif
        vec3 sum = frames > 0 ? acc.rgb : vec3(0.0);
#if !RESOLVE_ONLY
        if (gatherHere) {
            vec3 B = gatherExitance(xy, xo, no);
            if (u_listPreview != 0) {
                // Shown by the resolve that follows; no sum, no statistics.
                imageStore(u_accum, xy, vec4(B, -1.0));
            } else {
                vec3 oldMean = frames > 0 ? sum / float(frames) : vec3(0.0);
                sum += B;
                frames += 1;
                vec3 mean = sum / float(frames);
                imageStore(u_accum, xy, vec4(sum, float(frames)));
                // Non-negative floats order like their bit patterns: atomicMax on uint, first in
                // shared memory, then once per work group. Catch-up frames add nothing: the
                // convergence test is the whole image's (the host does not read them).
                if (frames > 1 && !listed) {
                    vec3 d = abs(mean - oldMean);
                    atomicMax(s_maxChange, floatBitsToUint(max(d.r, max(d.g, d.b))));
                }
                if (!listed)
                    atomicMax(s_maxMean, floatBitsToUint(max(mean.r, max(mean.g, mean.b))));
            }
        }
#endif
        vec3 mean = frames > 0 ? sum / float(frames) : vec3(0.0);
#if RESOLVE_ONLY
        if (acc.a < 0.0) mean = acc.rgb;  // a stroke's preview: one estimate, no sum
#endif
        // Eq. 3: L = F_t(η, ω_o) B/π, F_t = 1 − F_r for the exit direction.
        float cosO = max(0.0, dot(no, towardEye(xo)));
        float Ft = 1.0 - dipoleFresnelReflectance(cosO, u_eta);
        imageStore(u_target, xy, vec4(mean * (Ft / PI), 0.0));
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && gatherHere) {
        atomicMax(b_maxChange, s_maxChange);
        atomicMax(b_maxMean, s_maxMean);
    }
}
