// SPDX-License-Identifier: MIT
/// @file
/// @brief Shader library (embedded or on disk) and the #include preprocessor. No GL here, so the
/// build-time validation tool (ShaderPreprocessTool.cpp) shares this exact code.

#include <lucent/core/Error.h>
#include <lucent/gpu/Shader.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string_view>
#include <utility>

namespace lucent::gpu {
namespace detail {
// Defined in the build-generated LucentEmbeddedShaders.cpp (cmake/LucentShaders.cmake).
const std::vector<std::pair<std::string_view, std::string_view>>& embeddedShaderFiles();
}  // namespace detail

namespace fs = std::filesystem;

namespace {

std::string normalisePath(const std::string& path) {
    return fs::path(path).lexically_normal().generic_string();
}

const std::string_view* findEmbedded(const std::string& path) {
    for (const auto& [name, text] : detail::embeddedShaderFiles())
        if (name == path)
            return &text;
    return nullptr;
}

std::string trim(std::string_view s) {
    size_t b = 0;
    size_t e = s.size();
    while (b < e && (s[b] == ' ' || s[b] == '\t' || s[b] == '\r'))
        ++b;
    while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t' || s[e - 1] == '\r'))
        --e;
    return std::string(s.substr(b, e - b));
}

/// Splits a directive line "#  name rest" into (name, rest); name empty if not a directive.
std::pair<std::string, std::string> splitDirective(const std::string& line) {
    std::string t = trim(line);
    if (t.empty() || t[0] != '#')
        return {};
    size_t i = 1;
    while (i < t.size() && (t[i] == ' ' || t[i] == '\t'))
        ++i;
    size_t j = i;
    while (j < t.size() && (std::isalnum(static_cast<unsigned char>(t[j])) || t[j] == '_'))
        ++j;
    return {t.substr(i, j - i), trim(std::string_view(t).substr(j))};
}

struct Frame {
    bool cplusplus = false;  ///< a conditional on __cplusplus
    bool active = true;      ///< for __cplusplus frames: whether the current branch is kept
};

class Preprocessor {
public:
    Preprocessor(const ShaderLibrary& library, LineDirectives style)
        : m_library(library), m_style(style) {}

    PreprocessedShader run(const std::string& path, const std::vector<std::string>& defines) {
        m_defines = defines;
        emitFile(normalisePath(path), "", 0);
        if (!m_sawVersion)
            LUCENT_THROW(ValueError, "shader '", path,
                         "': no #version directive on its first line");
        return {m_out.str(), m_files};
    }

private:
    int fileId(const std::string& path) {
        for (size_t i = 0; i < m_files.size(); ++i)
            if (m_files[i] == path)
                return int(i);
        m_files.push_back(path);
        return int(m_files.size() - 1);
    }

    void lineDirective(int line, int id) {
        if (m_style == LineDirectives::Numeric)
            m_out << "#line " << line << ' ' << id << '\n';
        else
            m_out << "#line " << line << " \"" << m_files[size_t(id)] << "\"\n";
    }

    std::string resolveInclude(const std::string& from, const std::string& target) const {
        const std::string sibling =
            normalisePath((fs::path(from).parent_path() / target).generic_string());
        if (m_library.exists(sibling))
            return sibling;
        const std::string rooted = normalisePath(target);
        if (m_library.exists(rooted))
            return rooted;
        return {};
    }

    void emitFile(const std::string& path, const std::string& includedFrom, int depth) {
        if (depth > 32)
            LUCENT_THROW(ValueError, "shader include cycle (depth > 32) at '", path,
                         "' included from ", includedFrom);
        if (m_once.count(path))
            return;
        const std::string text = m_library.read(path);
        const int id = fileId(path);
        if (depth > 0)
            lineDirective(1, id);

        std::vector<Frame> frames;
        std::istringstream in(text);
        std::string line;
        int lineNo = 0;
        auto kept = [&] {
            for (const Frame& f : frames)
                if (f.cplusplus && !f.active)
                    return false;
            return true;
        };
        while (std::getline(in, line)) {
            ++lineNo;
            if (!line.empty() && line.back() == '\r')
                line.pop_back();
            const auto [name, rest] = splitDirective(line);
            const bool wasKept = kept();
            if (name == "ifdef" || name == "ifndef" || name == "if") {
                const bool onCpp = rest == "__cplusplus" || rest == "defined(__cplusplus)" ||
                                   rest == "defined __cplusplus" || rest == "!defined(__cplusplus)";
                if (onCpp) {
                    const bool negated = name == "ifndef" || rest[0] == '!';
                    frames.push_back({true, negated});
                    m_out << '\n';
                    continue;
                }
                frames.push_back({false, true});
            } else if (name == "elif" && !frames.empty() && frames.back().cplusplus) {
                LUCENT_THROW(ValueError, path, ":", lineNo,
                             ": #elif after a __cplusplus conditional is not supported");
            } else if (name == "else" && !frames.empty() && frames.back().cplusplus) {
                frames.back().active = !frames.back().active;
                m_out << '\n';
                continue;
            } else if (name == "endif") {
                if (frames.empty())
                    LUCENT_THROW(ValueError, path, ":", lineNo, ": #endif without #if");
                const bool cpp = frames.back().cplusplus;
                frames.pop_back();
                if (cpp) {
                    m_out << '\n';
                    continue;
                }
            }
            if (!wasKept) {
                m_out << '\n';
                continue;
            }
            if (name == "version") {
                if (depth > 0)
                    LUCENT_THROW(ValueError, path, ":", lineNo,
                                 ": #version in an included file (included from ", includedFrom,
                                 ")");
                m_sawVersion = true;
                m_out << line << '\n';
                if (m_style == LineDirectives::CppStyle)
                    m_out << "#extension GL_GOOGLE_cpp_style_line_directive : require\n";
                for (const std::string& d : m_defines) {
                    const size_t eq = d.find('=');
                    if (eq == std::string::npos)
                        m_out << "#define " << d << '\n';
                    else
                        m_out << "#define " << d.substr(0, eq) << ' ' << d.substr(eq + 1) << '\n';
                }
                lineDirective(lineNo + 1, id);
            } else if (name == "pragma" && rest == "once") {
                m_once.insert(path);
                m_out << '\n';
            } else if (name == "include") {
                if (rest.size() < 2 || rest.front() != '"' || rest.back() != '"')
                    LUCENT_THROW(ValueError, path, ":", lineNo,
                                 ": expected #include \"file\" (angle includes only under "
                                 "#ifdef __cplusplus)");
                const std::string target = rest.substr(1, rest.size() - 2);
                const std::string resolved = resolveInclude(path, target);
                if (resolved.empty())
                    LUCENT_THROW(IoError, path, ":", lineNo, ": cannot find included file '",
                                 target, "' (searched next to the file and in ", m_library.origin(),
                                 ")");
                if (!m_sawVersion)
                    LUCENT_THROW(ValueError, path, ":", lineNo,
                                 ": #include before the #version directive");
                emitFile(resolved, path + ":" + std::to_string(lineNo), depth + 1);
                lineDirective(lineNo + 1, id);
            } else {
                m_out << line << '\n';
            }
        }
        if (!frames.empty())
            LUCENT_THROW(ValueError, path, ": unterminated #if block at end of file");
    }

    const ShaderLibrary& m_library;
    LineDirectives m_style;
    std::vector<std::string> m_defines;
    std::ostringstream m_out;
    std::vector<std::string> m_files;
    std::set<std::string> m_once;
    bool m_sawVersion = false;
};

}  // namespace

ShaderLibrary::ShaderLibrary() {
    if (const char* dir = std::getenv("LUCENT_SHADER_DIR"); dir && *dir) {
        LUCENT_CHECK(fs::is_directory(dir), "LUCENT_SHADER_DIR='", dir, "' is not a directory");
        m_directory = dir;
    }
}

ShaderLibrary::ShaderLibrary(const std::string& directory) : m_directory(directory) {
    if (!fs::is_directory(directory))
        LUCENT_THROW(IoError, "shader directory '", directory, "' does not exist");
}

void ShaderLibrary::setFile(const std::string& path, const std::string& text) {
    m_memory[normalisePath(path)] = text;
}

bool ShaderLibrary::exists(const std::string& path) const {
    const std::string p = normalisePath(path);
    if (p.empty() || p.rfind("..", 0) == 0)
        return false;
    if (m_memory.count(p))
        return true;
    if (m_directory.empty())
        return findEmbedded(p) != nullptr;
    return fs::is_regular_file(fs::path(m_directory) / p);
}

std::string ShaderLibrary::read(const std::string& path) const {
    const std::string p = normalisePath(path);
    if (auto it = m_memory.find(p); it != m_memory.end())
        return it->second;
    if (m_directory.empty()) {
        if (const std::string_view* text = findEmbedded(p))
            return std::string(*text);
        LUCENT_THROW(IoError, "shader '", path, "' is not among the embedded shaders");
    }
    std::ifstream file(fs::path(m_directory) / p, std::ios::binary);
    if (!file)
        LUCENT_THROW(IoError, "cannot read shader '", path, "' in '", m_directory, "'");
    std::ostringstream ss;
    ss << file.rdbuf();
    return ss.str();
}

std::string ShaderLibrary::origin() const {
    return m_directory.empty() ? std::string("the embedded shaders") : m_directory;
}

std::vector<std::string> ShaderLibrary::embeddedFiles() {
    std::vector<std::string> out;
    for (const auto& entry : detail::embeddedShaderFiles())
        out.emplace_back(entry.first);
    return out;
}

PreprocessedShader preprocessShader(const ShaderLibrary& library, const std::string& path,
                                    const std::vector<std::string>& defines, LineDirectives style) {
    return Preprocessor(library, style).run(path, defines);
}

std::string PreprocessedShader::mapLog(const std::string& log) const {
    // Mesa: "0:12(5): error: ..."; NVIDIA: "0(12) : error C1008: ..."; glslang/AMD:
    // "ERROR: 0:12: ...". The leading integer is the #line source-string id.
    static const std::regex loc(R"(^(\s*(?:ERROR: |WARNING: )?)(\d+)([:(])(\d+))");
    std::istringstream in(log);
    std::ostringstream out;
    std::string line;
    while (std::getline(in, line)) {
        std::smatch m;
        if (std::regex_search(line, m, loc)) {
            const size_t id = std::stoul(m[2].str());
            if (id < files.size()) {
                line = m[1].str() + files[id] + m[3].str() + m[4].str() + m.suffix().str();
            }
        }
        out << line << '\n';
    }
    return out.str();
}

}  // namespace lucent::gpu
