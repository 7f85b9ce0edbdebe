// SPDX-License-Identifier: MIT
/// @file
/// @brief The evaluation's output files (Report.h).

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/evaluation/Report.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <sstream>

namespace lucent::evaluation {

namespace {

namespace fs = std::filesystem;

std::string fmt(double v, const char* f = "%.6g") {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

std::string jsonEscape(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '"' || c == '\\')
            out += '\\';
        if (uint8_t(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", unsigned(c));
            out += buf;
            continue;
        }
        out += c;
    }
    return out;
}

/// CSV field: quoted when it holds a comma or a quote.
std::string csvField(const std::string& s) {
    if (s.find_first_of(",\"") == std::string::npos)
        return s;
    std::string out = "\"";
    for (char c : s)
        out += c == '"' ? std::string("\"\"") : std::string(1, c);
    return out + "\"";
}

/// The scene features' columns, in SceneFeatures' field order.
struct FeatureColumn {
    const char* name;
    double planner::SceneFeatures::*real = nullptr;
    int planner::SceneFeatures::*integer = nullptr;
};
const std::vector<FeatureColumn>& featureColumns() {
    using F = planner::SceneFeatures;
    static const std::vector<FeatureColumn> columns = {
        {"size_mm", &F::sizeMm},
        {"mean_sigma_t", &F::meanSigmaT},
        {"mean_free_path_mm", &F::meanFreePathMm},
        {"optical_size", &F::opticalSize},
        {"albedo", &F::albedo},
        {"diffusion_length_mm", &F::diffusionLengthMm},
        {"sigma_t_variation", &F::sigmaTVariation},
        {"albedo_variation", &F::albedoVariation},
        {"mean_abs_g", &F::meanAbsG},
        {"eta", &F::eta},
        {"max_depth_mm", &F::maxDepthMm},
        {"thin_fraction", &F::thinFraction},
        {"back_lit_fraction", &F::backLitFraction},
        {"curvature", &F::curvature},
        {"pixels_covered", &F::pixelsCovered},
        {"inside_voxels", nullptr, &F::insideVoxels},
        {"lights", nullptr, &F::lights}};
    return columns;
}

/// Every column of a result but the features: (name, text, is-a-string).
struct Field {
    std::string name;
    std::string text;
    bool isString = false;
};

std::vector<Field> fields(const Result& r) {
    const Metrics& m = r.metrics;
    const bench::BlockError& lum = m.report.blocks[Metrics::LUM];
    std::vector<Field> f = {
        {"case", r.caseName, true},
        {"group", r.group, true},
        {"method", r.variant, true},
        {"setting", r.setting, true},
        {"quality", std::to_string(r.quality)},
        {"backend", r.backend, true},
        {"time_ms", fmt(r.msMedian)},
        {"time_min_ms", fmt(r.msMin)},
        {"runs", std::to_string(r.runs)},
        {"direct_ms", fmt(r.directMs)},
        {"cost_ratio", fmt(r.costRatio)},
        {"cpu_ms", fmt(r.cpuMsMedian)},
        {"direct_cpu_ms", fmt(r.directCpuMs)},
        {"cpu_cost_ratio", fmt(r.cpuCostRatio)},
        {"block_rel_l1", fmt(m.blockRelL1())},
        {"block_rel_l1_raw", fmt(lum.relL1)},
        {"block_rel_rmse", fmt(m.blockRelRmse())},
        {"block_rel_rmse_raw", fmt(lum.relRmse)},
        {"mean_ratio", fmt(m.meanRatio())},
        {"p95", fmt(m.p95())},
        {"noise_floor", fmt(lum.relL1Floor)},
        {"noise_floor_rmse", fmt(lum.relRmseFloor)},
        // Empty for the finest setting (nothing finer to compare with).
        {"block_rel_l1_to_finer", r.blockRelL1ToFiner >= 0 ? fmt(r.blockRelL1ToFiner) : ""},
        {"pixel_rel_rmse", fmt(m.report.channels[Metrics::LUM].relRmse)},
        {"pixel_rel_rmse_floor", fmt(m.report.channels[Metrics::LUM].relRmseFloor)},
    };
    const char* rgb[] = {"r", "g", "b"};
    for (int c = 0; c < 3; ++c)
        f.push_back({std::string("block_rel_l1_") + rgb[c], fmt(m.blockRelL1(c))});
    for (int c = 0; c < 3; ++c)
        f.push_back({std::string("block_rel_rmse_") + rgb[c], fmt(m.blockRelRmse(c))});
    for (int c = 0; c < 3; ++c)
        f.push_back({std::string("mean_ratio_") + rgb[c], fmt(m.meanRatio(c))});
    f.push_back({"pixels", std::to_string(m.report.pixelCount)});
    f.push_back({"meets_goal", m.meetsGoal() ? "1" : "0"});
    for (const FeatureColumn& c : featureColumns()) {
        std::string text;
        if (r.features)
            text = c.real ? fmt((*r.features).*c.real) : std::to_string((*r.features).*c.integer);
        f.push_back({std::string("feature_") + c.name, text});
    }
    return f;
}

/// Results grouped by case, in first-seen order.
std::vector<std::vector<const Result*>> byCase(const std::vector<Result>& results) {
    std::vector<std::vector<const Result*>> out;
    std::map<std::string, size_t> index;
    for (const Result& r : results) {
        const auto [it, inserted] = index.emplace(r.caseName, out.size());
        if (inserted)
            out.emplace_back();
        out[it->second].push_back(&r);
    }
    return out;
}

std::string label(const Result& r) {
    return r.setting == "-" ? r.variant : r.variant + " (" + r.setting + ")";
}

/// gnuplot data of one chart: one block per method (two blank lines apart, `index i`), rows
/// "cost_ratio block_rel_l1 time_ms" in quality order.
std::string chartData(const std::vector<const Result*>& results,
                      const std::vector<std::string>& methods) {
    std::string s;
    for (const std::string& m : methods) {
        s += "# " + m + "\n";
        std::vector<const Result*> mine;
        for (const Result* r : results)
            if (r->variant == m)
                mine.push_back(r);
        std::sort(mine.begin(), mine.end(), [](const Result* a, const Result* b) {
            return a->caseName != b->caseName ? a->caseName < b->caseName : a->quality < b->quality;
        });
        std::string lastCase;
        for (const Result* r : mine) {
            if (!lastCase.empty() && r->caseName != lastCase)
                s += "\n";  // a blank line breaks the line between cases
            lastCase = r->caseName;
            s += fmt(std::max(r->cpuCostRatio, 1e-3)) + " " +
                 fmt(std::max(r->metrics.blockRelL1(), 1e-4)) + " " + fmt(r->msMedian) + "\n";
        }
        s += "\n\n";
    }
    return s;
}

/// The methods among `results`, in first-seen order (one gnuplot index each).
std::vector<std::string> methodNames(const std::vector<const Result*>& results) {
    std::vector<std::string> names;
    for (const Result* r : results)
        if (std::find(names.begin(), names.end(), r->variant) == names.end())
            names.push_back(r->variant);
    return names;
}

std::vector<const Result*> pointers(const std::vector<Result>& results) {
    std::vector<const Result*> all;
    for (const Result& r : results)
        all.push_back(&r);
    return all;
}

}  // namespace

std::string csvHeader() {
    std::string s;
    for (const Field& f : fields(Result{})) {
        if (!s.empty())
            s += ',';
        s += f.name;
    }
    return s + "\n";
}

std::string toCsv(const std::vector<Result>& results) {
    std::string s = csvHeader();
    for (const Result& r : results) {
        std::string row;
        for (const Field& f : fields(r)) {
            if (!row.empty())
                row += ',';
            row += csvField(f.text);
        }
        s += row + "\n";
    }
    return s;
}

std::string toJson(const std::vector<Result>& results, const RunInfo& info) {
    std::ostringstream s;
    s << "{\n  \"suite\": \"" << jsonEscape(info.suite) << "\",\n  \"command\": \""
      << jsonEscape(info.command) << "\",\n  \"width\": " << info.width
      << ",\n  \"height\": " << info.height << ",\n  \"ref_spp\": " << info.refSpp
      << ",\n  \"ref_seed\": " << info.refSeed << ",\n  \"ref_floor\": " << fmt(info.refFloor)
      << ",\n  \"ref_max_spp\": " << info.refMaxSpp << ",\n  \"repeats\": " << info.repeats
      << ",\n  \"subsurface_only\": " << (info.subsurfaceOnly ? "true" : "false")
      << ",\n  \"metric\": \"4x4-block relative L1 of luminance over object-covered pixels, "
         "reference noise floor removed in quadrature\",\n"
      << "  \"goal\": {\"block_rel_l1\": " << GOAL_BLOCK_REL_L1
      << ", \"mean_ratio_tolerance\": " << GOAL_MEAN_RATIO_TOLERANCE << "},\n  \"cases\": [";
    for (size_t i = 0; i < info.cases.size(); ++i) {
        s << (i ? ", " : "") << "{\"name\": \"" << jsonEscape(info.cases[i]) << "\"";
        if (i < info.noiseFloors.size())
            s << ", \"noise_floor\": " << fmt(info.noiseFloors[i]);
        if (i < info.referenceSeconds.size())
            s << ", \"reference_seconds\": " << fmt(info.referenceSeconds[i]);
        if (i < info.referenceSpp.size())
            s << ", \"reference_spp\": " << info.referenceSpp[i];
        s << "}";
    }
    s << "],\n  \"skipped\": [";
    for (size_t i = 0; i < info.skipped.size(); ++i)
        s << (i ? ", " : "") << "\"" << jsonEscape(info.skipped[i]) << "\"";
    s << "],\n  \"results\": [\n";
    for (size_t i = 0; i < results.size(); ++i) {
        s << "    {";
        bool first = true;
        for (const Field& f : fields(results[i])) {
            if (f.text.empty() && !f.isString)
                continue;  // a feature of a case that could not be analysed
            s << (first ? "" : ", ") << "\"" << f.name << "\": ";
            if (f.isString)
                s << "\"" << jsonEscape(f.text) << "\"";
            else
                s << f.text;
            first = false;
        }
        s << "}" << (i + 1 < results.size() ? "," : "") << "\n";
    }
    s << "  ]\n}\n";
    return s.str();
}

std::string summaryMarkdown(const std::vector<Result>& results) {
    std::string s =
        "| case | best method | block rel. L1 | mean ratio | p95 | noise floor | cost (× "
        "direct, wall / CPU) | goal | cheapest within the goal |\n"
        "|---|---|---:|---:|---:|---:|---:|---|---|\n";
    for (const std::vector<const Result*>& rs : byCase(results)) {
        // The best method meets the goal if any does (the lowest block error among those):
        // a lower block error with its mean ratio outside 1 ± 0.05 is not the better answer.
        const Result* best = *std::min_element(rs.begin(), rs.end(), [](auto* a, auto* b) {
            const bool ma = a->metrics.meetsGoal(), mb = b->metrics.meetsGoal();
            if (ma != mb)
                return ma;
            const double ea = a->metrics.blockRelL1(), eb = b->metrics.blockRelL1();
            return ea != eb ? ea < eb : a->cpuCostRatio < b->cpuCostRatio;
        });
        const Result* cheapest = nullptr;
        for (const Result* r : rs)
            if (r->metrics.meetsGoal() && (!cheapest || r->cpuCostRatio < cheapest->cpuCostRatio))
                cheapest = r;
        s += "| " + best->caseName + " | " + label(*best) + " | " +
             fmt(best->metrics.blockRelL1(), "%.3f") + " | " +
             fmt(best->metrics.meanRatio(), "%.3f") + " | " + fmt(best->metrics.p95(), "%.2f") +
             " | " + fmt(best->noiseFloor, "%.3f") + " | " + fmt(best->costRatio, "%.1f") + " / " +
             fmt(best->cpuCostRatio, "%.1f") + " | " +
             (best->metrics.meetsGoal() ? "met" : "**missed**") + " | " +
             (cheapest ? label(*cheapest) + ", " + fmt(cheapest->cpuCostRatio, "%.1f") + "× CPU"
                       : std::string("none")) +
             " |\n";
    }
    return s;
}

std::string paretoMarkdown(const std::vector<Result>& results) {
    std::string s =
        "| case | method | CPU cost (× direct) | wall cost (× direct) | time (ms) | block rel. L1 "
        "| mean ratio |\n|---|---|---:|---:|---:|---:|---:|\n";
    for (const std::vector<const Result*>& rs : byCase(results)) {
        std::vector<double> cost, error;
        for (const Result* r : rs) {
            cost.push_back(r->cpuCostRatio);
            error.push_back(r->metrics.blockRelL1());
        }
        for (size_t i : paretoFront(cost, error)) {
            const Result& r = *rs[i];
            s += "| " + r.caseName + " | " + label(r) + " | " + fmt(r.cpuCostRatio, "%.2f") +
                 " | " + fmt(r.costRatio, "%.2f") + " | " + fmt(r.msMedian, "%.0f") + " | " +
                 fmt(r.metrics.blockRelL1(), "%.3f") + " | " + fmt(r.metrics.meanRatio(), "%.3f") +
                 " |\n";
        }
    }
    return s;
}

std::string gnuplotScript(const std::vector<Result>& results, const RunInfo& info) {
    std::ostringstream s;
    s << "# Run time vs error of the translucency methods (lucent-cli evaluate).\n"
      << "# Draw with: cd <this folder> && gnuplot charts.gp\n"
      << "# x: cost = process CPU time / the Direct render's of the same frame (log); y: "
         "4x4-block\n"
      << "# relative L1 of luminance against the exact reference, noise floor removed (log).\n"
      << "set terminal pngcairo size 1100,760 font 'sans,11'\n"
      << "set logscale xy\nset grid\nset key outside right top\n"

      << "set xlabel 'cost (process CPU time / Direct render of the same frame)'\n"
      << "set ylabel 'block relative L1 of luminance (noise floor removed)'\n"
      << "goal = " << GOAL_BLOCK_REL_L1 << "\n";
    // One colour and marker per method in every chart: its index among all the methods.
    const std::vector<std::string> allMethods = methodNames(pointers(results));
    const auto plot = [&](const std::string& data, const std::vector<std::string>& methods,
                          const std::vector<const Result*>& points, bool lines) {
        // The y range holds the points and the goal line (at least 0.05 .. 0.2).
        double lo = 0.05, hi = 0.2;
        for (const Result* r : points) {
            lo = std::min(lo, std::max(r->metrics.blockRelL1(), 1e-4));
            hi = std::max(hi, r->metrics.blockRelL1());
        }
        s << "set yrange [" << fmt(lo / 1.2) << ":" << fmt(hi * 1.2) << "]\n";
        s << "plot goal with lines dt 2 lc rgb 'grey40' title 'goal (10 %)'";
        for (size_t i = 0; i < methods.size(); ++i) {
            const size_t k = size_t(std::find(allMethods.begin(), allMethods.end(), methods[i]) -
                                    allMethods.begin());
            s << ", \\\n     '" << data << "' index " << i << " using 1:2 with "
              << (lines ? "linespoints" : "points") << " pt " << (k % 13) + 1 << " lc " << k + 1
              << " title '" << methods[i] << "'";
        }
        s << "\n";
    };
    s << "\nset output 'runtime_vs_error.png'\n"
      << "set title 'run time vs error, all cases (" << info.width << "x" << info.height
      << ", reference " << info.refSpp << " spp)'\n";
    plot("chart_summary.dat", allMethods, pointers(results), false);
    for (const std::vector<const Result*>& rs : byCase(results)) {
        const std::string c = fileSafe(rs.front()->caseName);
        s << "\nset terminal pngcairo size 760,480 font 'sans,9'\n"
          << "set output 'runtime_vs_error_" << c << ".png'\n"
          << "set title 'run time vs error: " << rs.front()->caseName << " (noise floor "
          << fmt(rs.front()->noiseFloor, "%.3f") << ")'\n";
        plot("chart_" + c + ".dat", methodNames(rs), rs, true);
    }
    return s.str();
}

namespace {

/// Writes `text` to dir/name atomically and records the path.
void writeInto(std::vector<std::string>& written, const std::string& dir, const std::string& name,
               const std::string& text) {
    const std::string path = (fs::path(dir) / name).string();
    writeFileAtomically(path, text);
    written.push_back(path);
}

/// The fields of one CSV line (RFC 4180 quoting: "a ""b"", c" is one field).
std::vector<std::string> csvSplit(const std::string& line) {
    std::vector<std::string> out(1);
    bool quoted = false;
    for (size_t i = 0; i < line.size(); ++i) {
        const char c = line[i];
        if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
            out.back() += '"';
            ++i;
        } else if (c == '"') {
            quoted = !quoted;
        } else if (c == ',' && !quoted) {
            out.emplace_back();
        } else if (c != '\r') {
            out.back() += c;
        }
    }
    return out;
}

}  // namespace

std::vector<Result> parseResultsCsv(const std::string& text, const std::string& origin) {
    std::istringstream in(text);
    std::string line;
    if (!std::getline(in, line))
        LUCENT_THROW(IoError, origin, ": empty (expected the header of results.csv)");
    const std::vector<std::string> header = csvSplit(line);
    std::vector<Result> results;
    int lineNo = 1;
    while (std::getline(in, line)) {
        ++lineNo;
        if (line.empty())
            continue;
        const std::vector<std::string> cells = csvSplit(line);
        if (cells.size() != header.size())
            LUCENT_THROW(IoError, origin, ":", lineNo, ": ", cells.size(),
                         " fields, the header has ", header.size());
        const auto text = [&](const std::string& name) -> const std::string& {
            const auto it = std::find(header.begin(), header.end(), name);
            if (it == header.end())
                LUCENT_THROW(IoError, origin, ": no column '", name, "'");
            return cells[size_t(it - header.begin())];
        };
        const auto number = [&](const std::string& name) {
            const std::string& t = text(name);
            char* end = nullptr;
            const double v = std::strtod(t.c_str(), &end);
            if (t.empty() || *end != '\0')
                LUCENT_THROW(IoError, origin, ":", lineNo, ": ", name, " '", t,
                             "' is not a number");
            return v;
        };
        Result r;
        r.caseName = text("case");
        r.group = text("group");
        r.variant = text("method");
        r.setting = text("setting");
        r.quality = int(number("quality"));
        r.backend = text("backend");
        r.msMedian = number("time_ms");
        r.msMin = number("time_min_ms");
        r.runs = int(number("runs"));
        r.directMs = number("direct_ms");
        r.costRatio = number("cost_ratio");
        r.cpuMsMedian = number("cpu_ms");
        r.directCpuMs = number("direct_cpu_ms");
        r.cpuCostRatio = number("cpu_cost_ratio");
        bench::ErrorReport& rep = r.metrics.report;
        bench::BlockError& lum = rep.blocks[Metrics::LUM];
        lum.relL1Net = number("block_rel_l1");
        lum.relL1 = number("block_rel_l1_raw");
        lum.relRmseNet = number("block_rel_rmse");
        lum.relRmse = number("block_rel_rmse_raw");
        rep.channels[Metrics::LUM].meanRatio = number("mean_ratio");
        lum.p95 = number("p95");
        lum.relL1Floor = number("noise_floor");
        lum.relRmseFloor = number("noise_floor_rmse");
        rep.channels[Metrics::LUM].relRmse = number("pixel_rel_rmse");
        rep.channels[Metrics::LUM].relRmseFloor = number("pixel_rel_rmse_floor");
        const char* rgb[] = {"r", "g", "b"};
        for (int c = 0; c < 3; ++c) {
            rep.blocks[c].relL1Net = number(std::string("block_rel_l1_") + rgb[c]);
            rep.blocks[c].relRmseNet = number(std::string("block_rel_rmse_") + rgb[c]);
            rep.channels[c].meanRatio = number(std::string("mean_ratio_") + rgb[c]);
        }
        rep.pixelCount = size_t(number("pixels"));
        r.noiseFloor = lum.relL1Floor;
        // Files written before the level check have no such column.
        if (std::find(header.begin(), header.end(), "block_rel_l1_to_finer") != header.end() &&
            !text("block_rel_l1_to_finer").empty())
            r.blockRelL1ToFiner = number("block_rel_l1_to_finer");
        if (!text("feature_size_mm").empty()) {
            planner::SceneFeatures f;
            for (const FeatureColumn& c : featureColumns()) {
                const double v = number(std::string("feature_") + c.name);
                if (c.real)
                    f.*c.real = v;
                else
                    f.*c.integer = int(v);
            }
            r.features = f;
        }
        results.push_back(std::move(r));
    }
    return results;
}

RunInfo parseRunInfoJson(const std::string& text, const std::string& origin) {
    RunInfo info;
    try {
        const nlohmann::json j = nlohmann::json::parse(text);
        info.suite = j.value("suite", "");
        info.command = j.value("command", "");
        info.width = j.value("width", 0);
        info.height = j.value("height", 0);
        info.refSpp = j.value("ref_spp", 0);
        info.refSeed = j.value("ref_seed", 1);
        info.refFloor = j.value("ref_floor", 0.0);
        info.refMaxSpp = j.value("ref_max_spp", 0);
        info.repeats = j.value("repeats", 0);
        info.subsurfaceOnly = j.value("subsurface_only", false);
        for (const nlohmann::json& c : j.at("cases")) {
            info.cases.push_back(c.at("name").get<std::string>());
            info.noiseFloors.push_back(c.value("noise_floor", 0.0));
            info.referenceSeconds.push_back(c.value("reference_seconds", 0.0));
            info.referenceSpp.push_back(c.value("reference_spp", info.refSpp));
        }
        for (const nlohmann::json& s : j.at("skipped"))
            info.skipped.push_back(s.get<std::string>());
    } catch (const nlohmann::json::exception& e) {
        LUCENT_THROW(IoError, origin, ": not the results.json of an evaluation (", e.what(), ")");
    }
    return info;
}

std::vector<std::string> writeDerivedReports(const std::vector<Result>& results,
                                             const RunInfo& info, const std::string& dir) {
    std::vector<std::string> written;
    const auto write = [&](const std::string& name, const std::string& text) {
        writeInto(written, dir, name, text);
    };
    write("summary.md", summaryMarkdown(results));
    write("pareto.md", paretoMarkdown(results));
    const std::vector<const Result*> all = pointers(results);
    write("chart_summary.dat", chartData(all, methodNames(all)));
    for (const std::vector<const Result*>& rs : byCase(results))
        write("chart_" + fileSafe(rs.front()->caseName) + ".dat", chartData(rs, methodNames(rs)));
    write("charts.gp", gnuplotScript(results, info));
    return written;
}

std::vector<std::string> writeReports(const std::vector<Result>& results, const RunInfo& info,
                                      const std::string& dir) {
    std::vector<std::string> written;
    writeInto(written, dir, "results.csv", toCsv(results));
    writeInto(written, dir, "results.json", toJson(results, info));
    const std::vector<std::string> derived = writeDerivedReports(results, info, dir);
    written.insert(written.end(), derived.begin(), derived.end());
    return written;
}

}  // namespace lucent::evaluation
