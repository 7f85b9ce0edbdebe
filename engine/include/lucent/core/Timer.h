// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Wall-clock stopwatch for CPU pass timings (milliseconds), the process's CPU time, and the
/// median of repeated timings.

#include <algorithm>
#include <chrono>
#include <ctime>
#include <vector>

namespace lucent {

class Timer {
public:
    Timer() : m_start(std::chrono::steady_clock::now()) {}
    void reset() { m_start = std::chrono::steady_clock::now(); }
    /// Milliseconds since construction or the last reset().
    [[nodiscard]] double elapsedMs() const {
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - m_start)
            .count();
    }

private:
    std::chrono::steady_clock::time_point m_start;
};

/// CPU time of the whole process (every thread, llvmpipe's included), ms: unlike wall time, not
/// inflated when the machine is shared and the process waits for a core.
inline double processCpuMs() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

/// Median of repeated timings (robust to the odd slow run on a shared machine): the middle
/// value, or the mean of the two middle values for an even count; 0 for none.
inline double medianMs(std::vector<double> samples) {
    if (samples.empty())
        return 0.0;
    std::sort(samples.begin(), samples.end());
    const size_t n = samples.size();
    return n % 2 ? samples[n / 2] : 0.5 * (samples[n / 2 - 1] + samples[n / 2]);
}

}  // namespace lucent
