// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Minimal argument parsing shared by lucent-cli subcommands: --flag, --key value,
/// --key=value, positional arguments; every parse error names the argument.

#include <lucent/core/Types.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace lucent::cli {

/// Parsed command line of one subcommand.
class Args {
public:
    /// @param valueOptions options that take a value (without leading dashes);
    /// @param flagOptions options that take none. Unknown options throw ValueError.
    Args(const std::vector<std::string>& argv, const std::vector<std::string>& valueOptions,
         const std::vector<std::string>& flagOptions);

    [[nodiscard]] bool has(const std::string& name) const;
    /// The last value of an option given several times.
    [[nodiscard]] std::optional<std::string> value(const std::string& name) const;
    /// Every value of a repeatable option, in the order given.
    [[nodiscard]] std::vector<std::string> values(const std::string& name) const;
    [[nodiscard]] std::string valueOr(const std::string& name, const std::string& fallback) const;
    /// Integer option within [lo, hi]; ValueError naming the option otherwise.
    [[nodiscard]] int intOr(const std::string& name, int fallback, int lo, int hi) const;
    /// Finite float option within [lo, hi]; ValueError naming the option otherwise.
    [[nodiscard]] float floatOr(const std::string& name, float fallback, float lo, float hi) const;
    /// "R,G,B" (or a single number for all three), finite, within [lo, hi].
    [[nodiscard]] std::optional<Rgb> rgb(const std::string& name, float lo, float hi) const;
    [[nodiscard]] const std::vector<std::string>& positional() const { return m_positional; }

    /// The value of `--name VALUE` or `--name=VALUE` in raw arguments, before parsing (for
    /// options that decide which other options exist, such as render's --method).
    static std::optional<std::string> peek(const std::vector<std::string>& argv,
                                           const std::string& name);

private:
    std::map<std::string, std::vector<std::string>> m_values;
    std::vector<std::string> m_flags;
    std::vector<std::string> m_positional;
};

/// Draws a one-line progress bar on stderr ("\r[####------] status"), for the commands whose
/// engine calls report progress (render, reference).
void printProgressBar(double fraction, const std::string& status);

/// A subcommand: `run` returns the process exit code; errors are thrown as lucent::Error.
struct Command {
    const char* name;
    const char* summary;
    const char* help;  ///< full --help text
    int (*run)(const std::vector<std::string>& args);
};

/// The subcommands, one per Command_<name>.cpp (CliMain.cpp lists them in this order).
extern const Command exportCommand, infoCommand, renderCommand, methodsCommand, referenceCommand,
    compareCommand, benchCommand, profileCommand, evaluateCommand, planCommand;

}  // namespace lucent::cli
