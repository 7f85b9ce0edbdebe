// SPDX-License-Identifier: MIT
/// @file
/// @brief Live preview costs (LiveCosts.h has the contract).

#include <lucent/core/Error.h>
#include <lucent/planner/LiveCosts.h>

#include "ModelData.h"
#include "PlannerJson.h"

#include <nlohmann/json.hpp>

#include <cmath>

namespace lucent::planner {

namespace {
constexpr const char* FORMAT = "lucent-planner-live-costs";
}  // namespace

LiveCosts parseLiveCosts(const std::string& text, const std::string& origin) {
    const nlohmann::json j =
        detail::parseVersionedJson(text, origin, FORMAT, "live costs", LiveCosts::VERSION,
                                   " (measure them again: docs/planner.md, \"Live costs\")");
    try {
        if (!j.contains("entries") || !j["entries"].is_array() || j["entries"].empty())
            LUCENT_THROW(ValueError, origin, ": 'entries' must be a non-empty array");
        LiveCosts c;
        c.source = j.value("source", "");
        c.directMs = j.value("direct_ms", 0.0);
        if (!(c.directMs >= 0) || !std::isfinite(c.directMs))
            LUCENT_THROW(ValueError, origin, ": direct_ms must be a finite number ≥ 0");
        for (const nlohmann::json& e : j["entries"]) {
            LiveCost l;
            l.method = e.value("method", "");
            l.setting = e.value("setting", "");
            if (l.method.empty() || l.setting.empty())
                LUCENT_THROW(ValueError, origin, ": an entry without 'method' or 'setting'");
            if (!e.contains("stroke_ratio") || !e["stroke_ratio"].is_number())
                LUCENT_THROW(ValueError, origin, ": entry '", l.method, " ", l.setting,
                             "' has no numeric 'stroke_ratio'");
            l.strokeRatio = e["stroke_ratio"].get<double>();
            if (!(l.strokeRatio > 0) || !std::isfinite(l.strokeRatio))
                LUCENT_THROW(ValueError, origin, ": entry '", l.method, " ", l.setting,
                             "': stroke_ratio must be a finite number > 0, got ", l.strokeRatio);
            c.entries.push_back(std::move(l));
        }
        return c;
    } catch (const nlohmann::json::exception& e) {
        LUCENT_THROW(ValueError, origin, ": malformed live costs file (", e.what(), ")");
    }
}

std::string formatLiveCosts(const LiveCosts& costs) {
    nlohmann::ordered_json j;
    j["format"] = FORMAT;
    j["version"] = LiveCosts::VERSION;
    j["source"] = costs.source;
    j["direct_ms"] = std::round(costs.directMs * 100) / 100;
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (const LiveCost& l : costs.entries) {
        nlohmann::ordered_json o;
        o["method"] = l.method;
        o["setting"] = l.setting;
        o["stroke_ratio"] = std::round(l.strokeRatio * 1e3) / 1e3;  // far below run-to-run noise
        list.push_back(std::move(o));
    }
    j["entries"] = std::move(list);
    return j.dump(1) + "\n";
}

const LiveCosts& defaultLiveCosts() {
    static const LiveCosts costs = parseLiveCosts(detail::PLANNER_LIVE_COSTS_JSON,
                                                  "resources/planner/live_costs.json (embedded)");
    return costs;
}

Models liveModels(const Models& offline, const LiveCosts& live, std::vector<std::string>* missing) {
    Models out;
    out.source = offline.source + "; live costs: " + live.source;
    out.ridge = offline.ridge;
    const size_t costTerms = costTermNames().size();
    for (const LiveCost& l : live.entries) {
        const CandidateModel* model = nullptr;
        for (const CandidateModel& m : offline.candidates)
            if (m.method == l.method && m.setting == l.setting)
                model = &m;
        if (!model) {
            if (missing)
                missing->push_back(l.method + " " + l.setting);
            continue;
        }
        CandidateModel c = *model;
        // Log-linear cost with only the intercept: exp(log r) = r on every scene. The harness
        // measures one scene, so nothing more can be fitted (docs/planner.md, "Live costs").
        c.cost.assign(costTerms, 0.0);
        c.cost[0] = std::log(l.strokeRatio);
        c.costLogRms = 0.0;
        out.candidates.push_back(std::move(c));
    }
    return out;
}

}  // namespace lucent::planner
