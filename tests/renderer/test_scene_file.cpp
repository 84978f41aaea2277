// Scene files: the shipped examples load as documented, models merge into one mesh, and every bad
// file is rejected with one line naming the file and the JSON field.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/scene.h"

namespace fs = std::filesystem;
using namespace penumbra::scene;

namespace {

const fs::path kScenes = fs::path(PENUMBRA_SOURCE_DIR) / "data" / "scenes";

std::size_t triangles(const Object& o) { return o.mesh->indices.size() / 3; }

const Object& find(const Scene& s, const std::string& name) {
  for (const auto& o : s.objects)
    if (o.name == name) return o;
  throw std::runtime_error("no object " + name);
}

void expect_near(const glm::vec3& got, const glm::vec3& want, float tol = 1e-4f) {
  EXPECT_NEAR(got.x, want.x, tol);
  EXPECT_NEAR(got.y, want.y, tol);
  EXPECT_NEAR(got.z, want.z, tol);
}

void expect_unit_normals(const MeshData& m) {
  for (const auto& v : m.vertices) {
    ASSERT_TRUE(std::isfinite(v.normal.x) && std::isfinite(v.normal.y) && std::isfinite(v.normal.z));
    ASSERT_NEAR(glm::length(v.normal), 1.0f, 1e-4f);
  }
}

// A fresh folder per test for hand-made scene and model files.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "_" + info->name();
    for (char& c : name)
      if (c == '/') c = '_';
    dir_ = fs::path(::testing::TempDir()) / ("penumbra_scene_file_" + name);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~TempDir() { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  const fs::path& path() const { return dir_; }

 private:
  fs::path dir_;
};

}  // namespace

TEST(SceneFile, ShapesExampleLoads) {
  const Scene s = load_scene_file(kScenes / "shapes.json");
  EXPECT_EQ(s.name, "shapes");
  ASSERT_EQ(s.objects.size(), 5u);
  EXPECT_EQ(s.objects[2].name, "ball");
  EXPECT_EQ(s.light.type, Light::Type::spot);
  EXPECT_NEAR(glm::length(s.light.direction), 1.0f, 1e-6f);
  expect_near(s.light.direction, glm::normalize(glm::vec3(-6, -10, -6)));
  EXPECT_FLOAT_EQ(s.light.spot_fov_deg, 70);
  EXPECT_FLOAT_EQ(s.light.ambient, 0.15f);
  EXPECT_FLOAT_EQ(s.camera.far_ws, 60);
  EXPECT_FLOAT_EQ(s.camera.up.y, 1);  // default kept
  expect_near(s.objects[0].albedo, {0.85f, 0.85f, 0.85f});
  expect_near(s.objects[4].albedo, Object{}.albedo);  // default kept

  // Ground is 20 × 20 at y = 0; the panel tilted by 60° about x reaches 2 + 2 sin 60° = 3.732.
  const Aabb b = s.bounds();
  expect_near(b.lo, {-10, 0, -10});
  expect_near(b.hi, {10, 2 + 2 * std::sin(glm::radians(60.0f)), 10});
  // Fence: 4 wide around x = 4, plus half a bar on each side.
  const Aabb fence = find(s, "fence").mesh->bounds().transformed(find(s, "fence").model);
  EXPECT_NEAR(fence.lo.x, 1.96f, 1e-4f);
  EXPECT_NEAR(fence.hi.x, 6.04f, 1e-4f);
  EXPECT_EQ(triangles(find(s, "fence")), (9u + 5u) * 12u);
}

TEST(SceneFile, ModelsExampleLoads) {
  const Scene s = load_scene_file(kScenes / "models.json");
  ASSERT_EQ(s.objects.size(), 4u);
  EXPECT_EQ(s.light.type, Light::Type::directional);
  EXPECT_NEAR(glm::length(s.light.direction), 1.0f, 1e-6f);
  EXPECT_FLOAT_EQ(s.light.size, 1.5f);

  const Object& tetra = find(s, "tetra");
  EXPECT_EQ(triangles(tetra), 4u);
  EXPECT_EQ(tetra.mesh, find(s, "small-tetra").mesh);  // one mesh per model file
  expect_unit_normals(*tetra.mesh);
  expect_near(tetra.mesh->bounds().lo, {0, 0, 0});
  expect_near(tetra.mesh->bounds().hi, {1, 1, 1});

  // The glTF's node graph (lift by 0.5, scale x and z by 2) is baked into the mesh.
  const Object& pyramid = find(s, "pyramid");
  EXPECT_EQ(triangles(pyramid), 6u);
  expect_unit_normals(*pyramid.mesh);
  expect_near(pyramid.mesh->bounds().lo, {-1, 0.5f, -1});
  expect_near(pyramid.mesh->bounds().hi, {1, 1.5f, 1});

  const Aabb b = s.bounds();
  expect_near(b.lo, {-5, 0, -5});
  expect_near(b.hi, {5, 1.5f, 5});
}

TEST(SceneFile, RotationIsXThenYThenZAfterScale) {
  TempDir dir;
  const Scene s = load_scene_file(dir.write("r.json", R"({"objects": [
    {"shape": "box", "size": [1, 1, 1], "rotate_deg": [90, 90, 0], "translate": [10, 0, 0]},
    {"shape": "box", "size": [1, 1, 1], "rotate_deg": [0, 0, 90], "scale": [2, 1, 1]}]})"));
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.name, "r");
  EXPECT_EQ(s.objects[0].name, "box");
  // +z turned 90° about x becomes -y, which 90° about y leaves alone (y first would give +x).
  expect_near(glm::vec3(s.objects[0].model * glm::vec4(0, 0, 1, 1)), {10, -1, 0});
  // Scaled to (2, 0, 0) first, then turned 90° about z.
  expect_near(glm::vec3(s.objects[1].model * glm::vec4(1, 0, 0, 1)), {0, 2, 0});
}

TEST(SceneFile, EmptyObjectListAndDefaults) {
  TempDir dir;
  const Scene s = load_scene_file(dir.write("e.json", "{}"));
  EXPECT_TRUE(s.objects.empty());
  EXPECT_TRUE(s.bounds().empty());
  expect_near(s.camera.position, Camera{}.position);
  expect_near(s.light.direction, Light{}.direction);
}

TEST(SceneFile, ModelQuadsAreTriangulatedAndDegenerateTrianglesDropped) {
  TempDir dir;
  // A unit square as one quad, a triangle repeating a vertex, and a zero-area sliver through a
  // vertex (5) that no other face uses.
  dir.write("m.obj",
            "v 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nv 2 0 0\n"
            "f 1 2 3 4\nf 1 1 2\nf 1 2 5\n");
  const Scene s = load_scene_file(dir.write("s.json", R"({"objects": [{"shape": "model", "path": "m.obj"}]})"));
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.objects[0].name, "m");
  EXPECT_EQ(triangles(s.objects[0]), 2u);
  expect_unit_normals(*s.objects[0].mesh);
  for (auto i : s.objects[0].mesh->indices) EXPECT_NEAR(s.objects[0].mesh->vertices[i].normal.y, 1.0f, 1e-5f);
}

TEST(SceneFile, ModelPathIsRelativeToTheSceneFile) {
  TempDir dir;
  fs::create_directories(dir.path() / "sub" / "meshes");
  dir.write("sub/meshes/t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const Scene s = load_scene_file(dir.write("sub/s.json", R"({"objects": [{"shape": "model", "path": "meshes/t.obj"}]})"));
  EXPECT_EQ(triangles(s.objects.at(0)), 1u);
}

// A .gltf whose embedded buffer is not base64 is refused before Assimp sees it (Assimp 5.2 leaks
// the decode buffer on it, assimp/assimp#6508), naming the field; the valid file still loads.
TEST(SceneFile, GltfDataUriThatIsNotBase64IsRefusedNamingTheField) {
  std::ifstream in(kScenes / "models" / "pyramid.gltf");
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t data = good.find(";base64,");
  ASSERT_NE(data, std::string::npos);
  const std::size_t payload = data + 8;
  struct Corruption {
    std::size_t at;
    std::string bytes;  // replaces `count` characters
    std::string expected;
    std::size_t count = 1;
  };
  const std::string field = "buffers[0].uri: ";
  for (const Corruption& c : {Corruption{10, "\xc3\xa4", field + "byte 0xc3 at character 10 of the base64 data is not base64", 2},
                              Corruption{4, "!", field + "byte 0x21 at character 4 of the base64 data is not base64"},
                              Corruption{0, "=", field + "byte 0x3d at character 0 of the base64 data is not base64"},
                              Corruption{7, "", field + "base64 data of 127 characters (not a multiple of 4)"},
                              // Not UTF-8 (the fuzzer's input): not JSON as glTF defines it. The
                              // strict reader names the line and column (nlohmann counts the bad byte read).
                              Corruption{57, "\xd5", "m.gltf:" + std::to_string(1 + std::count(good.begin(), good.begin() + payload, '\n')) +
                                                         ":" + std::to_string(payload + 58 - good.rfind('\n', payload)) +
                                                         ": malformed JSON: syntax error while parsing value - invalid string: ill-formed UTF-8 byte"}}) {
    SCOPED_TRACE(c.expected);
    TempDir dir;
    std::string bad = good;
    bad.replace(payload + c.at, c.count, c.bytes);
    dir.write("m.gltf", bad);
    try {
      load_scene_file(dir.write("s.json", R"({"objects": [{"shape": "model", "path": "m.gltf"}]})"));
      FAIL() << "accepted a buffer that is not base64";
    } catch (const SceneError& e) {
      const std::string expected = "objects[0].path: cannot read model 'm.gltf': " + c.expected;
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
      EXPECT_LT(std::string(e.what()).size(), 400u) << e.what();
    }
  }
}

struct BadCase {
  const char* name;
  const char* json;
  const char* expected;  // must follow "<file>: " in what(), or "<file>" when it starts with ':' (line:col)
};

// Keeps the parameter's name (not its bytes) in the test names CTest lists.
void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

class BadSceneFile : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadSceneFile, NamesFileAndField) {
  TempDir dir;
  dir.write("junk.glb", "this is not a binary glTF file at all");
  dir.write("lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n");
  dir.write("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
  // Issue 27: Assimp's own text named no line ("vertex index out of range" for a bad number).
  dir.write("bad-number.obj", "v 0 0 0\nv 1 0 zz\nv 0 1 0\nf 1 2 3\n");
  dir.write("bad-index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n# a comment\nf 1 2 7\n");
  dir.write("bad-corner.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n");
  const fs::path file = dir.write("bad.json", GetParam().json);
  try {
    load_scene_file(file);
    FAIL() << "accepted a bad scene file";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    const std::string expected = file.string() + (GetParam().expected[0] == ':' ? "" : ": ") + GetParam().expected;
    EXPECT_NE(what.find(expected), std::string::npos) << what << "\n does not contain\n" << expected;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(what.find('\r'), std::string::npos) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Cases, BadSceneFile,
    ::testing::Values(
        BadCase{"MalformedJson", "{\n  \"objects\": [\n    {\"shape\": \"box\" \"size\": [1, 1, 1]}\n  ]\n}\n",
                ":3:26: malformed JSON"},
        BadCase{"NumberOverflow", "{\"light\": {\n\"size\": 1e400}}", ":2:9: malformed JSON: number overflow"},
        BadCase{"TopLevelNotObject", "[1, 2]", "(top level): expected an object, got an array of 2 elements"},
        BadCase{"UnknownTopLevelKey", R"({"objcts": []})", "objcts: unknown key"},
        BadCase{"DuplicateKey", R"({"objects": [{"shape": "sphere", "radius": 1, "radius": 2}]})",
                "objects[0].radius: duplicate key"},
        BadCase{"NegativeRadius",
                R"({"objects": [{"shape": "plane", "size": [1, 1]}, {"shape": "box", "size": [1, 1, 1]},
                                {"shape": "sphere", "radius": -1}]})",
                "objects[2].radius: expected a positive number, got -1"},
        BadCase{"MisspeltShapeParameter", R"({"objects": [{"shape": "sphere", "radus": 1}]})",
                "objects[0].radus: unknown key for shape 'sphere'"},
        BadCase{"ParameterOfAnotherShape", R"({"objects": [{"shape": "box", "size": [1, 1, 1], "radius": 1}]})",
                "objects[0].radius: unknown key for shape 'box'"},
        BadCase{"MissingRadius", R"({"objects": [{"shape": "sphere"}]})", "objects[0].radius: missing"},
        BadCase{"MissingShape", R"({"objects": [{"radius": 1}]})", "objects[0].shape: missing"},
        BadCase{"UnknownShape", R"({"objects": [{"shape": "cube"}]})", "objects[0].shape: shape 'cube': expected plane, box, sphere, lattice or model"},
        BadCase{"ObjectNotAnObject", R"({"objects": [{"shape": "sphere", "radius": 1}, 7]})",
                "objects[1]: expected an object, got 7"},
        BadCase{"ObjectsNotAnArray", R"({"objects": {"shape": "sphere"}})", "objects: expected an array"},
        BadCase{"ZeroLightDirection", R"({"light": {"direction": [0, 0, 0]}})", "light.direction: must not be the zero vector"},
        BadCase{"SpotFovOutOfRange", R"({"light": {"type": "spot", "spot_fov_deg": 180}})",
                "light.spot_fov_deg: expected a number in (0, 180), got 180"},
        BadCase{"AmbientOutOfRange", R"({"light": {"ambient": 1.5}})", "light.ambient: expected a number in [0, 1]"},
        BadCase{"UnknownLightType", R"({"light": {"type": "point"}})", "light.type: type 'point': expected directional or spot"},
        BadCase{"UnknownProjection", R"({"camera": {"projection": "ortho"}})", "camera.projection: projection 'ortho': expected perspective or orthographic"},
        BadCase{"FarBeforeNear", R"({"camera": {"near_ws": 5, "far_ws": 2}})", "camera.far_ws: must be greater than near_ws"},
        BadCase{"UnknownCameraKey", R"({"camera": {"fov": 40}})", "camera.fov: unknown key"},
        BadCase{"ShortTranslate", R"({"objects": [{"shape": "sphere", "radius": 1, "translate": [1, 2]}]})",
                "objects[0].translate: expected an array of 3 numbers, got an array of 2 elements"},
        BadCase{"FloatOverflowInVector", R"({"objects": [{"shape": "sphere", "radius": 1, "translate": [0, 1e39, 0]}]})",
                "objects[0].translate[1]: expected a finite number"},
        BadCase{"StringForNumber", R"({"camera": {"fov_y_deg": "50"}})", "camera.fov_y_deg: expected a number, got \"50\""},
        BadCase{"BoolForNumber", R"({"objects": [{"shape": "sphere", "radius": true}]})",
                "objects[0].radius: expected a number, got true"},
        BadCase{"AlbedoOutOfRange", R"({"objects": [{"shape": "sphere", "radius": 1, "albedo": [0.5, 1.5, 0]}]})",
                "objects[0].albedo[1]: expected a number in [0, 1], got 1.5"},
        BadCase{"ZeroScale", R"({"objects": [{"shape": "sphere", "radius": 1, "scale": 0}]})",
                "objects[0].scale: expected a non-zero number, got 0"},
        BadCase{"ZeroScaleComponent", R"({"objects": [{"shape": "sphere", "radius": 1, "scale": [1, 0, 1]}]})",
                "objects[0].scale[1]: expected a non-zero number, got 0"},
        BadCase{"FractionalBarCount",
                R"({"objects": [{"shape": "lattice", "width": 1, "height": 1, "bars_x": 2.5, "bars_y": 2, "bar_width": 0.1}]})",
                "objects[0].bars_x: expected an integer"},
        BadCase{"PlaneSizeHasThreeNumbers", R"({"objects": [{"shape": "plane", "size": [1, 1, 1]}]})",
                "objects[0].size: expected an array of 2 numbers"},
        BadCase{"MissingModel", R"({"objects": [{"shape": "model", "path": "missing.glb"}]})",
                "objects[0].path: cannot read model 'missing.glb': no such file"},
        BadCase{"UnreadableModel", R"({"objects": [{"shape": "model", "path": "junk.glb"}]})",
                "objects[0].path: cannot read model 'junk.glb': "},
        BadCase{"ModelWithOnlyLines", R"({"objects": [{"shape": "model", "path": "lines.obj"}]})",
                "objects[0].path: model 'lines.obj' contains no triangles"},
        BadCase{"ModelWithOnlyDegenerateTriangles", R"({"objects": [{"shape": "model", "path": "flat.obj"}]})",
                "objects[0].path: model 'flat.obj' contains no triangles"},
        BadCase{"ObjNotANumberNamesItsLine", R"({"objects": [{"shape": "model", "path": "bad-number.obj"}]})",
                "objects[0].path: cannot read model bad-number.obj:2: 'zz' in a 'v' line is not a number"},
        BadCase{"ObjIndexOutOfRangeNamesItsLine", R"({"objects": [{"shape": "model", "path": "bad-index.obj"}]})",
                "objects[0].path: cannot read model bad-index.obj:5: face index 7 is out of range (3 vertices before this line)"},
        BadCase{"ObjCornerNotAnIndexNamesItsLine", R"({"objects": [{"shape": "model", "path": "bad-corner.obj"}]})",
                "objects[0].path: cannot read model bad-corner.obj:4: face corner 'x' is not an index"},
        BadCase{"EmptyFile", "", ":1:1: malformed JSON"},
        BadCase{"PathWithOneKey", R"({"camera_path": {"keys": [{"frame": 0, "position": [0, 1, 0], "target": [1, 1, 0]}]}})",
                "camera_path.keys: expected an array of at least 2 objects, got an array of 1 element"},
        BadCase{"PathNotFromFrameZero",
                R"({"camera_path": {"keys": [{"frame": 1, "position": [0, 1, 0], "target": [1, 1, 0]},
                                             {"frame": 5, "position": [1, 1, 0], "target": [2, 1, 0]}]}})",
                "camera_path.keys[0].frame: the first key must be at frame 0, got 1"},
        BadCase{"PathFramesNotIncreasing",
                R"({"camera_path": {"keys": [{"frame": 0, "position": [0, 1, 0], "target": [1, 1, 0]},
                                             {"frame": 0, "position": [1, 1, 0], "target": [2, 1, 0]}]}})",
                "camera_path.keys[1].frame: frames must increase from key to key, got 0 after 0"},
        BadCase{"PathKeyLooksAtItself",
                R"({"camera_path": {"keys": [{"frame": 0, "position": [0, 1, 0], "target": [1, 1, 0]},
                                             {"frame": 3, "position": [1, 1, 0], "target": [1, 1, 0]}]}})",
                "camera_path.keys[1].target: must differ from the key's position"},
        BadCase{"PathKeyMisspelt",
                R"({"camera_path": {"keys": [{"frame": 0, "positon": [0, 1, 0], "target": [1, 1, 0]},
                                             {"frame": 3, "position": [1, 1, 0], "target": [2, 1, 0]}]}})",
                "camera_path.keys[0].positon: unknown key"},
        BadCase{"PathFractionalFrame",
                R"({"camera_path": {"keys": [{"frame": 0, "position": [0, 1, 0], "target": [1, 1, 0]},
                                             {"frame": 2.5, "position": [1, 1, 0], "target": [2, 1, 0]}]}})",
                "camera_path.keys[1].frame: expected an integer"},
        BadCase{"ObjectPathNamesNoObject",
                R"({"objects": [{"name": "a", "shape": "sphere", "radius": 1}],
                    "object_paths": [{"object": "b", "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 5, "translate": [1, 0, 0]}]}]})",
                "object_paths[0].object: must name exactly one object, 'b' names 0"},
        BadCase{"ObjectPathNamesTwoObjects",
                R"({"objects": [{"name": "a", "shape": "sphere", "radius": 1}, {"name": "a", "shape": "sphere", "radius": 2}],
                    "object_paths": [{"object": "a", "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 5, "translate": [1, 0, 0]}]}]})",
                "object_paths[0].object: must name exactly one object, 'a' names 2"},
        BadCase{"ObjectPathWithOneKey",
                R"({"objects": [{"name": "a", "shape": "sphere", "radius": 1}],
                    "object_paths": [{"object": "a", "keys": [{"frame": 0, "translate": [0, 0, 0]}]}]})",
                "object_paths[0].keys: expected an array of at least 2 objects, got an array of 1 element"},
        BadCase{"ObjectPathFramesNotIncreasing",
                R"({"objects": [{"name": "a", "shape": "sphere", "radius": 1}],
                    "object_paths": [{"object": "a", "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 0, "translate": [1, 0, 0]}]}]})",
                "object_paths[0].keys[1].frame: frames must increase from key to key, got 0 after 0"},
        BadCase{"ObjectPathUnknownKey",
                R"({"objects": [{"name": "a", "shape": "sphere", "radius": 1}],
                    "object_paths": [{"object": "a", "speed": 2, "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 5, "translate": [1, 0, 0]}]}]})",
                "object_paths[0].speed: unknown key"},
        // Issue 45: two paths for one object (the last won), and paths no frame poses.
        BadCase{"ObjectPathTwiceForOneObject",
                R"({"objects": [{"name": "a", "shape": "sphere", "radius": 1}],
                    "camera_path": {"keys": [{"frame": 0, "position": [0, 1, 5], "target": [0, 0, 0]},
                                             {"frame": 9, "position": [1, 1, 5], "target": [0, 0, 0]}]},
                    "object_paths": [{"object": "a", "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 5, "translate": [1, 0, 0]}]},
                                     {"object": "a", "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 5, "translate": [0, 0, 9]}]}]})",
                "object_paths[1].object: 'a' already has a path (object_paths[0]); give an object one path"},
        BadCase{"ObjectPathWithoutCameraPath",
                R"({"objects": [{"name": "a", "shape": "sphere", "radius": 1}],
                    "object_paths": [{"object": "a", "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 5, "translate": [1, 0, 0]}]}]})",
                "object_paths: needs a camera_path: objects move over its frames, and this scene has none"}),
    [](const ::testing::TestParamInfo<BadCase>& p) { return std::string(p.param.name); });

// The complete example in docs/scene-format.md stays a valid scene.
TEST(SceneFile, DocumentedExampleLoads) {
  std::ifstream in(fs::path(PENUMBRA_SOURCE_DIR) / "docs" / "scene-format.md");
  const std::string doc((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto start = doc.find("```json\n");
  ASSERT_NE(start, std::string::npos);
  const auto end = doc.find("```", start + 8);
  ASSERT_NE(end, std::string::npos);
  TempDir dir;
  fs::create_directories(dir.path() / "models");
  fs::copy_file(kScenes / "models" / "pyramid.gltf", dir.path() / "models" / "pyramid.gltf");
  const Scene s = load_scene_file(dir.write("example.json", doc.substr(start + 8, end - start - 8)));
  EXPECT_EQ(s.name, "example");
  EXPECT_EQ(s.objects.size(), 5u);
}

TEST(SceneFile, MissingSceneFile) {
  try {
    load_scene_file(kScenes / "no-such-scene.json");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-scene.json: cannot read scene file"), std::string::npos) << e.what();
  }
}

TEST(SceneFile, CameraPathPassesThroughItsKeys) {
  TempDir dir;
  const Scene s = load_scene_file(dir.write("p.json", R"({"camera": {"fov_y_deg": 40},
    "camera_path": {"keys": [{"frame": 0, "position": [0, 2, 0], "target": [10, 2, 0]},
                             {"frame": 10, "position": [10, 2, 0], "target": [20, 2, 0]},
                             {"frame": 40, "position": [10, 32, 0], "target": [0, 0, 0]}]}})"));
  const CameraPath& p = s.camera_path;
  ASSERT_EQ(p.keys.size(), 3u);
  EXPECT_EQ(p.frames(), 41);
  for (const CameraKey& k : p.keys) {
    const Camera c = p.at(s.camera, k.frame);
    expect_near(c.position, k.position);
    expect_near(c.target, k.target);
    EXPECT_FLOAT_EQ(c.fov_y_deg, 40);  // the scene camera's lens is kept
  }
  // Clamped beyond the ends; continuous in between (no jump larger than the keys' spacing allows).
  expect_near(p.at(s.camera, -5).position, p.keys.front().position);
  expect_near(p.at(s.camera, 100).position, p.keys.back().position);
  for (double f = 0; f < 40; f += 0.25)
    EXPECT_LT(glm::distance(p.at(s.camera, f).position, p.at(s.camera, f + 0.25).position), 0.6f) << f;
}

TEST(SceneFile, WrittenSceneReadsBack) {
  TempDir dir;
  Scene s = load_scene_file(kScenes / "shapes.json");
  s.camera_path.keys = {{0, {0, 2, 9}, {0, 1, 0}}, {30, {5, 12, 9}, {0, 0, 0}}};
  write_scene_file(s, dir.path() / "out" / "copy.json");
  EXPECT_FALSE(fs::exists(dir.path() / "out" / "copy.json.tmp"));
  const Scene back = load_scene_file(dir.path() / "out" / "copy.json");
  EXPECT_EQ(back.name, s.name);
  ASSERT_EQ(back.objects.size(), s.objects.size());
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    SCOPED_TRACE(s.objects[i].name);
    EXPECT_EQ(back.objects[i].name, s.objects[i].name);
    // The reader drops zero-area triangles (the sphere's poles, where float rounding decides which
    // of the thin ones have zero area); every other one comes back.
    MeshData placed;
    placed.append(*s.objects[i].mesh, s.objects[i].model);
    std::size_t with_area = 0;
    for (std::size_t t = 0; t < placed.indices.size(); t += 3) {
      const glm::vec3 a = placed.vertices[placed.indices[t]].position;
      with_area += glm::cross(placed.vertices[placed.indices[t + 1]].position - a, placed.vertices[placed.indices[t + 2]].position - a) !=
                   glm::vec3(0);
    }
    if (with_area == triangles(s.objects[i])) EXPECT_EQ(triangles(back.objects[i]), with_area);
    else EXPECT_NEAR(static_cast<double>(triangles(back.objects[i])), static_cast<double>(with_area), 0.01 * static_cast<double>(with_area));
    expect_near(back.objects[i].albedo, s.objects[i].albedo);
    // The transform is baked into the written mesh.
    const Aabb want = s.objects[i].mesh->bounds().transformed(s.objects[i].model);
    const Aabb got = back.objects[i].mesh->bounds().transformed(back.objects[i].model);
    expect_near(got.lo, want.lo, 1e-3f);
    expect_near(got.hi, want.hi, 1e-3f);
    expect_unit_normals(*back.objects[i].mesh);
  }
  expect_near(back.camera.position, s.camera.position);
  EXPECT_FLOAT_EQ(back.camera.far_ws, s.camera.far_ws);
  EXPECT_EQ(back.light.type, s.light.type);
  expect_near(back.light.position, s.light.position);
  expect_near(back.light.direction, s.light.direction);
  EXPECT_FLOAT_EQ(back.light.size, s.light.size);
  ASSERT_EQ(back.camera_path.keys.size(), 2u);
  EXPECT_EQ(back.camera_path.keys[1].frame, 30);
  expect_near(back.camera_path.keys[1].position, {5, 12, 9});
}

// Instances: objects sharing one mesh are written as one model file, each with its placement
// (any rotation about X, Y and Z, a scale per axis); a mirrored instance cannot be placed so, and
// its mesh's objects are written in world space, a file each. Both load back where they were.
TEST(SceneFile, InstancesShareOneWrittenModelUnlessOneIsMirrored) {
  const auto box = std::make_shared<const MeshData>(make_box({1, 2, 3}));
  const auto ball = std::make_shared<const MeshData>(make_sphere(0.5f, 8, 6));
  glm::mat4 turned = glm::translate(glm::mat4(1), {3, 1, -2});
  turned = glm::rotate(turned, glm::radians(35.0f), glm::vec3(0, 0, 1));
  turned = glm::rotate(turned, glm::radians(-70.0f), glm::vec3(0, 1, 0));
  turned = glm::rotate(turned, glm::radians(20.0f), glm::vec3(1, 0, 0));
  turned = glm::scale(turned, {2, 0.5f, 1.5f});
  Scene s;
  s.objects = {{"box", box, glm::mat4(1)},
               {"box", box, glm::translate(glm::mat4(1), {5, 0, 0})},
               {"box", box, turned},
               {"ball", ball, glm::translate(glm::mat4(1), {0, 3, 0})},
               {"ball", ball, glm::scale(glm::translate(glm::mat4(1), {0, -3, 0}), {-1, 1, 1})}};
  TempDir dir;
  write_scene_file(s, dir.path() / "inst.json");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path() / "inst"), fs::directory_iterator()), 3)
      << "one file for the boxes, one per ball";
  const Scene back = load_scene_file(dir.path() / "inst.json");
  ASSERT_EQ(back.objects.size(), s.objects.size());
  EXPECT_EQ(back.objects[0].mesh, back.objects[1].mesh);
  EXPECT_EQ(back.objects[0].mesh, back.objects[2].mesh);
  EXPECT_NE(back.objects[3].mesh, back.objects[4].mesh);
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    SCOPED_TRACE(i);
    const Aabb want = s.objects[i].mesh->bounds().transformed(s.objects[i].model);
    const Aabb got = back.objects[i].mesh->bounds().transformed(back.objects[i].model);
    expect_near(got.lo, want.lo, 1e-4f);
    expect_near(got.hi, want.hi, 1e-4f);
    if (i < 3) {  // the box's 24 vertices come back in order: each corner where it was
      MeshData placed_want, placed_got;
      placed_want.append(*s.objects[i].mesh, s.objects[i].model);
      placed_got.append(*back.objects[i].mesh, back.objects[i].model);
      ASSERT_EQ(placed_got.vertices.size(), placed_want.vertices.size());
      for (std::size_t v = 0; v < placed_want.vertices.size(); ++v)
        expect_near(placed_got.vertices[v].position, placed_want.vertices[v].position, 1e-4f);
    }
  }
}

// Issue 45: each primitive got its own mesh (10 000 equal boxes were 10 000 meshes, and 100 000
// ran out of memory). Objects of one shape and parameters share one mesh, whatever their
// placement, as the outdoor town's instances and one model file's objects do; others do not.
TEST(SceneFile, IdenticalPrimitivesShareOneMesh) {
  std::string objects;
  for (int i = 0; i < 500; ++i) {
    objects += R"({"shape": "box", "size": [0.2, 0.4, 0.2], "translate": [)" + std::to_string(i) + R"(, 0, 0]},)";
    objects += R"({"shape": "sphere", "radius": 0.5, "translate": [0, )" + std::to_string(i) + R"(, 0], "albedo": [1, 0, 0]},)";
  }
  objects += R"({"shape": "box", "size": [0.2, 0.4, 0.3]}, {"shape": "plane", "size": [10, 10]}, {"shape": "plane", "size": [10, 10]},)";
  objects += R"({"shape": "lattice", "width": 2, "height": 2, "bars_x": 3, "bars_y": 0, "bar_width": 0.1},)";
  objects += R"({"shape": "lattice", "width": 2, "height": 2, "bars_x": 0, "bars_y": 3, "bar_width": 0.1})";
  TempDir dir;
  const Scene s = load_scene_file(dir.write("many.json", R"({"objects": [)" + objects + "]}"));
  ASSERT_EQ(s.objects.size(), 1005u);
  std::set<const MeshData*> meshes;
  for (const Object& o : s.objects) meshes.insert(o.mesh.get());
  // 0.2 x 0.4 x 0.2 boxes, 0.5 spheres, the other box, the planes, two lattices.
  EXPECT_EQ(meshes.size(), 6u);
  EXPECT_EQ(s.objects[0].mesh, s.objects[998].mesh);
  EXPECT_EQ(s.objects[1].mesh, s.objects[999].mesh);
  EXPECT_NE(s.objects[0].mesh, s.objects[1000].mesh) << "another size is another mesh";
  EXPECT_EQ(s.objects[1001].mesh, s.objects[1002].mesh);
  EXPECT_NE(s.objects[1003].mesh, s.objects[1004].mesh) << "bars across, not along: another lattice";
  EXPECT_NE(s.objects[0].model, s.objects[2].model) << "each keeps its own placement";
  expect_near(s.objects[1].albedo, {1, 0, 0});
}

// Issue 45: a model path that is a directory or a device was "no such file".
TEST(SceneFile, AModelPathIsSaidAsWhatItIs) {
  TempDir dir;
  fs::create_directories(dir.path() / "folder.obj");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"folder.obj", "cannot read model 'folder.obj': not a regular file (a directory)"},
      {"/dev/null", "cannot read model '/dev/null': not a regular file (a device)"},
      {"missing.obj", "cannot read model 'missing.obj': no such file"}};
  for (const auto& [model, expected] : cases) {
    SCOPED_TRACE(model);
    const fs::path file = dir.write("m.json", R"({"objects": [{"shape": "model", "path": ")" + model + R"("}]})");
    try {
      load_scene_file(file);
      ADD_FAILURE() << "accepted";
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find("objects[0].path: " + expected), std::string::npos) << e.what();
    }
  }
}

// Issue 45: a directional light's angular diameter has a range: 180° made the model's tan(size / 2)
// infinite ("the shadow map's frame is not finite") and 400° rendered as 40°. A spot light's size is
// a width in world units and is not bounded so.
TEST(SceneFile, ADirectionalLightsAngularDiameterIsAtMost90Degrees) {
  TempDir dir;
  EXPECT_EQ(load_scene_file(dir.write("sun.json", R"({"light": {"size": 90}})")).light.size, 90.0f);
  EXPECT_EQ(load_scene_file(dir.write("spot.json", R"({"light": {"type": "spot", "size": 400}})")).light.size, 400.0f);
  for (const char* size : {"90.01", "180", "400", "1e6"}) {
    SCOPED_TRACE(size);
    const fs::path file = dir.write("wide.json", std::string(R"({"light": {"size": )") + size + "}}");
    try {
      load_scene_file(file);
      ADD_FAILURE() << "accepted";
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find("light.size: a directional light's angular diameter must be at most 90 degrees"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(SceneFile, WritingRefusesANameWithoutJson) {
  TempDir dir;
  EXPECT_THROW(write_scene_file(Scene{}, dir.path() / "scene.txt"), SceneError);
}

TEST(SceneFile, LoadSceneDispatchesOnJsonExtension) {
  EXPECT_EQ(load_scene((kScenes / "shapes.json").string()).objects.size(), 5u);
}
