// SPDX-License-Identifier: MIT
/// @file
/// @brief The Auto planner (Planner.h has the contract).

#include <lucent/core/Error.h>
#include <lucent/planner/Planner.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace lucent::planner {

namespace {

std::string nameOf(const Candidate& c) {
    return c.setting.empty() ? c.method : c.method + " " + c.setting;
}

std::string format(const char* fmt, double a, double b = 0.0) {
    char buf[96];
    std::snprintf(buf, sizeof buf, fmt, a, b);
    return buf;
}

/// "dirpole (3 settings), sslpv 32 skipped: why" for the candidates left out, one clause per
/// reason (a method whose every setting fails the same way is named once).
std::string skippedClauses(const std::vector<std::pair<const Candidate*, std::string>>& skipped) {
    std::vector<std::string> reasons;
    for (const auto& [c, why] : skipped)
        if (std::find(reasons.begin(), reasons.end(), why) == reasons.end())
            reasons.push_back(why);
    std::string out;
    for (const std::string& why : reasons) {
        std::vector<std::pair<std::string, std::vector<const Candidate*>>> byMethod;
        for (const auto& [c, w] : skipped) {
            if (w != why)
                continue;
            auto it = std::find_if(byMethod.begin(), byMethod.end(),
                                   [&](const auto& m) { return m.first == c->method; });
            if (it == byMethod.end())
                byMethod.push_back({c->method, {c}});
            else
                it->second.push_back(c);
        }
        std::string names;
        for (const auto& [method, list] : byMethod) {
            names += names.empty() ? "" : ", ";
            names += list.size() == 1 ? nameOf(*list.front())
                                      : method + " (" + std::to_string(list.size()) + " settings)";
        }
        out += "; " + names + " skipped: " + why;
    }
    return out;
}

}  // namespace

Plan plan(const std::vector<Candidate>& candidates, const SceneFeatures& features,
          const Budget& budget, const Plan* previous) {
    LUCENT_CHECK(budget.directMs > 0 && std::isfinite(budget.directMs),
                 "plan: the Direct frame time must be > 0 ms, got ", budget.directMs);
    // An infinite budget is allowed: no time limit (the most accurate candidate).
    LUCENT_CHECK(budget.frameMs > 0, "plan: the frame budget must be > 0 ms, got ", budget.frameMs);
    LUCENT_CHECK(budget.hostMs >= 0 && std::isfinite(budget.hostMs),
                 "plan: the host time must be a finite number >= 0 ms, got ", budget.hostMs);
    LUCENT_CHECK(budget.hysteresis >= 0 && budget.hysteresis < 1,
                 "plan: hysteresis must be in [0, 1), got ", budget.hysteresis);
    LUCENT_CHECK(budget.errorTolerance >= 0 && budget.errorTolerance < 1,
                 "plan: the error tolerance must be in [0, 1), got ", budget.errorTolerance);
    LUCENT_CHECK(budget.errorMargin >= 0 && std::isfinite(budget.errorMargin),
                 "plan: the error margin must be a finite number >= 0, got ", budget.errorMargin);
    const bool errorTarget = budget.maxError > 0;

    Plan p;
    p.sceneClass = classify(features);
    std::vector<std::pair<const Candidate*, std::string>> skipped;
    for (size_t i = 0; i < candidates.size(); ++i) {
        const Candidate& c = candidates[i];
        if (c.unusable) {
            const std::string why = c.unusable(features);
            if (!why.empty()) {
                skipped.emplace_back(&c, why);
                continue;
            }
        }
        Option o;
        o.index = i;
        o.ms = c.costRatio(features) * budget.directMs + budget.hostMs;
        o.error = c.error(features);
        LUCENT_CHECK(std::isfinite(o.ms) && o.ms >= 0 && std::isfinite(o.error) && o.error >= 0,
                     "plan: the models of ", nameOf(c), " predict ", o.ms, " ms and error ",
                     o.error);
        o.fits = errorTarget ? o.error <= budget.maxError : o.ms <= budget.frameMs;
        p.options.push_back(o);
    }
    if (p.options.empty()) {
        p.reason = "no method can render this scene" + skippedClauses(skipped);
        return p;
    }
    // Nothing fits the time budget: relax it to the fastest candidate's time × (1 + tolerance),
    // and choose within that as within a budget (least error, ties, hysteresis).
    double relaxedMs = 0.0;
    if (!errorTarget && budget.overrunTolerance > 0 &&
        std::none_of(p.options.begin(), p.options.end(), [](const Option& o) { return o.fits; })) {
        double fastest = std::numeric_limits<double>::infinity();
        for (const Option& o : p.options)
            fastest = std::min(fastest, o.ms);
        relaxedMs = fastest * (1.0 + budget.overrunTolerance);
        for (Option& o : p.options)
            o.fits = o.ms <= relaxedMs;
    }
    // Fitting options first; among them the least error (time budget) or the least time
    // (error target), the other quantity breaking ties. If none fits: the cheapest (time
    // budget) or the most accurate (error target), the closest to fitting.
    std::stable_sort(p.options.begin(), p.options.end(), [&](const Option& a, const Option& b) {
        if (a.fits != b.fits)
            return a.fits;
        const bool byError = errorTarget ? !a.fits : a.fits;
        if (byError)
            return a.error != b.error ? a.error < b.error : a.ms < b.ms;
        return a.ms != b.ms ? a.ms < b.ms : a.error < b.error;
    });
    p.valid = true;
    p.chosen = p.options.front();
    bool cheaperAtEqualError = false;
    if (!errorTarget && p.chosen.fits) {
        const double equalBelow =
            p.chosen.error * (1.0 + budget.errorTolerance) + budget.errorMargin;
        for (const Option& o : p.options)
            if (o.fits && o.error <= equalBelow && o.ms < p.chosen.ms) {
                p.chosen = o;
                cheaperAtEqualError = true;
            }
    }

    // Hysteresis: within one scene class, keep the previous choice while it still fits and
    // the new best is not clearly better.
    if (previous && previous->valid && previous->sceneClass == p.sceneClass) {
        const auto prev = std::find_if(p.options.begin(), p.options.end(), [&](const Option& o) {
            return o.index == previous->choice;
        });
        if (prev != p.options.end() && prev->fits && prev->index != p.chosen.index) {
            const double keepBelow = 1.0 - budget.hysteresis;
            const bool clearlyBetter = errorTarget ? p.chosen.ms < prev->ms * keepBelow
                                                   : p.chosen.error < prev->error * keepBelow;
            if (!clearlyBetter) {
                p.chosen = *prev;
                p.kept = true;
            }
        }
    }
    p.choice = p.chosen.index;
    if (relaxedMs > 0) {  // chosen within the relaxed budget; none fits the real one
        for (Option& o : p.options)
            o.fits = false;
        p.chosen.fits = false;
    }

    const Candidate& chosen = candidates[p.choice];
    const char* timeFormat = budget.directKnown ? "%.0f ms" : "%.1f× Direct";
    p.reason = nameOf(chosen) + ": " + describe(p.sceneClass, features.eta) + "; predicted " +
               format(timeFormat, p.chosen.ms);
    if (!errorTarget)
        p.reason += std::isfinite(budget.frameMs) ? format(" (budget %.0f ms)", budget.frameMs)
                                                  : std::string(" (no time budget)");
    p.reason += format(", block error %.2f", p.chosen.error);
    if (errorTarget)
        p.reason += format(" (target %.2f)", budget.maxError);
    if (relaxedMs > 0)
        p.reason +=
            format(", over budget: nothing fits, the least error within %.0f ms", relaxedMs);
    else if (!p.chosen.fits)
        p.reason += errorTarget ? ", no method reaches the target" : ", over budget";
    if (cheaperAtEqualError && !p.kept)
        p.reason += budget.errorMargin > 0
                        ? format(", the cheapest within %.0f %% + %.3f of the least error",
                                 100.0 * budget.errorTolerance, budget.errorMargin)
                        : format(", the cheapest within %.0f %% of the least error",
                                 100.0 * budget.errorTolerance);
    if (p.kept)
        p.reason +=
            ", kept: the best differs by less than " + format("%.0f %%", 100.0 * budget.hysteresis);
    // The runner-up, and why it lost.
    for (const Option& o : p.options) {
        if (o.index == p.choice)
            continue;
        const std::string why =
            !o.fits ? (errorTarget ? format("error %.2f", o.error) : format(timeFormat, o.ms))
                    : (errorTarget ? format(timeFormat, o.ms) : format("error %.2f", o.error));
        p.reason += "; next: " + nameOf(candidates[o.index]) + " (" + why + ")";
        break;
    }
    p.reason += skippedClauses(skipped);
    return p;
}

}  // namespace lucent::planner
