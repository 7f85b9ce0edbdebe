// SPDX-License-Identifier: MIT
#include "CliArgs.h"

#include <lucent/core/Error.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace lucent::cli {

Args::Args(const std::vector<std::string>& argv, const std::vector<std::string>& valueOptions,
           const std::vector<std::string>& flagOptions) {
    auto isIn = [](const std::vector<std::string>& v, const std::string& s) {
        return std::find(v.begin(), v.end(), s) != v.end();
    };
    for (size_t i = 0; i < argv.size(); ++i) {
        const std::string& a = argv[i];
        if (a.size() > 1 && a[0] == '-' && !(a.size() > 1 && (std::isdigit(a[1]) || a[1] == '.'))) {
            std::string name = a.substr(a[1] == '-' ? 2 : 1);
            std::optional<std::string> inlineValue;
            if (auto eq = name.find('='); eq != std::string::npos) {
                inlineValue = name.substr(eq + 1);
                name = name.substr(0, eq);
            }
            if (isIn(flagOptions, name)) {
                if (inlineValue)
                    LUCENT_THROW(ValueError, "option --", name, " takes no value");
                m_flags.push_back(name);
            } else if (isIn(valueOptions, name)) {
                if (inlineValue) {
                    m_values[name].push_back(*inlineValue);
                } else {
                    if (i + 1 >= argv.size())
                        LUCENT_THROW(ValueError, "option --", name, " needs a value");
                    m_values[name].push_back(argv[++i]);
                }
            } else {
                LUCENT_THROW(ValueError, "unknown option '", a, "' (see --help)");
            }
        } else {
            m_positional.push_back(a);
        }
    }
}

bool Args::has(const std::string& name) const {
    return m_values.count(name) || std::find(m_flags.begin(), m_flags.end(), name) != m_flags.end();
}

std::optional<std::string> Args::value(const std::string& name) const {
    auto it = m_values.find(name);
    if (it == m_values.end())
        return std::nullopt;
    return it->second.back();
}

std::vector<std::string> Args::values(const std::string& name) const {
    auto it = m_values.find(name);
    return it == m_values.end() ? std::vector<std::string>{} : it->second;
}

std::optional<std::string> Args::peek(const std::vector<std::string>& argv,
                                      const std::string& name) {
    std::optional<std::string> found;
    for (size_t i = 0; i < argv.size(); ++i) {
        if (argv[i] == "--" + name && i + 1 < argv.size())
            found = argv[++i];
        else if (argv[i].rfind("--" + name + "=", 0) == 0)
            found = argv[i].substr(name.size() + 3);
    }
    return found;
}

std::string Args::valueOr(const std::string& name, const std::string& fallback) const {
    return value(name).value_or(fallback);
}

int Args::intOr(const std::string& name, int fallback, int lo, int hi) const {
    auto v = value(name);
    if (!v)
        return fallback;
    size_t used = 0;
    long long r = 0;
    try {
        r = std::stoll(*v, &used);
    } catch (...) {
        used = 0;
    }
    if (used != v->size())
        LUCENT_THROW(ValueError, "--", name, ": '", *v, "' is not an integer");
    if (r < lo || r > hi)
        LUCENT_THROW(ValueError, "--", name, ": ", r, " is outside [", lo, ", ", hi, "]");
    return int(r);
}

namespace {
float parseFloat(const std::string& name, const std::string& text, float lo, float hi) {
    size_t used = 0;
    float r = 0;
    try {
        r = std::stof(text, &used);
    } catch (...) {
        used = 0;
    }
    if (used != text.size() || !std::isfinite(r))
        LUCENT_THROW(ValueError, "--", name, ": '", text, "' is not a finite number");
    if (r < lo || r > hi)
        LUCENT_THROW(ValueError, "--", name, ": ", r, " is outside [", lo, ", ", hi, "]");
    return r;
}
}  // namespace

float Args::floatOr(const std::string& name, float fallback, float lo, float hi) const {
    auto v = value(name);
    return v ? parseFloat(name, *v, lo, hi) : fallback;
}

std::optional<Rgb> Args::rgb(const std::string& name, float lo, float hi) const {
    auto v = value(name);
    if (!v)
        return std::nullopt;
    std::vector<std::string> parts;
    std::stringstream ss(*v);
    for (std::string p; std::getline(ss, p, ',');)
        parts.push_back(p);
    if (parts.size() == 1)
        return Rgb(parseFloat(name, parts[0], lo, hi));
    if (parts.size() != 3)
        LUCENT_THROW(ValueError, "--", name, ": expected R,G,B, got '", *v, "'");
    return Rgb(parseFloat(name, parts[0], lo, hi), parseFloat(name, parts[1], lo, hi),
               parseFloat(name, parts[2], lo, hi));
}

void printProgressBar(double fraction, const std::string& status) {
    constexpr int WIDTH = 30;
    const int filled = int(std::clamp(fraction, 0.0, 1.0) * WIDTH + 0.5);
    std::string bar(size_t(WIDTH), '-');
    for (int i = 0; i < filled; ++i)
        bar[size_t(i)] = '#';
    std::fprintf(stderr, "\r[%s] %s ", bar.c_str(), status.c_str());
    std::fflush(stderr);
}

}  // namespace lucent::cli
