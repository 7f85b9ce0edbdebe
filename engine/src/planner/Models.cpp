// SPDX-License-Identifier: MIT
#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/planner/LevelCheck.h>
#include <lucent/planner/Models.h>

#include "ModelData.h"
#include "PlannerJson.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>

namespace lucent::planner {

namespace {

constexpr double MIN_ERROR = 1e-3;  // block errors below the reference noise floor read as 0
constexpr double MIN_COST = 1e-3;

/// ln of a clamped positive value.
double logOf(double v, double floor) {
    return std::log(std::max(v, floor));
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Terms
// ---------------------------------------------------------------------------------------------

const std::vector<std::string>& costTermNames() {
    static const std::vector<std::string> names = {"1", "coverage", "extra_lights"};
    return names;
}

std::vector<double> costTerms(const SceneFeatures& f) {
    // Image-space methods scale with the covered pixels, light views with the lights; SSLPV's
    // propagation with neither (its intercept carries it).
    const double coverage =
        f.imagePixels > 0 ? std::clamp(f.pixelsCovered / f.imagePixels, 0.0, 1.0) : 0.0;
    return {1.0, coverage, double(std::max(0, f.lights - 1))};
}

const std::vector<std::string>& errorTermNames() {
    static const std::vector<std::string> names = {"1",
                                                   "log10_optical_size/3",
                                                   "1-albedo",
                                                   "sigma_t_variation",
                                                   "2*albedo_variation",
                                                   "mean_abs_g",
                                                   "eta-1",
                                                   "back_lit_fraction",
                                                   "curvature",
                                                   "thin_fraction"};
    return names;
}

std::vector<double> errorTerms(const SceneFeatures& f) {
    // Each of order one over the scenes Lucent is for (docs/planner.md, "Models"): optical
    // sizes 1–1000 mean free paths, η 1–2.5, curvature capped where the object is as small as
    // the light's spread (the diffusion models have stopped meaning anything there).
    return {1.0,
            std::log10(std::max(f.opticalSize, 1.0)) / 3.0,
            std::clamp(1.0 - f.albedo, 0.0, 1.0),
            std::min(f.sigmaTVariation, 2.0),
            std::min(2.0 * f.albedoVariation, 2.0),
            std::clamp(f.meanAbsG, 0.0, 1.0),
            std::clamp(f.eta - 1.0, 0.0, 2.0),
            std::clamp(f.backLitFraction, 0.0, 1.0),
            std::min(f.curvature, 2.0),
            std::clamp(f.thinFraction, 0.0, 1.0)};
}

namespace {

double dot(const std::vector<double>& a, const std::vector<double>& b) {
    LUCENT_ASSERT(a.size() == b.size());
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i)
        s += a[i] * b[i];
    return s;
}

/// exp of a log prediction, kept finite (a model evaluated far outside its data must not
/// return Inf to the planner).
double expClamped(double logValue) {
    return std::exp(std::clamp(logValue, -20.0, 20.0));
}

}  // namespace

double predictCost(const CandidateModel& model, const SceneFeatures& f) {
    return expClamped(dot(model.cost, costTerms(f)));
}

double predictError(const CandidateModel& model, const SceneFeatures& f) {
    return expClamped(dot(model.error, errorTerms(f)));
}

// ---------------------------------------------------------------------------------------------
// Fitting
// ---------------------------------------------------------------------------------------------

namespace {

/// Solves A x = b (n × n, row-major) by Gaussian elimination with partial pivoting; A is
/// symmetric positive definite here (ridge normal equations), so the pivots stay away from 0.
std::vector<double> solve(std::vector<double> a, std::vector<double> b) {
    const size_t n = b.size();
    for (size_t col = 0; col < n; ++col) {
        size_t pivot = col;
        for (size_t r = col + 1; r < n; ++r)
            if (std::abs(a[r * n + col]) > std::abs(a[pivot * n + col]))
                pivot = r;
        LUCENT_CHECK(std::abs(a[pivot * n + col]) > 1e-300, "model fit: singular system");
        if (pivot != col) {
            for (size_t c = 0; c < n; ++c)
                std::swap(a[col * n + c], a[pivot * n + c]);
            std::swap(b[col], b[pivot]);
        }
        for (size_t r = col + 1; r < n; ++r) {
            const double m = a[r * n + col] / a[col * n + col];
            for (size_t c = col; c < n; ++c)
                a[r * n + c] -= m * a[col * n + c];
            b[r] -= m * b[col];
        }
    }
    std::vector<double> x(n);
    for (size_t i = n; i-- > 0;) {
        double s = b[i];
        for (size_t c = i + 1; c < n; ++c)
            s -= a[i * n + c] * x[c];
        x[i] = s / a[i * n + i];
    }
    return x;
}

/// Ridge least squares: minimises (1/m) Σ (x_i·c − y_i)² + λ Σ_{k ≥ 1} c_k² (term 0, the
/// intercept, is not penalised, so a model without scene dependence is the mean log).
std::vector<double> ridgeFit(const std::vector<std::vector<double>>& x,
                             const std::vector<double>& y, double lambda) {
    const size_t n = x.front().size();
    const double m = double(x.size());
    std::vector<double> ata(n * n, 0.0), aty(n, 0.0);
    for (size_t i = 0; i < x.size(); ++i)
        for (size_t r = 0; r < n; ++r) {
            aty[r] += x[i][r] * y[i] / m;
            for (size_t c = 0; c < n; ++c)
                ata[r * n + c] += x[i][r] * x[i][c] / m;
        }
    for (size_t k = 1; k < n; ++k)
        ata[k * n + k] += lambda;
    // A tiny diagonal on the intercept keeps the system regular for a single distinct row.
    ata[0] += 1e-12;
    return solve(std::move(ata), std::move(aty));
}

/// Leave-one-out RMS of the log residual (each row predicted by a fit without it).
double leaveOneOutRms(const std::vector<std::vector<double>>& x, const std::vector<double>& y,
                      double lambda) {
    double sum = 0;
    for (size_t out = 0; out < x.size(); ++out) {
        std::vector<std::vector<double>> xs;
        std::vector<double> ys;
        for (size_t i = 0; i < x.size(); ++i)
            if (i != out) {
                xs.push_back(x[i]);
                ys.push_back(y[i]);
            }
        const double r = dot(ridgeFit(xs, ys, lambda), x[out]) - y[out];
        sum += r * r;
    }
    return std::sqrt(sum / double(x.size()));
}

}  // namespace

Models fitModels(const std::vector<MeasuredRow>& rows, double ridge) {
    LUCENT_CHECK(std::isfinite(ridge) && ridge >= 0, "model fit: ridge must be finite and >= 0");
    // Group by candidate, keeping the order in which candidates first appear.
    std::vector<std::pair<std::string, std::string>> order;
    std::map<std::pair<std::string, std::string>, std::vector<const MeasuredRow*>> groups;
    for (const MeasuredRow& r : rows) {
        if (!(r.costRatio > 0) || !std::isfinite(r.costRatio) || !(r.blockRelL1 >= 0) ||
            !std::isfinite(r.blockRelL1))
            continue;
        const auto key = std::make_pair(r.method, r.setting);
        if (!groups.count(key))
            order.push_back(key);
        groups[key].push_back(&r);
    }
    Models models;
    models.ridge = ridge;
    for (const auto& key : order) {
        const std::vector<const MeasuredRow*>& g = groups[key];
        std::set<std::string> cases;
        for (const MeasuredRow* r : g)
            cases.insert(r->caseName);
        if (cases.size() < 2)
            continue;
        std::vector<std::vector<double>> xc, xe;
        std::vector<double> yc, ye;
        for (const MeasuredRow* r : g) {
            xc.push_back(costTerms(r->features));
            yc.push_back(logOf(r->costRatio, MIN_COST));
            xe.push_back(errorTerms(r->features));
            ye.push_back(logOf(r->blockRelL1, MIN_ERROR));
        }
        CandidateModel m;
        m.method = key.first;
        m.setting = key.second;
        m.cases = int(cases.size());
        m.cost = ridgeFit(xc, yc, ridge);
        m.error = ridgeFit(xe, ye, ridge);
        m.costLogRms = leaveOneOutRms(xc, yc, ridge);
        m.errorLogRms = leaveOneOutRms(xe, ye, ridge);
        models.candidates.push_back(std::move(m));
    }
    if (models.candidates.empty())
        LUCENT_THROW(ValueError,
                     "model fit: no candidate was measured on at least 2 cases with a positive, "
                     "finite cost ratio and error");
    return models;
}

// ---------------------------------------------------------------------------------------------
// Evaluation CSV
// ---------------------------------------------------------------------------------------------

namespace {

/// Splits one CSV line (RFC 4180 quoting: "a, b" and "" inside quotes).
std::vector<std::string> splitCsv(const std::string& line) {
    std::vector<std::string> out;
    std::string field;
    bool quoted = false;
    for (size_t i = 0; i < line.size(); ++i) {
        const char c = line[i];
        if (quoted) {
            if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
                field += '"';
                ++i;
            } else if (c == '"') {
                quoted = false;
            } else {
                field += c;
            }
        } else if (c == '"') {
            quoted = true;
        } else if (c == ',') {
            out.push_back(field);
            field.clear();
        } else if (c != '\r') {
            field += c;
        }
    }
    out.push_back(field);
    return out;
}

/// "pixelsCovered" → "pixels_covered".
std::string snakeCase(const std::string& camel) {
    std::string s;
    for (char c : camel) {
        if (c >= 'A' && c <= 'Z') {
            s += '_';
            s += char(c - 'A' + 'a');
        } else {
            s += c;
        }
    }
    return s;
}

/// The SceneFeatures fields read from an evaluation CSV.
struct FeatureColumn {
    const char* name;  ///< camelCase, as in SceneFeatures
    double SceneFeatures::*field;
};
constexpr FeatureColumn FEATURE_COLUMNS[] = {
    {"sizeMm", &SceneFeatures::sizeMm},
    {"meanSigmaT", &SceneFeatures::meanSigmaT},
    {"meanFreePathMm", &SceneFeatures::meanFreePathMm},
    {"opticalSize", &SceneFeatures::opticalSize},
    {"albedo", &SceneFeatures::albedo},
    {"diffusionLengthMm", &SceneFeatures::diffusionLengthMm},
    {"sigmaTVariation", &SceneFeatures::sigmaTVariation},
    {"albedoVariation", &SceneFeatures::albedoVariation},
    {"meanAbsG", &SceneFeatures::meanAbsG},
    {"eta", &SceneFeatures::eta},
    {"maxDepthMm", &SceneFeatures::maxDepthMm},
    {"thinFraction", &SceneFeatures::thinFraction},
    {"backLitFraction", &SceneFeatures::backLitFraction},
    {"curvature", &SceneFeatures::curvature},
    {"pixelsCovered", &SceneFeatures::pixelsCovered},
    {"imagePixels", &SceneFeatures::imagePixels},
};

/// The features the models' terms read: a CSV without them cannot be fitted.
bool requiredFeature(const std::string& camel) {
    static const std::set<std::string> required = {
        "opticalSize", "albedo",          "sigmaTVariation", "albedoVariation", "meanAbsG",
        "eta",         "backLitFraction", "curvature",       "thinFraction",    "pixelsCovered"};
    return required.count(camel) > 0;
}

double parseNumber(const std::string& text, const std::string& column, const std::string& where) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size())
        LUCENT_THROW(ValueError, where, ": column ", column, ": '", text, "' is not a number");
    return v;
}

}  // namespace

std::vector<MeasuredRow> readMeasurements(const std::string& csvPath, CostMeasure cost) {
    const std::string text = readInputFile(csvPath, "evaluation CSV");
    std::istringstream in(text);
    std::string line;
    if (!std::getline(in, line))
        LUCENT_THROW(ValueError, csvPath, ": empty file (expected a header row)");
    const std::vector<std::string> header = splitCsv(line);
    auto column = [&](std::initializer_list<const char*> names) -> int {
        for (const char* n : names)
            for (size_t i = 0; i < header.size(); ++i)
                if (header[i] == n)
                    return int(i);
        return -1;
    };
    auto require = [&](std::initializer_list<const char*> names) {
        const int c = column(names);
        if (c < 0)
            LUCENT_THROW(ValueError, csvPath, ": no column '", *names.begin(),
                         "' in the header (an evaluation CSV of `lucent-cli evaluate --suite`)");
        return c;
    };
    const int caseCol = require({"case", "scene"});
    const int methodCol = require({"method"});
    const int settingCol = require({"setting"});
    const int errorCol = require({"block_rel_l1"});
    const bool cpu = cost == CostMeasure::CpuTime;
    const char* costName = cpu ? "cpu_cost_ratio" : "cost_ratio";
    const int costCol = column({costName});
    const int timeCol = cpu ? column({"cpu_ms"}) : column({"time_ms", "ms_median"});
    const int directCol = cpu ? column({"direct_cpu_ms"}) : column({"direct_ms"});
    if (costCol < 0 && (timeCol < 0 || directCol < 0))
        LUCENT_THROW(ValueError, csvPath, ": no column '", costName, "' (nor ",
                     cpu ? "'cpu_ms' with 'direct_cpu_ms'" : "'time_ms' with 'direct_ms'",
                     ") in the header");
    std::vector<std::pair<int, double SceneFeatures::*>> features;
    for (const FeatureColumn& fc : FEATURE_COLUMNS) {
        const std::string snake = snakeCase(fc.name);
        const std::string prefixed = "feature_" + snake;
        const int c = column({fc.name, snake.c_str(), prefixed.c_str()});
        if (c < 0 && requiredFeature(fc.name))
            LUCENT_THROW(ValueError, csvPath, ": no scene-feature column '", snake,
                         "' (the models need the SceneFeatures of each case)");
        if (c >= 0)
            features.emplace_back(c, fc.field);
    }
    const int lightsCol = column({"lights", "feature_lights"});
    const int floorCol = column({"noise_floor", "block_rel_l1_floor"});
    const int toFinerCol = column({"block_rel_l1_to_finer"});

    std::vector<MeasuredRow> rows;
    int lineNo = 1;
    while (std::getline(in, line)) {
        ++lineNo;
        if (line.empty() || line == "\r")
            continue;
        const std::vector<std::string> f = splitCsv(line);
        const std::string where = csvPath + ":" + std::to_string(lineNo);
        if (f.size() != header.size())
            LUCENT_THROW(ValueError, where, ": ", f.size(), " fields, the header has ",
                         header.size());
        MeasuredRow r;
        r.caseName = f[size_t(caseCol)];
        r.method = f[size_t(methodCol)];
        r.setting = f[size_t(settingCol)];
        r.blockRelL1 = parseNumber(f[size_t(errorCol)], "block_rel_l1", where);
        if (directCol >= 0 && !f[size_t(directCol)].empty())
            r.directUnitMs = parseNumber(f[size_t(directCol)], header[size_t(directCol)], where);
        if (costCol >= 0) {
            r.costRatio = parseNumber(f[size_t(costCol)], costName, where);
        } else {
            const double direct = parseNumber(f[size_t(directCol)], "direct_ms", where);
            r.costRatio =
                direct > 0 ? parseNumber(f[size_t(timeCol)], "time_ms", where) / direct : 0.0;
        }
        for (const auto& [c, field] : features)
            r.features.*field = parseNumber(f[size_t(c)], header[size_t(c)], where);
        if (floorCol >= 0)
            r.noiseFloor = parseNumber(f[size_t(floorCol)], header[size_t(floorCol)], where);
        if (toFinerCol >= 0 && !f[size_t(toFinerCol)].empty())
            r.blockRelL1ToFiner =
                parseNumber(f[size_t(toFinerCol)], "block_rel_l1_to_finer", where);
        if (lightsCol >= 0)
            r.features.lights = int(parseNumber(f[size_t(lightsCol)], "lights", where));
        rows.push_back(std::move(r));
    }
    return rows;
}

std::vector<std::string> costUnitWarnings(const std::vector<MeasuredRow>& rows, double limit) {
    std::map<std::string, std::vector<const MeasuredRow*>> byCase;
    for (const MeasuredRow& r : rows)
        if (r.directUnitMs > 0.0 && std::isfinite(r.directUnitMs))
            byCase[r.caseName].push_back(&r);
    std::vector<std::string> warnings;
    for (const auto& [caseName, caseRows] : byCase) {
        std::vector<double> units;
        for (const MeasuredRow* r : caseRows)
            units.push_back(r->directUnitMs);
        std::nth_element(units.begin(), units.begin() + long(units.size() / 2), units.end());
        const double median = units[units.size() / 2];
        std::map<std::string, double> offByMethod;  // the method's unit furthest from the median
        for (const MeasuredRow* r : caseRows) {
            const double off = r->directUnitMs;
            if (std::max(off, median) <= limit * std::min(off, median))
                continue;
            double& worst = offByMethod[r->method];
            if (worst == 0.0 ||
                std::abs(std::log(off / median)) > std::abs(std::log(worst / median)))
                worst = off;
        }
        for (const auto& [method, unit] : offByMethod) {
            char buf[320];
            std::snprintf(buf, sizeof buf,
                          "%s: %s's cost ratios were taken against a Direct render of %.1f ms "
                          "where the case's median unit is %.1f ms (%.1fx apart): not "
                          "comparable with the other methods' (re-measure them in one run)",
                          caseName.c_str(), method.c_str(), unit, median,
                          unit > median ? unit / median : median / unit);
            warnings.emplace_back(buf);
        }
    }
    return warnings;
}

// ---------------------------------------------------------------------------------------------
// Models file
// ---------------------------------------------------------------------------------------------

namespace {
constexpr const char* FORMAT = "lucent-planner-models";

std::vector<double> coefficients(const nlohmann::json& j, const char* key,
                                 const std::vector<std::string>& terms, const std::string& where) {
    if (!j.contains(key) || !j[key].is_array())
        LUCENT_THROW(ValueError, where, ": '", key, "' must be an array of numbers");
    std::vector<double> c;
    for (const nlohmann::json& v : j[key]) {
        if (!v.is_number() || !std::isfinite(v.get<double>()))
            LUCENT_THROW(ValueError, where, ": '", key,
                         "' holds a value that is not a finite number");
        c.push_back(v.get<double>());
    }
    if (c.size() != terms.size())
        LUCENT_THROW(ValueError, where, ": '", key, "' has ", c.size(),
                     " coefficients, the terms are ", terms.size());
    return c;
}

}  // namespace

Models parseModels(const std::string& text, const std::string& origin) {
    const nlohmann::json j =
        detail::parseVersionedJson(text, origin, FORMAT, "planner models", Models::VERSION,
                                   " (refit them: docs/planner.md, \"Models\")");
    try {
        if (j.value("cost_terms", std::vector<std::string>{}) != costTermNames() ||
            j.value("error_terms", std::vector<std::string>{}) != errorTermNames())
            LUCENT_THROW(
                ValueError, origin,
                ": the model terms differ from this build's (refit them: docs/planner.md)");
        Models m;
        m.source = j.value("source", "");
        m.ridge = j.value("ridge", 0.0);
        if (!j.contains("candidates") || !j["candidates"].is_array() || j["candidates"].empty())
            LUCENT_THROW(ValueError, origin, ": 'candidates' must be a non-empty array");
        for (const nlohmann::json& c : j["candidates"]) {
            CandidateModel cm;
            cm.method = c.value("method", "");
            cm.setting = c.value("setting", "");
            const std::string where = origin + ": candidate '" + cm.method + " " + cm.setting + "'";
            if (cm.method.empty())
                LUCENT_THROW(ValueError, origin, ": a candidate without a 'method'");
            cm.cost = coefficients(c, "cost", costTermNames(), where);
            cm.error = coefficients(c, "error", errorTermNames(), where);
            cm.cases = c.value("cases", 0);
            cm.costLogRms = c.value("cost_log_rms", 0.0);
            cm.errorLogRms = c.value("error_log_rms", 0.0);
            m.candidates.push_back(std::move(cm));
        }
        return m;
    } catch (const nlohmann::json::exception& e) {
        LUCENT_THROW(ValueError, origin, ": malformed models file (", e.what(), ")");
    }
}

Models loadModels(const std::string& path) {
    return parseModels(readInputFile(path, "planner models"), path);
}

std::string formatModels(const Models& models) {
    nlohmann::ordered_json j;
    j["format"] = FORMAT;
    j["version"] = Models::VERSION;
    j["source"] = models.source;
    j["ridge"] = std::round(models.ridge * 1e6) / 1e6;
    j["cost_terms"] = costTermNames();
    j["error_terms"] = errorTermNames();
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    auto rounded = [](const std::vector<double>& v) {
        std::vector<double> r;
        for (double x : v)
            r.push_back(std::round(x * 1e6) / 1e6);  // 6 decimals: far below the fit's noise
        return r;
    };
    for (const CandidateModel& c : models.candidates) {
        nlohmann::ordered_json o;
        o["method"] = c.method;
        o["setting"] = c.setting;
        o["cases"] = c.cases;
        o["cost_log_rms"] = std::round(c.costLogRms * 1e4) / 1e4;
        o["error_log_rms"] = std::round(c.errorLogRms * 1e4) / 1e4;
        o["cost"] = rounded(c.cost);
        o["error"] = rounded(c.error);
        list.push_back(std::move(o));
    }
    j["candidates"] = std::move(list);
    return j.dump(1) + "\n";
}

void saveModels(const Models& models, const std::string& path) {
    writeFileAtomically(path, formatModels(models));
}

const Models& defaultModels() {
    static const Models models =
        parseModels(detail::PLANNER_MODELS_JSON, "resources/planner/models.json (embedded)");
    return models;
}

namespace {
/// The cases of `rows`, in first-seen order.
std::vector<std::string> caseNames(const std::vector<MeasuredRow>& rows) {
    std::vector<std::string> cases;
    for (const MeasuredRow& r : rows)
        if (std::find(cases.begin(), cases.end(), r.caseName) == cases.end())
            cases.push_back(r.caseName);
    return cases;
}

/// The row of `rows` that scores the same candidate on the same case as `of` with a finite error
/// (another reference's score of the same render), or nullptr.
const MeasuredRow* sameCandidate(const std::vector<MeasuredRow>& rows, const MeasuredRow& of) {
    const auto row = std::find_if(rows.begin(), rows.end(), [&](const MeasuredRow& r) {
        return r.caseName == of.caseName && r.method == of.method && r.setting == of.setting &&
               std::isfinite(r.blockRelL1);
    });
    return row == rows.end() ? nullptr : &*row;
}
}  // namespace

std::vector<FrontCheck> checkAgainstFront(const std::vector<MeasuredRow>& rows,
                                          const Models& models, double budgetRatio,
                                          double errorTolerance, LevelTolerance levelTolerance,
                                          bool measuredErrors,
                                          const std::vector<MeasuredRow>* plannedErrors) {
    LUCENT_CHECK(budgetRatio > 0, "front check: the budget must be > 0 times the Direct frame");
    LUCENT_CHECK(std::isfinite(levelTolerance.absolute) && levelTolerance.absolute >= 0 &&
                     std::isfinite(levelTolerance.relative) && levelTolerance.relative >= 0,
                 "front check: the level tolerances must be finite and >= 0");
    const std::vector<std::string> cases = caseNames(rows);
    auto label = [](const std::string& method, const std::string& setting) {
        return method + " " + setting;
    };
    const std::vector<Candidate> all = toCandidates(models);
    std::vector<FrontCheck> out;
    for (const std::string& name : cases) {
        // The case's measured candidates that have a model, in the models' order.
        std::vector<const MeasuredRow*> measured;
        std::vector<Candidate> candidates;
        for (size_t i = 0; i < models.candidates.size(); ++i) {
            const CandidateModel& m = models.candidates[i];
            const auto row = std::find_if(rows.begin(), rows.end(), [&](const MeasuredRow& r) {
                return r.caseName == name && r.method == m.method && r.setting == m.setting &&
                       r.costRatio > 0 && std::isfinite(r.costRatio) && std::isfinite(r.blockRelL1);
            });
            if (row == rows.end())
                continue;
            measured.push_back(&*row);
            candidates.push_back(all[i]);
        }
        if (measured.empty())
            continue;
        // With measured errors: the rows Auto plans by, one per measured candidate.
        std::vector<const MeasuredRow*> planning = measured;
        if (measuredErrors && plannedErrors)
            for (const MeasuredRow*& p : planning) {
                const MeasuredRow* row = sameCandidate(*plannedErrors, *p);
                if (!row)
                    LUCENT_THROW(ValueError, "front check: the planning errors have no row for ",
                                 p->caseName, ": ", p->method, " ", p->setting);
                p = row;
            }
        if (measuredErrors)  // the scene's own errors, as measuredModels(…, ErrorsOnly) gives
            for (size_t k = 0; k < planning.size(); ++k) {
                const double e = std::max(planning[k]->blockRelL1, 1e-6);
                candidates[k].error = [e](const SceneFeatures&) { return e; };
            }
        Budget budget;
        budget.directMs = 1.0;
        budget.frameMs = budgetRatio;
        budget.errorTolerance = errorTolerance;
        if (measuredErrors)  // what the planning reference can tell apart (chooseByMeasuring)
            for (const MeasuredRow* r : planning)
                budget.errorMargin = std::max(budget.errorMargin, r->noiseFloor);
        const Plan p = plan(candidates, measured.front()->features, budget);
        const MeasuredRow* pick = measured[p.choice];
        FrontCheck c;
        // The level check on the case's measured differences between adjacent levels.
        if (!levelTolerance.off() && !measuredErrors) {
            const std::vector<std::string> levels = modelLevels(models, pick->method);
            const auto row = [&](const std::string& setting) -> const MeasuredRow* {
                for (const MeasuredRow* r : measured)
                    if (r->method == pick->method && r->setting == setting)
                        return r;
                return nullptr;
            };
            const auto at = std::find(levels.begin(), levels.end(), pick->setting);
            if (at != levels.end()) {
                const size_t kept = coarsestEquivalentLevel(
                    levels, size_t(at - levels.begin()),
                    [&](size_t i) {
                        const MeasuredRow* r = row(levels[i]);
                        return r && row(levels[i + 1]) ? r->blockRelL1ToFiner : -1.0;
                    },
                    levelTolerance.at(p.chosen.error));
                if (levels[kept] != pick->setting) {
                    c.planned = label(pick->method, pick->setting);
                    pick = row(levels[kept]);
                }
            }
        }
        const MeasuredRow& chosen = *pick;
        c.caseName = name;
        c.chosen = label(chosen.method, chosen.setting);
        c.chosenCost = chosen.costRatio;
        c.chosenError = chosen.blockRelL1;
        const MeasuredRow* cheapest = &chosen;
        for (const MeasuredRow* r : measured)
            if (r->blockRelL1 <= chosen.blockRelL1 + std::max(r->noiseFloor, chosen.noiseFloor) &&
                r->costRatio < cheapest->costRatio)
                cheapest = r;
        c.cheapestAtError = label(cheapest->method, cheapest->setting);
        c.cheapestCost = cheapest->costRatio;
        c.timeRatio = chosen.costRatio / cheapest->costRatio;
        const MeasuredRow* best = nullptr;
        for (const MeasuredRow* r : measured) {
            const bool fits = r->costRatio <= budgetRatio;
            if (!best) {
                best = r;
                continue;
            }
            const bool bestFits = best->costRatio <= budgetRatio;
            if (fits != bestFits
                    ? fits
                    : (fits ? r->blockRelL1 < best->blockRelL1 : r->costRatio < best->costRatio))
                best = r;
        }
        c.bestInBudget = label(best->method, best->setting);
        c.bestError = best->blockRelL1;
        // Errors closer than the reference noise floor are the same point as far as the
        // measurement can tell.
        c.choseBest =
            best == &chosen ||
            ((chosen.costRatio <= budgetRatio) == (best->costRatio <= budgetRatio) &&
             chosen.blockRelL1 <= best->blockRelL1 + std::max(chosen.noiseFloor, best->noiseFloor));
        out.push_back(std::move(c));
    }
    return out;
}

std::vector<MeasuredRow> previewRows(std::vector<MeasuredRow> rows) {
    std::erase_if(rows, [](const MeasuredRow& r) {
        return r.method == "reference" || r.method.rfind("reference:", 0) == 0 ||
               r.method == "direct";
    });
    return rows;
}

std::vector<FrontCheck> crossValidatedCheck(const std::vector<MeasuredRow>& rows, double ridge,
                                            double budgetRatio, double errorTolerance,
                                            LevelTolerance levelTolerance, bool measuredErrors,
                                            const std::vector<MeasuredRow>* plannedErrors) {
    const std::vector<std::string> cases = caseNames(rows);
    if (cases.size() < 2)
        LUCENT_THROW(ValueError, "cross-validated check: ", cases.size(),
                     " case(s); leaving one out needs at least 2");
    std::vector<FrontCheck> out;
    for (const std::string& name : cases) {
        std::vector<MeasuredRow> train, test;
        for (const MeasuredRow& r : rows)
            (r.caseName == name ? test : train).push_back(r);
        Models models;
        try {
            models = fitModels(previewRows(std::move(train)), ridge);
        } catch (const ValueError&) {
            continue;  // nothing to fit without this case
        }
        std::vector<FrontCheck> c =
            checkAgainstFront(test, models, budgetRatio, errorTolerance, levelTolerance,
                              measuredErrors, plannedErrors);
        out.insert(out.end(), c.begin(), c.end());
    }
    return out;
}

std::vector<MeasuredRow> withErrorsOf(std::vector<MeasuredRow> rows,
                                      const std::vector<MeasuredRow>& errors) {
    for (MeasuredRow& r : rows) {
        const MeasuredRow* e = sameCandidate(errors, r);
        if (!e)
            LUCENT_THROW(ValueError, "the other reference's errors have no row for ", r.caseName,
                         ": ", r.method, " ", r.setting);
        r.blockRelL1 = e->blockRelL1;
        r.noiseFloor = e->noiseFloor;
    }
    return rows;
}

std::vector<Candidate> toCandidates(const Models& models) {
    std::vector<Candidate> out;
    for (const CandidateModel& m : models.candidates) {
        Candidate c;
        c.method = m.method;
        c.setting = m.setting;
        c.costRatio = [m](const SceneFeatures& f) { return predictCost(m, f); };
        c.error = [m](const SceneFeatures& f) { return predictError(m, f); };
        out.push_back(std::move(c));
    }
    return out;
}

}  // namespace lucent::planner
