// SPDX-License-Identifier: MIT
/// @file
/// @brief Levels the scene does not need (LevelCheck.h).

#include <lucent/bench/ErrorMetrics.h>
#include <lucent/core/Error.h>
#include <lucent/methods/Registry.h>
#include <lucent/planner/LevelCheck.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

namespace lucent::planner {

size_t coarsestEquivalentLevel(const std::vector<std::string>& levels, size_t chosen,
                               const std::function<double(size_t)>& differenceToNext,
                               double tolerance, std::vector<LevelStep>* steps) {
    LUCENT_CHECK(chosen < levels.size(), "level check: the chosen level is not in the list");
    LUCENT_CHECK(std::isfinite(tolerance) && tolerance >= 0,
                 "level check: the tolerance must be finite and >= 0");
    size_t kept = chosen;
    double summed = 0.0;
    // Summed, not each step on its own: by the triangle inequality of the (finer-normalised)
    // block L1, the image kept then differs from the chosen one by at most about the tolerance.
    while (kept > 0 && tolerance > 0) {
        const double d = differenceToNext(kept - 1);
        if (!(d >= 0) || !std::isfinite(d))
            break;
        const bool take = summed + d <= tolerance;
        if (steps)
            steps->push_back({levels[kept - 1], levels[kept], d, take});
        if (!take)
            break;
        summed += d;
        --kept;
    }
    return kept;
}

std::vector<std::string> modelLevels(const Models& models, const std::string& method) {
    const std::string name = method.substr(0, method.find(':'));
    if (!methods::exists(name))
        return {};
    std::vector<std::string> out;
    for (const methods::ParamPreset& q : methods::find(name).quality)
        for (const CandidateModel& m : models.candidates)
            if (m.method == method && m.setting == q.name) {
                out.push_back(q.name);
                break;
            }
    return out;
}

namespace {

std::string percent(double fraction) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f %%", 100.0 * fraction);
    return buf;
}

void checkOptions(const LevelCheckOptions& options) {
    LUCENT_CHECK(std::isfinite(options.tolerance.absolute) && options.tolerance.absolute >= 0 &&
                     std::isfinite(options.tolerance.relative) && options.tolerance.relative >= 0,
                 "level check: the tolerances must be finite and >= 0");
    LUCENT_CHECK(options.width >= 8, "level check: the frame must be at least 8 pixels wide");
}

}  // namespace

LevelCheck checkLevels(const Scene& scene, const Models& models, const AutoChoice& choice,
                       const LevelCheckOptions& options) {
    checkOptions(options);
    const std::string method = choice.candidate();
    LevelCheck out;
    out.setting = choice.setting;
    const std::vector<std::string> levels = modelLevels(models, method);
    const auto at = std::find(levels.begin(), levels.end(), choice.setting);
    if (at == levels.end() || at == levels.begin() || options.tolerance.off())
        return out;
    const double tolerance = options.tolerance.at(choice.plan.chosen.error);

    // The check frame: the camera's view at the evaluation suite's width (the differences are
    // measured as the suite measures the levels' errors, and the image is cheap next to a
    // grid's solve); the height keeps the aspect.
    Scene small = scene;
    const double aspect = double(scene.camera.height) / double(std::max(scene.camera.width, 1));
    small.camera.width = std::min(options.width, scene.camera.width);
    small.camera.height = std::max(1, int(std::lround(small.camera.width * aspect)));

    std::vector<std::optional<ImageRgb>> images(levels.size());
    const auto render = [&](size_t i) -> const ImageRgb& {
        if (!images[i])
            images[i] = renderCandidate(small, method, levels[i], options.render).radiance;
        return *images[i];
    };
    const auto differenceToNext = [&](size_t i) -> double {
        if (options.cancel && options.cancel->load())
            return -1.0;
        const ImageRgb& finer = render(i + 1);
        const ImageRgb& coarser = render(i);
        // The background is not what the levels differ in.
        const std::vector<uint8_t> mask = bench::maskOfNonBlack(coarser, finer);
        if (std::find(mask.begin(), mask.end(), uint8_t(1)) == mask.end())
            return 0.0;  // both black: nothing to tell apart
        return bench::compareImages(coarser, finer, nullptr, nullptr, &mask)
            .blocks[bench::ErrorReport::LUMINANCE]
            .relL1;
    };
    const size_t kept = coarsestEquivalentLevel(levels, size_t(at - levels.begin()),
                                                differenceToNext, tolerance, &out.steps);
    out.setting = levels[kept];
    double summed = 0.0;
    for (const LevelStep& s : out.steps)
        if (s.taken)
            summed += s.difference;
    std::string note;
    if (kept != size_t(at - levels.begin()))
        note = levels[kept] + ": " + choice.setting + " changes the image by " + percent(summed) +
               " (at most " + percent(tolerance) + ")";
    else if (!out.steps.empty())
        note = choice.setting + " kept: " + out.steps.front().coarser + " differs by " +
               percent(out.steps.front().difference) + " (more than " + percent(tolerance) + ")";
    for (const LevelStep& s : out.steps)
        if (!s.taken && kept != size_t(at - levels.begin()))
            note += "; " + s.coarser + " would by " + percent(summed + s.difference);
    out.note = note;
    return out;
}

void applyLevelCheck(AutoChoice& choice, const Models& models, const LevelCheck& check) {
    const std::string method = choice.candidate();
    if (check.setting == choice.setting) {
        if (!check.note.empty())
            choice.plan.reason += "; level check: " + check.note;
        return;
    }
    // The reason starts with what runs (the status bar cuts a long line at its end), then why,
    // then the models' own reason for their pick.
    const std::string head = check.setting + ": ";
    const std::string why =
        check.note.rfind(head, 0) == 0 ? check.note.substr(head.size()) : check.note;
    choice.plan.reason = method + " " + check.setting + " by the level check" +
                         (why.empty() ? "" : ": " + why) +
                         "; the models' pick: " + choice.plan.reason;
    const CandidateRun run = resolveCandidate(method, check.setting);
    choice.setting = check.setting;
    choice.params = run.params;
    // The plan names the candidate now rendered (its predictions, for the status line).
    for (size_t i = 0; i < models.candidates.size(); ++i)
        if (models.candidates[i].method == method &&
            models.candidates[i].setting == check.setting) {
            choice.plan.choice = i;
            for (const Option& o : choice.plan.options)
                if (o.index == i)
                    choice.plan.chosen = o;
        }
}

void runLevelCheck(const Scene& scene, const Models& models, AutoChoice& choice,
                   const LevelCheckOptions& options) {
    checkOptions(options);  // the caller's mistakes throw; a failed render does not
    LevelCheck check;
    try {
        check = checkLevels(scene, models, choice, options);
    } catch (const Error& e) {
        if (options.render.log)
            options.render.log(std::string("level check skipped (") + e.what() +
                               "); the models' level is kept");
        return;
    }
    applyLevelCheck(choice, models, check);
}

}  // namespace lucent::planner
