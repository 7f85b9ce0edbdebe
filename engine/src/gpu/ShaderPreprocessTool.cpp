// SPDX-License-Identifier: MIT
/// @file
/// @brief lucent-shader-preprocess: resolves a shader's #include with the engine's preprocessor
/// and writes the result, for build-time validation with glslangValidator
/// (cmake/LucentShaders.cmake).
///   lucent-shader-preprocess --root DIR [--validate] [--define NAME[=V]]... --output OUT FILE
/// --validate emits `#line N "file"` (GL_GOOGLE_cpp_style_line_directive) so glslangValidator
/// reports original file names.

#include <lucent/core/Error.h>
#include <lucent/gpu/Shader.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
    std::string root;
    std::string output;
    std::string input;
    bool validate = false;
    std::vector<std::string> defines;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--root" && i + 1 < argc) {
            root = argv[++i];
        } else if (a == "--output" && i + 1 < argc) {
            output = argv[++i];
        } else if (a == "--define" && i + 1 < argc) {
            defines.emplace_back(argv[++i]);
        } else if (a == "--validate") {
            validate = true;
        } else if (!a.empty() && a[0] != '-' && input.empty()) {
            input = a;
        } else {
            std::fprintf(stderr, "lucent-shader-preprocess: unexpected argument '%s'\n", a.c_str());
            return 2;
        }
    }
    if (root.empty() || output.empty() || input.empty()) {
        std::fprintf(stderr,
                     "usage: lucent-shader-preprocess --root DIR [--validate] [--define N[=V]] "
                     "--output OUT FILE\n");
        return 2;
    }
    try {
        const lucent::gpu::ShaderLibrary library(root);
        const auto pre =
            lucent::gpu::preprocessShader(library, input, defines,
                                          validate ? lucent::gpu::LineDirectives::CppStyle
                                                   : lucent::gpu::LineDirectives::Numeric);
        std::filesystem::create_directories(std::filesystem::path(output).parent_path());
        std::ofstream out(output, std::ios::binary);
        out << pre.source;
        if (!out) {
            std::fprintf(stderr, "lucent-shader-preprocess: cannot write '%s'\n", output.c_str());
            return 1;
        }
    } catch (const lucent::Error& e) {
        std::fprintf(stderr, "%s/%s: error: %s\n", root.c_str(), input.c_str(), e.what());
        return 1;
    }
    return 0;
}
