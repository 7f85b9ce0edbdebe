// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief For LeakSanitizer runs (the asan-ubsan preset) of the app's GUI tests: keeps every
/// shared object loaded at the end of main() mapped until the process exits.
///
/// The Mesa driver (swrast_dri.so) is unloaded when Qt closes the X display, before LSan's
/// check at exit; what it allocated then shows as "<unknown module>", which no suppression can
/// name. Pinned with RTLD_NODELETE, its leaks keep their module name, and
/// tests/unit/app/lsan.supp suppresses those of the system libraries (never the project's).
///
///     int main(...) { ...; const int rc = RUN_ALL_TESTS(); keepLibrariesLoaded(); return rc; }

#include <dlfcn.h>
#include <link.h>

#include <string>
#include <vector>

namespace lucent::app::test {

inline void keepLibrariesLoaded() {
    std::vector<std::string> names;
    dl_iterate_phdr(
        [](dl_phdr_info* info, size_t, void* out) {
            if (info->dlpi_name && info->dlpi_name[0] != '\0')
                static_cast<std::vector<std::string>*>(out)->push_back(info->dlpi_name);
            return 0;
        },
        &names);
    for (const std::string& name : names)
        dlopen(name.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);  // a reference kept
}

}  // namespace lucent::app::test
