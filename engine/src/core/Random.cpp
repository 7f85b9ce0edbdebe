// SPDX-License-Identifier: MIT
#include <lucent/core/Random.h>

namespace lucent {

float halton(uint32_t i, uint32_t base) {
    const double invBase = 1.0 / base;
    double f = invBase, r = 0.0;
    while (i > 0) {
        r += f * double(i % base);
        i /= base;
        f *= invBase;
    }
    return float(r);
}

}  // namespace lucent
