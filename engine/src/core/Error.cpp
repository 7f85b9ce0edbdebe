// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>

#include <cstdio>
#include <cstdlib>

namespace lucent::detail {

void assertionFailed(const char* expr, const char* file, int line) {
    // An internal invariant is broken: continuing would corrupt user data.
    std::fprintf(stderr, "lucent: assertion failed: %s (%s:%d)\n", expr, file, line);
    std::abort();
}

}  // namespace lucent::detail
