// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Small helpers the method folders share (private to the methods module).

#include <lucent/methods/Method.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace lucent::methods::detail {

/// printf-style formatting of one number for Stats values and log lines.
inline std::string num(double v, const char* format = "%.4g") {
    char buf[64];
    std::snprintf(buf, sizeof buf, format, v);
    return buf;
}

/// Whether two light lists are equal field by field (a change re-injects / restarts).
inline bool sameLights(const std::vector<Light>& a, const std::vector<Light>& b) {
    if (a.size() != b.size())
        return false;
    for (size_t i = 0; i < a.size(); ++i) {
        const Light& x = a[i];
        const Light& y = b[i];
        if (x.type != y.type || x.position != y.position || x.direction != y.direction ||
            x.intensity != y.intensity || x.spotOuterDeg != y.spotOuterDeg ||
            x.spotInnerDeg != y.spotInnerDeg || x.radius != y.radius)
            return false;
    }
    return true;
}

/// A registry factory for method class M (constructed from the info and the context).
template <class M>
std::unique_ptr<Method> make(const MethodInfo& info, const MethodContext& context) {
    return std::make_unique<M>(info, context);
}

}  // namespace lucent::methods::detail
