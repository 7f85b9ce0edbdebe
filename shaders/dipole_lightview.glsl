// SPDX-License-Identifier: MIT
// Irradiance images ("views") of the image-space dipole: the camera's (view 0) and the light
// views of Mertens et al. 2005 §7.1 (views 1..). GLSL mirror of the view helpers of
// engine/src/dipole/ImageSpace.cpp (lookUp, areaJacobian, pixelFootprint, visibleIn,
// tangentPlanePoint); docs/methods/dipole.md §3d.
//
// The including shader defines the per-view accessors declared below (which textures and
// matrices view v reads); rows of every view image are GL rows (bottom first) and projections
// use top-first rows like SurfaceBuffers::project, then flip.
#pragma once

mat4 viewClip(int v);        // clipFromWorld of view v
bool viewOrtho(int v);       // orthographic projection
vec3 viewEye(int v);         // perspective: centre of projection (mm)
vec3 viewDirection(int v);   // orthographic: unit direction the view looks
ivec2 viewSize(int v);       // texels
vec4 viewPosition(int v, ivec2 pix);    // xyz mm, a covered
vec3 viewNormal(int v, ivec2 pix);      // unit normal
vec3 viewIrradiance(int v, ivec2 pix);  // E (W/mm²)

vec3 towardEyeOf(int v, vec3 p) {
    return viewOrtho(v) ? -normalize(viewDirection(v)) : normalize(viewEye(v) - p);
}

// Texel (GL rows) of view v containing p. False behind the view or outside its image.
bool projectView(int v, vec3 p, out ivec2 pix) {
    ivec2 size = viewSize(v);
    vec4 clip = viewClip(v) * vec4(p, 1.0);
    if (!(clip.w > 0.0)) return false;
    vec2 ndc = clip.xy / clip.w;
    vec2 px = vec2((ndc.x * 0.5 + 0.5) * float(size.x), (0.5 - ndc.y * 0.5) * float(size.y));
    if (px.x < 0.0 || px.y < 0.0 || px.x >= float(size.x) || px.y >= float(size.y)) return false;
    ivec2 top = ivec2(px);
    pix = ivec2(top.x, size.y - 1 - top.y);
    return true;
}

struct ViewHit {
    ivec2 pix;
    vec3 p;  // the surface point (mm)
    vec3 n;  // its unit normal
};

// The covered texel of view v behind pPlane; the view's ray through pPlane meets that texel's
// tangent plane ("location p_i on the surface from the depth texture", Mertens et al. 2005 §6.2).
bool lookUp(int v, vec3 pPlane, out ViewHit h) {
    if (!projectView(v, pPlane, h.pix)) return false;
    vec4 q = viewPosition(v, h.pix);
    if (q.w == 0.0) return false;
    h.p = q.xyz;
    h.n = normalize(viewNormal(v, h.pix));
    bool ortho = viewOrtho(v);
    vec3 origin = ortho ? pPlane : viewEye(v);
    vec3 dir = ortho ? normalize(viewDirection(v)) : normalize(pPlane - viewEye(v));
    float denom = dot(dir, h.n);
    if (abs(denom) > 0.1) h.p = origin + dir * (dot(h.p - origin, h.n) / denom);
    return true;
}

// Eq. 8–9 Jacobian |dA_p/dA_p′| = (cos α′/cos α)(d²/d′²) of view v, clamped to maxJacobian
// (jacobian false: 1).
float areaJacobian(int v, vec3 p, vec3 np, vec3 pPlane, vec3 no, bool jacobian, float maxJacobian) {
    if (!jacobian) return 1.0;
    float cosA = abs(dot(np, towardEyeOf(v, p)));
    float cosAp = abs(dot(no, towardEyeOf(v, pPlane)));
    float ratio = 1.0;
    if (!viewOrtho(v)) {
        float d = length(viewEye(v) - p), dp = length(viewEye(v) - pPlane);
        ratio = dp > 0.0 ? (d * d) / (dp * dp) : 1.0;
    }
    return cosA > 1e-6 ? min(maxJacobian, cosAp / cosA * ratio) : maxJacobian;
}

// World size (mm) of one texel of view v at x: 2·w/(P₁₁·height), P₁₁ = |row 1 of the clip
// matrix's linear part| (perspective 1/tan(fov/2), orthographic 2/height), w the clip w (1 for
// orthographic). 0 behind the view.
float pixelFootprint(int v, vec3 x) {
    mat4 m = viewClip(v);
    float p11 = length(vec3(m[0][1], m[1][1], m[2][1]));
    float w = viewOrtho(v) ? 1.0 : (m * vec4(x, 1.0)).w;
    return w > 0.0 && p11 > 0.0 ? 2.0 * w / (p11 * float(viewSize(v).y)) : 0.0;
}

// Is x (found through a view with texel footprint footprintOther at x) visible in view v? Its
// texel is covered and that texel's tangent-plane point along the ray through x is x, within
// one footprint of each view.
bool visibleIn(int v, vec3 x, float footprintOther) {
    ViewHit h;
    if (!lookUp(v, x, h)) return false;
    return length(h.p - x) <= pixelFootprint(v, x) + footprintOther;
}

// Where view v's ray through x meets the tangent plane (xo, no); false if it (nearly) misses or
// the point leaves the view.
bool tangentPlanePoint(int v, vec3 x, vec3 xo, vec3 no, out vec3 pPlane) {
    vec3 dir = -towardEyeOf(v, x);
    float c = dot(dir, no);
    if (abs(c) < 1e-4) return false;
    pPlane = x + dir * (dot(xo - x, no) / c);
    ivec2 pix;
    return projectView(v, pPlane, pix);
}
