// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The planner's data files (models, live costs): one JSON header check, so both say
/// the same thing about a file that is not theirs.

#include <lucent/core/Error.h>

#include <nlohmann/json.hpp>

#include <string>

namespace lucent::planner::detail {

/// Parses `text` and checks its "format" and "version" fields.
/// @param kind what the file is, for messages ("planner models")
/// @param remedy appended to a version mismatch (e.g. " (refit them: docs/planner.md)")
/// @throw ValueError naming `origin`.
inline nlohmann::json parseVersionedJson(const std::string& text, const std::string& origin,
                                         const char* format, const char* kind, int version,
                                         const char* remedy) {
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        LUCENT_THROW(ValueError, origin, ": not valid JSON (", e.what(), ")");
    }
    if (!j.is_object() || !j.contains("format") || !j["format"].is_string() ||
        j["format"].get<std::string>() != format)
        LUCENT_THROW(ValueError, origin, ": not a ", kind, " file (\"format\": \"", format,
                     "\" expected)");
    const int found =
        j.contains("version") && j["version"].is_number_integer() ? j["version"].get<int>() : 0;
    if (found != version)
        LUCENT_THROW(ValueError, origin, ": ", kind, " version ", found,
                     ", this build reads version ", version, remedy);
    return j;
}

}  // namespace lucent::planner::detail
