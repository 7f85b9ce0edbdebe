// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief What a live preview frame costs: per method at one setting, the stroke → frame time
/// of the app's viewport as a ratio to the render of a Direct frame of the same viewport,
/// measured by the app's latency harness (`lucent --benchmark --live-costs PATH`) and shipped
/// as data (resources/planner/live_costs.json, embedded).
///
///     Models live = liveModels(defaultModels(), defaultLiveCosts());
///     AutoChoice c = chooseMethod(scene, live, {.frameMs = 50, .directMs = directRenderMs},
///                                 true, nullptr, methods::Backend::Gl);
///
/// Why a second cost table: the fitted cost models (Models.h) predict an offline render to
/// convergence through methods::renderImage (context creation, every sample), while the live
/// preview keeps its GL objects and its passes between frames and spreads a progressive
/// method's samples over idle frames. What an artist waits for after a stroke is the first
/// frame, and that frame's cost differs by an order of magnitude from the offline render's.
/// The error of a live candidate is the offline error model of the setting it converges to:
/// the preview refines until then.
///
/// The shipped ratios are those of the machine they were measured on; a user re-measures them
/// on theirs (`lucent-cli bench calibrate`, the app's Edit ▸ Preferences ▸ Calibrate Live
/// Costs; lucent/planner/LiveCalibration.h) into userLiveCostsPath(), which the app plans with
/// when it is there (loadLiveCosts).

#include <lucent/planner/Models.h>

#include <string>
#include <vector>

namespace lucent::planner {

/// One live candidate.
struct LiveCost {
    std::string method;   ///< registry name[:variant], as in Models ("sslpv:paper")
    std::string setting;  ///< quality level the preview converges to ("128 spp", "grid 32")
    /// Stroke → frame (median) / the Direct frame's render time (median), measured in one run.
    double strokeRatio = 0.0;
};

struct LiveCosts {
    static constexpr int VERSION = 1;
    std::string source;  ///< the command, viewport size, machine and date of the measurement
    /// The unit as the harness measured it (ms; 0 when not recorded): the Direct frame's render
    /// on the measuring machine. Tests pin Auto to it for a choice that does not depend on load.
    double directMs = 0.0;
    std::string date;      ///< UTC date of the measurement, "2026-12-03" ("" when not recorded)
    std::string renderer;  ///< the GL renderer measured on ("" when not recorded)
    int cpuThreads = 0;    ///< hardware threads of the measuring machine (0: not recorded)
    /// Whether the ratios include the app's own per-frame host time (its event loop and buffer
    /// swap): true for the app's latency harness, which times the window's frames; false for a
    /// headless calibration (lucent-cli bench calibrate, the app's Calibrate Live Costs), which
    /// renders into a framebuffer. Auto adds the host time it measures to the predictions of
    /// a table without it (Budget::hostMs). JSON "host_included"; absent: false.
    bool hostIncluded = false;
    std::vector<LiveCost> entries;
};

/// JSON (docs/planner.md, "Live costs"). @throw ValueError naming `origin` for malformed JSON,
/// another version, a missing field or a ratio that is not a finite number > 0.
LiveCosts parseLiveCosts(const std::string& json, const std::string& origin);
std::string formatLiveCosts(const LiveCosts& costs);

/// The live costs shipped with this build (resources/planner/live_costs.json, embedded).
const LiveCosts& defaultLiveCosts();

/// Environment variable naming the user's calibration file instead of the rule below (tests,
/// or a calibration kept elsewhere).
inline constexpr const char* LIVE_COSTS_ENV = "LUCENT_LIVE_COSTS";

/// Where this user's calibration lives: $LUCENT_LIVE_COSTS when set and not empty, else
/// $XDG_CONFIG_HOME/lucent/live_costs.json (XDG Base Directory Specification: a relative
/// XDG_CONFIG_HOME is ignored), else $HOME/.config/lucent/live_costs.json; "" when none of
/// these variables is set. The CLI writes there and the app reads there.
std::string userLiveCostsPath();

/// Writes `costs` to `path` (formatLiveCosts) atomically, creating its folder.
/// @throw IoError naming the path.
void saveLiveCosts(const LiveCosts& costs, const std::string& path);

/// The live costs to plan with and where they came from.
struct LiveCostsInUse {
    LiveCosts costs;          ///< the user's calibration, or the shipped table
    bool calibrated = false;  ///< from the user's file
    std::string path;         ///< the file looked at ("" when there is no location)
    /// Why the file at `path` exists but is not used (malformed, another version, a shipped
    /// candidate missing): say it to the user. "" when it is used or absent.
    std::string warning;
};

/// The user's calibration at `path` when the file exists, parses and has a ratio for every
/// shipped candidate (then in the shipped order; entries the build does not ship are dropped);
/// the shipped table otherwise, with a warning when the file exists but cannot be used.
/// Never throws for a bad file: a preview must not fail because of one.
LiveCostsInUse loadLiveCosts(const std::string& path);

/// One line for the user: "calibrated on this machine 2026-12-03 (llvmpipe)" or "shipped
/// (llvmpipe, 2 threads, 2026-12-02)".
std::string describeLiveCosts(const LiveCostsInUse& inUse);

/// The live preview's models: one candidate per entry of `live` that `offline` has an error
/// model for, with that error model and a constant cost of the entry's strokeRatio. Entries
/// without an offline model are left out (say which through `missing`, if given).
Models liveModels(const Models& offline, const LiveCosts& live,
                  std::vector<std::string>* missing = nullptr);

}  // namespace lucent::planner
