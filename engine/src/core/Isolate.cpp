// SPDX-License-Identifier: MIT
/// @file
/// @brief Child-process isolation of untrusted readers (see lucent/core/Isolate.h).

#include <lucent/core/Isolate.h>

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <new>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace lucent {

namespace {

// AddressSanitizer and ThreadSanitizer reserve terabytes of shadow memory and replace the
// allocator: an address-space limit would stop them, and their allocator reports an allocation
// past it and aborts where the real one throws std::bad_alloc. GCC defines __SANITIZE_ADDRESS__
// and __SANITIZE_THREAD__, clang answers __has_feature.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool SANITIZER_ALLOCATOR = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
constexpr bool SANITIZER_ALLOCATOR = true;
#else
constexpr bool SANITIZER_ALLOCATOR = false;
#endif
#else
constexpr bool SANITIZER_ALLOCATOR = false;
#endif

/// Virtual size of this process in bytes (/proc/self/statm, first field, in pages).
uint64_t addressSpaceBytes() {
    std::ifstream statm("/proc/self/statm");
    uint64_t pages = 0;
    statm >> pages;
    return pages * uint64_t(::sysconf(_SC_PAGESIZE));
}

bool writeAll(int fd, const void* data, size_t n) {
    const char* p = static_cast<const char*>(data);
    while (n > 0) {
        const ssize_t w = ::write(fd, p, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return false;
        p += w;
        n -= size_t(w);
    }
    return true;
}

/// Runs `work` and turns what it throws into the status byte and payload the child sends.
/// @return true if `work` succeeded.
bool runWork(const ImportLimits& limits, const std::function<std::string()>& work,
             std::string& payload) {
    try {
        payload = work();
        return true;
    } catch (const std::bad_alloc&) {
        payload = "out of memory: the file needs more than the import limit of " +
                  std::to_string(limits.maxDecodedBytes) + " bytes";
    } catch (const std::exception& e) {
        payload = e.what();
    } catch (...) {
        payload = "unknown error";
    }
    return false;
}

[[noreturn]] void runChild(int fd, const ImportLimits& limits, uint64_t baseBytes,
                           const std::function<std::string()>& work) {
    std::signal(SIGXCPU, SIG_DFL);
    std::signal(SIGPIPE, SIG_DFL);
    // A reader that crashes on a corrupt file is what this child exists to contain: it dies of
    // its own signal, which the parent reports. Under AddressSanitizer the crash would otherwise
    // print a sanitizer report into the user's terminal and end as "Aborted".
    for (const int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL})
        std::signal(sig, SIG_DFL);
    const rlimit cpu{rlim_t(limits.maxReaderCpuSeconds), rlim_t(limits.maxReaderCpuSeconds) + 1};
    ::setrlimit(RLIMIT_CPU, &cpu);
    if (!SANITIZER_ALLOCATOR) {
        const rlimit as{rlim_t(baseBytes + limits.maxDecodedBytes),
                        rlim_t(baseBytes + limits.maxDecodedBytes)};
        ::setrlimit(RLIMIT_AS, &as);
    }
    std::string payload;
    const char status = runWork(limits, work, payload) ? 'K' : 'E';
    const uint64_t n = payload.size();
    const bool ok = writeAll(fd, &status, 1) && writeAll(fd, &n, sizeof n) &&
                    writeAll(fd, payload.data(), payload.size());
    // _exit: no atexit handlers, static destructors or leak checks of the parent's state.
    ::_exit(ok ? 0 : 1);
}

}  // namespace

std::string runIsolated(const std::string& what, const std::function<std::string()>& work) {
    const ImportLimits limits = importLimits();
#if LUCENT_ISOLATE_IN_PROCESS
    // Fuzz builds only (the `fuzz` preset): the reader runs in this process, so that the
    // sanitizers and libFuzzer's coverage, memory and time limits see it; errors read as they
    // would from the child.
    std::string result;
    if (!runWork(limits, work, result))
        throw IoError(what + ": " + result);
    return result;
#endif
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0)
        LUCENT_THROW(IoError, what, ": cannot create a pipe: ", std::strerror(errno));
    const uint64_t baseBytes = addressSpaceBytes();
    std::fflush(nullptr);  // buffered output would otherwise be written twice
    const pid_t pid = ::fork();
    if (pid < 0) {
        const int err = errno;
        ::close(fds[0]);
        ::close(fds[1]);
        LUCENT_THROW(IoError, what, ": cannot start a child process: ", std::strerror(err));
    }
    if (pid == 0) {
        ::close(fds[0]);
        runChild(fds[1], limits, baseBytes, work);
    }
    ::close(fds[1]);
    std::string data;
    bool tooLarge = false;
    char buf[1 << 16];
    for (;;) {
        const ssize_t r = ::read(fds[0], buf, sizeof buf);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break;
        if (data.size() + size_t(r) > limits.maxDecodedBytes + 9) {
            tooLarge = true;
            ::kill(pid, SIGKILL);
            break;
        }
        data.append(buf, size_t(r));
    }
    ::close(fds[0]);
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    if (tooLarge)
        LUCENT_THROW(IoError, what, ": returned more than the import limit of ",
                     limits.maxDecodedBytes, " bytes");
    if (WIFSIGNALED(status)) {
        const int sig = WTERMSIG(status);
        if (sig == SIGXCPU)
            LUCENT_THROW(IoError, what, ": stopped after its CPU time limit of ",
                         limits.maxReaderCpuSeconds, " s (a corrupt file parsed without end?)");
        LUCENT_THROW(IoError, what, ": crashed (", strsignal(sig),
                     ") on a file it cannot read (corrupt?)");
    }
    uint64_t n = 0;
    if (data.size() < 1 + sizeof n)
        LUCENT_THROW(IoError, what, ": ended without a result");
    std::memcpy(&n, data.data() + 1, sizeof n);
    if (n != data.size() - 1 - sizeof n)
        LUCENT_THROW(IoError, what, ": returned an incomplete result");
    std::string payload = data.substr(1 + sizeof n);
    if (data[0] != 'K')
        throw IoError(what + ": " + payload);
    return payload;
}

}  // namespace lucent
