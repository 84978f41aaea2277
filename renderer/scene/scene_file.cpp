// JSON scene files (format: docs/scene-format.md). Every error names the file and the JSON field
// path, on one line, so a typo in a sweep's scene is caught before anything is rendered.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <map>
#include <new>
#include <optional>
#include <set>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <glm/gtc/matrix_transform.hpp>
#define GLM_ENABLE_EXPERIMENTAL
#include <glm/gtx/euler_angles.hpp>
#include <nlohmann/json.hpp>

#include "json/json_fields.h"
#include "json/json_input.h"
#include "scene/scene.h"
#include "text/printable.h"

namespace penumbra::scene {
namespace {

using nlohmann::json;

using text::one_line;

using json_input::describe;

std::string fmt(float f) {
  std::ostringstream s;
  s << f;
  return s.str();
}

using json_input::child;
using json_input::element;
using json_input::Field;
using json_input::Type;

// Reads one parsed scene document; every accessor checks type, range and finiteness through
// json_input::Reader (its errors, json_input::FieldError, become SceneError in load_scene_file).
class SceneReader {
 public:
  explicit SceneReader(std::filesystem::path file) : file_(std::move(file)), r_(file_.string()) {}

  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw SceneError(one_line(file_.string() + ": " + (path.empty() ? "(top level)" : path) + ": " + what));
  }

  void require_object(const json& v, const std::string& path) const { r_.check(v, path, {.type = Type::object}); }

  void check_keys(const json& obj, const std::string& path, std::initializer_list<std::string_view> allowed,
                  std::string_view context = {}) const {
    json_input::ObjectSpec spec;
    for (auto a : allowed) spec.fields.push_back({.name = std::string(a)});
    r_.object(obj, path, spec, context);
  }

  static const json* find(const json& obj, std::string_view key) {
    const auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
  }

  const json& required(const json& obj, const std::string& path, std::string_view key, const std::string& why) const {
    return *r_.get(obj, path, {.name = std::string(key), .required = true, .why = why});
  }

  // A number that a float holds (the renderer's type): 1e39 is refused, not made infinite.
  float number(const json& v, const std::string& path) const { return checked(v, path, {.type = Type::number}); }

  float positive(const json& v, const std::string& path) const {
    return checked(v, path, {.type = Type::number, .min = 0, .exclusive_min = true});
  }

  float non_zero(const json& v, const std::string& path) const {
    const float f = number(v, path);
    if (f == 0) fail(path, "expected a non-zero number, got " + describe(v));
    return f;
  }

  // Open interval (lo, hi).
  float open_range(const json& v, const std::string& path, float lo, float hi) const {
    return checked(v, path, {.type = Type::number, .min = lo, .max = hi, .exclusive_min = true, .exclusive_max = true});
  }

  float unit_interval(const json& v, const std::string& path) const {
    return checked(v, path, {.type = Type::number, .min = 0, .max = 1});
  }

  int integer(const json& v, const std::string& path, int lo, int hi) const {
    r_.check(v, path, {.type = Type::integer, .min = lo, .max = hi});
    return static_cast<int>(v.get<std::int64_t>());
  }

  std::string string(const json& v, const std::string& path) const {
    r_.check(v, path, {.type = Type::string});
    return v.get<std::string>();
  }

  // One of `names`; returns its index. The field's last name says what it is ("type 'point'").
  std::size_t choice(const json& v, const std::string& path, std::span<const std::string_view> names) const {
    Field f{.type = Type::string, .noun = path.substr(path.find_last_of(".]") + 1)};
    for (auto n : names) f.choices.emplace_back(n);
    r_.check(v, path, f);
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), v.get<std::string>()) - names.begin());
  }

  const json& array(const json& v, const std::string& path, std::size_t n) const {
    r_.check(v, path, {.type = Type::array, .min_items = n, .max_items = n, .items = json_input::item({.type = Type::number})});
    return v;
  }

  glm::vec2 vec2_positive(const json& v, const std::string& path) const {
    array(v, path, 2);
    return {positive(v[0], element(path, 0)), positive(v[1], element(path, 1))};
  }

  glm::vec3 vec3(const json& v, const std::string& path) const {
    array(v, path, 3);
    return {number(v[0], element(path, 0)), number(v[1], element(path, 1)), number(v[2], element(path, 2))};
  }

  template <class Check>
  glm::vec3 vec3(const json& v, const std::string& path, Check check) const {
    array(v, path, 3);
    glm::vec3 out;
    for (int i = 0; i < 3; ++i) out[i] = (this->*check)(v[static_cast<std::size_t>(i)], element(path, static_cast<std::size_t>(i)));
    return out;
  }

  glm::vec3 non_zero_vec3(const json& v, const std::string& path) const {
    const glm::vec3 out = vec3(v, path);
    if (out == glm::vec3(0)) fail(path, "must not be the zero vector");
    return out;
  }

  float colour_component(const json& v, const std::string& path) const {
    return checked(v, path, {.type = Type::number, .min = 0});
  }

  void check_field(const json& v, const std::string& path, const Field& f) const { r_.check(v, path, f); }

  const std::filesystem::path& file() const { return file_; }

 private:
  float checked(const json& v, const std::string& path, const Field& f) const {
    r_.check(v, path, f);
    const auto out = v.get<float>();
    if (!std::isfinite(out)) fail(path, "expected a finite number, got " + describe(v));
    // Rounded to a float, 1e-50 is no longer positive and 179.9999999 no longer below 180.
    if (!json_input::number_in_range(out, f)) fail(path, "expected " + json_input::range_phrase(f) + ", got " + describe(v));
    return out;
  }

  std::filesystem::path file_;
  json_input::Reader r_;
};

constexpr std::array<std::string_view, 2> kProjections = {"perspective", "orthographic"};
constexpr std::array<std::string_view, 2> kLightTypes = {"directional", "spot"};
constexpr std::array<std::string_view, 5> kShapes = {"plane", "box", "sphere", "lattice", "model"};

Camera read_camera(const SceneReader& r, const json& j, const std::string& path) {
  r.require_object(j, path);
  r.check_keys(j, path, {"projection", "position", "target", "up", "fov_y_deg", "ortho_height_ws", "near_ws", "far_ws"});
  Camera c;
  if (const json* v = r.find(j, "projection"))
    c.projection = r.choice(*v, child(path, "projection"), kProjections) == 0
                       ? Camera::Projection::perspective
                       : Camera::Projection::orthographic;
  if (const json* v = r.find(j, "position")) c.position = r.vec3(*v, child(path, "position"));
  if (const json* v = r.find(j, "target")) c.target = r.vec3(*v, child(path, "target"));
  if (const json* v = r.find(j, "up")) c.up = r.non_zero_vec3(*v, child(path, "up"));
  if (const json* v = r.find(j, "fov_y_deg")) c.fov_y_deg = r.open_range(*v, child(path, "fov_y_deg"), 0, 180);
  if (const json* v = r.find(j, "ortho_height_ws")) c.ortho_height_ws = r.positive(*v, child(path, "ortho_height_ws"));
  if (const json* v = r.find(j, "near_ws")) c.near_ws = r.positive(*v, child(path, "near_ws"));
  if (const json* v = r.find(j, "far_ws")) c.far_ws = r.positive(*v, child(path, "far_ws"));
  if (c.position == c.target) r.fail(child(path, "target"), "must differ from the camera position");
  if (!(c.far_ws > c.near_ws))
    r.fail(child(path, "far_ws"), "must be greater than near_ws (" + fmt(c.near_ws) + "), got " + fmt(c.far_ws));
  return c;
}

Light read_light(const SceneReader& r, const json& j, const std::string& path) {
  r.require_object(j, path);
  r.check_keys(j, path, {"type", "direction", "position", "spot_fov_deg", "size", "color", "ambient"});
  Light l;
  if (const json* v = r.find(j, "type"))
    l.type = r.choice(*v, child(path, "type"), kLightTypes) == 0 ? Light::Type::directional : Light::Type::spot;
  if (const json* v = r.find(j, "direction")) l.direction = glm::normalize(r.non_zero_vec3(*v, child(path, "direction")));
  if (!std::isfinite(l.direction.x + l.direction.y + l.direction.z))  // e.g. [1e-30, 0, 0] underflows
    r.fail(child(path, "direction"), "too short to normalize");
  if (const json* v = r.find(j, "position")) l.position = r.vec3(*v, child(path, "position"));
  if (const json* v = r.find(j, "spot_fov_deg")) l.spot_fov_deg = r.open_range(*v, child(path, "spot_fov_deg"), 0, 180);
  if (const json* v = r.find(j, "size")) {
    l.size = r.positive(*v, child(path, "size"));
    if (l.type == Light::Type::directional && l.size > Light::kMaxAngularDiameterDeg)
      r.fail(child(path, "size"), "a directional light's angular diameter must be at most 90 degrees (the sun's is 0.53)");
  }
  if (const json* v = r.find(j, "color")) l.color = r.vec3(*v, child(path, "color"), &SceneReader::colour_component);
  if (const json* v = r.find(j, "ambient")) l.ambient = r.unit_interval(*v, child(path, "ambient"));
  return l;
}

CameraPath read_camera_path(const SceneReader& r, const json& j, const std::string& path) {
  r.require_object(j, path);
  r.check_keys(j, path, {"keys"});
  const std::string keys_path = child(path, "keys");
  const json& keys = r.required(j, path, "keys", "a path needs its keys");
  r.check_field(keys, keys_path, {.type = Type::array, .min_items = 2, .items = json_input::item({.type = Type::object})});
  CameraPath out;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const std::string at = element(keys_path, i);
    const json& k = keys[i];
    r.require_object(k, at);
    r.check_keys(k, at, {"frame", "position", "target"});
    CameraKey key;
    key.frame = r.integer(r.required(k, at, "frame", "every key needs its frame"), child(at, "frame"), 0, 10'000'000);
    key.position = r.vec3(r.required(k, at, "position", "every key needs a position"), child(at, "position"));
    key.target = r.vec3(r.required(k, at, "target", "every key needs a target"), child(at, "target"));
    if (i == 0 && key.frame != 0) r.fail(child(at, "frame"), "the first key must be at frame 0, got " + std::to_string(key.frame));
    if (i > 0 && key.frame <= out.keys.back().frame)
      r.fail(child(at, "frame"), "frames must increase from key to key, got " + std::to_string(key.frame) + " after " +
                                     std::to_string(out.keys.back().frame));
    if (key.position == key.target) r.fail(child(at, "target"), "must differ from the key's position");
    out.keys.push_back(key);
  }
  return out;
}

// `object_paths`: each names exactly one of `scene`'s objects (read before), keys as a camera
// path's (at least 2, from frame 0, frames increasing) with a finite `translate` each.
std::vector<ObjectPath> read_object_paths(const SceneReader& r, const json& j, const std::string& path, const Scene& scene) {
  r.check_field(j, path, {.type = Type::array, .items = json_input::item({.type = Type::object})});
  std::vector<ObjectPath> out;
  for (std::size_t p = 0; p < j.size(); ++p) {
    const std::string at = element(path, p);
    const json& o = j[p];
    r.require_object(o, at);
    r.check_keys(o, at, {"object", "keys"});
    ObjectPath op;
    op.object = r.string(r.required(o, at, "object", "a path needs the name of the object it moves"), child(at, "object"));
    std::size_t named = 0;
    for (const Object& obj : scene.objects) named += obj.name == op.object;
    if (named != 1)
      r.fail(child(at, "object"), "must name exactly one object, '" + op.object + "' names " + std::to_string(named));
    // Two paths for one object: one would silently win over the other.
    for (std::size_t q = 0; q < out.size(); ++q)
      if (out[q].object == op.object)
        r.fail(child(at, "object"), "'" + op.object + "' already has a path (" + element(path, q) + "); give an object one path");
    const std::string keys_path = child(at, "keys");
    const json& keys = r.required(o, at, "keys", "a path needs its keys");
    r.check_field(keys, keys_path, {.type = Type::array, .min_items = 2, .items = json_input::item({.type = Type::object})});
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const std::string k_at = element(keys_path, i);
      r.require_object(keys[i], k_at);
      r.check_keys(keys[i], k_at, {"frame", "translate"});
      ObjectKey key;
      key.frame = r.integer(r.required(keys[i], k_at, "frame", "every key needs its frame"), child(k_at, "frame"), 0, 10'000'000);
      key.translate = r.vec3(r.required(keys[i], k_at, "translate", "every key needs a translate"), child(k_at, "translate"));
      if (i == 0 && key.frame != 0) r.fail(child(k_at, "frame"), "the first key must be at frame 0, got " + std::to_string(key.frame));
      if (i > 0 && key.frame <= op.keys.back().frame)
        r.fail(child(k_at, "frame"), "frames must increase from key to key, got " + std::to_string(key.frame) + " after " +
                                         std::to_string(op.keys.back().frame));
      op.keys.push_back(key);
    }
    out.push_back(std::move(op));
  }
  return out;
}

// Normals Assimp could not make (a vertex used only by degenerate triangles, a file's own bad
// normals) are rebuilt from the area-weighted normals of the triangles around the vertex.
void repair_normals(MeshData& m) {
  const auto bad = [](const glm::vec3& n) {
    const float len = glm::length(n);
    return !std::isfinite(len) || len < 1e-6f;
  };
  if (std::none_of(m.vertices.begin(), m.vertices.end(), [&](const Vertex& v) { return bad(v.normal); })) return;
  std::vector<glm::vec3> sum(m.vertices.size(), glm::vec3(0));
  for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const std::uint32_t a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
    const glm::vec3 n = glm::cross(m.vertices[b].position - m.vertices[a].position, m.vertices[c].position - m.vertices[a].position);
    for (auto i : {a, b, c}) sum[i] += n;
  }
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    if (!bad(m.vertices[i].normal)) {
      m.vertices[i].normal = glm::normalize(m.vertices[i].normal);
      continue;
    }
    m.vertices[i].normal = bad(sum[i]) ? glm::vec3(0, 1, 0) : glm::normalize(sum[i]);
  }
}

// Assimp 5.2 leaks the buffer of a base64 data URI it cannot decode (assimp/assimp#6508, open
// upstream; found by fuzz_model_gltf), so a .gltf's embedded buffers and images are checked here
// first, which also names the field. The file must be JSON as glTF 2.0 defines it (UTF-8, no
// duplicate keys): the strict reader's error line is returned as it is. Returns what is wrong, or
// nothing.
std::optional<std::string> gltf_data_uri_problem(const std::filesystem::path& file, const std::string& as_written) {
  json doc;
  try {
    std::ifstream in(file, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) return "cannot read the file";
    doc = json_input::parse(text, as_written, {.max_bytes = std::size_t{1} << 30, .max_depth = 128});
  } catch (const json_input::JsonError& e) {
    return e.what();
  }
  if (!doc.is_object()) return std::nullopt;
  for (const char* array : {"buffers", "images"}) {
    const auto list = doc.find(array);
    if (list == doc.end() || !list->is_array()) continue;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const json& item = (*list)[i];
      if (!item.is_object()) continue;
      const auto uri = item.find("uri");
      if (uri == item.end() || !uri->is_string()) continue;
      const std::string& u = uri->get_ref<const std::string&>();
      if (u.rfind("data:", 0) != 0) continue;
      const std::size_t comma = u.find(',');
      if (comma == std::string::npos || u.substr(0, comma).find(";base64") == std::string::npos) continue;
      const std::string_view payload = std::string_view(u).substr(comma + 1);
      const std::string field = std::string(array) + "[" + std::to_string(i) + "].uri";
      if (payload.size() % 4 != 0)
        return field + ": base64 data of " + std::to_string(payload.size()) + " characters (not a multiple of 4)";
      for (std::size_t k = 0; k < payload.size(); ++k) {
        const unsigned char c = static_cast<unsigned char>(payload[k]);
        const bool padding = c == '=' && k + 2 >= payload.size() && (k + 1 == payload.size() || payload[k + 1] == '=');
        if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '+' || c == '/' || padding) continue;
        char hex[8];
        std::snprintf(hex, sizeof hex, "0x%02x", c);
        return field + ": byte " + hex + " at character " + std::to_string(k) + " of the base64 data is not base64";
      }
    }
  }
  return std::nullopt;
}

// Where Assimp refused an OBJ file, the line that made it, for the error: Assimp's OBJ messages
// name no line ("vertex index out of range" for "v 0 0 zz"). Checks what the format requires of
// the lines Assimp reads: numbers in v/vn/vt, and in every face at least three corners whose
// indices (1-based, or negative: relative to the end) point at an element already read.
std::optional<std::string> obj_problem(const std::filesystem::path& file, const std::string& as_written) {
  std::ifstream in(file, std::ios::binary);
  std::string line;
  long counts[3] = {0, 0, 0};  // v, vt, vn
  for (int number = 1; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string key;
    words >> key;
    const std::string at = as_written + ":" + std::to_string(number) + ": ";
    const int kind = key == "v" ? 0 : key == "vt" ? 1 : key == "vn" ? 2 : -1;
    if (kind >= 0) {
      const int needed = kind == 1 ? 1 : 3;
      std::string word;
      int read = 0;
      for (; read < needed && words >> word; ++read) {
        char* end = nullptr;
        (void)std::strtod(word.c_str(), &end);
        if (end == word.c_str() || *end != '\0') return at + "'" + one_line(word) + "' in a '" + key + "' line is not a number";
      }
      if (read < needed) return at + "a '" + key + "' line needs " + std::to_string(needed) + " numbers";
      ++counts[kind];
    } else if (key == "f") {
      std::string corner;
      int corners = 0;
      while (words >> corner) {
        ++corners;
        std::size_t start = 0;
        for (int slot = 0; slot < 3 && start <= corner.size(); ++slot) {
          const std::size_t slash = corner.find('/', start);
          const std::string index = corner.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
          start = slash == std::string::npos ? corner.size() + 1 : slash + 1;
          if (index.empty() && slot > 0) continue;  // v//vn
          char* end = nullptr;
          const long i = std::strtol(index.c_str(), &end, 10);
          if (index.empty() || *end != '\0') return at + "face corner '" + one_line(corner) + "' is not an index";
          const long count = counts[slot];
          if (i == 0 || i > count || i < -count)
            return at + "face index " + std::to_string(i) + " is out of range (" + std::to_string(count) + " " +
                   (slot == 0 ? "vertices" : slot == 1 ? "texture coordinates" : "normals") + " before this line)";
        }
      }
      if (corners < 3) return at + "a face needs at least 3 corners, this one has " + std::to_string(corners);
    }
  }
  return std::nullopt;
}

// All triangles of every mesh in a model file, node transforms applied, as one mesh.
MeshData load_model(const SceneReader& r, const std::filesystem::path& file, const std::string& path, const std::string& as_written) {
  const std::string prefix = "cannot read model '" + as_written + "': ";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    // Said as what it is: a directory or /dev/null was "no such file".
    const auto status = std::filesystem::status(file, ec);
    const std::string what = !std::filesystem::exists(status)                ? "no such file"
                             : std::filesystem::is_directory(status)         ? "not a regular file (a directory)"
                             : std::filesystem::is_character_file(status)    ? "not a regular file (a device)"
                                                                              : "not a regular file";
    r.fail(path, prefix + what + " (looked for " + file.string() + ")");
  }

  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
  if (extension == ".gltf")
    if (const auto problem = gltf_data_uri_problem(file, as_written)) r.fail(path, prefix + *problem);

  Assimp::Importer importer;
  // Pre-transformed to world space but not joined by material: each node's mesh stays its own
  // draw unit for culling.
  importer.SetPropertyBool(AI_CONFIG_PP_PTV_KEEP_HIERARCHY, true);
  const aiScene* s = importer.ReadFile(file.string(), aiProcess_Triangulate | aiProcess_GenSmoothNormals |
                                                          aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices);
  if (!s) {
    if (extension == ".obj")
      if (const auto problem = obj_problem(file, as_written)) r.fail(path, "cannot read model " + *problem);
    r.fail(path, prefix + importer.GetErrorString());
  }

  MeshData out;
  for (unsigned mi = 0; mi < s->mNumMeshes; ++mi) {
    const aiMesh& mesh = *s->mMeshes[mi];
    const auto base = static_cast<std::uint32_t>(out.vertices.size());
    for (unsigned vi = 0; vi < mesh.mNumVertices; ++vi) {
      const aiVector3D& p = mesh.mVertices[vi];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        r.fail(path, "model '" + as_written + "' has a non-finite vertex position");
      const glm::vec3 n = mesh.mNormals ? glm::vec3(mesh.mNormals[vi].x, mesh.mNormals[vi].y, mesh.mNormals[vi].z) : glm::vec3(0);
      out.vertices.push_back({{p.x, p.y, p.z}, n});
    }
    // Points and lines (kept by Triangulate) have no surface; zero-area triangles add nothing.
    for (unsigned fi = 0; fi < mesh.mNumFaces; ++fi) {
      const aiFace& f = mesh.mFaces[fi];
      if (f.mNumIndices != 3) continue;
      const std::uint32_t a = base + f.mIndices[0], b = base + f.mIndices[1], c = base + f.mIndices[2];
      const glm::vec3 pa = out.vertices[a].position;
      if (glm::cross(out.vertices[b].position - pa, out.vertices[c].position - pa) == glm::vec3(0)) continue;
      out.indices.insert(out.indices.end(), {a, b, c});
    }
    out.close_unit();  // one unit per node's mesh
  }
  if (out.indices.empty()) r.fail(path, "model '" + as_written + "' contains no triangles");
  repair_normals(out);
  return out;
}

// Scale first, then rotation about the world X, Y and Z axes in that order, then translation.
glm::mat4 object_transform(const glm::vec3& translate, const glm::vec3& rotate_deg, const glm::vec3& scale) {
  glm::mat4 m = glm::translate(glm::mat4(1), translate);
  m = glm::rotate(m, glm::radians(rotate_deg.z), glm::vec3(0, 0, 1));
  m = glm::rotate(m, glm::radians(rotate_deg.y), glm::vec3(0, 1, 0));
  m = glm::rotate(m, glm::radians(rotate_deg.x), glm::vec3(1, 0, 0));
  return glm::scale(m, scale);
}

class ObjectReader {
 public:
  explicit ObjectReader(const SceneReader& r) : r_(r) {}

  Object read(const json& j, const std::string& path) {
    r_.require_object(j, path);
    const std::size_t shape = r_.choice(r_.required(j, path, "shape", "every object needs a shape"), child(path, "shape"), kShapes);
    const std::string shape_name(kShapes[shape]);
    const std::string where = "for shape '" + shape_name + "'";
    const std::string why = "required" + where;

    Object o;
    o.name = shape_name;
    switch (shape) {
      case 0:
        r_.check_keys(j, path, {"name", "shape", "size", "translate", "rotate_deg", "scale", "albedo"}, where);
        {
          const glm::vec2 size = r_.vec2_positive(r_.required(j, path, "size", why), child(path, "size"));
          o.mesh = primitive(shape, {size.x, size.y}, [&] { return make_plane(size.x, size.y); });
        }
        break;
      case 1:
        r_.check_keys(j, path, {"name", "shape", "size", "translate", "rotate_deg", "scale", "albedo"}, where);
        {
          const glm::vec3 size = r_.vec3(r_.required(j, path, "size", why), child(path, "size"), &SceneReader::positive);
          o.mesh = primitive(shape, {size.x, size.y, size.z}, [&] { return make_box(size); });
        }
        break;
      case 2:
        r_.check_keys(j, path, {"name", "shape", "radius", "translate", "rotate_deg", "scale", "albedo"}, where);
        {
          const float radius = r_.positive(r_.required(j, path, "radius", why), child(path, "radius"));
          o.mesh = primitive(shape, {radius}, [&] { return make_sphere(radius); });
        }
        break;
      case 3: {
        r_.check_keys(j, path,
                      {"name", "shape", "width", "height", "bars_x", "bars_y", "bar_width", "translate", "rotate_deg", "scale", "albedo"},
                      where);
        const float width = r_.positive(r_.required(j, path, "width", why), child(path, "width"));
        const float height = r_.positive(r_.required(j, path, "height", why), child(path, "height"));
        const int bars_x = r_.integer(r_.required(j, path, "bars_x", why), child(path, "bars_x"), 0, kMaxBars);
        const int bars_y = r_.integer(r_.required(j, path, "bars_y", why), child(path, "bars_y"), 0, kMaxBars);
        const float bar_width = r_.positive(r_.required(j, path, "bar_width", why), child(path, "bar_width"));
        if (bars_x + bars_y == 0) r_.fail(child(path, "bars_y"), "a lattice needs at least one bar (bars_x and bars_y are both 0)");
        o.mesh = primitive(shape, {width, height, static_cast<float>(bars_x), static_cast<float>(bars_y), bar_width},
                           [&] { return make_lattice(width, height, bars_x, bars_y, bar_width); });
        break;
      }
      default: {
        r_.check_keys(j, path, {"name", "shape", "path", "translate", "rotate_deg", "scale", "albedo"}, where);
        const std::string field = child(path, "path");
        const std::string as_written = r_.string(r_.required(j, path, "path", why), field);
        if (as_written.empty()) r_.fail(field, "expected a file path, got an empty string");
        const std::filesystem::path file = (r_.file().parent_path() / as_written).lexically_normal();
        auto& cached = models_[file];
        if (!cached) cached = share(load_model(r_, file, field, as_written));
        o.mesh = cached;
        o.name = std::filesystem::path(as_written).stem().string();
        break;
      }
    }

    if (const json* v = r_.find(j, "name")) o.name = r_.string(*v, child(path, "name"));
    glm::vec3 translate(0), rotate_deg(0), scale(1);
    if (const json* v = r_.find(j, "translate")) translate = r_.vec3(*v, child(path, "translate"));
    if (const json* v = r_.find(j, "rotate_deg")) rotate_deg = r_.vec3(*v, child(path, "rotate_deg"));
    if (const json* v = r_.find(j, "scale")) {
      // Zero would flatten the object and make its normal matrix singular.
      scale = v->is_number() ? glm::vec3(r_.non_zero(*v, child(path, "scale")))
                             : r_.vec3(*v, child(path, "scale"), &SceneReader::non_zero);
    }
    o.model = object_transform(translate, rotate_deg, scale);
    if (const json* v = r_.find(j, "albedo")) o.albedo = r_.vec3(*v, child(path, "albedo"), &SceneReader::unit_interval);
    return o;
  }

  std::size_t distinct_meshes() const { return models_.size() + primitives_.size(); }

 private:
  static constexpr int kMaxBars = 10000;  // beyond this a lattice is a typo, not a stimulus
  static std::shared_ptr<const MeshData> share(MeshData m) { return std::make_shared<const MeshData>(std::move(m)); }

  // One mesh per shape and parameters, shared by every object that names them, as the outdoor
  // town's instances share theirs: 10 000 equal boxes were 10 000 meshes (4.5 s to render).
  template <class Make>
  std::shared_ptr<const MeshData> primitive(std::size_t shape, std::vector<float> parameters, Make&& make) {
    auto& cached = primitives_[{shape, std::move(parameters)}];
    if (!cached) cached = share(make());
    return cached;
  }

  const SceneReader& r_;
  std::map<std::filesystem::path, std::shared_ptr<const MeshData>> models_;  // one mesh per file
  std::map<std::pair<std::size_t, std::vector<float>>, std::shared_ptr<const MeshData>> primitives_;
};

std::string read_text(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw SceneError(one_line(path.string() + ": cannot read scene file: " +
                              (std::filesystem::exists(path, ec) ? "not a regular file" : "no such file")));
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw SceneError(one_line(path.string() + ": cannot read scene file"));
  return text.str();
}

// Duplicate keys, overflow and syntax errors are refused by the shared strict reader.
json parse(const std::filesystem::path& path, const std::string& text) {
  try {
    return json_input::parse(text, path.string());
  } catch (const json_input::JsonError& e) {
    throw SceneError(one_line(e.what()));
  }
}

// --- writing ---------------------------------------------------------------------------------

// Shortest decimal that reads back as the same float.
std::string number(float f) {
  char buf[32];
  for (int digits = 6; digits <= 9; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, static_cast<double>(f));
    if (std::strtof(buf, nullptr) == f) break;
  }
  return buf;
}
std::string vec3_text(const glm::vec3& v) { return "[" + number(v.x) + ", " + number(v.y) + ", " + number(v.z) + "]"; }
std::string quoted(const std::string& s) { return json(s).dump(); }

// The mesh with `model` applied, as glTF 2.0 binary (positions and normals; materials are not
// part of the format, the scene file carries the albedo): one glTF mesh per draw unit, so that
// loading it back keeps the units (vertices two units share are written with each). Assimp's
// writer copies its whole buffer for every mesh it adds, so more than kMaxGlbMeshes units are
// written as that many runs of neighbouring units: the outdoor town is written in 1.5 s (one
// mesh per unit: 20 s; 64 runs: 6 s), its trees as 16 meshes of 16 or 17 trees.
constexpr std::size_t kMaxGlbMeshes = 16;
void write_glb(const MeshData& mesh, const glm::mat4& model, const std::filesystem::path& file) {
  MeshData world;
  world.append(mesh, model);
  std::vector<DrawUnit> units = mesh.draw_units();
  if (units.size() > kMaxGlbMeshes) {
    std::vector<DrawUnit> runs;
    for (std::size_t g = 0; g < kMaxGlbMeshes; ++g) {
      const std::size_t from = units.size() * g / kMaxGlbMeshes, to = units.size() * (g + 1) / kMaxGlbMeshes;
      DrawUnit run{units[from].first_index, 0, {}};
      for (std::size_t k = from; k < to; ++k) run.index_count += units[k].index_count, run.bounds.extend(units[k].bounds);
      runs.push_back(run);
    }
    units = std::move(runs);
  }
  const auto count = static_cast<unsigned>(units.size());
  aiScene scene;
  scene.mRootNode = new aiNode("root");
  scene.mRootNode->mNumMeshes = count;
  scene.mRootNode->mMeshes = new unsigned[count];
  scene.mNumMaterials = 1;
  scene.mMaterials = new aiMaterial*[1]{new aiMaterial()};
  scene.mNumMeshes = count;
  scene.mMeshes = new aiMesh*[count];
  std::vector<std::uint32_t> local(world.vertices.size());
  std::vector<std::uint32_t> used;
  for (unsigned u = 0; u < count; ++u) {
    scene.mRootNode->mMeshes[u] = u;
    aiMesh& m = *(scene.mMeshes[u] = new aiMesh());
    used.clear();
    std::fill(local.begin(), local.end(), ~0u);
    const DrawUnit& unit = units[u];
    for (std::uint32_t i = unit.first_index; i < unit.first_index + unit.index_count; ++i)
      if (local[world.indices[i]] == ~0u) local[world.indices[i]] = static_cast<std::uint32_t>(used.size()), used.push_back(world.indices[i]);
    m.mMaterialIndex = 0;
    m.mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    m.mNumVertices = static_cast<unsigned>(used.size());
    m.mVertices = new aiVector3D[m.mNumVertices];
    m.mNormals = new aiVector3D[m.mNumVertices];
    for (unsigned i = 0; i < m.mNumVertices; ++i) {
      const Vertex& v = world.vertices[used[i]];
      m.mVertices[i] = {v.position.x, v.position.y, v.position.z};
      m.mNormals[i] = {v.normal.x, v.normal.y, v.normal.z};
    }
    m.mNumFaces = unit.index_count / 3;
    m.mFaces = new aiFace[m.mNumFaces];
    for (unsigned f = 0; f < m.mNumFaces; ++f) {
      const std::uint32_t* t = &world.indices[unit.first_index + 3 * f];
      m.mFaces[f].mNumIndices = 3;
      m.mFaces[f].mIndices = new unsigned[3]{local[t[0]], local[t[1]], local[t[2]]};
    }
  }
  Assimp::Exporter exporter;
  if (exporter.Export(&scene, "glb2", file.string()) != aiReturn_SUCCESS)
    throw SceneError(one_line(file.string() + ": cannot write model: " + exporter.GetErrorString()));
}

// An object's model matrix as the scene file's translate, rotate_deg (about X, then Y, then Z) and
// scale, when it is one: object_transform gives the matrix back from the written numbers within
// float rounding (no reflection, no shear). Instances are written so, sharing one model file.
struct Placement {
  glm::vec3 translate{0}, rotate_deg{0}, scale{1};
};
std::optional<Placement> placement_of(const glm::mat4& model) {
  const glm::mat3 m(model);
  if (model[0][3] != 0 || model[1][3] != 0 || model[2][3] != 0 || model[3][3] != 1) return std::nullopt;
  const glm::vec3 scale{glm::length(m[0]), glm::length(m[1]), glm::length(m[2])};
  if (!(scale.x > 0 && scale.y > 0 && scale.z > 0)) return std::nullopt;
  const glm::mat3 rotation(m[0] / scale.x, m[1] / scale.y, m[2] / scale.z);
  float size = 1;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) size = std::max(size, std::abs(model[c][r]));
  // The candidate as the file will hold it, if it gives `model` back.
  const auto exact = [&](glm::vec3 rotate_deg, glm::vec3 s, float per_deg, float per_unit) -> std::optional<Placement> {
    Placement p{glm::vec3(model[3]), rotate_deg, s};
    if (per_deg > 0) p.rotate_deg = glm::round(p.rotate_deg * per_deg) / per_deg;  // 90, not 89.99999
    if (per_unit > 0) p.scale = glm::round(p.scale * per_unit) / per_unit;         // 1, not 0.99999994
    for (glm::vec3* v : {&p.translate, &p.rotate_deg, &p.scale})
      for (int k = 0; k < 3; ++k) (*v)[k] = std::strtof(number((*v)[k]).c_str(), nullptr);
    const glm::mat4 back = object_transform(p.translate, p.rotate_deg, p.scale);
    float error = 0;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) error = std::max(error, std::abs(back[c][r] - model[c][r]));
    if (!(error <= 1e-5f * size)) return std::nullopt;
    return p;
  };
  // A turn about the vertical alone (instances on the ground), else the general Z·Y·X angles;
  // rounded where rounding changes nothing beyond float precision.
  const glm::vec3 about_y(0, glm::degrees(std::atan2(-rotation[0][2], rotation[0][0])), 0);
  float z = 0, y = 0, x = 0;
  glm::extractEulerAngleZYX(glm::mat4(rotation), z, y, x);  // rotation = Rz(z) Ry(y) Rx(x)
  const glm::vec3 general = glm::degrees(glm::vec3(x, y, z));
  for (const glm::vec3& angles : {about_y, general})
    for (const auto& [per_deg, per_unit] : {std::pair{1e3f, 1e6f}, std::pair{0.0f, 0.0f}})
      if (auto p = exact(angles, scale, per_deg, per_unit)) return p;
  return std::nullopt;
}

// A file name from an object's name: letters, digits, '-' and '_' kept, the rest '_'.
std::string file_stem(std::size_t index, const std::string& name) {
  std::string out = std::to_string(index) + "-";
  for (char c : name) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  return out;
}

Scene read_scene(const std::filesystem::path& path, const json& doc) {
  const SceneReader r(path);
  r.require_object(doc, "");
  r.check_keys(doc, "", {"name", "camera", "light", "camera_path", "object_paths", "objects"});

  Scene scene;
  scene.name = path.stem().string();
  if (const json* v = r.find(doc, "name")) scene.name = r.string(*v, "name");
  if (const json* v = r.find(doc, "camera")) scene.camera = read_camera(r, *v, "camera");
  if (const json* v = r.find(doc, "light")) scene.light = read_light(r, *v, "light");
  if (const json* v = r.find(doc, "camera_path")) scene.camera_path = read_camera_path(r, *v, "camera_path");
  if (const json* v = r.find(doc, "objects")) {
    r.check_field(*v, "objects", {.type = Type::array, .items = json_input::item({.type = Type::object})});
    ObjectReader objects(r);
    for (std::size_t i = 0; i < v->size(); ++i) {
      try {
        scene.objects.push_back(objects.read((*v)[i], element("objects", i)));
      } catch (const std::bad_alloc&) {
        // Said with the count it reached (100 000 objects ended in "std::bad_alloc", naming nothing).
        const std::size_t meshes = objects.distinct_meshes();
        scene.objects.clear();
        scene.objects.shrink_to_fit();
        r.fail(element("objects", i), "out of memory after " + std::to_string(i) + " of " + std::to_string(v->size()) +
                                           " objects (" + std::to_string(meshes) +
                                           " distinct meshes; objects of one shape and size, or one model file, share one)");
      }
    }
  }
  if (const json* v = r.find(doc, "object_paths")) {
    scene.object_paths = read_object_paths(r, *v, "object_paths", scene);
    // Objects are posed at a frame of the camera path: without one no frame poses them.
    if (!scene.object_paths.empty() && scene.camera_path.empty())
      r.fail("object_paths", "needs a camera_path: objects move over its frames, and this scene has none");
  }
  return scene;
}

}  // namespace

void write_scene_file(const Scene& scene, const std::filesystem::path& path) {
  if (path.extension() != ".json") throw SceneError(one_line(path.string() + ": a scene file must end in .json"));
  const std::filesystem::path models = path.stem();
  std::error_code ec;
  std::filesystem::create_directories(path.parent_path() / models, ec);
  if (ec) throw SceneError(one_line((path.parent_path() / models).string() + ": cannot create folder: " + ec.message()));

  const Camera& c = scene.camera;
  const Light& l = scene.light;
  std::ostringstream o;
  o << "{\n  \"name\": " << quoted(scene.name) << ",\n";
  o << "  \"camera\": {\"projection\": \"" << (c.projection == Camera::Projection::perspective ? "perspective" : "orthographic")
    << "\", \"position\": " << vec3_text(c.position) << ", \"target\": " << vec3_text(c.target) << ", \"up\": " << vec3_text(c.up)
    << ",\n             \"fov_y_deg\": " << number(c.fov_y_deg) << ", \"ortho_height_ws\": " << number(c.ortho_height_ws)
    << ", \"near_ws\": " << number(c.near_ws) << ", \"far_ws\": " << number(c.far_ws) << "},\n";
  o << "  \"light\": {\"type\": \"" << (l.type == Light::Type::directional ? "directional" : "spot") << "\", \"direction\": "
    << vec3_text(l.direction);
  if (l.type == Light::Type::spot) o << ", \"position\": " << vec3_text(l.position) << ", \"spot_fov_deg\": " << number(l.spot_fov_deg);
  o << ", \"size\": " << number(l.size) << ", \"color\": " << vec3_text(l.color) << ", \"ambient\": " << number(l.ambient) << "},\n";
  if (!scene.camera_path.empty()) {
    o << "  \"camera_path\": {\"keys\": [\n";
    for (std::size_t i = 0; i < scene.camera_path.keys.size(); ++i) {
      const CameraKey& k = scene.camera_path.keys[i];
      o << "    {\"frame\": " << k.frame << ", \"position\": " << vec3_text(k.position) << ", \"target\": " << vec3_text(k.target) << "}"
        << (i + 1 < scene.camera_path.keys.size() ? "," : "") << "\n";
    }
    o << "  ]},\n";
  }
  if (!scene.object_paths.empty()) {
    o << "  \"object_paths\": [\n";
    for (std::size_t p = 0; p < scene.object_paths.size(); ++p) {
      const ObjectPath& op = scene.object_paths[p];
      path_object(scene, op);  // exactly one object has the name, or the file would not load
      o << "    {\"object\": " << quoted(op.object) << ", \"keys\": [";
      for (std::size_t i = 0; i < op.keys.size(); ++i)
        o << (i ? ", " : "") << "{\"frame\": " << op.keys[i].frame << ", \"translate\": " << vec3_text(op.keys[i].translate) << "}";
      o << "]}" << (p + 1 < scene.object_paths.size() ? "," : "") << "\n";
    }
    o << "  ],\n";
  }
  // A mesh several objects share (instances) is written once in its own space when every one of
  // them has a placement (translate, rotate_deg, scale); any other mesh is written in world space.
  std::map<const MeshData*, std::vector<std::size_t>> users;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) users[scene.objects[i].mesh.get()].push_back(i);
  std::vector<std::optional<Placement>> placed(scene.objects.size());
  for (const auto& [mesh, objects] : users) {
    if (objects.size() < 2) continue;
    std::vector<std::optional<Placement>> p;
    for (std::size_t i : objects) p.push_back(placement_of(scene.objects[i].model));
    if (std::all_of(p.begin(), p.end(), [](const auto& v) { return v.has_value(); }))
      for (std::size_t k = 0; k < objects.size(); ++k) placed[objects[k]] = p[k];
  }
  std::map<const MeshData*, std::filesystem::path> written;
  o << "  \"objects\": [\n";
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& obj = scene.objects[i];
    std::filesystem::path model = models / (file_stem(i, obj.name) + ".glb");
    if (!placed[i]) {
      write_glb(*obj.mesh, obj.model, path.parent_path() / model);
    } else if (const auto w = written.find(obj.mesh.get()); w != written.end()) {
      model = w->second;
    } else {
      write_glb(*obj.mesh, glm::mat4(1), path.parent_path() / model);
      written.emplace(obj.mesh.get(), model);
    }
    o << "    {\"name\": " << quoted(obj.name) << ", \"shape\": \"model\", \"path\": " << quoted(model.generic_string());
    if (placed[i]) {
      o << ", \"translate\": " << vec3_text(placed[i]->translate);
      if (placed[i]->rotate_deg != glm::vec3(0)) o << ", \"rotate_deg\": " << vec3_text(placed[i]->rotate_deg);
      if (placed[i]->scale != glm::vec3(1)) o << ", \"scale\": " << vec3_text(placed[i]->scale);
    }
    o << ", \"albedo\": " << vec3_text(obj.albedo) << "}" << (i + 1 < scene.objects.size() ? "," : "") << "\n";
  }
  o << "  ]\n}\n";

  // The scene file last, through a temporary name: a reader never sees a half-written file.
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << o.str();
    out.close();
    if (!out) throw SceneError(one_line(path.string() + ": cannot write scene file"));
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw SceneError(one_line(path.string() + ": cannot write scene file: " + ec.message()));
}

Scene load_scene_file(const std::filesystem::path& path) {
  try {
    return read_scene(path, parse(path, read_text(path)));
  } catch (const json_input::FieldError& e) {
    throw SceneError(one_line(e.what()));
  }
}

}  // namespace penumbra::scene
