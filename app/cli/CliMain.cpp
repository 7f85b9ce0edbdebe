// SPDX-License-Identifier: MIT
/// @file
/// @brief lucent-cli: dispatches to one subcommand; any lucent::Error becomes a one-line
/// reason on stderr and exit code 1 (2 for usage errors).

#include "CliArgs.h"

#include <lucent/core/Error.h>

#include <cstdio>
#include <cstring>
#include <exception>
#include <vector>

namespace lucent::cli {
// Each Command_<name>.cpp defines its table entry; CMake defines LUCENT_CLI_HAS_<NAME>.
#define LUCENT_DECLARE(name) extern const Command name##Command;
#ifdef LUCENT_CLI_HAS_EXPORT
LUCENT_DECLARE(export)
#endif
#ifdef LUCENT_CLI_HAS_INFO
LUCENT_DECLARE(info)
#endif
#ifdef LUCENT_CLI_HAS_RENDER
LUCENT_DECLARE(render)
#endif
#ifdef LUCENT_CLI_HAS_REFERENCE
LUCENT_DECLARE(reference)
#endif
#ifdef LUCENT_CLI_HAS_COMPARE
LUCENT_DECLARE(compare)
#endif
#ifdef LUCENT_CLI_HAS_BENCH
LUCENT_DECLARE(bench)
#endif
#ifdef LUCENT_CLI_HAS_PROFILE
LUCENT_DECLARE(profile)
#endif
#ifdef LUCENT_CLI_HAS_EVALUATE
LUCENT_DECLARE(evaluate)
#endif
#undef LUCENT_DECLARE

static std::vector<const Command*> commands() {
    return {
#ifdef LUCENT_CLI_HAS_EXPORT
        &exportCommand,
#endif
#ifdef LUCENT_CLI_HAS_INFO
        &infoCommand,
#endif
#ifdef LUCENT_CLI_HAS_RENDER
        &renderCommand,
#endif
#ifdef LUCENT_CLI_HAS_REFERENCE
        &referenceCommand,
#endif
#ifdef LUCENT_CLI_HAS_COMPARE
        &compareCommand,
#endif
#ifdef LUCENT_CLI_HAS_BENCH
        &benchCommand,
#endif
#ifdef LUCENT_CLI_HAS_PROFILE
        &profileCommand,
#endif
#ifdef LUCENT_CLI_HAS_EVALUATE
        &evaluateCommand,
#endif
    };
}

static void printUsage(std::FILE* out) {
    std::fprintf(
        out,
        "usage: lucent-cli <command> [options]   (lucent-cli <command> --help)\n\ncommands:\n");
    for (const Command* c : commands())
        std::fprintf(out, "  %-10s %s\n", c->name, c->summary);
}

}  // namespace lucent::cli

int main(int argc, char** argv) {
    using namespace lucent::cli;
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
        printUsage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    for (const Command* c : commands()) {
        if (std::strcmp(argv[1], c->name) != 0)
            continue;
        std::vector<std::string> args(argv + 2, argv + argc);
        for (const auto& a : args)
            if (a == "--help" || a == "-h") {
                std::fputs(c->help, stdout);
                return 0;
            }
        try {
            return c->run(args);
        } catch (const lucent::ValueError& e) {
            std::fprintf(stderr, "lucent-cli %s: %s\n", c->name, e.what());
            return 2;
        } catch (const std::exception& e) {
            std::fprintf(stderr, "lucent-cli %s: %s\n", c->name, e.what());
            return 1;
        }
    }
    std::fprintf(stderr, "lucent-cli: unknown command '%s'\n", argv[1]);
    printUsage(stderr);
    return 2;
}
