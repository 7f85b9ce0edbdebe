// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief What lucent-cli's subcommands share: the CLI11 help layout, validators CLI11 lacks,
/// the progress bar, and one `add<Name>Command` per Command_<name>.cpp (CliMain.cpp calls them
/// in the order `lucent-cli --help` lists the commands). CLI-only: CLI11 stays out of the engine.

#include <lucent/core/Types.h>
#include <lucent/planner/MeasureScene.h>
#include <lucent/planner/Planner.h>

#include <CLI/CLI.hpp>

#include <string>
#include <utility>
#include <vector>

namespace lucent::cli {

/// What a command may need beyond its parsed options.
struct CommandContext {
    std::vector<std::string> arguments;  ///< the raw arguments after the command's name
};

/// Adds subcommand `name` to `parent` with its help: `usage` (the synopsis, "usage: lucent-cli
/// NAME ..." lines), then `details` (what it does), then CLI11's list of the options.
/// @param summary the one line `lucent-cli --help` shows for the command.
CLI::App* addCommand(CLI::App& parent, const std::string& name, const std::string& summary,
                     const std::string& usage, const std::string& details);

/// CLI11's file and directory checks, without their description in the help's type column
/// (the type names already say FILE or DIR).
CLI::Validator existingFile();
CLI::Validator existingDirectory();

/// The required positional SCENE.json (an existing file).
CLI::Option* addSceneArgument(CLI::App& app, std::string& scene);

/// --width W and --height H, [1, 16384] pixels, overriding the scene camera's image size.
void addImageSizeOptions(CLI::App& app, int& width, int& height);
/// Applies the --width/--height of `app` that were given to the camera's size (pixels).
void overrideImageSize(const CLI::App& app, int width, int height, int& cameraWidth,
                       int& cameraHeight);

/// A finite number in [lo, hi]. (CLI::Range alone lets "nan" through: every comparison with
/// NaN is false.)
CLI::Validator finiteRange(double lo, double hi);

/// Auto's level check (lucent/planner/LevelCheck.h): --level-tolerance T, --level-relative K
/// and --no-level-check into `tolerance` (off() after --no-level-check).
void addLevelCheckOptions(CLI::App& app, planner::LevelTolerance& tolerance,
                          const std::string& group);

/// Auto measuring on its own (planner::chooseByMeasuring): --measure into `measure`, and
/// --measure-width W, --measure-spp N into `options`.
void addMeasureOptions(CLI::App& app, bool& measure, planner::OwnReferenceOptions& options,
                       const std::string& group);

/// An option that takes one of `choices`' names and stores the matching value in `target`.
/// (CLI::IsMember's error lists the names; CLI::CheckedTransformer's would list the enum's
/// numbers too.)
template <typename T>
CLI::Option* addChoiceOption(CLI::App& app, const std::string& name, T& target,
                             const std::vector<std::pair<std::string, T>>& choices,
                             const std::string& help) {
    std::vector<std::string> names;
    for (const auto& choice : choices)
        names.push_back(choice.first);
    return app
        .add_option_function<std::string>(
            name,
            [&target, choices](const std::string& value) {
                for (const auto& [choiceName, choiceValue] : choices)
                    if (choiceName == value)
                        target = choiceValue;
            },
            help)
        ->check(CLI::IsMember(names));
}

/// "R,G,B" (or one number for all three), each finite and within [lo, hi].
/// @throw ValueError naming `option` otherwise.
Rgb parseRgb(const std::string& option, const std::string& text, float lo, float hi);

/// Draws a one-line progress bar on stderr ("\r[####------] status"), for the commands whose
/// engine calls report progress (render, reference).
void printProgressBar(double fraction, const std::string& status);

//! @{ \name The subcommands, one per Command_<name>.cpp
void addExportCommand(CLI::App& cli, const CommandContext& context);
void addInfoCommand(CLI::App& cli, const CommandContext& context);
void addRenderCommand(CLI::App& cli, const CommandContext& context);
void addMethodsCommand(CLI::App& cli, const CommandContext& context);
void addReferenceCommand(CLI::App& cli, const CommandContext& context);
void addCompareCommand(CLI::App& cli, const CommandContext& context);
void addBenchCommand(CLI::App& cli, const CommandContext& context);
void addProfileCommand(CLI::App& cli, const CommandContext& context);
void addEvaluateCommand(CLI::App& cli, const CommandContext& context);
void addPlanCommand(CLI::App& cli, const CommandContext& context);
//! @}

}  // namespace lucent::cli
