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

static std::vector<const Command*> commands() {
    return {&exportCommand,  &infoCommand,  &renderCommand,  &methodsCommand,  &referenceCommand,
            &compareCommand, &benchCommand, &profileCommand, &evaluateCommand, &planCommand};
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
