// SPDX-License-Identifier: MIT
/// @file
/// @brief Live preview costs (LiveCosts.h has the contract).

#include <lucent/core/Error.h>
#include <lucent/planner/LiveCosts.h>

#include "ModelData.h"
#include "PlannerJson.h"

#include <lucent/core/FileIO.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>

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
        c.date = j.value("date", "");
        c.renderer = j.value("renderer", "");
        c.cpuThreads = j.value("cpu_threads", 0);
        if (j.contains("host_included") && !j["host_included"].is_boolean())
            LUCENT_THROW(ValueError, origin, ": host_included must be true or false");
        c.hostIncluded = j.value("host_included", false);
        if (c.cpuThreads < 0)
            LUCENT_THROW(ValueError, origin, ": cpu_threads must be ≥ 0");
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
    if (!costs.date.empty())
        j["date"] = costs.date;
    if (!costs.renderer.empty())
        j["renderer"] = costs.renderer;
    if (costs.cpuThreads > 0)
        j["cpu_threads"] = costs.cpuThreads;
    j["host_included"] = costs.hostIncluded;
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

std::string userLiveCostsPath() {
    const auto env = [](const char* name) {
        const char* v = std::getenv(name);
        return std::string(v ? v : "");
    };
    if (std::string given = env(LIVE_COSTS_ENV); !given.empty())
        return given;
    // The XDG Base Directory Specification: $XDG_CONFIG_HOME when set to an absolute path,
    // else $HOME/.config.
    std::filesystem::path config = env("XDG_CONFIG_HOME");
    if (config.empty() || !config.is_absolute()) {
        const std::string home = env("HOME");
        if (home.empty())
            return {};
        config = std::filesystem::path(home) / ".config";
    }
    return (config / "lucent" / "live_costs.json").string();
}

void saveLiveCosts(const LiveCosts& costs, const std::string& path) {
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    std::error_code ec;
    if (!folder.empty())
        std::filesystem::create_directories(folder, ec);
    if (ec)
        LUCENT_THROW(IoError, "cannot create the folder '", folder.string(), "' for '", path,
                     "': ", ec.message());
    writeFileAtomically(path, formatLiveCosts(costs));
}

LiveCostsInUse loadLiveCosts(const std::string& path) {
    LiveCostsInUse out;
    out.costs = defaultLiveCosts();
    out.path = path;
    std::error_code ec;
    if (path.empty() || !std::filesystem::exists(path, ec))
        return out;
    const std::string again =
        " (Edit ▸ Preferences ▸ Calibrate Live Costs, or lucent-cli bench "
        "calibrate); planning with the shipped live costs";
    try {
        // A regular file of at most 1 MiB (a table is a few kB): a FIFO or a device at the
        // path must not hang the app's start-up.
        const LiveCosts user =
            parseLiveCosts(readInputFile(path, "live costs file", uint64_t(1) << 20), path);
        // The shipped candidates in the shipped order, each with the user's ratio: the planner's
        // candidates stay those of this build, and a file made by another version that lacks
        // one says so instead of leaving a method out of Auto.
        LiveCosts aligned = user;
        aligned.entries.clear();
        std::string missing;
        for (const LiveCost& shipped : defaultLiveCosts().entries) {
            const LiveCost* found = nullptr;
            for (const LiveCost& u : user.entries)
                if (u.method == shipped.method && u.setting == shipped.setting)
                    found = &u;
            if (found)
                aligned.entries.push_back(*found);
            else
                missing += (missing.empty() ? "" : ", ") + shipped.method + " " + shipped.setting;
        }
        if (!missing.empty())
            LUCENT_THROW(ValueError, path, ": no ratio for ", missing,
                         " (measured by another version of Lucent)");
        out.costs = std::move(aligned);
        out.calibrated = true;
    } catch (const std::exception& e) {
        out.warning = std::string("the live-cost calibration cannot be used: ") + e.what() +
                      "; calibrate again" + again;
    }
    return out;
}

std::string describeLiveCosts(const LiveCostsInUse& inUse) {
    const LiveCosts& c = inUse.costs;
    // The renderer's name without its details: "llvmpipe (LLVM 15.0.6, 256 bits)" → "llvmpipe".
    const std::string renderer = c.renderer.substr(0, c.renderer.find(" ("));
    std::string details;
    const auto add = [&details](const std::string& part) {
        if (!part.empty())
            details += (details.empty() ? "" : ", ") + part;
    };
    if (inUse.calibrated) {
        std::string line = "calibrated on this machine";
        if (!c.date.empty())
            line += " " + c.date;
        return renderer.empty() ? line : line + " (" + renderer + ")";
    }
    add(renderer);
    if (c.cpuThreads > 0)
        add(std::to_string(c.cpuThreads) + (c.cpuThreads == 1 ? " thread" : " threads"));
    add(c.date);
    return details.empty() ? "shipped" : "shipped (" + details + ")";
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
