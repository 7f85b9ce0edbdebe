#version 450 core
// SPDX-License-Identifier: MIT
// App preview "Single scattering (ray-marched)" as a SceneRenderer subsurface pass (owner: app;
// driven by app/gui/PreviewPasses.cpp). Units: mm, mm^-1, W/sr, radiance W/(mm^2 sr).
//
// Per covered G-buffer pixel: the single-scattering term of the radiative transfer equation
// (Chandrasekhar 1960; pbrt-v3 Sec. 15.1, eq. 15.1 restricted to one scattering event),
// integrated by ray marching along the refracted view ray through the painted volume, with
// transmittance exp(-integral sigma_t) towards the camera and towards each light. It runs in
// the reduced medium (similarity relation sigma_s' = (1-g) sigma_s, isotropic phase 1/(4 pi);
// Wyman et al. 1989), which keeps the deep penetration of forward-scattering media.
// Surface: Fresnel reflectance by Schlick's approximation (Schlick 1994, eq. 24) with
// R0 = ((eta-1)/(eta+1))^2; the transmitted fraction 1-F enters the medium. The renderer adds
// the direct surface reflection in its shading pass.

#ifndef LOCAL_SIZE
#define LOCAL_SIZE 8
#endif
layout(local_size_x = LOCAL_SIZE, local_size_y = LOCAL_SIZE) in;

const int MAX_LIGHTS = 8;
const float PI = 3.14159265358979;

layout(binding = 0) uniform sampler2D u_position;  // rgb world position (mm), a coverage
layout(binding = 1) uniform sampler2D u_normal;    // rgb unit normal facing the camera
layout(binding = 2) uniform sampler3D u_sigmaT;    // rgb reduced extinction sigma_t, mm^-1
layout(binding = 3) uniform sampler3D u_sigmaS;    // rgb reduced scattering sigma_s', mm^-1
layout(binding = 0, rgba32f) uniform writeonly image2D u_target;

uniform ivec2 u_size;
uniform vec3 u_eye;
uniform int u_steps;       // view-ray march steps
uniform int u_lightSteps;  // shadow-ray march steps
uniform float u_eta;
uniform int u_lightCount;
uniform int u_lightType[MAX_LIGHTS];  // 0 point, 1 spot, 2 directional (sphere: as point)
uniform vec3 u_lightPos[MAX_LIGHTS];
uniform vec3 u_lightDir[MAX_LIGHTS];  // direction light travels (spot axis / directional)
uniform vec3 u_lightI[MAX_LIGHTS];    // W/sr (point, spot) or W/mm^2 (directional)
uniform vec2 u_spotCos[MAX_LIGHTS];   // cos(outer), cos(inner)
uniform vec3 u_gridOrigin;            // mm
uniform float u_gridSize;             // mm, edge of the cubic grid
uniform float u_voxelSize;            // mm
uniform vec3 u_ambient;               // W/mm^2 of uniform ambient irradiance (display aid)
uniform int u_meshId;                 // G-buffer mesh id + 1 to shade; 0: every covered pixel

vec3 texCoord(vec3 p) { return (p - u_gridOrigin) / u_gridSize; }

// Distance along unit direction d from p (inside or on the grid box) to the box exit.
float exitDistance(vec3 p, vec3 d) {
    vec3 lo = u_gridOrigin, hi = u_gridOrigin + vec3(u_gridSize);
    vec3 inv = 1.0 / max(abs(d), vec3(1e-8)) * sign(d + vec3(1e-12));
    vec3 t0 = (lo - p) * inv, t1 = (hi - p) * inv;
    vec3 tmax = max(t0, t1);
    return max(0.0, min(min(tmax.x, tmax.y), tmax.z));
}

// Direction to light i from p (unit) and the irradiance it delivers on a surface facing it
// (W/mm^2): I/r^2 for point-like lights (inverse-square law), the given value for
// directional ones.
void lightAt(int i, vec3 p, out vec3 toLight, out vec3 E) {
    if (u_lightType[i] == 2) {
        toLight = -normalize(u_lightDir[i]);
        E = u_lightI[i];
        return;
    }
    vec3 d = u_lightPos[i] - p;
    float r2 = max(dot(d, d), 1e-4);
    toLight = d * inversesqrt(r2);
    vec3 I = u_lightI[i];
    if (u_lightType[i] == 1)
        I *= smoothstep(u_spotCos[i].x, u_spotCos[i].y, dot(-toLight, normalize(u_lightDir[i])));
    E = I / r2;
}

// exp(-integral of sigma_t) from p towards the light to the grid's edge: u_lightSteps equal
// steps sampled at their midpoints (midpoint rule).
vec3 shadowTransmittance(vec3 p, vec3 toLight) {
    float len = exitDistance(p, toLight);
    float ds = len / float(u_lightSteps);
    vec3 tau = vec3(0.0);
    for (int k = 0; k < u_lightSteps; ++k)
        tau += texture(u_sigmaT, texCoord(p + toLight * (float(k) + 0.5) * ds)).rgb;
    return exp(-tau * ds);
}

float schlickFresnel(float cosTheta) {
    float r0 = (u_eta - 1.0) / (u_eta + 1.0);
    r0 *= r0;
    return r0 + (1.0 - r0) * pow(1.0 - clamp(cosTheta, 0.0, 1.0), 5.0);
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= u_size.x || px.y >= u_size.y)
        return;
    vec4 pos = texelFetch(u_position, px, 0);
    vec4 nrm = texelFetch(u_normal, px, 0);
    if (pos.a < 0.5 || (u_meshId > 0 && int(nrm.a + 0.5) != u_meshId)) {
        imageStore(u_target, px, vec4(0.0));
        return;
    }
    vec3 p0 = pos.xyz;
    vec3 n = normalize(nrm.xyz);
    vec3 V = normalize(u_eye - p0);
    if (dot(n, V) < 0.0)
        n = -n;
    float F = schlickFresnel(dot(n, V));

    vec3 wt = refract(-V, n, 1.0 / u_eta);
    if (dot(wt, wt) < 1e-6)
        wt = -n;
    wt = normalize(wt);
    // At most u_steps steps of at most two voxels: thin parts (ears, fins) are sampled at the
    // voxel scale; deeper than 2*u_steps voxels the view transmittance is ~0 for the media
    // painted here (sigma_t >= 0.1 mm^-1 over >= 20 mm gives T < 0.14).
    float len = exitDistance(p0, wt);
    float ds = min(len / float(u_steps), 2.0 * u_voxelSize);
    vec3 T = vec3(1.0 - F);
    // Sample offset within each step from interleaved gradient noise (Jimenez 2014, "Next
    // Generation Post Processing in Call of Duty: Advanced Warfare"): turns the banding of a
    // fixed step pattern into fine noise, unbiased over pixels.
    float jitter = fract(52.9829189 * fract(dot(vec2(px) + 0.5, vec2(0.06711056, 0.00583715))));
    vec3 L = vec3(0.0);
    for (int k = 0; k < u_steps; ++k) {
        vec3 p = p0 + wt * (float(k) + jitter) * ds;
        vec3 tc = texCoord(p);
        vec3 sigT = texture(u_sigmaT, tc).rgb;
        vec3 sigS = texture(u_sigmaS, tc).rgb;
        if (dot(sigS, sigS) > 0.0) {
            vec3 inS = vec3(0.0);
            for (int i = 0; i < u_lightCount; ++i) {
                vec3 toLight, Ei;
                lightAt(i, p, toLight, Ei);
                inS += Ei * shadowTransmittance(p, toLight);
            }
            // L += T * sigma_s' * p(w) * E_light * ds with the isotropic phase 1/(4 pi);
            // T * (1 - exp(-sigma_t ds)) / sigma_t replaces T * ds (exact per segment).
            vec3 segment = vec3(ds);
            for (int c = 0; c < 3; ++c)
                if (sigT[c] * ds > 1e-4)
                    segment[c] = (1.0 - exp(-sigT[c] * ds)) / sigT[c];
            L += T * sigS * (inS + u_ambient) / (4.0 * PI) * segment;
        }
        T *= exp(-sigT * ds);
        if (max(T.r, max(T.g, T.b)) < 1e-3)
            break;
    }
    // A faint rim keeps silhouettes readable: F times the ambient.
    L += F * u_ambient / PI;
    imageStore(u_target, px, vec4(L, 1.0));
}
