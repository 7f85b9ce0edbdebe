// SPDX-License-Identifier: MIT
/// @file
/// @brief The one list of translucency methods. Each method lives in its own folder
/// (engine/src/methods/<folder>/) and defines the MethodEntry function named here.

#include <lucent/methods/Registry.h>

#include <lucent/core/Error.h>

namespace lucent::methods {

// The list: one line per method, in the order the CLI and the app's selector show them.
#define LUCENT_METHODS(X)     \
    X(directMethod)           \
    X(singleScatteringMethod) \
    X(sslpvMethod)            \
    X(dipoleMethod)           \
    X(betterDipoleMethod)     \
    X(dirpoleMethod)          \
    X(combinedMethod)         \
    X(referenceMethod)

#define LUCENT_DECLARE_METHOD(entry) MethodEntry entry();
LUCENT_METHODS(LUCENT_DECLARE_METHOD)
#undef LUCENT_DECLARE_METHOD

namespace {

const std::vector<MethodEntry>& entries() {
#define LUCENT_METHOD_ENTRY(entry) entry(),
    static const std::vector<MethodEntry> list = {LUCENT_METHODS(LUCENT_METHOD_ENTRY)};
#undef LUCENT_METHOD_ENTRY
    return list;
}

const MethodEntry& findEntry(const std::string& name) {
    for (const MethodEntry& e : entries())
        if (e.info.name == name)
            return e;
    std::string known;
    for (const MethodEntry& e : entries())
        known += (known.empty() ? "" : ", ") + e.info.name;
    LUCENT_THROW(ValueError, "unknown method '", name, "' (known: ", known, ")");
}

}  // namespace

const std::vector<const MethodInfo*>& all() {
    static const std::vector<const MethodInfo*> list = [] {
        std::vector<const MethodInfo*> out;
        for (const MethodEntry& e : entries())
            out.push_back(&e.info);
        return out;
    }();
    return list;
}

const MethodInfo& find(const std::string& name) {
    return findEntry(name).info;
}

bool exists(const std::string& name) {
    for (const MethodEntry& e : entries())
        if (e.info.name == name)
            return true;
    return false;
}

std::unique_ptr<Method> create(const std::string& name, const ParamSet& given,
                               const MethodContext& context) {
    const MethodEntry& e = findEntry(name);
    LUCENT_CHECK(context.backend != Backend::Auto, name,
                 ": resolve the backend (resolveBackend) before creating an instance");
    LUCENT_CHECK(context.backend != Backend::Gl || e.info.caps.gl, name, " has no GL pass");
    LUCENT_CHECK(context.backend != Backend::Cpu || e.info.caps.cpu, name, " has no CPU renderer");
    std::unique_ptr<Method> m = e.create(e.info, context);
    m->setParams(given);
    return m;
}

Backend resolveBackend(const MethodInfo& info, Backend requested, bool glAvailable,
                       const std::string& glReason) {
    const Capabilities& c = info.caps;
    if (requested == Backend::Cpu) {
        LUCENT_CHECK(c.cpu, info.name, " has no CPU renderer (it runs on: gl)");
        return Backend::Cpu;
    }
    if (requested == Backend::Gl) {
        LUCENT_CHECK(c.gl, info.name, " has no GL pass (it runs on: cpu)");
        if (!glAvailable)
            LUCENT_THROW(GpuError, info.name, ": no headless OpenGL 4.5 context: ", glReason);
        return Backend::Gl;
    }
    const bool wantGl = c.gl && (!c.cpu || c.preferred == Backend::Gl);
    if (wantGl && glAvailable)
        return Backend::Gl;
    if (c.cpu)
        return Backend::Cpu;
    LUCENT_THROW(GpuError, info.name, ": no headless OpenGL 4.5 context: ", glReason);
}

}  // namespace lucent::methods
