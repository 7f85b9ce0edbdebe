// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Lucent's three error tiers (modelled on Falcor's Core/Error.h):
///   - LUCENT_THROW(Type, ...)   recoverable failures: I/O, bad files, bad user parameters;
///   - LUCENT_CHECK(cond, ...)   preconditions on public API calls, always on, throws ValueError;
///   - LUCENT_ASSERT(cond)       internal invariants, compiled out unless LUCENT_ENABLE_ASSERTS
///                               or a debug build.
/// Library code never terminates the process.

#include <sstream>
#include <stdexcept>
#include <string>

namespace lucent {

/// Base of every exception Lucent throws; what() is a message a user can act on.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};
/// A file could not be read or written, or its contents are malformed.
class IoError : public Error {
public:
    using Error::Error;
};
/// A parameter is out of its documented range, NaN/Inf, or inconsistent with others.
class ValueError : public Error {
public:
    using Error::Error;
};
/// An OpenGL context, shader or resource failed.
class GpuError : public Error {
public:
    using Error::Error;
};
/// The operation was cancelled by the caller.
class Cancelled : public Error {
public:
    using Error::Error;
};

namespace detail {
template <typename... Args>
std::string concat(const Args&... args) {
    std::ostringstream os;
    (os << ... << args);
    return os.str();
}
[[noreturn]] void assertionFailed(const char* expr, const char* file, int line);
}  // namespace detail

}  // namespace lucent

/// Throws `Type` (a lucent::Error subclass) with the streamed arguments as its message.
#define LUCENT_THROW(Type, ...) throw Type(::lucent::detail::concat(__VA_ARGS__))

/// Public API precondition: throws lucent::ValueError with the message when `cond` is false.
#define LUCENT_CHECK(cond, ...)                              \
    do {                                                     \
        if (!(cond))                                         \
            LUCENT_THROW(::lucent::ValueError, __VA_ARGS__); \
    } while (false)

#if defined(LUCENT_ENABLE_ASSERTS) || !defined(NDEBUG)
/// Internal invariant; aborts with file and line when violated (debug / asserts builds only).
#define LUCENT_ASSERT(cond)                                               \
    do {                                                                  \
        if (!(cond))                                                      \
            ::lucent::detail::assertionFailed(#cond, __FILE__, __LINE__); \
    } while (false)
#else
#define LUCENT_ASSERT(cond) \
    do {                    \
    } while (false)
#endif
