// SPDX-License-Identifier: MIT
/// @file
/// @brief The path tracer's medium of a painted object fills the object's mesh up to its
/// surface: the masked-out voxels the mesh partly fills carry material (BoundarySkin.h).

#include <lucent/mesh/Procedural.h>
#include <lucent/reference/GridMedium.h>
#include <lucent/reference/PathTracer.h>
#include <lucent/scene/Scene.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace lucent;
using namespace lucent::reference;

namespace {

MaterialSample jadeLike() {
    MaterialSample s;
    s.sigma_t = Rgb(4.f, 3.f, 2.f);
    s.sigma_s = Rgb(3.6f, 2.5f, 1.2f);
    s.g = Rgb(0.f);
    return s;
}

}  // namespace

TEST(GridMediumFromMaterial, TheMediumFillsTheMeshUpToItsSurface) {
    // The suite's painted slab: 30 × 30 × 3 mm at 48³. Its voxels are 2/3 mm, so two of its
    // side faces pass through voxel centres and its two large faces cut voxels whose centres
    // lie a sixth of a millimetre outside: the mask (centre inside) leaves those voxels out.
    // Every point inside the mesh must still read the material, and points more than one
    // voxel outside must read vacuum.
    const SceneObject obj = makeObject(makeBox({30.f, 30.f, 3.f}), 48, jadeLike());
    const GridMedium medium = GridMedium::fromMaterial(*obj.material, {});
    const float expected = toMedium(jadeLike()).sigma_t.r;
    const float h = obj.material->spec().voxelSize;
    int inside = 0, wrong = 0;
    for (int k = 0; k <= 12; ++k)
        for (int j = 0; j <= 60; ++j)
            for (int i = 0; i <= 60; ++i) {
                // Lattice over the box, the outer points 10 µm under its faces.
                const Point3f p(-14.99f + 29.98f * float(i) / 60.f,
                                -14.99f + 29.98f * float(j) / 60.f,
                                -1.49f + 2.98f * float(k) / 12.f);
                ++inside;
                if (medium.sigmaT(p, 0) != expected)
                    ++wrong;
            }
    EXPECT_EQ(wrong, 0) << "of " << inside << " points inside the mesh read other than its "
                        << "material";
    for (const Point3f& p : {Point3f(15.f + 2.f * h, 0.f, 0.f), Point3f(0.f, -15.f - 2.f * h, 0.f),
                             Point3f(0.f, 0.f, 1.5f + 2.f * h)})
        EXPECT_EQ(medium.sigmaT(p, 0), 0.f) << "at " << p.x << ", " << p.y << ", " << p.z;

    // A sphere (curved faces cut voxels everywhere) at the suite's resolution.
    const SceneObject ball = makeObject(makeSphere(10.f, 4), 48, jadeLike());
    const GridMedium ballMedium = GridMedium::fromMaterial(*ball.material, {});
    wrong = 0;
    for (int k = 0; k <= 40; ++k)
        for (int j = 0; j <= 40; ++j)
            for (int i = 0; i <= 40; ++i) {
                const Point3f p = Point3f(-10.f) + 20.f * Point3f(i, j, k) / 40.f;
                // Points within 0.98 of the radius: inside the subdivided sphere (its flat
                // facets lie within 0.3 % of the radius at 4 subdivisions).
                if (glm::length(p) < 9.8f && ballMedium.sigmaT(p, 0) != expected)
                    ++wrong;
            }
    EXPECT_EQ(wrong, 0);
}

TEST(GridMediumFromMaterial, AMaskedObjectRendersAsTheMediumFillingItsMesh) {
    // A back-lit 2 mm slab at 16³ (voxels 10/13 mm): its large faces cut voxels whose centres
    // lie outside, 0.23 mm of each face (about one mean free path). With the mask as every
    // front end builds it, the image must be the image of the same mesh with every voxel
    // inside, where the mesh alone bounds the medium. Both media are made heterogeneous (one
    // voxel of the second, in the padding outside the mesh, holds less) and tracked under one
    // global majorant, so equal values inside the mesh give the same paths: the images must
    // be equal to the bit. A vacuum skin under the faces (the estimator before version 3)
    // changed every pixel.
    Scene masked;
    masked.objects.push_back(makeObject(makeBox({10.f, 10.f, 2.f}), 16, jadeLike()));
    masked.eta = 1.3f;
    Light back;
    back.type = Light::Type::Directional;
    back.direction = glm::normalize(Vector3f(0.2f, 0.1f, 1.f));  // travelling towards +z
    back.intensity = Rgb(1.f);
    masked.lights.push_back(back);
    masked.camera.position = {0.f, 0.f, 30.f};
    masked.camera.target = {0.f, 0.f, 0.f};
    masked.camera.fovYDeg = 20.f;
    masked.camera.width = masked.camera.height = 12;
    const MaterialVolume& maskedVolume = *masked.objects.front().material;
    ASSERT_LT(std::count(maskedVolume.insideMask().begin(), maskedVolume.insideMask().end(), 1),
              long(maskedVolume.spec().voxelCount()));

    Scene filled = masked;
    auto everyVoxel = std::make_shared<MaterialVolume>(maskedVolume.spec(), jadeLike());
    MaterialSample less = jadeLike();
    less.sigma_t *= 0.5f;
    less.sigma_s *= 0.5f;
    everyVoxel->set(Coord(0, 0, 0), less);  // a padding corner, outside the mesh
    filled.objects.front().material = everyVoxel;

    ReferenceOptions o;
    o.spp = 12;
    o.majorant = MajorantMode::Global;
    const ReferenceImage a = renderReference(masked, o);
    const ReferenceImage b = renderReference(filled, o);
    double sumA = 0, sumB = 0;
    for (size_t i = 0; i < a.mean.pixels().size(); ++i) {
        sumA += luminance(a.mean.pixels()[i]);
        sumB += luminance(b.mean.pixels()[i]);
    }
    ASSERT_GT(sumB, 0.0);
    EXPECT_EQ(a.mean.pixels(), b.mean.pixels()) << "masked / filled = " << sumA / sumB;
}
