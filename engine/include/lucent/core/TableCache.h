// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief One shared table per key for the process: the lookup tables built once per η (the
/// directional dipole's energy, exit-angle and incidence tables, the diffusion mode's
/// exact-total ratio) are made on first use and handed out as shared_ptr to const.
///
///     auto t = sharedTable<DirpoleExitTable>(eta, [&] { return DirpoleExitTable(eta); });

#include <cstddef>
#include <map>
#include <memory>
#include <mutex>

namespace lucent {

/// Keys are few (one η per scene, a target or two); a cache keeps at most this many tables and
/// starts afresh beyond (tables already handed out live on in their shared_ptrs), so an η
/// dragged through many values does not accumulate tables.
inline constexpr size_t TABLE_CACHE_LIMIT = 32;

/// The process's table of type `Table` for `key`, built by `make()` (outside the lock: a slow
/// build does not block other keys; two threads racing on a new key may both build it, and the
/// first stored wins). Thread-safe. One cache per (Table, Key) type pair.
template <typename Table, typename Key, typename Make>
std::shared_ptr<const Table> sharedTable(const Key& key, Make&& make) {
    static std::mutex mutex;
    static std::map<Key, std::shared_ptr<const Table>> cache;
    {
        const std::lock_guard<std::mutex> lock(mutex);
        if (const auto it = cache.find(key); it != cache.end())
            return it->second;
    }
    auto table = std::make_shared<const Table>(make());
    const std::lock_guard<std::mutex> lock(mutex);
    if (cache.size() >= TABLE_CACHE_LIMIT)
        cache.clear();
    return cache.emplace(key, std::move(table)).first->second;
}

}  // namespace lucent
