// SPDX-License-Identifier: MIT
/// @file
/// @brief lucent-cli: parses the command line with CLI11 and runs one subcommand; a usage error
/// (CLI11's or an engine ValueError) becomes a one-line reason on stderr and exit code 2, any
/// other error exit code 1.

#include "CliCommon.h"

#include <lucent/core/Error.h>

#include <cstdio>
#include <exception>
#include <string>

namespace {

/// "lucent-cli render" when a subcommand was recognised, else "lucent-cli".
std::string commandName(const CLI::App& cli) {
    std::string name = "lucent-cli";
    for (const CLI::App* sub = &cli; !sub->get_subcommands().empty();) {
        sub = sub->get_subcommands().front();
        name += " " + sub->get_name();
    }
    return name;
}

}  // namespace

int main(int argc, char** argv) {
    using namespace lucent::cli;
    CLI::App cli(
        "Lucent's command line: export and inspect material volumes, render and compare "
        "with every translucency method, evaluate, plan and benchmark.",
        "lucent-cli");
    cli.formatter(std::make_shared<CLI::Formatter>());
    cli.get_formatter()->label("Usage", "usage");
    // As before CLI11: an option given twice keeps its last value (repeatable ones say so).
    cli.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    cli.require_subcommand(1);

    CommandContext context;
    if (argc > 2)
        context.arguments.assign(argv + 2, argv + argc);
    addExportCommand(cli, context);
    addInfoCommand(cli, context);
    addRenderCommand(cli, context);
    addMethodsCommand(cli, context);
    addReferenceCommand(cli, context);
    addCompareCommand(cli, context);
    addBenchCommand(cli, context);
    addProfileCommand(cli, context);
    addEvaluateCommand(cli, context);
    addPlanCommand(cli, context);
    cli.footer("lucent-cli <command> --help: the command's options.");  // after: not inherited

    if (argc < 2) {
        std::fputs(cli.help().c_str(), stderr);
        return 2;
    }
    try {
        cli.parse(argc, argv);
        return 0;
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0)  // --help
            return cli.exit(e);
        // One line, naming the command.
        if (cli.get_subcommands().empty() && argv[1][0] != '-')
            std::fprintf(stderr,
                         "lucent-cli: unknown command '%s' (lucent-cli --help lists them)\n",
                         argv[1]);
        else
            std::fprintf(stderr, "%s: %s (see --help)\n", commandName(cli).c_str(), e.what());
        return 2;
    } catch (const lucent::ValueError& e) {
        std::fprintf(stderr, "%s: %s\n", commandName(cli).c_str(), e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s: %s\n", commandName(cli).c_str(), e.what());
        return 1;
    }
}
