// SPDX-License-Identifier: MIT
/// @file
/// @brief SSLPV propagation matrices by quadrature, Fresnel, refraction and RSM solid angles.

#include <lucent/sslpv/Transfer.h>

#include <lucent/core/Error.h>
#include <lucent/core/Quadrature.h>
#include <lucent/core/SphericalHarmonics.h>

#include <cmath>
#include <mutex>
#include <vector>

namespace lucent::sslpv {
namespace {

/// Real orthonormal SH up to band 2 in double precision (same basis and order as shEvaluate).
void shEvalD(const double w[3], double* out) {
    const double x = w[0], y = w[1], z = w[2];
    out[0] = 0.282094791773878143;           // 1/(2√π)
    const double k1 = 0.488602511902919921;  // √(3/4π)
    out[1] = k1 * y;
    out[2] = k1 * z;
    out[3] = k1 * x;
    const double k2 = 1.092548430592079070;   // √(15/4π)
    const double k20 = 0.315391565252520006;  // √(5/16π)
    const double k22 = 0.546274215296039535;  // √(15/16π)
    out[4] = k2 * x * y;
    out[5] = k2 * y * z;
    out[6] = k20 * (3.0 * z * z - 1.0);
    out[7] = k2 * x * z;
    out[8] = k22 * (x * x - y * y);
}

}  // namespace

PropagationMatrix computePropagationMatrix(int order, int axis, int sign, int nodes) {
    LUCENT_CHECK(order == 1 || order == 2, "SSLPV: SH order must be 1 or 2, got ", order);
    LUCENT_CHECK(axis >= 0 && axis <= 2, "SSLPV: axis must be 0, 1 or 2, got ", axis);
    LUCENT_CHECK(sign == 1 || sign == -1, "SSLPV: sign must be +1 or -1, got ", sign);
    LUCENT_CHECK(nodes >= 2 && nodes <= 512, "SSLPV: quadrature nodes must be in [2, 512], got ",
                 nodes);
    const int count = shCount(order);
    const QuadratureRule rule = gaussLegendre(nodes);
    const std::vector<double>& gx = rule.x;
    const std::vector<double>& gw = rule.w;

    // Destination cell d: unit cube centred at the origin; source centre s = sign·e_axis.
    double s[3] = {0.0, 0.0, 0.0};
    s[axis] = double(sign);
    double acc[SSLPV_MAX_COEFFS][SSLPV_MAX_COEFFS] = {};
    for (int fa = 0; fa < 3; ++fa) {
        for (int fs = -1; fs <= 1; fs += 2) {
            if (fa == axis && fs == sign)
                continue;  // the face shared by s and d is excluded
            // v_j = ∫_{Δω_{f,s}} y_j(ω) dω over face f, as seen from s (§4).
            double v[SSLPV_MAX_COEFFS] = {};
            const int b = (fa + 1) % 3, c = (fa + 2) % 3;
            for (int iu = 0; iu < nodes; ++iu) {
                for (int iv = 0; iv < nodes; ++iv) {
                    double p[3];
                    p[fa] = 0.5 * fs;
                    p[b] = 0.5 * gx[iu];
                    p[c] = 0.5 * gx[iv];
                    const double r[3] = {p[0] - s[0], p[1] - s[1], p[2] - s[2]};
                    const double r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
                    const double len = std::sqrt(r2);
                    // dω = |n_f·r| dA / |r|³; dA = (½)² w_u w_v on the [−½,½]² face.
                    const double dOmega = std::abs(r[fa]) / (r2 * len) * 0.25 * gw[iu] * gw[iv];
                    const double dir[3] = {r[0] / len, r[1] / len, r[2] / len};
                    double y[SSLPV_MAX_COEFFS];
                    shEvalD(dir, y);
                    for (int j = 0; j < count; ++j)
                        v[j] += y[j] * dOmega;
                }
            }
            // (1/π) ∫_{2π} (n_f·ω) y_i dω = (1/π) √(4π/(2l+1)) z_l y_i(n_f): the clamped cosine
            // lobe rotated to n_f (zonal rotation, Sloan 2008; zonal z_l from the SSLPV project
            // page errata).
            double nf[3] = {0.0, 0.0, 0.0};
            nf[fa] = double(fs);
            double yn[SSLPV_MAX_COEFFS];
            shEvalD(nf, yn);
            for (int i = 0; i < count; ++i) {
                const int l = i == 0 ? 0 : (i < 4 ? 1 : 2);
                const double lobe = std::sqrt(4.0 * M_PI / (2 * l + 1)) *
                                    double(clampedCosineZonal(l)) * yn[i] / M_PI;
                for (int j = 0; j < count; ++j)
                    acc[i][j] += lobe * v[j];
            }
        }
    }
    PropagationMatrix out;
    out.count = count;
    for (int i = 0; i < count; ++i)
        for (int j = 0; j < count; ++j)
            out.m[i * SSLPV_MAX_COEFFS + j] = float(acc[i][j]);
    return out;
}

const std::array<PropagationMatrix, 6>& propagationMatrices(int order) {
    LUCENT_CHECK(order == 1 || order == 2, "SSLPV: SH order must be 1 or 2, got ", order);
    static std::array<PropagationMatrix, 6> cache[2];
    static std::once_flag once[2];
    const int k = order - 1;
    std::call_once(once[k], [&] {
        for (int axis = 0; axis < 3; ++axis)
            for (int sign = -1; sign <= 1; sign += 2)
                cache[k][neighbourIndex(axis, sign)] = computePropagationMatrix(order, axis, sign);
    });
    return cache[k];
}

Vector3f refractInto(const Vector3f& wi, const Normal3f& n, float eta) {
    // Snell's law, vector form: t = wi/η + (cosi/η − cost) n with cosi = −wi·n (outside → in).
    const float cosI = std::clamp(-glm::dot(wi, n), 0.f, 1.f);
    const float inv = 1.f / eta;
    const float sin2T = inv * inv * (1.f - cosI * cosI);
    const float cosT = std::sqrt(std::max(0.f, 1.f - sin2T));
    const Vector3f t = inv * wi + (inv * cosI - cosT) * n;
    const float len = glm::length(t);
    return len > 0.f ? t / len : -n;
}

float rsmTexelSolidAngle(float tanHalfFov, float aspect, int nx, int ny, float cosTheta,
                         float nearPlane) {
    // §3.1: Δω_p ≈ A_p cos θ_p / |r_p|², with the near-plane pixel area divided by near² (seed
    // 003).
    const float width = 2.f * nearPlane * tanHalfFov;
    const float area = width * (aspect * width) / (float(nx) * float(ny));
    const float r = nearPlane / cosTheta;
    return area * cosTheta / (r * r);
}

}  // namespace lucent::sslpv
