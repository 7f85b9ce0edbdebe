// SPDX-License-Identifier: MIT
#include <lucent/core/Parallel.h>

#include <lucent/core/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#if defined(__SANITIZE_THREAD__)
#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>
#endif

namespace lucent {

namespace {

#if defined(__SANITIZE_THREAD__)
/// The ThreadSanitizer build (the `tsan` preset) runs the chunks on std::threads, not on
/// oneTBB's workers. libtbb is not built with TSan, so TSan sees neither the fork and join
/// edges of tbb::parallel_for nor TBB handing its task objects from thread to thread, and
/// reports races inside TBB's own headers ("data race on vptr" in start_for). A suppression
/// cannot name TBB without hiding every race under a parallel_for, because TSan matches a
/// suppression against every frame of both stacks. Threads are pthreads, which TSan
/// intercepts, so here it sees exactly the ordering tbb::parallel_for promises and no more:
/// the caller before every chunk, every chunk before the return, the chunks unordered among
/// themselves. Same contract as the TBB path: chunks of at most `grain` indices, at most
/// maxThreads() at once, the first exception rethrown after every chunk has stopped.
void runChunksOnThreads(int64_t begin, int64_t end,
                        const std::function<void(int64_t, int64_t)>& body, int64_t grain) {
    const int64_t chunk = std::max<int64_t>(grain, 1);
    const int64_t chunks = (end - begin + chunk - 1) / chunk;
    std::atomic<int64_t> next{0};
    std::exception_ptr error;
    std::mutex errorMutex;
    const auto work = [&] {
        for (int64_t c = next.fetch_add(1); c < chunks; c = next.fetch_add(1)) {
            const int64_t b = begin + c * chunk;
            try {
                body(b, std::min(end, b + chunk));
            } catch (...) {
                const std::lock_guard lock(errorMutex);
                if (!error)
                    error = std::current_exception();
                next.store(chunks);  // the other threads take no new chunk
                return;
            }
        }
    };
    std::vector<std::thread> helpers;
    const int64_t threads = std::min<int64_t>(chunks, maxThreads());
    for (int64_t t = 1; t < threads; ++t)
        helpers.emplace_back(work);
    work();
    for (std::thread& h : helpers)
        h.join();
    if (error)
        std::rethrow_exception(error);
}
#endif

}  // namespace

void parallelFor(int64_t begin, int64_t end, const std::function<void(int64_t, int64_t)>& body,
                 int64_t grain) {
    if (end <= begin)
        return;
    if (end - begin <= grain || maxThreads() == 1) {
        body(begin, end);
        return;
    }
#if defined(__SANITIZE_THREAD__)
    runChunksOnThreads(begin, end, body, grain);
#else
    tbb::parallel_for(tbb::blocked_range<int64_t>(begin, end, std::max<int64_t>(grain, 1)),
                      [&](const tbb::blocked_range<int64_t>& r) { body(r.begin(), r.end()); });
#endif
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
