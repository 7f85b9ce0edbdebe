// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Runs an upstream reader that cannot be made safe by checking its input first in a
/// child process with resource limits (docs/file-formats.md, "Import limits"): a crash, a
/// runaway allocation or endless parsing in the reader becomes an IoError in the caller.
///
///     std::string bytes = runIsolated("VTK reader for 'a.vtp'", [&] {
///         return serialise(readWithVtk("a.vtp"));   // runs in the child
///     });

#include <cstdint>
#include <functional>
#include <string>

namespace lucent {

/// Runs `work` in a forked child whose address space may grow by at most
/// importLimits().maxDecodedBytes beyond the parent's (not under AddressSanitizer, whose shadow
/// memory needs the whole address space) and whose CPU time is at most
/// importLimits().maxReaderCpuSeconds (a bound on work, independent of the wall clock and of
/// the machine's load). The child runs only `work` and then _exits: it must not depend on
/// threads of the parent (thread pools do not exist in the child).
/// @param what names the job in messages, e.g. "VTK reader for 'a.vtp'".
/// @return the bytes `work` returned (at most maxDecodedBytes).
/// @throw IoError with `what` and the reason: `work` threw (its message), the child was killed
/// by a signal (a crash), exceeded its CPU time, or returned more than the limit.
std::string runIsolated(const std::string& what, const std::function<std::string()>& work);

}  // namespace lucent
