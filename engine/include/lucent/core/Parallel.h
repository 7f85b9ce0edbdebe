// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Parallel loops over index ranges, backed by oneTBB (kept out of this header).
///
///     parallelFor(0, n, [&](int64_t begin, int64_t end) { for (...) ... }, /*grain=*/256);
///     ThreadLimit limit(1);   // scoped: all parallelFor calls use at most 1 thread

#include <cstdint>
#include <functional>
#include <memory>

namespace lucent {

/// Calls `body(begin, end)` on disjoint chunks covering [begin, end), possibly concurrently.
/// @param grain smallest chunk size worth a task.
void parallelFor(int64_t begin, int64_t end, const std::function<void(int64_t, int64_t)>& body,
                 int64_t grain = 1);

/// Number of worker threads parallelFor may use right now.
int maxThreads();

/// Scoped cap on the worker threads of every parallelFor in the process (tbb::global_control).
class ThreadLimit {
public:
    /// @param threads ≥ 1.
    explicit ThreadLimit(int threads);
    ~ThreadLimit();
    ThreadLimit(const ThreadLimit&) = delete;
    ThreadLimit& operator=(const ThreadLimit&) = delete;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace lucent
