// SPDX-License-Identifier: MIT
/// @file
/// @brief PreviewRenderer without Qt widgets (headless EGL context, the app's own renderer):
/// the volume overlay (only over the object, the slice view's colour map, off = untouched),
/// linearImage() against the displayed image, and pass reuse on a paint stroke (identical to a
/// full re-render). Skips cleanly when no headless OpenGL 4.5 context exists.

#include "GlTestContext.h"
#include "PreviewRenderer.h"
#include "SliceView.h"

#include <lucent/core/Error.h>
#include <lucent/core/Image.h>
#include <lucent/planner/AutoMethod.h>
#include <lucent/scene/SceneFile.h>

#include <QImage>

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <thread>
#include <vector>

using namespace lucent;
using namespace lucent::app;

namespace {

constexpr int W = 160, H = 96;  // render = framebuffer size (no upscaling)

/// An RGBA8 framebuffer standing in for Qt's, read back top row first.
struct Target {
    GLuint tex = 0, fbo = 0;
    Target() {
        glCreateTextures(GL_TEXTURE_2D, 1, &tex);
        glTextureStorage2D(tex, 1, GL_RGBA8, W, H);
        glCreateFramebuffers(1, &fbo);
        glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, tex, 0);
    }
    ~Target() {
        glDeleteFramebuffers(1, &fbo);
        glDeleteTextures(1, &tex);
    }
    Target(const Target&) = delete;
    Target& operator=(const Target&) = delete;
    [[nodiscard]] std::vector<std::array<uint8_t, 4>> read() const {
        std::vector<std::array<uint8_t, 4>> gl(size_t(W) * H), out(size_t(W) * H);
        glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glGetTextureImage(tex, 0, GL_RGBA, GL_UNSIGNED_BYTE, GLsizei(gl.size() * 4), gl.data());
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                out[size_t(y) * W + size_t(x)] = gl[size_t(H - 1 - y) * W + size_t(x)];
        return out;
    }
};

struct PreviewFixture : ::testing::Test {
    Scene scene;
    Target* target = nullptr;
    PreviewRenderer preview;

    void SetUp() override {
        LUCENT_REQUIRE_GL();
        scene = makeDefaultScene();
        target = new Target;
        preview.create();
    }
    void TearDown() override {
        if (preview.isCreated())
            preview.destroy();
        delete target;
        if (auto* ctx = lucent::test::sharedGlContext()) {
            EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
            const auto errors = ctx->debugLog().takeErrors();
            EXPECT_TRUE(errors.empty()) << errors.front();
        }
    }

    PreviewFrame frame(const RenderSettings& s, bool first = false) {
        PreviewFrame f;
        f.scene = &scene;
        f.volume = scene.objects[0].material.get();
        f.shownMesh = &scene.objects[0].mesh;
        f.sceneReplaced = first;
        f.dirtyBricks = f.volume->takeDirtyBricks();
        f.camera = scene.camera;
        f.camera.width = W;
        f.camera.height = H;
        f.settings = s;
        f.framebuffer = target->fbo;
        f.framebufferWidth = W;
        f.framebufferHeight = H;
        return f;
    }
    std::vector<std::array<uint8_t, 4>> render(PreviewRenderer& r, const RenderSettings& s,
                                               bool first = false) {
        PreviewFrame f = frame(s, first);
        r.render(f);
        return target->read();
    }
};

RenderSettings directSettings() {
    RenderSettings s;
    s.method = "direct";
    s.resolutionScale = 1.f;
    return s;
}

/// Pixels covered by the object: linear radiance differs from the background's (corner pixel).
std::vector<uint8_t> coverage(const ImageRgb& linear) {
    const Rgb bg = linear.at(0, 0);
    std::vector<uint8_t> c(size_t(W) * H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            c[size_t(y) * W + size_t(x)] = linear.at(x, y) != bg;
    return c;
}

/// Distance (max over channels, display units) from an 8-bit colour to SliceView's viridis,
/// sampled at 4096 values of t (consecutive samples differ by < 1/255 per channel).
float viridisDistance(const std::array<uint8_t, 4>& p) {
    float best = 1e9f;
    for (int i = 0; i <= 4096; ++i) {
        const QRgb v = viridis(float(i) / 4096.f);
        const float d =
            float(std::max({std::abs(int(p[0]) - qRed(v)), std::abs(int(p[1]) - qGreen(v)),
                            std::abs(int(p[2]) - qBlue(v))}));
        best = std::min(best, d);
    }
    return best / 255.f;
}

/// Sets σt and σs′ of the inside voxels within `half` voxels of the grid centre (marks the
/// bricks dirty, as a brush stroke does).
void paintBlock(MaterialVolume& vol, int half, Rgb sigma_t, Rgb sigma_s) {
    const int c = vol.resolution() / 2;
    for (int z = c - half; z <= c + half; ++z)
        for (int y = c - half; y <= c + half; ++y)
            for (int x = c - half; x <= c + half; ++x)
                if (vol.isInside(Coord(x, y, z))) {
                    MaterialSample m = vol.at(Coord(x, y, z));
                    m.sigma_t = sigma_t;
                    m.sigma_s = sigma_s;
                    vol.set(Coord(x, y, z), m);
                }
}

/// Saves a read-back image under LUCENT_TEST_OUTPUT_DIR for inspection.
void savePng(const std::vector<std::array<uint8_t, 4>>& px, const char* name) {
    QImage img(W, H, QImage::Format_RGBA8888);
    for (int y = 0; y < H; ++y)
        std::memcpy(img.scanLine(y), px.data() + size_t(y) * W, size_t(W) * 4);
    img.save(QStringLiteral(LUCENT_TEST_OUTPUT_DIR "/") + QLatin1String(name));
}

}  // namespace

TEST_F(PreviewFixture, VolumeOverlayChangesOnlyObjectPixels) {
    RenderSettings s = directSettings();
    const auto off = render(preview, s, /*first=*/true);
    const ImageRgb linear = preview.linearImage();
    const std::vector<uint8_t> covered = coverage(linear);

    s.volumeOverlay = true;
    s.overlayChannel = 0;
    s.overlayOpacity = 0.5f;
    const auto on = render(preview, s);
    // The overlay samples voxels whose centres lie inside the mesh, so a changed pixel lies
    // within half a voxel diagonal (√3/2·h) of the silhouette: less than one pixel here (the
    // object spans ~128 voxels over fewer than 96 pixels), hence the 1-pixel dilation.
    int changed = 0, coveredCount = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            coveredCount += covered[size_t(y) * W + size_t(x)];
            if (on[size_t(y) * W + size_t(x)] == off[size_t(y) * W + size_t(x)])
                continue;
            ++changed;
            bool near = false;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int u = std::clamp(x + dx, 0, W - 1), v = std::clamp(y + dy, 0, H - 1);
                    near = near || covered[size_t(v) * W + size_t(u)];
                }
            EXPECT_TRUE(near) << "overlay changed background pixel " << x << "," << y;
        }
    ASSERT_GT(coveredCount, W * H / 20);  // the object is in view
    // Nearly every ray through the object meets inside voxels (a few silhouette pixels graze it).
    EXPECT_GT(changed, coveredCount * 8 / 10);
    // The overlay is not part of the linear image.
    const ImageRgb linearOn = preview.linearImage();
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            ASSERT_EQ(linearOn.at(x, y), linear.at(x, y));

    // Opacity 1: the pixels are the slice view's colour map, within 8-bit rounding; the
    // heterogeneous default material gives more than one colour.
    s.overlayOpacity = 1.f;
    const auto opaque = render(preview, s);
    std::vector<std::array<uint8_t, 4>> colours;
    for (size_t i = 0; i < opaque.size(); ++i)
        if (opaque[i] != off[i]) {
            ASSERT_LE(viridisDistance(opaque[i]), 1.5f / 255.f) << "pixel " << i;
            if (std::find(colours.begin(), colours.end(), opaque[i]) == colours.end())
                colours.push_back(opaque[i]);
        }
    EXPECT_GT(colours.size(), size_t(1));
    savePng(off, "preview_overlay_off.png");
    savePng(on, "preview_overlay_half.png");
    savePng(opaque, "preview_overlay_opaque.png");
    std::printf("overlay: %d of %d covered pixels changed, %zu colours\n", changed, coveredCount,
                colours.size());

    // Opacity 0 and overlay off: exactly the image without overlay.
    s.overlayOpacity = 0.f;
    EXPECT_EQ(render(preview, s), off);
    s.volumeOverlay = false;
    EXPECT_EQ(render(preview, s), off);
}

TEST_F(PreviewFixture, OverlayFollowsPaintedBricksLikeAFullUpload) {
    RenderSettings s = directSettings();
    s.volumeOverlay = true;
    s.overlayOpacity = 1.f;
    render(preview, s, /*first=*/true);
    // Paint a block of voxels at the centre far above the current σt (new range maximum).
    paintBlock(*scene.objects[0].material, 6, Rgb(50.f), Rgb(1.f));
    const auto incremental = render(preview, s);  // dirty bricks only
    PreviewRenderer fresh;
    fresh.create();
    const auto full = render(fresh, s, /*first=*/true);
    fresh.destroy();
    EXPECT_EQ(incremental, full);
}

// Auto (the default method): the planner chooses a registry method with a GL pass, says why,
// and keeps its choice while nothing changes.
TEST_F(PreviewFixture, AutoRunsThePlannersChoiceAndSaysWhy) {
    RenderSettings s = directSettings();
    s.method = AUTO_METHOD;
    EXPECT_EQ(RenderSettings{}.method, AUTO_METHOD) << "Auto is the default";
    // Direct while the planner times its unit, a Direct frame of this size: ten frames (the
    // first is not counted), then its choice.
    for (int i = 0; i < 10; ++i) {
        render(preview, s, /*first=*/i == 0);
        EXPECT_TRUE(preview.isPlanning()) << "frame " << i;
        EXPECT_EQ(preview.stats().method, "direct") << "frame " << i;
        EXPECT_TRUE(preview.stats().autoReason.empty()) << "frame " << i;
    }
    render(preview, s);
    const PreviewStats first = preview.stats();
    std::printf("Auto: %s\n", first.autoReason.c_str());
    EXPECT_FALSE(first.autoReason.empty());
    EXPECT_FALSE(first.autoChoice.empty());
    EXPECT_TRUE(PreviewRenderer::isPreviewMethod(first.method)) << first.method;
    EXPECT_EQ(first.autoChoice.rfind(first.method, 0), 0u) << first.autoChoice;
    render(preview, s);
    EXPECT_EQ(preview.stats().method, first.method);
    EXPECT_EQ(preview.stats().autoReason, first.autoReason);
    // Another method chosen by hand: no Auto reason.
    s.method = "direct";
    render(preview, s);
    EXPECT_TRUE(preview.stats().autoReason.empty());
}

TEST_F(PreviewFixture, AutoAddsTheAppsHostTimeToHeadlessLiveCosts) {
    // A headless calibration leaves Qt's share of a frame out of its ratios (hostIncluded
    // false): Auto adds the viewport's measured host time to every prediction. The app's
    // harness's table has it in (true): the same host time changes nothing.
    RenderSettings s = directSettings();
    s.method = AUTO_METHOD;
    preview.pinAutoDirectMs(5.0);  // no timing: the predictions are ratio × 5 ms (+ host)
    const planner::LiveCostsInUse shipped = PreviewRenderer::liveCostTable().inUse;
    const auto firstCandidateMs = [&](bool hostIncluded, double hostMs) {
        planner::LiveCostsInUse in = shipped;
        in.costs.hostIncluded = hostIncluded;
        PreviewRenderer::useLiveCosts(in);
        PreviewFrame f = frame(s, /*first=*/true);
        f.hostMs = hostMs;
        preview.render(f);
        const planner::AutoChoice* c = preview.autoChoice();
        EXPECT_NE(c, nullptr);
        if (c)
            for (const planner::Option& o : c->plan.options)
                if (o.index == 0)
                    return o.ms;
        return -1.0;
    };
    const double base = firstCandidateMs(false, 0.0);
    EXPECT_NEAR(base, shipped.costs.entries[0].strokeRatio * 5.0, 1e-9);
    EXPECT_NEAR(firstCandidateMs(false, 12.5) - base, 12.5, 1e-9);
    EXPECT_NEAR(firstCandidateMs(true, 12.5) - base, 0.0, 1e-9);
    PreviewRenderer::useLiveCosts(shipped);
}

TEST_F(PreviewFixture, LinearImageToneMapsToTheDisplayedImage) {
    RenderSettings s = directSettings();
    s.method = "single-scattering";
    s.exposureStops = 1.5f;
    const auto shown = render(preview, s, /*first=*/true);
    const ImageRgb linear = preview.linearImage();
    ASSERT_EQ(linear.width(), W);
    ASSERT_EQ(linear.height(), H);
    const ToneMap tm{std::exp2(s.exposureStops), ToneMap::Curve::Reinhard};
    double maxError = 0.0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const Rgb l = linear.at(x, y);
            ASSERT_TRUE(std::isfinite(l.r) && std::isfinite(l.g) && std::isfinite(l.b));
            const Rgb d = toneMapToDisplay(l, tm);
            for (int k = 0; k < 3; ++k)
                maxError = std::max(
                    maxError, std::abs(double(d[k]) - shown[size_t(y) * W + size_t(x)][k] / 255.0));
        }
    // 8-bit quantisation of the display (≤ 0.5/255) plus GPU/CPU pow rounding (~1e-6).
    EXPECT_LE(maxError, 1.0 / 255.0);
    PreviewRenderer unused;
    EXPECT_THROW((void)unused.linearImage(), Error);  // before create()
}

TEST_F(PreviewFixture, StrokeFrameReusesPassesAndMatchesFullRender) {
    RenderSettings s = directSettings();
    s.method = "single-scattering";
    s.params = methods::ParamSet::fromAssignments({"steps=8", "light-steps=2"});
    render(preview, s, /*first=*/true);
    render(preview, s);
    const ImageRgb unpaintedLinear = preview.linearImage();
    const PreviewStats before = preview.stats();
    MaterialVolume& vol = *scene.objects[0].material;
    paintBlock(vol, 10, Rgb(2.1f, 1.f, 1.f), Rgb(2.f, 0.2f, 0.2f));  // a reddish block
    const auto stroke = render(preview, s);
    const PreviewStats after = preview.stats();
    EXPECT_GT(after.bricksUploaded, 0);
    EXPECT_LT(after.bricksUploaded, vol.brickCount());  // incremental upload
    EXPECT_EQ(after.gbufferReused, before.gbufferReused + 1);
    EXPECT_EQ(after.directReused, before.directReused + 1);
    EXPECT_EQ(after.shadowsReused, before.shadowsReused + 1);
    const ImageRgb strokeLinear = preview.linearImage();
    PreviewRenderer fresh;
    fresh.create();
    const auto full = render(fresh, s, /*first=*/true);
    const ImageRgb fullLinear = fresh.linearImage();
    fresh.destroy();
    // The stroke shows: in linear radiance. The block lies deep inside, where single scattering
    // changes by ~2.5e-5 of a 0.15 maximum, below the display's 8 bits (they differed only
    // while the surface highlight, removed on 2026-12-07, moved pixels across quantisation steps).
    EXPECT_NE(strokeLinear.pixels(), unpaintedLinear.pixels());
    EXPECT_EQ(stroke, full);  // and the reused passes change nothing else
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            ASSERT_EQ(strokeLinear.at(x, y), fullLinear.at(x, y)) << x << "," << y;
    EXPECT_EQ(render(preview, s), stroke);  // idle frame after the stroke: same image
}

TEST_F(PreviewFixture, DirectionalDipoleAndCombinedRenderTranslucency) {
    ASSERT_TRUE(PreviewRenderer::isPreviewMethod("dirpole"));
    ASSERT_TRUE(PreviewRenderer::isPreviewMethod("combined"));
    const ImageRgb shape = [&] {
        render(preview, directSettings(), /*first=*/true);
        return preview.linearImage();
    }();
    const std::vector<uint8_t> covered = coverage(shape);
    for (const std::string method : {"dirpole", "combined"}) {
        RenderSettings s = directSettings();
        s.method = method;
        s.subsurfaceOnly = true;  // the method's term alone
        // A few samples suffice to see light inside the object; combined's SSLPV part at 16³.
        s.params = methods::ParamSet::fromAssignments({"spp-frame=4"});
        if (method == "combined")
            s.params.set("grid", 16);
        render(preview, s);
        const ImageRgb sss = preview.linearImage();
        int lit = 0, coveredCount = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const Rgb v = sss.at(x, y);
                ASSERT_TRUE(std::isfinite(v.r) && std::isfinite(v.g) && std::isfinite(v.b));
                ASSERT_TRUE(v.r >= 0.f && v.g >= 0.f && v.b >= 0.f) << x << "," << y;
                if (!covered[size_t(y) * W + size_t(x)]) {
                    ASSERT_EQ(v, Rgb(0.f)) << "subsurface term outside the object";
                    continue;
                }
                ++coveredCount;
                lit += v.r + v.g + v.b > 0.f;
            }
        std::printf("method %s: %d of %d object pixels lit; frames %s\n", method.c_str(), lit,
                    coveredCount, preview.stats().methodStat("frames").c_str());
        // The back-lit default object glows through: most of its pixels get some radiance.
        EXPECT_GT(lit, coveredCount / 2) << "method " << method;
        EXPECT_EQ(preview.stats().method, method);
        EXPECT_FALSE(preview.stats().methodStats.empty());
    }
}

// Issue 15, "lights that miss the object": the preview leaves out a spot aimed away from the
// mesh (Statistics dock: "skipped light 1 (spot): …"), draws the same image as without it and,
// while it keeps missing, moving it redraws no shadow map; aimed at the object it is drawn.
TEST_F(PreviewFixture, SpotThatMissesTheMeshIsSkippedUntilItReachesIt) {
    const RenderSettings s = directSettings();
    render(preview, s, /*first=*/true);
    const auto unlit = render(preview, s);
    const Bounds3f box = scene.objects[0].mesh.bounds();
    const float size = glm::length(box.extent());
    Light spot;
    spot.type = Light::Type::Spot;
    spot.position = box.center() + Vector3f(0.f, 2.f * size, 0.f);
    spot.direction = Vector3f(0.f, 1.f, 0.f);  // up, away from the mesh below it
    spot.intensity = Rgb(10.f * size * size);
    scene.lights.push_back(spot);
    EXPECT_EQ(render(preview, s), unlit);
    ASSERT_EQ(preview.stats().skippedLights.size(), 1u);
    EXPECT_NE(preview.stats().skippedLights[0].find("(spot): its cone misses the object"),
              std::string::npos)
        << preview.stats().skippedLights[0];
    const long long shadowsReused = preview.stats().shadowsReused;
    scene.lights.back().position.x += 0.25f * size;  // still aimed away
    EXPECT_EQ(render(preview, s), unlit);
    EXPECT_EQ(preview.stats().shadowsReused, shadowsReused + 1) << "the skipped spot moved";
    scene.lights.back().direction = Vector3f(0.f, -1.f, 0.f);  // down, onto the mesh
    EXPECT_NE(render(preview, s), unlit);
    EXPECT_TRUE(preview.stats().skippedLights.empty());
}
