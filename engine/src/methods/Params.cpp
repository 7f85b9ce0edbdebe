// SPDX-License-Identifier: MIT
#include <lucent/methods/Params.h>

#include <lucent/core/Error.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lucent::methods {

const char* backendName(Backend backend) {
    switch (backend) {
        case Backend::Gl:
            return "gl";
        case Backend::Cpu:
            return "cpu";
        case Backend::Auto:
            break;
    }
    return "auto";
}

Backend parseBackend(const std::string& name) {
    if (name == "auto")
        return Backend::Auto;
    if (name == "gl")
        return Backend::Gl;
    if (name == "cpu")
        return Backend::Cpu;
    LUCENT_THROW(ValueError, "backend: '", name, "' is not auto, gl or cpu");
}

const char* paramTypeName(ParamType type) {
    switch (type) {
        case ParamType::Bool:
            return "bool";
        case ParamType::Int:
            return "int";
        case ParamType::Float:
            return "float";
        case ParamType::Choice:
            break;
    }
    return "choice";
}

namespace {

/// "%g" of a range bound: integers print without a fraction.
std::string number(double v) {
    char buf[40];
    if (v == std::floor(v) && std::fabs(v) < 1e15)
        std::snprintf(buf, sizeof buf, "%.0f", v);  // 1073741824, not 1.07374182e+09
    else
        std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

}  // namespace

const std::string& ParamDescriptor::defaultFor(Backend backend, bool live) const {
    if (live && !liveDefault.empty())
        return liveDefault;
    if (backend == Backend::Cpu && !cpuDefault.empty())
        return cpuDefault;
    return defaultValue;
}

std::string ParamDescriptor::rangeText() const {
    switch (type) {
        case ParamType::Bool:
            return "on|off";
        case ParamType::Int:
        case ParamType::Float: {
            // Appended piecewise: GCC 12 warns (-Wrestrict, a false positive) on
            // "literal" + std::string&&.
            std::string s = "[";
            s += number(min);
            s += ", ";
            s += number(max);
            s += "]";
            return s;
        }
        case ParamType::Choice:
            break;
    }
    std::string s;
    for (const std::string& c : choices)
        s += (s.empty() ? "" : "|") + c;
    return s;
}

std::string ParamDescriptor::validate(const std::string& text, const std::string& method) const {
    switch (type) {
        case ParamType::Bool:
            if (text == "on" || text == "true" || text == "1")
                return "on";
            if (text == "off" || text == "false" || text == "0")
                return "off";
            LUCENT_THROW(ValueError, method, ": ", name, " must be on or off (got '", text, "')");
        case ParamType::Int: {
            size_t used = 0;
            long long v = 0;
            try {
                v = std::stoll(text, &used);
            } catch (...) {
                used = 0;
            }
            if (used == 0 || used != text.size())
                LUCENT_THROW(ValueError, method, ": ", name, ": '", text, "' is not an integer");
            if (double(v) < min || double(v) > max)
                LUCENT_THROW(ValueError, method, ": ", name, ": ", v, " is outside ", rangeText());
            return std::to_string(v);
        }
        case ParamType::Float: {
            size_t used = 0;
            float v = 0.f;
            try {
                v = std::stof(text, &used);
            } catch (...) {
                used = 0;
            }
            if (used == 0 || used != text.size() || !std::isfinite(v))
                LUCENT_THROW(ValueError, method, ": ", name, ": '", text,
                             "' is not a finite number");
            if (double(v) < min || double(v) > max)
                LUCENT_THROW(ValueError, method, ": ", name, ": ", text, " is outside ",
                             rangeText());
            return text;
        }
        case ParamType::Choice:
            break;
    }
    if (std::find(choices.begin(), choices.end(), text) == choices.end())
        LUCENT_THROW(ValueError, method, ": ", name, ": '", text, "' is not one of ", rangeText());
    return text;
}

// ---------------------------------------------------------------------------------------------
// ParamSet

ParamSet ParamSet::fromAssignments(const std::vector<std::string>& items) {
    ParamSet p;
    for (const std::string& item : items) {
        const size_t eq = item.find('=');
        if (eq == std::string::npos || eq == 0)
            LUCENT_THROW(ValueError, "parameter '", item, "': expected NAME=VALUE");
        p.set(item.substr(0, eq), item.substr(eq + 1));
    }
    return p;
}

void ParamSet::set(const std::string& name, const std::string& value) {
    for (auto& [n, v] : m_items)
        if (n == name) {
            v = value;
            return;
        }
    m_items.emplace_back(name, value);
}

void ParamSet::set(const std::string& name, int value) {
    set(name, std::to_string(value));
}

void ParamSet::set(const std::string& name, double value) {
    set(name, number(value));
}

void ParamSet::set(const std::string& name, bool value) {
    set(name, std::string(value ? "on" : "off"));
}

void ParamSet::merge(const ParamSet& other) {
    for (const auto& [n, v] : other.m_items)
        set(n, v);
}

bool ParamSet::has(const std::string& name) const {
    return find(name) != nullptr;
}

const std::string* ParamSet::find(const std::string& name) const {
    for (const auto& [n, v] : m_items)
        if (n == name)
            return &v;
    return nullptr;
}

std::string ParamSet::toString() const {
    std::string s;
    for (const auto& [n, v] : m_items)
        s += (s.empty() ? "" : " ") + n + "=" + v;
    return s;
}

// ---------------------------------------------------------------------------------------------
// Params

Params::Params(const std::string& method, const std::vector<ParamDescriptor>& descriptors,
               const ParamSet& given, Backend backend, bool live)
    : m_method(method) {
    for (const auto& [name, value] : given.items()) {
        const bool known = std::any_of(descriptors.begin(), descriptors.end(),
                                       [&](const ParamDescriptor& d) { return d.name == name; });
        if (known)
            continue;
        std::string names;
        for (const ParamDescriptor& d : descriptors)
            names += (names.empty() ? "" : ", ") + d.name;
        LUCENT_THROW(ValueError, method, " has no parameter '", name, "' (",
                     names.empty() ? std::string("it has none") : "it has: " + names, ")");
    }
    for (const ParamDescriptor& d : descriptors) {
        const std::string* v = given.find(d.name);
        m_entries.push_back(
            {&d, d.validate(v ? *v : d.defaultFor(backend, live), method), v != nullptr});
    }
}

const Params::Entry& Params::entry(const std::string& name, ParamType type) const {
    for (const Entry& e : m_entries)
        if (e.descriptor->name == name) {
            LUCENT_CHECK(e.descriptor->type == type, m_method, ": parameter ", name, " is a ",
                         paramTypeName(e.descriptor->type), ", read as a ", paramTypeName(type));
            m_read.insert(name);
            return e;
        }
    LUCENT_THROW(ValueError, m_method, ": no parameter '", name, "' is declared");
}

bool Params::getBool(const std::string& name) const {
    return entry(name, ParamType::Bool).value == "on";
}

int Params::getInt(const std::string& name) const {
    return std::stoi(entry(name, ParamType::Int).value);
}

float Params::getFloat(const std::string& name) const {
    return std::stof(entry(name, ParamType::Float).value);
}

const std::string& Params::getChoice(const std::string& name) const {
    return entry(name, ParamType::Choice).value;
}

const std::string& Params::text(const std::string& name) const {
    for (const Entry& e : m_entries)
        if (e.descriptor->name == name) {
            m_read.insert(name);
            return e.value;
        }
    LUCENT_THROW(ValueError, m_method, ": no parameter '", name, "' is declared");
}

bool Params::isGiven(const std::string& name) const {
    for (const Entry& e : m_entries)
        if (e.descriptor->name == name)
            return e.given;
    return false;
}

std::vector<std::string> Params::unused() const {
    std::vector<std::string> out;
    for (const Entry& e : m_entries)
        if (e.given && !m_read.count(e.descriptor->name))
            out.push_back(e.descriptor->name);
    return out;
}

ParamSet Params::values() const {
    ParamSet p;
    for (const Entry& e : m_entries)
        p.set(e.descriptor->name, e.value);
    return p;
}

}  // namespace lucent::methods
