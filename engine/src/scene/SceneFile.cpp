// SPDX-License-Identifier: MIT
/// @file
/// @brief The versioned JSON scene format (docs/file-formats.md, "Scene file (JSON)"):
/// strict parsing where every error names its field, building of the objects, saving of
/// projects (scene JSON + sidecar VDB) and the built-in default scene.

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/material/Brush.h>
#include <lucent/material/Presets.h>
#include <lucent/material/Procedural.h>
#include <lucent/mesh/MeshIO.h>
#include <lucent/mesh/Procedural.h>
#include <lucent/mesh/Voxelize.h>
#include <lucent/scene/SceneFile.h>

#include <lucent/io/VdbIO.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>

namespace lucent {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr int MAX_IMAGE_SIZE = 16384;  // pixels per side
/// A scene holds a few lights and a camera and refers to its mesh and material files: 16 MiB
/// is far more than any scene needs.
constexpr uint64_t MAX_SCENE_FILE_BYTES = uint64_t(16) << 20;

std::string typeName(const json& v) {
    if (v.is_null())
        return "null";
    if (v.is_boolean())
        return "a boolean";
    if (v.is_number())
        return "a number";
    if (v.is_string())
        return "a string";
    if (v.is_array())
        return "an array";
    return "an object";
}

[[noreturn]] void fieldError(const std::string& path, const std::string& what) {
    LUCENT_THROW(IoError, "scene: field '", path, "': ", what);
}
[[noreturn]] void valueError(const std::string& path, const std::string& what) {
    LUCENT_THROW(ValueError, "scene: field '", path, "': ", what);
}

/// A JSON object being read, with its dotted path for messages.
class Obj {
public:
    Obj(const json& j, std::string path) : m_j(j), m_path(std::move(path)) {
        if (!j.is_object())
            fieldError(m_path.empty() ? "<root>" : m_path,
                       "expected an object, got " + typeName(j));
    }
    [[nodiscard]] std::string sub(const std::string& key) const {
        return m_path.empty() ? key : m_path + "." + key;
    }
    /// Every key must be one of `allowed`.
    void allowOnly(std::initializer_list<const char*> allowed) const {
        for (const auto& item : m_j.items()) {
            // Not a structured binding: clang 14 (the fuzz build) cannot capture one.
            const std::string& key = item.key();
            const bool ok = std::any_of(allowed.begin(), allowed.end(),
                                        [&](const char* a) { return key == a; });
            if (!ok) {
                std::string list;
                for (const char* a : allowed)
                    list += std::string(list.empty() ? "" : ", ") + a;
                fieldError(sub(key), "unknown field (expected one of: " + list + ")");
            }
        }
    }
    [[nodiscard]] bool has(const char* key) const { return m_j.contains(key); }
    [[nodiscard]] const json& at(const char* key) const {
        if (!m_j.contains(key))
            fieldError(sub(key), "missing required field");
        return m_j.at(key);
    }
    [[nodiscard]] const json& raw() const { return m_j; }

private:
    const json& m_j;
    std::string m_path;
};

float number(const json& v, const std::string& path) {
    if (!v.is_number())
        fieldError(path, "expected a number, got " + typeName(v));
    const double d = v.get<double>();
    if (!std::isfinite(d) || std::abs(d) > 3.4e38)
        valueError(path, "number is not finite");
    return float(d);
}
float positive(const json& v, const std::string& path) {
    const float x = number(v, path);
    if (!(x > 0.f))
        valueError(path, "must be > 0, got " + std::to_string(x));
    return x;
}
int integer(const json& v, const std::string& path, int lo, int hi) {
    if (!v.is_number_integer())
        fieldError(path, "expected an integer, got " + typeName(v));
    const auto i = v.get<int64_t>();
    if (i < lo || i > hi)
        valueError(path, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                             "], got " + std::to_string(i));
    return int(i);
}
std::string string(const json& v, const std::string& path) {
    if (!v.is_string())
        fieldError(path, "expected a string, got " + typeName(v));
    return v.get<std::string>();
}
Vector3f vec3(const json& v, const std::string& path) {
    if (!v.is_array() || v.size() != 3)
        fieldError(path, "expected 3 numbers, got " + typeName(v));
    Vector3f r;
    for (int i = 0; i < 3; ++i)
        r[i] = number(v[size_t(i)], path + "[" + std::to_string(i) + "]");
    return r;
}
Rgb nonNegativeRgb(const json& v, const std::string& path) {
    const Rgb r = vec3(v, path);
    if (r.r < 0.f || r.g < 0.f || r.b < 0.f)
        valueError(path, "values must be ≥ 0");
    return r;
}
Vector3f direction(const json& v, const std::string& path) {
    const Vector3f d = vec3(v, path);
    const float len = glm::length(d);
    if (!(len > 1e-12f))
        valueError(path, "direction must be non-zero");
    return d / len;
}

std::string resolvePath(const std::string& file, const std::string& baseDir) {
    const fs::path p(file);
    if (p.is_absolute() || baseDir.empty())
        return p.lexically_normal().string();
    return (fs::path(baseDir) / p).lexically_normal().string();
}

// ---- Mesh ----------------------------------------------------------------------------------

MeshSource parseMeshSource(const json& j, const std::string& baseDir) {
    const Obj o(j, "mesh");
    MeshSource src;
    if (o.has("file")) {
        o.allowOnly({"file", "scale"});
        if (o.has("procedural"))
            fieldError("mesh", "give either 'file' or 'procedural'");
        src.file = resolvePath(string(o.at("file"), "mesh.file"), baseDir);
        if (o.has("scale"))
            src.scale = positive(o.at("scale"), "mesh.scale");
        return src;
    }
    if (!o.has("procedural"))
        fieldError("mesh.procedural", "missing required field (or 'mesh.file')");
    src.procedural = string(o.at("procedural"), "mesh.procedural");
    if (src.procedural == "sphere") {
        o.allowOnly({"procedural", "radius", "subdivisions"});
        src.params = {
            positive(o.at("radius"), "mesh.radius"),
            float(o.has("subdivisions") ? integer(o.at("subdivisions"), "mesh.subdivisions", 0, 7)
                                        : 4)};
    } else if (src.procedural == "box") {
        o.allowOnly({"procedural", "size"});
        const Vector3f s = vec3(o.at("size"), "mesh.size");
        if (!(s.x > 0.f && s.y > 0.f && s.z > 0.f))
            valueError("mesh.size", "lengths must be > 0");
        src.params = {s.x, s.y, s.z};
    } else if (src.procedural == "torus") {
        o.allowOnly({"procedural", "radii"});
        const json& r = o.at("radii");
        if (!r.is_array() || r.size() != 2)
            fieldError("mesh.radii", "expected 2 numbers [major, minor], got " + typeName(r));
        const float major = positive(r[0], "mesh.radii[0]");
        const float minor = positive(r[1], "mesh.radii[1]");
        if (!(major > minor))
            valueError("mesh.radii", "major radius must exceed minor radius");
        src.params = {major, minor};
    } else if (src.procedural == "thin-thick") {
        o.allowOnly({"procedural", "size"});
        src.params = {positive(o.at("size"), "mesh.size")};
    } else {
        valueError("mesh.procedural", "unknown shape '" + src.procedural +
                                          "' (expected sphere, box, torus or thin-thick)");
    }
    return src;
}

TriangleMesh buildMesh(const MeshSource& src, std::vector<std::string>& warnings) {
    if (!src.file.empty()) {
        MeshReport report;
        TriangleMesh mesh = loadMesh(src.file, src.scale, &report);
        warnings.insert(warnings.end(), report.warnings.begin(), report.warnings.end());
        return mesh;
    }
    const auto& p = src.params;
    if (src.procedural == "sphere")
        return makeSphere(p.at(0), p.size() > 1 ? int(p[1]) : 4);
    if (src.procedural == "box")
        return makeBox({p.at(0), p.at(1), p.at(2)});
    if (src.procedural == "torus")
        return makeTorus(p.at(0), p.at(1));
    if (src.procedural == "thin-thick")
        return makeThinThick(p.at(0));
    LUCENT_THROW(ValueError, "scene: unknown procedural mesh '", src.procedural, "'");
}

// ---- Material ------------------------------------------------------------------------------

MaterialSource parseMaterialSource(const json& j, const std::string& baseDir) {
    const Obj o(j, "material");
    MaterialSource src;
    const int kinds = int(o.has("preset")) + int(o.has("vdb")) + int(o.has("sigma_t"));
    if (kinds != 1)
        fieldError("material",
                   "give exactly one of 'preset', 'vdb' or uniform values "
                   "'sigma_t'/'sigma_s'/'g'");
    if (o.has("preset")) {
        o.allowOnly({"preset"});
        src.preset = string(o.at("preset"), "material.preset");
        try {
            src.value = findPreset(src.preset).sample();
        } catch (const Error& e) {
            valueError("material.preset", e.what());
        }
    } else if (o.has("vdb")) {
        o.allowOnly({"vdb"});
        src.vdbFile = resolvePath(string(o.at("vdb"), "material.vdb"), baseDir);
    } else {
        o.allowOnly({"sigma_t", "sigma_s", "g"});
        src.uniform = true;
        src.value.sigma_t = nonNegativeRgb(o.at("sigma_t"), "material.sigma_t");
        src.value.sigma_s = nonNegativeRgb(o.at("sigma_s"), "material.sigma_s");
        src.value.g = o.has("g") ? vec3(o.at("g"), "material.g") : Rgb(0.f);
        for (int c = 0; c < 3; ++c) {
            if (src.value.sigma_s[c] > src.value.sigma_t[c])
                valueError("material.sigma_s",
                           "σs′ must not exceed σt (channel " + std::to_string(c) + ")");
            if (std::abs(src.value.g[c]) > G_MAX)
                valueError("material.g", "|g| must be ≤ 0.99");
            if (src.value.sigma_t[c] > SIGMA_MAX)
                valueError("material.sigma_t", "σt too large");
        }
    }
    return src;
}

// ---- Lights and camera ---------------------------------------------------------------------

Light parseLight(const json& j, const std::string& path) {
    const Obj o(j, path);
    Light l;
    const std::string type = string(o.at("type"), o.sub("type"));
    if (type == "point") {
        o.allowOnly({"type", "position", "intensity"});
        l.type = Light::Type::Point;
        l.position = vec3(o.at("position"), o.sub("position"));
        l.intensity = nonNegativeRgb(o.at("intensity"), o.sub("intensity"));
    } else if (type == "spot") {
        o.allowOnly({"type", "position", "direction", "intensity", "inner_deg", "outer_deg"});
        l.type = Light::Type::Spot;
        l.position = vec3(o.at("position"), o.sub("position"));
        l.direction = direction(o.at("direction"), o.sub("direction"));
        l.intensity = nonNegativeRgb(o.at("intensity"), o.sub("intensity"));
        if (o.has("outer_deg"))
            l.spotOuterDeg = number(o.at("outer_deg"), o.sub("outer_deg"));
        if (o.has("inner_deg"))
            l.spotInnerDeg = number(o.at("inner_deg"), o.sub("inner_deg"));
        if (!(l.spotOuterDeg > 0.f && l.spotOuterDeg <= 90.f))
            valueError(o.sub("outer_deg"), "must be in (0, 90] degrees");
        if (!(l.spotInnerDeg >= 0.f && l.spotInnerDeg <= l.spotOuterDeg))
            valueError(o.sub("inner_deg"), "must be in [0, outer_deg] degrees");
    } else if (type == "directional") {
        o.allowOnly({"type", "direction", "irradiance"});
        l.type = Light::Type::Directional;
        l.direction = direction(o.at("direction"), o.sub("direction"));
        l.intensity = nonNegativeRgb(o.at("irradiance"), o.sub("irradiance"));
    } else if (type == "sphere") {
        o.allowOnly({"type", "position", "radius", "radiance"});
        l.type = Light::Type::Sphere;
        l.position = vec3(o.at("position"), o.sub("position"));
        l.radius = positive(o.at("radius"), o.sub("radius"));
        l.intensity = nonNegativeRgb(o.at("radiance"), o.sub("radiance"));
    } else {
        valueError(o.sub("type"), "unknown light type '" + type +
                                      "' (expected point, spot, directional or sphere)");
    }
    return l;
}

Camera parseCamera(const json& j) {
    const Obj o(j, "camera");
    o.allowOnly({"position", "target", "up", "fov_y_deg", "ortho_height", "width", "height", "near",
                 "far"});
    Camera c;
    c.position = vec3(o.at("position"), "camera.position");
    c.target = vec3(o.at("target"), "camera.target");
    if (o.has("up"))
        c.up = vec3(o.at("up"), "camera.up");
    const Vector3f fwd = c.target - c.position;
    if (!(glm::length(fwd) > 1e-6f))
        valueError("camera.target", "must differ from camera.position");
    if (!(glm::length(glm::cross(glm::normalize(fwd), c.up)) > 1e-4f))
        valueError("camera.up", "must not be parallel to the viewing direction");
    c.up = glm::normalize(c.up);
    if (o.has("fov_y_deg") == o.has("ortho_height"))
        fieldError("camera.fov_y_deg",
                   "give exactly one of 'fov_y_deg' (perspective) or "
                   "'ortho_height' (orthographic)");
    if (o.has("fov_y_deg")) {
        c.fovYDeg = number(o.at("fov_y_deg"), "camera.fov_y_deg");
        if (!(c.fovYDeg > 0.f && c.fovYDeg < 180.f))
            valueError("camera.fov_y_deg", "must be in (0, 180) degrees");
    } else {
        c.orthographic = true;
        c.orthoHeight = positive(o.at("ortho_height"), "camera.ortho_height");
    }
    c.width = integer(o.at("width"), "camera.width", 1, MAX_IMAGE_SIZE);
    c.height = integer(o.at("height"), "camera.height", 1, MAX_IMAGE_SIZE);
    if (o.has("near"))
        c.nearPlane = positive(o.at("near"), "camera.near");
    if (o.has("far"))
        c.farPlane = positive(o.at("far"), "camera.far");
    if (!(c.farPlane > c.nearPlane))
        valueError("camera.far", "must exceed camera.near");
    return c;
}

/// A VDB material belongs to the mesh it was painted in: its inside voxels must be (nearly)
/// those of this mesh in the material's grid. Otherwise light entering the mesh meets no
/// material (0 W injected) without any error. Below half the voxels in common it is an error;
/// below 95 % a warning (a mesh edited after painting).
void checkMaterialFitsMesh(const TriangleMesh& mesh, const MaterialVolume& material,
                           const std::string& vdbFile, std::vector<std::string>& warnings) {
    const std::vector<uint8_t> meshInside = voxelizeSolid(mesh, material.spec());
    const std::vector<uint8_t>& materialInside = material.insideMask();
    size_t inMesh = 0, inMaterial = 0, inBoth = 0;
    for (size_t i = 0; i < meshInside.size() && i < materialInside.size(); ++i) {
        inMesh += meshInside[i] != 0;
        inMaterial += materialInside[i] != 0;
        inBoth += meshInside[i] != 0 && materialInside[i] != 0;
    }
    const double overlap = double(inBoth) / double(std::max<size_t>({inMesh, inMaterial, 1}));
    const std::string percent = std::to_string(int(std::floor(100.0 * overlap))) + " %";
    if (overlap < 0.5)
        valueError("material.vdb",
                   "the VDB material '" + vdbFile + "' does not fit the mesh: only " + percent +
                       " of their inside voxels are common (" + std::to_string(inMesh) +
                       " voxels of the mesh, " + std::to_string(inMaterial) +
                       " of the material); was it painted in another mesh, or at another scale?");
    if (overlap < 0.95)
        warnings.push_back("the VDB material '" + vdbFile + "' and the mesh share only " + percent +
                           " of their inside voxels (mesh edited after painting?)");
}

/// A scene without a camera looks at its object from +z: the bounding sphere fills the 40°
/// vertical field of view with a 5 % margin.
Camera framingCamera(const Bounds3f& bounds) {
    Camera c;
    const float radius = std::max(0.5f * glm::length(bounds.extent()), 1e-3f);
    const float distance = 1.05f * radius / std::sin(glm::radians(0.5f * c.fovYDeg));
    c.target = bounds.center();
    c.position = c.target + Vector3f(0.f, 0.f, distance);
    c.nearPlane = std::max(1e-3f, 0.01f * distance);
    c.farPlane = std::max(c.farPlane, 100.f * distance);
    return c;
}

/// Builds mesh, grid, mask and material of one object.
SceneObject buildObject(const MeshSource& meshSrc, const MaterialSource& matSrc, float eta,
                        bool resolutionGiven, std::vector<std::string>& warnings) {
    SceneObject obj;
    obj.meshSource = meshSrc;
    obj.materialSource = matSrc;
    obj.mesh = buildMesh(meshSrc, warnings);
    if (!matSrc.vdbFile.empty()) {
        io::ImportedMaterial imported = io::importVdb(matSrc.vdbFile);
        if (resolutionGiven && imported.volume.resolution() != matSrc.resolution)
            valueError("resolution", "is " + std::to_string(matSrc.resolution) +
                                         " but the VDB material '" + matSrc.vdbFile + "' has " +
                                         std::to_string(imported.volume.resolution()));
        checkMaterialFitsMesh(obj.mesh, imported.volume, matSrc.vdbFile, warnings);
        obj.materialSource.resolution = imported.volume.resolution();
        obj.materialSource.value = imported.volume.base();
        obj.material = std::make_shared<MaterialVolume>(std::move(imported.volume));
    } else {
        SceneObject filled = makeObject(std::move(obj.mesh), matSrc.resolution, matSrc.value);
        obj.mesh = std::move(filled.mesh);
        obj.material = std::move(filled.material);
    }
    obj.material->setEta(eta);
    return obj;
}

json vecJson(const Vector3f& v) {
    return json::array({v.x, v.y, v.z});
}

}  // namespace

Scene parseScene(const std::string& jsonText, const std::string& baseDir) {
    json root;
    try {
        root = json::parse(jsonText);
    } catch (const json::parse_error& e) {
        LUCENT_THROW(IoError, "scene: not valid JSON (byte ", e.byte, "): ", e.what());
    } catch (const json::exception& e) {
        // E.g. out_of_range for a number beyond a double's range (found by fuzzing): the
        // parser's other exceptions must not leave the importer as foreign exceptions.
        LUCENT_THROW(IoError, "scene: not valid JSON: ", e.what());
    }
    const Obj o(root, "");
    o.allowOnly(
        {"version", "mesh", "material", "resolution", "eta", "lights", "environment", "camera"});
    if (o.has("version")) {
        const int version = integer(o.at("version"), "version", 1, 1 << 20);
        if (version > SCENE_FORMAT_VERSION)
            LUCENT_THROW(IoError, "scene: field 'version': ", version,
                         " is newer than this build supports (", SCENE_FORMAT_VERSION, ")");
    }
    Scene scene;
    const MeshSource meshSrc = parseMeshSource(o.at("mesh"), baseDir);
    MaterialSource matSrc = parseMaterialSource(o.at("material"), baseDir);
    const bool resolutionGiven = o.has("resolution");
    if (resolutionGiven)
        matSrc.resolution = integer(o.at("resolution"), "resolution", GridSpec::MIN_RESOLUTION,
                                    GridSpec::MAX_RESOLUTION);
    // The voxel count is a claim the file makes, like an element count in a mesh header: it
    // sets the voxelisation's work and the material's memory (≈ 40 bytes a voxel), so it meets
    // the import limit before anything is allocated (at the default limit every resolution up
    // to MAX_RESOLUTION passes). A file that gives none claims the default's 128³ voxels; a VDB
    // material brings its own grid, which its reader checks.
    if (resolutionGiven || matSrc.vdbFile.empty()) {
        const uint64_t voxels =
            uint64_t(matSrc.resolution) * uint64_t(matSrc.resolution) * uint64_t(matSrc.resolution);
        if (voxels > importLimits().maxElements)
            valueError("resolution",
                       std::string(resolutionGiven ? "" : "(not given: the default) ") +
                           std::to_string(matSrc.resolution) + "^3 = " + std::to_string(voxels) +
                           " voxels is more than the import limit of " +
                           std::to_string(importLimits().maxElements) +
                           " elements; use a lower resolution");
    }
    if (o.has("eta")) {
        scene.eta = number(o.at("eta"), "eta");
        if (!(scene.eta >= 1.f && scene.eta <= 3.f))
            valueError("eta", "must be in [1, 3]");
    }
    const json& lights = o.at("lights");
    if (!lights.is_array())
        fieldError("lights", "expected an array, got " + typeName(lights));
    for (size_t i = 0; i < lights.size(); ++i)
        scene.lights.push_back(parseLight(lights[i], "lights[" + std::to_string(i) + "]"));
    if (o.has("environment")) {
        const Obj env(o.at("environment"), "environment");
        env.allowOnly({"radiance"});
        scene.environment = nonNegativeRgb(env.at("radiance"), env.sub("radiance"));
    }
    if (o.has("camera"))
        scene.camera = parseCamera(o.at("camera"));
    scene.objects.push_back(
        buildObject(meshSrc, matSrc, scene.eta, resolutionGiven, scene.warnings));
    if (!o.has("camera"))
        scene.camera = framingCamera(scene.objects.front().mesh.bounds());
    return scene;
}

Scene loadScene(const std::string& path) {
    // A regular file of bounded size only: a path such as /dev/zero or a FIFO would be read
    // without end.
    const std::string text = readInputFile(path, "scene file", MAX_SCENE_FILE_BYTES);
    const std::string baseDir = fs::path(path).parent_path().string();
    try {
        return parseScene(text, baseDir.empty() ? "." : baseDir);
    } catch (const IoError& e) {
        LUCENT_THROW(IoError, path, ": ", e.what());
    } catch (const ValueError& e) {
        LUCENT_THROW(ValueError, path, ": ", e.what());
    }
}

std::string sceneToJson(const Scene& scene) {
    LUCENT_CHECK(scene.objects.size() == 1,
                 "sceneToJson: the format holds exactly one object, got ", scene.objects.size());
    const SceneObject& obj = scene.objects.front();
    json root;
    root["version"] = SCENE_FORMAT_VERSION;
    json mesh;
    const MeshSource& ms = obj.meshSource;
    if (!ms.file.empty()) {
        mesh["file"] = ms.file;
        mesh["scale"] = ms.scale;
    } else {
        mesh["procedural"] = ms.procedural;
        const auto& p = ms.params;
        LUCENT_CHECK(!p.empty(), "sceneToJson: procedural mesh '", ms.procedural,
                     "' has no parameters");
        if (ms.procedural == "sphere") {
            mesh["radius"] = p[0];
            if (p.size() > 1)
                mesh["subdivisions"] = int(p[1]);
        } else if (ms.procedural == "box") {
            LUCENT_CHECK(p.size() == 3, "sceneToJson: box needs 3 sizes");
            mesh["size"] = json::array({p[0], p[1], p[2]});
        } else if (ms.procedural == "torus") {
            LUCENT_CHECK(p.size() == 2, "sceneToJson: torus needs 2 radii");
            mesh["radii"] = json::array({p[0], p[1]});
        } else if (ms.procedural == "thin-thick") {
            mesh["size"] = p[0];
        } else {
            LUCENT_THROW(ValueError, "sceneToJson: unknown procedural mesh '", ms.procedural, "'");
        }
    }
    root["mesh"] = mesh;
    json mat;
    const MaterialSource& mt = obj.materialSource;
    if (!mt.vdbFile.empty()) {
        mat["vdb"] = mt.vdbFile;
    } else if (!mt.preset.empty()) {
        mat["preset"] = mt.preset;
    } else {
        mat["sigma_t"] = vecJson(mt.value.sigma_t);
        mat["sigma_s"] = vecJson(mt.value.sigma_s);
        mat["g"] = vecJson(mt.value.g);
    }
    root["material"] = mat;
    root["resolution"] = obj.material ? obj.material->resolution() : mt.resolution;
    root["eta"] = scene.eta;
    json lights = json::array();
    for (const Light& l : scene.lights) {
        json jl;
        switch (l.type) {
            case Light::Type::Point:
                jl = {{"type", "point"},
                      {"position", vecJson(l.position)},
                      {"intensity", vecJson(l.intensity)}};
                break;
            case Light::Type::Spot:
                jl = {{"type", "spot"},
                      {"position", vecJson(l.position)},
                      {"direction", vecJson(l.direction)},
                      {"intensity", vecJson(l.intensity)},
                      {"inner_deg", l.spotInnerDeg},
                      {"outer_deg", l.spotOuterDeg}};
                break;
            case Light::Type::Directional:
                jl = {{"type", "directional"},
                      {"direction", vecJson(l.direction)},
                      {"irradiance", vecJson(l.intensity)}};
                break;
            case Light::Type::Sphere:
                jl = {{"type", "sphere"},
                      {"position", vecJson(l.position)},
                      {"radius", l.radius},
                      {"radiance", vecJson(l.intensity)}};
                break;
        }
        lights.push_back(jl);
    }
    root["lights"] = lights;
    if (scene.environment != Rgb(0.f))
        root["environment"] = {{"radiance", vecJson(scene.environment)}};
    const Camera& c = scene.camera;
    json cam = {{"position", vecJson(c.position)},
                {"target", vecJson(c.target)},
                {"up", vecJson(c.up)},
                {"width", c.width},
                {"height", c.height},
                {"near", c.nearPlane},
                {"far", c.farPlane}};
    if (c.orthographic)
        cam["ortho_height"] = c.orthoHeight;
    else
        cam["fov_y_deg"] = c.fovYDeg;
    root["camera"] = cam;
    return root.dump(2) + "\n";
}

namespace {

/// The two sidecar names of the project at `jsonPath`: "<stem>.vdb" and "<stem>.1.vdb".
std::array<fs::path, 2> sidecarNames(const fs::path& jsonPath) {
    fs::path a = jsonPath, b = jsonPath;
    a.replace_extension(".vdb");
    b.replace_extension(".1.vdb");
    return {a, b};
}

/// The sidecar file name the project file at `jsonPath` refers to now; empty if there is no
/// such file or it cannot be read as a project (then nothing of it is kept or removed).
std::string referencedSidecar(const fs::path& jsonPath) {
    std::error_code ec;
    if (!fs::is_regular_file(jsonPath, ec))
        return {};
    try {
        const json j = json::parse(
            readInputFile(jsonPath.string(), "project file", MAX_SCENE_FILE_BYTES), nullptr,
            /*allow_exceptions=*/false);
        if (j.is_object() && j.contains("material") && j["material"].is_object() &&
            j["material"].contains("vdb") && j["material"]["vdb"].is_string())
            return j["material"]["vdb"].get<std::string>();
    } catch (const std::exception&) {
    }
    return {};
}

}  // namespace

std::vector<std::string> projectFiles(const std::string& path) {
    std::vector<std::string> files;
    std::error_code ec;
    if (fs::is_regular_file(path, ec))
        files.push_back(path);
    for (const fs::path& sidecar : sidecarNames(fs::path(path)))
        if (fs::is_regular_file(sidecar, ec))
            files.push_back(sidecar.string());
    return files;
}

void removeProject(const std::string& path) {
    for (const std::string& file : projectFiles(path)) {
        std::error_code ec;
        fs::remove(file, ec);
    }
}

void saveProject(const Scene& scene, const std::string& path) {
    LUCENT_CHECK(scene.objects.size() == 1 && scene.objects.front().material,
                 "saveProject: the scene needs exactly one object with a material");
    const fs::path jsonPath(path);
    LUCENT_CHECK(jsonPath.extension() != ".vdb", "saveProject: '", path, "' must not end in .vdb");
    const fs::path dir = jsonPath.parent_path().empty() ? fs::path(".") : jsonPath.parent_path();

    // One commit point: the rename of the JSON. The material goes to the sidecar name the
    // project on disk does not use now ("<stem>.vdb" and "<stem>.1.vdb" alternate), so until
    // the JSON is replaced the old JSON still refers to its own, untouched sidecar. A save
    // killed at any moment leaves the old project or the new one, never the new material
    // under the old JSON or the reverse. Renaming the two files one after the other would
    // leave that window open.
    const std::array<fs::path, 2> names = sidecarNames(jsonPath);
    const std::string current = referencedSidecar(jsonPath);
    const fs::path vdbPath = current == names[0].filename().string() ? names[1] : names[0];

    // The JSON refers to the sidecar by its file name, and to a mesh file relative to the
    // project folder when possible, so a project folder can be moved as a whole.
    Scene copy;
    copy.lights = scene.lights;
    copy.environment = scene.environment;
    copy.camera = scene.camera;
    copy.eta = scene.eta;
    SceneObject o;
    o.meshSource = scene.objects.front().meshSource;
    o.materialSource = scene.objects.front().materialSource;
    o.material = scene.objects.front().material;
    if (!o.meshSource.file.empty()) {
        std::error_code ec;
        const fs::path rel = fs::proximate(fs::absolute(o.meshSource.file), fs::absolute(dir), ec);
        if (!ec)
            o.meshSource.file = rel.string();
    }
    o.materialSource.vdbFile = vdbPath.filename().string();
    o.materialSource.preset.clear();
    copy.objects.push_back(std::move(o));
    const std::string text = sceneToJson(copy);

    // Both files are written and synced as temporaries first, so a failed write (full disk,
    // read-only folder) replaces nothing.
    AtomicFile vdbFile(vdbPath.string());
    AtomicFile jsonFile(path);
    vdbFile.sink().write(io::encodeVdb(*scene.objects.front().material));
    jsonFile.sink().write(text);
    vdbFile.finish();
    jsonFile.finish();
    vdbFile.commit();   // a name the project on disk does not refer to
    jsonFile.commit();  // the commit point
    // The other sidecar is now unreferenced (the previous save's, or a killed save's), and so
    // are the temporaries killed saves left for it.
    const fs::path other = vdbPath == names[0] ? names[1] : names[0];
    std::error_code ec;
    fs::remove(other, ec);
    removeStaleTemporaries(other.string());
}

Scene makeDefaultScene() {
    constexpr float SIZE = 40.f;  // mm, overall height of the thin-thick shape
    Scene scene;
    scene.eta = 1.3f;
    MeshSource ms;
    ms.procedural = "thin-thick";
    ms.params = {SIZE};
    MaterialSource mt;
    mt.preset = "skin1";
    mt.value = findPreset(mt.preset).sample();
    mt.resolution = GridSpec::DEFAULT_RESOLUTION;
    SceneObject obj = buildObject(ms, mt, scene.eta, /*resolutionGiven=*/false, scene.warnings);
    obj.materialSource.preset.clear();  // painted below: no longer the plain preset
    obj.materialSource.uniform = true;

    // Heterogeneous pre-painting (deterministic): marble-like veins of a denser, more
    // absorbing material through the skin base, then the ears made more translucent.
    MaterialVolume& vol = *obj.material;
    ProceduralFill fill;
    fill.pattern = ProceduralPattern::Marble;
    fill.materialA = mt.value;
    fill.materialB = {mt.value.sigma_t * 3.f + Rgb(0.3f, 0.6f, 0.8f), mt.value.sigma_s * 3.f,
                      mt.value.g};
    fill.scale = 12.f;
    fill.amplitude = 4.f;
    fill.sharpness = 6.f;
    fill.direction = {0.3f, 1.f, 0.2f};
    fill.seed = 7;
    fillProcedural(vol, fill);
    BrushSettings brush;
    brush.mode = BrushMode::Multiply;
    brush.channels = uint8_t(Channel::SigmaT) | uint8_t(Channel::SigmaS);
    brush.value = {Rgb(0.5f), Rgb(0.5f), Rgb(1.f)};
    brush.radius = 0.3f * SIZE;
    brush.falloff = Falloff::Smooth;
    const Bounds3f b = obj.mesh.bounds();
    for (float side : {-1.f, 1.f})
        stamp(vol, brush, {side * 0.75f * b.hi.x, 0.f, 0.f});
    scene.objects.push_back(std::move(obj));

    Light back;  // behind the object (−z), slightly above: light bleeds through the ears
    back.type = Light::Type::Point;
    back.position = {0.f, 0.25f * SIZE, -2.5f * SIZE};
    back.intensity = Rgb(2.0e4f);
    scene.lights.push_back(back);
    Light key;  // weak front fill so the thick body is not black
    key.type = Light::Type::Point;
    key.position = {1.5f * SIZE, SIZE, 2.5f * SIZE};
    key.intensity = Rgb(2.0e3f);
    scene.lights.push_back(key);

    scene.camera.position = {0.f, 0.f, 3.f * SIZE};
    scene.camera.target = {0.f, 0.f, 0.f};
    scene.camera.up = {0.f, 1.f, 0.f};
    scene.camera.fovYDeg = 40.f;
    scene.camera.width = 512;
    scene.camera.height = 384;
    return scene;
}

}  // namespace lucent
