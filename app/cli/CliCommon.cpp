// SPDX-License-Identifier: MIT
#include "CliCommon.h"

#include <lucent/core/Error.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

namespace lucent::cli {

namespace {

/// A command's help: the hand-written synopsis and explanation first (they say which options
/// go together, which a flat option list cannot), then CLI11's option list with each option's
/// type, range and description.
class CommandFormatter : public CLI::Formatter {
public:
    CommandFormatter(std::string usage, std::string details)
        : m_usage(std::move(usage)), m_details(std::move(details)) {
        column_width(32);
    }

    std::string make_help(const CLI::App* app, std::string name,
                          CLI::AppFormatMode mode) const override {
        if (mode == CLI::AppFormatMode::Sub)
            return make_expanded(app);
        std::string out = m_usage;
        if (!m_details.empty())
            out += "\n" + m_details;
        return out + make_positionals(app) + make_groups(app, mode) + make_subcommands(app, mode) +
               "\n" + make_footer(app);
    }

private:
    std::string m_usage, m_details;
};

std::string numberText(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

/// The number in `text` when all of it is one finite number.
bool parseFinite(const std::string& text, double& value) {
    return CLI::detail::lexical_cast(text, value) && std::isfinite(value);
}

}  // namespace

CLI::App* addCommand(CLI::App& parent, const std::string& name, const std::string& summary,
                     const std::string& usage, const std::string& details) {
    CLI::App* sub = parent.add_subcommand(name, summary);
    sub->formatter(std::make_shared<CommandFormatter>(usage, details));
    return sub;
}

CLI::Validator existingFile() {
    CLI::Validator v = CLI::ExistingFile;
    v.description("");
    return v;
}

CLI::Validator existingDirectory() {
    CLI::Validator v = CLI::ExistingDirectory;
    v.description("");
    return v;
}

CLI::Option* addSceneArgument(CLI::App& app, std::string& scene) {
    return app.add_option("SCENE.json", scene, "the scene file (docs/file-formats.md)")
        ->required()
        ->check(existingFile());
}

void addImageSizeOptions(CLI::App& app, int& width, int& height) {
    app.add_option("--width", width, "override the scene camera's image width (pixels)")
        ->type_name("W")
        ->check(CLI::Range(1, 16384));
    app.add_option("--height", height, "override the scene camera's image height (pixels)")
        ->type_name("H")
        ->check(CLI::Range(1, 16384));
}

void overrideImageSize(const CLI::App& app, int width, int height, int& cameraWidth,
                       int& cameraHeight) {
    if (app.count("--width"))
        cameraWidth = width;
    if (app.count("--height"))
        cameraHeight = height;
}

void addLevelCheckOptions(CLI::App& app, planner::LevelTolerance& tolerance,
                          const std::string& group) {
    CLI::Option* absolute =
        app.add_option("--level-tolerance", tolerance.absolute,
                       "the level check: after the plan, the chosen level and the method's cheaper "
                       "ones are rendered on a 64-pixel-wide frame and the cheapest whose image "
                       "differs from the chosen one by at most max(T, K x its predicted error) "
                       "(4x4-block rel. L1, summed over the steps) is taken (default T 0.02)")
            ->type_name("T")
            ->check(finiteRange(0.0, 1.0))
            ->group(group);
    CLI::Option* relative =
        app.add_option("--level-relative", tolerance.relative,
                       "the level check's K (default 1: a cheaper image within the chosen one's "
                       "own predicted error)")
            ->type_name("K")
            ->check(finiteRange(0.0, 10.0))
            ->group(group);
    app.add_flag_callback(
           "--no-level-check",
           [&tolerance] {
               tolerance = {0.0, 0.0};
           },
           "keep the level the models chose")
        ->excludes(absolute)
        ->excludes(relative)
        ->group(group);
}

void addMeasureOptions(CLI::App& app, bool& measure, planner::OwnReferenceOptions& options,
                       const std::string& group) {
    CLI::Option* flag =
        app.add_flag("--measure", measure,
                     "after the models' plan, render the exact reference of the frame at a small "
                     "size and every candidate within the budget against it, and plan again with "
                     "the measured errors (the level check is then not needed)")
            ->group(group);
    app.add_option("--measure-width", options.width,
                   "--measure: pixels across of the reference and the renders (default 64)")
        ->type_name("W")
        ->check(CLI::Range(8, 1024))
        ->needs(flag)
        ->group(group);
    app.add_option("--measure-spp", options.referenceSpp,
                   "--measure: the reference's samples per pixel (default 128)")
        ->type_name("N")
        ->check(CLI::Range(3, 65536))
        ->needs(flag)
        ->group(group);
}

CLI::Validator finiteRange(double lo, double hi) {
    const std::string range = "[" + numberText(lo) + ", " + numberText(hi) + "]";
    return CLI::Validator(
        [lo, hi, range](std::string& text) -> std::string {
            double v = 0.0;
            if (!parseFinite(text, v))
                return "'" + text + "' is not a finite number";
            if (v < lo || v > hi)
                return text + " is outside " + range;
            return {};
        },
        "in " + range);
}

Rgb parseRgb(const std::string& option, const std::string& text, float lo, float hi) {
    std::vector<std::string> parts;
    std::stringstream ss(text);
    for (std::string p; std::getline(ss, p, ',');)
        parts.push_back(p);
    auto channel = [&](const std::string& part) {
        double v = 0.0;
        if (!parseFinite(part, v))
            LUCENT_THROW(ValueError, option, ": '", part, "' is not a finite number");
        if (v < double(lo) || v > double(hi))
            LUCENT_THROW(ValueError, option, ": ", part, " is outside [", lo, ", ", hi, "]");
        return float(v);
    };
    if (parts.size() == 1)
        return Rgb(channel(parts[0]));
    if (parts.size() != 3)
        LUCENT_THROW(ValueError, option, ": expected R,G,B, got '", text, "'");
    return Rgb(channel(parts[0]), channel(parts[1]), channel(parts[2]));
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
