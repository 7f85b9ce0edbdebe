// SPDX-License-Identifier: MIT
/// @file
/// @brief `lucent-cli methods [NAME] [--json]`: the registered translucency methods with their
/// backends and parameters (lucent/methods/Registry.h).

#include "CliCommon.h"

#include <lucent/core/Error.h>
#include <lucent/methods/Registry.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace lucent::cli {

namespace {

std::string backends(const methods::Capabilities& c) {
    std::string s;
    if (c.gl)
        s += c.cpu && c.preferred == methods::Backend::Gl ? "gl (default), " : "gl, ";
    if (c.cpu)
        s += c.gl && c.preferred == methods::Backend::Cpu ? "cpu (default)" : "cpu";
    if (!s.empty() && s.back() == ' ')
        s.resize(s.size() - 2);
    return s;
}

std::string defaults(const methods::ParamDescriptor& d) {
    std::string s = d.defaultValue;
    if (!d.cpuDefault.empty())
        s += " (cpu: " + d.cpuDefault + ")";
    if (!d.liveDefault.empty())
        s += " (live: " + d.liveDefault + ")";
    return s;
}

const char* scopeNote(methods::ParamScope scope) {
    switch (scope) {
        case methods::ParamScope::Offline:
            return " [offline only]";
        case methods::ParamScope::Live:
            return " [live only]";
        case methods::ParamScope::Both:
            break;
    }
    return "";
}

std::string jsonString(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\')
            out += '\\';
        out += c;
    }
    return out + "\"";
}

void printText(const methods::MethodInfo& m) {
    std::printf("%s: %s\n", m.name.c_str(), m.summary.c_str());
    std::printf("  backends: %s%s; docs: %s\n", backends(m.caps).c_str(),
                m.caps.progressive ? ", progressive" : "", m.docs.c_str());
    for (const methods::ParamDescriptor& d : m.params)
        std::printf("  --%-16s %-6s %-26s default %s: %s%s\n", d.name.c_str(),
                    methods::paramTypeName(d.type), d.rangeText().c_str(), defaults(d).c_str(),
                    d.help.c_str(), scopeNote(d.scope));
    if (!m.variants.empty()) {
        std::string v;
        for (const methods::ParamPreset& p : m.variants)
            v += (v.empty() ? "" : ", ") + m.name + ":" + p.name;
        std::printf("  evaluate variants: %s\n", v.c_str());
    }
    if (!m.quality.empty()) {
        std::string q;
        for (const methods::ParamPreset& p : m.quality)
            q += (q.empty() ? "" : "; ") + p.name;
        std::printf("  evaluate quality levels: %s\n", q.c_str());
    }
}

void printJson(const std::vector<const methods::MethodInfo*>& list) {
    std::printf("[\n");
    for (size_t i = 0; i < list.size(); ++i) {
        const methods::MethodInfo& m = *list[i];
        std::printf("  {\"name\": %s, \"title\": %s, \"summary\": %s, \"docs\": %s,\n",
                    jsonString(m.name).c_str(), jsonString(m.title).c_str(),
                    jsonString(m.summary).c_str(), jsonString(m.docs).c_str());
        std::printf("   \"gl\": %s, \"cpu\": %s, \"progressive\": %s, \"params\": [",
                    m.caps.gl ? "true" : "false", m.caps.cpu ? "true" : "false",
                    m.caps.progressive ? "true" : "false");
        for (size_t k = 0; k < m.params.size(); ++k) {
            const methods::ParamDescriptor& d = m.params[k];
            std::printf(
                "%s\n    {\"name\": %s, \"type\": \"%s\", \"range\": %s, \"default\": %s, "
                "\"help\": %s}",
                k ? "," : "", jsonString(d.name).c_str(), methods::paramTypeName(d.type),
                jsonString(d.rangeText()).c_str(), jsonString(defaults(d)).c_str(),
                jsonString(d.help).c_str());
        }
        std::printf("]}%s\n", i + 1 < list.size() ? "," : "");
    }
    std::printf("]\n");
}

struct MethodsOptions {
    std::string name;
    bool json = false;
};

void runMethods(const MethodsOptions& args) {
    std::vector<const methods::MethodInfo*> list = methods::all();
    if (!args.name.empty())
        list = {&methods::find(args.name)};  // ValueError naming the closest method
    if (args.json) {
        printJson(list);
        return;
    }
    for (size_t i = 0; i < list.size(); ++i) {
        if (i)
            std::printf("\n");
        printText(*list[i]);
    }
}

}  // namespace

void addMethodsCommand(CLI::App& cli, const CommandContext&) {
    CLI::App* sub = addCommand(
        cli, "methods", "list the translucency methods, their backends and parameters",
        "usage: lucent-cli methods [NAME] [--json]\n",
        "Lists every registered method (or NAME only): its backends (gl: the GPU scene renderer\n"
        "with the method's subsurface pass; cpu: its CPU renderer; the default is what\n"
        "`render` uses when GL is available), and each parameter with its type, range, default\n"
        "and meaning. Parameters are given to `render` as --NAME VALUE or --param NAME=VALUE.\n");
    auto args = std::make_shared<MethodsOptions>();
    sub->add_option("NAME", args->name, "one method only");
    sub->add_flag("--json", args->json, "machine-readable list");
    sub->callback([args] { runMethods(*args); });
}

}  // namespace lucent::cli
