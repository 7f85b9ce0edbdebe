// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The registry of translucency methods: name → descriptor + factory, the one list of
/// methods (engine/src/methods/Registry.cpp). The CLI (`render --method`, `methods`,
/// `evaluate`) is built from it; the app's method selector and settings widgets are to be
/// (docs/architecture.md, "Not yet on the registry").
///
///     for (const MethodInfo* info : methods::all()) std::puts(info->name.c_str());
///     auto m = methods::create("sslpv", params, {Backend::Gl, /*live=*/true});
///
/// Adding a method: one folder engine/src/methods/<name>/ defining a MethodEntry and one line
/// in Registry.cpp (docs/architecture.md shows a worked example).

#include <lucent/methods/Method.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace lucent::methods {

/// A method's registry line: its description and how to make an instance.
struct MethodEntry {
    MethodInfo info;
    /// Makes an unconfigured instance (create() then calls setParams()).
    std::function<std::unique_ptr<Method>(const MethodInfo&, const MethodContext&)> create;
};

/// Every method, in the order front ends list them.
const std::vector<const MethodInfo*>& all();
/// The method called `name`. @throw ValueError listing the known names.
const MethodInfo& find(const std::string& name);
/// Whether `name` is a registered method.
bool exists(const std::string& name);
/// An instance of `name` on context.backend (Gl or Cpu) with the given parameter values.
/// @throw ValueError for an unknown name, a backend the method lacks, or a bad parameter.
std::unique_ptr<Method> create(const std::string& name, const ParamSet& given,
                               const MethodContext& context);

/// The backend a render of `info` uses when `requested` is asked for: Auto picks the method's
/// preferred backend if it has it and (for Gl) `glAvailable`, else its other backend.
/// @throw ValueError when the method lacks the requested backend; GpuError when only GL would
/// do and it is not available (`glReason` says why).
Backend resolveBackend(const MethodInfo& info, Backend requested, bool glAvailable,
                       const std::string& glReason = "");

}  // namespace lucent::methods
