// SPDX-License-Identifier: MIT
/// @file
/// @brief The registry (one list, every entry complete), typed parameters (validation, defaults
/// per backend, unused values) and backend resolution.

#include <lucent/core/Error.h>
#include <lucent/methods/Registry.h>

#include <gtest/gtest.h>

#include <memory>
#include <set>
#include <string>
#include <vector>

namespace lucent::methods {
namespace {

TEST(MethodsRegistry, ListsEveryMethodOnceWithItsDescription) {
    std::set<std::string> names;
    for (const MethodInfo* m : all()) {
        EXPECT_TRUE(names.insert(m->name).second) << m->name << " is registered twice";
        EXPECT_FALSE(m->title.empty()) << m->name;
        EXPECT_FALSE(m->summary.empty()) << m->name;
        EXPECT_FALSE(m->docs.empty()) << m->name;
        EXPECT_TRUE(m->caps.gl || m->caps.cpu) << m->name << " runs nowhere";
        // Every default is a valid value (Params validates them all).
        for (Backend b : {Backend::Gl, Backend::Cpu})
            for (bool live : {false, true})
                EXPECT_NO_THROW(Params(m->name, m->params, {}, b, live)) << m->name;
    }
    for (const char* expected : {"direct", "single-scattering", "sslpv", "dipole", "better-dipole",
                                 "dirpole", "combined", "reference"})
        EXPECT_TRUE(names.count(expected)) << expected;
}

TEST(MethodsRegistry, UnknownNamesListTheKnownOnes) {
    try {
        (void)find("dipol");
        FAIL() << "expected ValueError";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("better-dipole"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(exists("dipol"));
    EXPECT_TRUE(exists("dirpole"));
}

TEST(MethodsParams, ValidatesTypeAndRangeNamingTheParameter) {
    const MethodInfo& dipole = find("dipole");
    auto message = [&](const std::string& assignment) {
        try {
            Params p(dipole.name, dipole.params, ParamSet::fromAssignments({assignment}),
                     Backend::Gl, false);
        } catch (const ValueError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(message("spp=0").find("spp"), std::string::npos);
    EXPECT_NE(message("spp=many").find("not an integer"), std::string::npos);
    EXPECT_NE(message("light-views=maybe").find("on or off"), std::string::npos);
    EXPECT_NE(message("grid=32").find("it has: spp"), std::string::npos);
    EXPECT_EQ(message("spp=64"), "");
}

TEST(MethodsParams, DefaultsDependOnBackendAndUse) {
    const MethodInfo& dipole = find("dipole");
    // The GL pass accumulates 256 samples; the CPU gather's default is 32 (as lucent-cli's).
    EXPECT_EQ(Params(dipole.name, dipole.params, {}, Backend::Gl, false).getInt("spp"), 256);
    EXPECT_EQ(Params(dipole.name, dipole.params, {}, Backend::Cpu, false).getInt("spp"), 32);
    ParamSet given;
    given.set("spp", 64);
    const Params p(dipole.name, dipole.params, given, Backend::Cpu, false);
    EXPECT_EQ(p.getInt("spp"), 64);
    EXPECT_TRUE(p.isGiven("spp"));
    EXPECT_FALSE(p.isGiven("seed"));
}

TEST(MethodsParams, ReportsGivenValuesNobodyRead) {
    const MethodInfo& dipole = find("dipole");
    ParamSet given = ParamSet::fromAssignments({"spp=64", "seed=3"});
    const Params p(dipole.name, dipole.params, given, Backend::Gl, false);
    EXPECT_EQ(p.getInt("spp"), 64);
    ASSERT_EQ(p.unused().size(), 1u);
    EXPECT_EQ(p.unused()[0], "seed");
    EXPECT_THROW(ParamSet::fromAssignments({"spp"}), ValueError);
}

// Combined's SSLPV part (docs/methods/combined.md, "The SSLPV part"): auto is the diffusion mode
// unless the split or the propagation need propagation steps; an explicit diffusion part refuses
// them, naming the parameter that allows them, instead of running something else.
TEST(MethodsParams, CombinedDiffusionPartNamesWhatItCannotRun) {
    const auto message = [](const std::vector<std::string>& assignments, Backend backend) {
        try {
            (void)create("combined", ParamSet::fromAssignments(assignments), {backend, false, {}});
        } catch (const ValueError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(message({"split=steps", "sslpv-mode=diffusion"}, Backend::Cpu).find("sslpv-mode"),
              std::string::npos);
    EXPECT_NE(
        message({"propagation=gl", "sslpv-mode=diffusion"}, Backend::Gl).find("propagation=cpu"),
        std::string::npos);
    for (const char* part : {"sslpv-mode=auto", "sslpv-mode=calibrated"}) {
        EXPECT_EQ(message({"split=steps", part}, Backend::Cpu), "") << part;
        EXPECT_EQ(message({"propagation=gl", part}, Backend::Gl), "") << part;
    }
    const auto partOf = [](const std::vector<std::string>& assignments) {
        std::unique_ptr<Method> m =
            create("combined", ParamSet::fromAssignments(assignments), {Backend::Cpu, false, {}});
        for (const auto& [key, value] : m->stats())
            if (key == "sslpv part")
                return value;
        return std::string("(missing)");
    };
    EXPECT_EQ(partOf({}), "diffusion");
    EXPECT_EQ(partOf({"split=steps"}), "calibrated");
    EXPECT_EQ(partOf({"sslpv-mode=calibrated"}), "calibrated");
}

TEST(MethodsRegistry, AutoPicksThePreferredBackendAndFallsBack) {
    const MethodInfo& dipole = find("dipole");
    EXPECT_EQ(resolveBackend(dipole, Backend::Auto, true), Backend::Gl);
    EXPECT_EQ(resolveBackend(dipole, Backend::Auto, false), Backend::Cpu);
    EXPECT_THROW((void)resolveBackend(dipole, Backend::Gl, false, "no EGL"), GpuError);
    const MethodInfo& direct = find("direct");
    EXPECT_THROW((void)resolveBackend(direct, Backend::Cpu, true), ValueError);
    EXPECT_THROW((void)resolveBackend(direct, Backend::Auto, false, "no EGL"), GpuError);
    const MethodInfo& reference = find("reference");
    EXPECT_EQ(resolveBackend(reference, Backend::Auto, true), Backend::Cpu);
}

}  // namespace
}  // namespace lucent::methods
