// SPDX-License-Identifier: MIT
#include <lucent/core/Parallel.h>

#include <lucent/core/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

namespace lucent {

void parallelFor(int64_t begin, int64_t end, const std::function<void(int64_t, int64_t)>& body,
                 int64_t grain) {
    if (end <= begin)
        return;
    if (end - begin <= grain || maxThreads() == 1) {
        body(begin, end);
        return;
    }
    tbb::parallel_for(tbb::blocked_range<int64_t>(begin, end, std::max<int64_t>(grain, 1)),
                      [&](const tbb::blocked_range<int64_t>& r) { body(r.begin(), r.end()); });
}

int maxThreads() {
    return int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

struct ThreadLimit::Impl {
    explicit Impl(int threads)
        : control(tbb::global_control::max_allowed_parallelism, size_t(threads)) {}
    tbb::global_control control;
};

ThreadLimit::ThreadLimit(int threads) {
    LUCENT_CHECK(threads >= 1, "thread count must be at least 1, got ", threads);
    m_impl = std::make_unique<Impl>(threads);
}

ThreadLimit::~ThreadLimit() = default;

}  // namespace lucent
