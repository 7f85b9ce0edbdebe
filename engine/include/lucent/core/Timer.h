// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Wall-clock stopwatch for CPU pass timings (milliseconds).

#include <chrono>

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

}  // namespace lucent
