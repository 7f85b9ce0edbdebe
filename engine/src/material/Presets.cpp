// SPDX-License-Identifier: MIT
/// @file
/// @brief Preset parsing (nlohmann_json) and lookup (Presets.h).
#include <lucent/material/Presets.h>

#include <lucent/core/Error.h>

#include "PresetData.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>

namespace lucent {

namespace {

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

Rgb readRgb(const nlohmann::json& obj, const char* key, const std::string& where, float lo,
            float hi) {
    const auto it = obj.find(key);
    if (it == obj.end())
        LUCENT_THROW(IoError, where, ": missing field \"", key, "\"");
    if (!it->is_array() || it->size() != 3)
        LUCENT_THROW(IoError, where, ".", key, ": expected an array of 3 numbers");
    Rgb out;
    for (int c = 0; c < 3; ++c) {
        const auto& v = (*it)[size_t(c)];
        if (!v.is_number())
            LUCENT_THROW(IoError, where, ".", key, "[", c, "] is not a number");
        out[c] = v.get<float>();
        if (!std::isfinite(out[c]) || out[c] < lo || out[c] > hi)
            LUCENT_THROW(IoError, where, ".", key, "[", c, "] = ", out[c], " is outside [", lo,
                         ", ", hi, "]");
    }
    return out;
}

std::vector<MaterialPreset> loadAll() {
    std::vector<MaterialPreset> all =
        parsePresetJson(detail::PRESETS_JENSEN2001_JSON, "resources/presets/jensen2001.json");
    for (MaterialPreset& p :
         parsePresetJson(detail::PRESETS_ARTIST_JSON, "resources/presets/artist.json")) {
        for (const MaterialPreset& q : all)
            if (lower(q.name) == lower(p.name))
                LUCENT_THROW(IoError, "resources/presets/artist.json: preset \"", p.name,
                             "\" duplicates a measured preset");
        all.push_back(std::move(p));
    }
    return all;
}

}  // namespace

std::vector<MaterialPreset> parsePresetJson(const std::string& text, const std::string& origin) {
    nlohmann::json doc;
    try {
        doc = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        LUCENT_THROW(IoError, origin, ": invalid JSON: ", e.what());
    }
    if (!doc.is_object())
        LUCENT_THROW(IoError, origin, ": top level must be an object");
    std::string fileSource;
    if (const auto it = doc.find("source"); it != doc.end() && it->is_string())
        fileSource = it->get<std::string>();
    const auto list = doc.find("presets");
    if (list == doc.end() || !list->is_array())
        LUCENT_THROW(IoError, origin, ": missing array \"presets\"");
    std::vector<MaterialPreset> out;
    for (size_t i = 0; i < list->size(); ++i) {
        const auto& e = (*list)[i];
        std::string where = origin + ": presets[" + std::to_string(i) + "]";
        if (!e.is_object())
            LUCENT_THROW(IoError, where, " is not an object");
        const auto name = e.find("name");
        if (name == e.end() || !name->is_string() || name->get<std::string>().empty())
            LUCENT_THROW(IoError, where, ": missing or empty \"name\"");
        MaterialPreset p;
        p.name = name->get<std::string>();
        where += " (\"" + p.name + "\")";
        for (const MaterialPreset& q : out)
            if (lower(q.name) == lower(p.name))
                LUCENT_THROW(IoError, where, ": duplicate name");
        p.sigma_s_reduced = readRgb(e, "sigma_s_reduced", where, 0.f, SIGMA_MAX);
        p.sigma_a = readRgb(e, "sigma_a", where, 0.f, SIGMA_MAX);
        if (e.contains("g"))
            p.g = readRgb(e, "g", where, -G_MAX, G_MAX);
        const auto eta = e.find("eta");
        if (eta == e.end() || !eta->is_number())
            LUCENT_THROW(IoError, where, ": missing number \"eta\"");
        p.eta = eta->get<float>();
        if (!std::isfinite(p.eta) || p.eta < 1.f || p.eta > 3.f)
            LUCENT_THROW(IoError, where, ".eta = ", p.eta, " is outside [1, 3]");
        if (const auto src = e.find("source"); src != e.end() && src->is_string())
            p.source = src->get<std::string>();
        else
            p.source = fileSource;
        if (p.source.empty())
            LUCENT_THROW(IoError, where, ": no \"source\" citation");
        out.push_back(std::move(p));
    }
    return out;
}

const std::vector<MaterialPreset>& allPresets() {
    static const std::vector<MaterialPreset> presets = loadAll();
    return presets;
}

const MaterialPreset& findPreset(const std::string& name) {
    const std::string key = lower(name);
    for (const MaterialPreset& p : allPresets())
        if (lower(p.name) == key)
            return p;
    std::string valid;
    for (const MaterialPreset& p : allPresets())
        valid += (valid.empty() ? "" : ", ") + p.name;
    LUCENT_THROW(ValueError, "unknown material preset \"", name, "\"; valid names: ", valid);
}

}  // namespace lucent
