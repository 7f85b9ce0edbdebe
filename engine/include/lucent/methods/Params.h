// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The typed parameters of a translucency method: descriptors (name, type, range,
/// default, help) that `lucent-cli render` and `lucent-cli methods` are built from (and the
/// app's settings widgets are to be), the values a caller gives (ParamSet: text, as on a command
/// line), and their resolved, validated form (Params) that a method reads.
///
/// Usage (what lucent::methods::renderImage does for a method):
/// @code
///   ParamSet given;  given.set("spp", "64");  given.set("seed", 3);
///   Params p(info, given, Backend::Gl, /*live=*/false);  // throws ValueError naming the field
///   int spp = p.getInt("spp");                           // 64; an unset one gives its default
///   for (const std::string& name : p.unused()) ...       // given but never read (pbrt's
///                                                        // ParameterDictionary::ReportUnused)
/// @endcode
/// Anchors: pbrt-v4 ParameterDictionary (typed look-ups, ReportUnused), Mitsuba 3 Properties.

#include <set>
#include <string>
#include <utility>
#include <vector>

namespace lucent::methods {

/// Where a method runs.
enum class Backend {
    Auto,  ///< the method's preferred backend when it can run here, else its other one
    Gl,    ///< gpu::SceneRenderer with the method's subsurface pass (OpenGL 4.5)
    Cpu,   ///< the method's CPU renderer (no GL)
};
/// "auto", "gl", "cpu".
const char* backendName(Backend backend);
/// @throw ValueError for anything but auto, gl or cpu.
Backend parseBackend(const std::string& name);

/// Value type of a parameter.
enum class ParamType {
    Bool,    ///< on/off (also accepts true/false, 1/0)
    Int,     ///< integer in [min, max]
    Float,   ///< finite number in [min, max]
    Choice,  ///< one of `choices`
};
/// "bool", "int", "float", "choice".
const char* paramTypeName(ParamType type);

/// Where a parameter applies.
enum class ParamScope {
    Both,     ///< offline renders and the live preview
    Offline,  ///< renderImage only (e.g. the total sample count of a progressive method)
    Live,     ///< the live preview only
};

/// One parameter of a method: everything a front end needs to offer it and to check a value.
struct ParamDescriptor {
    ParamDescriptor() = default;
    /// In field order; the per-backend and live defaults and the scope are optional, so that the
    /// methods' tables stay one brace list per parameter.
    ParamDescriptor(std::string name_, ParamType type_, std::string help_, double min_, double max_,
                    std::vector<std::string> choices_, std::string defaultValue_,
                    std::string cpuDefault_ = {}, std::string liveDefault_ = {},
                    ParamScope scope_ = ParamScope::Both)
        : name(std::move(name_)),
          type(type_),
          help(std::move(help_)),
          min(min_),
          max(max_),
          choices(std::move(choices_)),
          defaultValue(std::move(defaultValue_)),
          cpuDefault(std::move(cpuDefault_)),
          liveDefault(std::move(liveDefault_)),
          scope(scope_) {}

    std::string name;  ///< kebab-case, as on the command line: "spp-frame"
    ParamType type = ParamType::Int;
    std::string help;                  ///< one line, with the unit
    double min = 0.0, max = 0.0;       ///< Int, Float: inclusive range
    std::vector<std::string> choices;  ///< Choice: the accepted values
    std::string defaultValue;          ///< as text ("256", "on", "kernel")
    std::string cpuDefault;            ///< on the CPU backend, when it differs ("": the same)
    std::string liveDefault;           ///< in the live preview, when it differs ("": the same)
    ParamScope scope = ParamScope::Both;

    /// The default for a backend (Gl or Cpu) and use (live or offline).
    [[nodiscard]] const std::string& defaultFor(Backend backend, bool live) const;
    /// Checks `text` against the type and range. @return the canonical text ("on"/"off" for
    /// Bool). @throw ValueError "<method>: <name> ..." naming what is wrong.
    [[nodiscard]] std::string validate(const std::string& text, const std::string& method) const;
    /// "[1, 4096]", "on|off", "kernel|steps" for help texts.
    [[nodiscard]] std::string rangeText() const;
};

/// Parameter values as given (text, in the order given; a later set() of a name replaces it).
class ParamSet {
public:
    ParamSet() = default;
    /// From "k=v" pairs. @throw ValueError for an item without '=' or an empty name.
    static ParamSet fromAssignments(const std::vector<std::string>& items);

    void set(const std::string& name, const std::string& value);
    void set(const std::string& name, const char* value) { set(name, std::string(value)); }
    void set(const std::string& name, int value);
    void set(const std::string& name, double value);  ///< "%.9g": round trips a float
    void set(const std::string& name, bool value);    ///< "on" / "off"
    /// Sets every value of `other` (later ones win).
    void merge(const ParamSet& other);

    [[nodiscard]] bool has(const std::string& name) const;
    [[nodiscard]] const std::string* find(const std::string& name) const;
    [[nodiscard]] const std::vector<std::pair<std::string, std::string>>& items() const {
        return m_items;
    }
    [[nodiscard]] bool empty() const { return m_items.empty(); }
    /// "k=v k=v" (stable: cache keys, labels).
    [[nodiscard]] std::string toString() const;

private:
    std::vector<std::pair<std::string, std::string>> m_items;
};

/// Validated values of one method on one backend: every descriptor has a value (given or its
/// default), typed look-ups never fail for a declared name of the right type.
class Params {
public:
    Params() = default;
    /// @param method the method's name (for messages); @param descriptors its parameters;
    /// @param backend Gl or Cpu (selects cpuDefault); @param live selects liveDefault.
    /// @throw ValueError for a name the method does not have (listing the ones it has) or a
    /// value of the wrong type or out of range (naming the parameter and the range).
    Params(const std::string& method, const std::vector<ParamDescriptor>& descriptors,
           const ParamSet& given, Backend backend, bool live);

    [[nodiscard]] bool getBool(const std::string& name) const;
    [[nodiscard]] int getInt(const std::string& name) const;
    [[nodiscard]] float getFloat(const std::string& name) const;
    [[nodiscard]] const std::string& getChoice(const std::string& name) const;
    /// The value as text, whatever the type.
    [[nodiscard]] const std::string& text(const std::string& name) const;
    /// Whether the caller gave the value (not the default).
    [[nodiscard]] bool isGiven(const std::string& name) const;
    /// Given values that no get*() read so far (pbrt's ReportUnused).
    [[nodiscard]] std::vector<std::string> unused() const;
    /// Every value (declared order), as text.
    [[nodiscard]] ParamSet values() const;

private:
    struct Entry {
        const ParamDescriptor* descriptor;
        std::string value;
        bool given;
    };
    const Entry& entry(const std::string& name, ParamType type) const;

    std::string m_method;
    std::vector<Entry> m_entries;
    mutable std::set<std::string> m_read;
};

}  // namespace lucent::methods
