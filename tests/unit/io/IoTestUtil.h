// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Shared helpers of the io tests: a seeded random painted volume and IoError checks.

#include <lucent/core/Error.h>
#include <lucent/core/Random.h>
#include <lucent/material/MaterialVolume.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace lucent::test {

inline std::string outputPath(const std::string& name) {
    std::filesystem::create_directories(std::string(LUCENT_TEST_OUTPUT_DIR) + "/io");
    return std::string(LUCENT_TEST_OUTPUT_DIR) + "/io/" + name;
}

/// A `res`³ volume with an off-centre ball inside mask (so some blocks are empty, some full,
/// some partial) and every inside voxel painted with an independent random valid sample.
inline MaterialVolume randomPaintedVolume(int res, uint64_t seed) {
    GridSpec spec;
    spec.origin = Point3f(-3.25f, 1.5f, 7.125f);
    spec.voxelSize = 0.37f;
    spec.resolution = res;
    const MaterialSample base{Rgb(1.5f, 2.f, 2.5f), Rgb(1.f, 1.5f, 2.f), Rgb(0.1f, 0.2f, 0.3f)};
    MaterialVolume vol(spec, base);
    vol.setEta(1.45f);
    std::vector<uint8_t> mask(spec.voxelCount(), 0);
    const glm::vec3 centre(0.45f * float(res), 0.5f * float(res), 0.55f * float(res));
    const float radius = 0.42f * float(res);
    for (int z = 0; z < res; ++z)
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x)
                if (glm::length(glm::vec3(x, y, z) + 0.5f - centre) < radius)
                    mask[spec.linearIndex({x, y, z})] = 1;
    vol.setInsideMask(mask);
    Pcg32 rng(seed);
    for (int z = 0; z < res; ++z)
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                MaterialSample s;
                for (int c = 0; c < 3; ++c) {
                    s.sigma_t[c] = 10.f * rng.uniform();
                    s.sigma_s[c] = s.sigma_t[c] * rng.uniform();
                    s.g[c] = 1.8f * rng.uniform() - 0.9f;
                }
                vol.set({x, y, z}, s);
            }
    return vol;
}

/// Runs `fn`, expects an IoError whose message names `path` and contains `fragment`.
template <typename Fn>
void expectIoError(Fn fn, const std::string& path, const std::string& fragment) {
    try {
        fn();
        ADD_FAILURE() << "expected an IoError for '" << path << "' (" << fragment << ")";
    } catch (const IoError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(path), std::string::npos) << "message does not name the file: " << msg;
        EXPECT_NE(msg.find(fragment), std::string::npos)
            << "message lacks '" << fragment << "': " << msg;
    } catch (const std::exception& e) {
        ADD_FAILURE() << "expected IoError, got another exception: " << e.what();
    }
}

}  // namespace lucent::test
