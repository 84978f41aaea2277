// Issue 28: the five readers of files a person may edit (scene files, study configs, session.json,
// calibration.json, display-calibration.json) refuse the same kinds of mistakes in the same words:
// "<file>: <field path>: <one wording per kind>" (common/json/json_fields.h).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <unistd.h>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "adaptive/calibration.h"
#include "display/display_calibration.h"
#include "json/json_input.h"
#include "procedure/config.h"
#include "procedure/session_record.h"
#include "scene/scene.h"

namespace fs = std::filesystem;
using namespace penumbra;

namespace {

const fs::path kDir = fs::temp_directory_path() / ("penumbra-json-readers-" + std::to_string(::getpid()));

// The error line of reading `text` as a file of `reader`'s kind named `name`, or "accepted".
using ReadFn = std::function<void(const fs::path&)>;

std::string error(const ReadFn& read, const std::string& name, const std::string& text) {
  fs::create_directories(kDir);
  const fs::path p = kDir / name;
  std::ofstream(p, std::ios::binary | std::ios::trunc) << text;
  try {
    read(p);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "accepted";
}

const ReadFn kScene = [](const fs::path& p) { scene::load_scene_file(p); };
const ReadFn kConfig = [](const fs::path& p) { procedure::load_config(p); };
const ReadFn kCalibration = [](const fs::path& p) { adaptive::load_calibration(p); };
const ReadFn kDisplay = [](const fs::path& p) { display::load_calibration(p); };
const ReadFn kSession = [](const fs::path& p) {
  procedure::check_session_json(json_input::read_file(p, {.max_bytes = 1 << 20, .max_depth = 16}), p.string());
};

// Valid files, each with a placeholder "@" (a JSON fragment, a field of the top object or of one
// inside it) where a test puts a mistake.
const std::string kSceneBase = R"({"camera": {"far_ws": 100 @}, "objects": [{"shape": "sphere", "radius": 1}]})";
const std::string kConfigBase = R"({"rounds": [{"pattern": "stair", "contrast": 1}], "quest": {"beta": 3.5 @}})";
const std::string kCalibrationBase = R"({"schema_version": 2, "entries": [{"technique": "pcf", "c": 3, "obtained_by": "study" @}]})";
const std::string kDisplayBase = [] {
  const double gamma = std::log(0.5) / std::log(186 / 255.0);
  return R"({"schema_version": 1, "model": "gamma", "method": "checkerboard-match", "gamma": )" + nlohmann::json(gamma).dump() +
         R"(, "points": [], "matched_level": 186 @})";
}();
const std::string kSessionBase =
    R"({"session_id": "s-1", "participant": "p", "seed": 1, "config": {}, "quest": {}, "display": {} @})";

std::string with(const std::string& base, const std::string& fragment) {
  std::string s = base;
  return s.replace(s.find('@'), 1, fragment);
}
std::string without(const std::string& base, const std::string& field) {
  nlohmann::json j = nlohmann::json::parse(with(base, ""));
  j.erase(field);
  return j.dump();
}

// The one wording of each kind.
std::string wrong_type(const std::string& expected, const std::string& got) { return "expected " + expected + ", got " + got; }
std::string out_of_range(const std::string& range, const std::string& got) { return "expected " + range + ", got " + got; }
std::string bad_choice(const std::string& field, const std::string& value, const std::string& choices) {
  return field + " '" + value + "': expected " + choices;
}
std::string unknown_key() { return "unknown key (allowed: "; }
std::string missing() { return "missing"; }

struct Case {
  const char* kind;
  const char* file;
  ReadFn read;
  std::string text, path, wording;
  bool prefix = false;  // the wording goes on (a list of allowed keys, a reason)
};

std::vector<Case> cases() {
  return {
      {"wrong type", "scene.json", kScene, with(kSceneBase, R"(, "near_ws": "0.1")"), "camera.near_ws", wrong_type("a number", "\"0.1\"")},
      {"wrong type", "study.json", kConfig, with(kConfigBase, R"(, "delta": "0.1")"), "quest.delta", wrong_type("a number", "\"0.1\"")},
      {"wrong type", "calibration.json", kCalibration, with(kCalibrationBase, R"(, "kernel": 3)"), "entries[0].kernel",
       wrong_type("a string", "3")},
      {"wrong type", "display-calibration.json", kDisplay, with(kDisplayBase, R"(, "source": 3)"), "source", wrong_type("a string", "3")},
      {"wrong type", "session.json", kSession, with(kSessionBase, R"(, "observer": 3)"), "observer", wrong_type("a string", "3")},

      {"out of range", "scene.json", kScene, with(kSceneBase, R"(, "fov_y_deg": 180)"), "camera.fov_y_deg",
       out_of_range("a number in (0, 180)", "180")},
      {"out of range", "scene.json", kScene, with(kSceneBase, R"(, "near_ws": -1)"), "camera.near_ws", out_of_range("a positive number", "-1")},
      {"out of range", "study.json", kConfig, with(kConfigBase, R"(, "delta": 0.7)"), "quest.delta", out_of_range("a number in [0, 0.5]", "0.7")},
      {"out of range", "calibration.json", kCalibration, with(kCalibrationBase, R"(, "trials": -1)"), "entries[0].trials",
       out_of_range("an integer in [0, 2147483647] or null", "-1")},
      {"out of range", "display-calibration.json", kDisplay, with(kDisplayBase, R"(, "black_cd_m2": 200000)"), "black_cd_m2",
       out_of_range("a number in [0, 100000] or null", "200000")},
      {"out of range", "session.json", kSession, with(kSessionBase, R"(, "randomization": {"seed": -1, "seed_from": "config", "round_order": []})"),
       "randomization.seed", out_of_range("a non-negative integer", "-1")},

      {"unknown key", "scene.json", kScene, with(kSceneBase, R"(, "fov": 40)"), "camera.fov", unknown_key(), true},
      {"unknown key", "study.json", kConfig, with(kConfigBase, R"(, "betta": 3)"), "quest.betta", unknown_key(), true},
      // calibration.json is open (its schema: additionalProperties true): penumbra-fit adds fields.
      {"unknown key", "display-calibration.json", kDisplay, with(kDisplayBase, R"(, "gama": 2)"), "gama", unknown_key(), true},
      {"unknown key", "session.json", kSession, with(kSessionBase, R"(, "sesion_id": "x")"), "sesion_id", unknown_key(), true},

      {"bad choice", "scene.json", kScene, with(kSceneBase, R"(, "projection": "ortho")"), "camera.projection",
       bad_choice("projection", "ortho", "perspective or orthographic")},
      {"bad choice", "study.json", kConfig, with(kConfigBase, "").replace(1, 0, R"("task": "3afc", )"), "task",
       bad_choice("task", "3afc", "2afc or yesno")},
      {"bad choice", "calibration.json", kCalibration, with(kCalibrationBase, "").replace(kCalibrationBase.find("study"), 5, "guess"),
       "entries[0].obtained_by", bad_choice("obtained_by", "guess", "study, image-observer, simulated, mixed or published")},
      {"bad choice", "display-calibration.json", kDisplay, with(kDisplayBase, "").replace(kDisplayBase.find("checkerboard-match"), 18, "spectro"),
       "method", bad_choice("method", "spectro", "photometer or checkerboard-match")},
      {"bad choice", "session.json", kSession, with(kSessionBase, R"(, "log": "log.csv")"), "log", bad_choice("log", "log.csv", "trials.csv")},

      {"missing", "scene.json", kScene, R"({"objects": [{"shape": "sphere"}]})", "objects[0].radius", missing(), true},
      {"missing", "study.json", kConfig, R"({"quest": {}})", "rounds", missing(), true},
      {"missing", "calibration.json", kCalibration, R"({"schema_version": 2})", "entries", missing()},
      {"missing", "display-calibration.json", kDisplay, without(kDisplayBase, "points"), "points", missing()},
      {"missing", "session.json", kSession, without(kSessionBase, "config"), "config", missing()},
  };
}

}  // namespace

TEST(JsonReaders, SameMistakesReadTheSameInEveryFile) {
  const std::vector<Case> table = cases();
  // The unchanged bases load (or fail only past the generic checks: a session's empty config).
  EXPECT_EQ(error(kScene, "scene.json", with(kSceneBase, "")), "accepted");
  EXPECT_EQ(error(kConfig, "study.json", with(kConfigBase, "")), "accepted");
  EXPECT_EQ(error(kCalibration, "calibration.json", with(kCalibrationBase, "")), "accepted");
  EXPECT_EQ(error(kDisplay, "display-calibration.json", with(kDisplayBase, "")), "accepted");
  EXPECT_EQ(error(kSession, "session.json", with(kSessionBase, "")).rfind((kDir / "session.json").string() + " (config): rounds: missing", 0), 0u);

  std::set<std::string> kinds_per_file;
  for (const Case& c : table) {
    SCOPED_TRACE(std::string(c.kind) + " in " + c.file);
    const std::string expected = (kDir / c.file).string() + ": " + c.path + ": " + c.wording;
    const std::string got = error(c.read, c.file, c.text);
    if (c.prefix) EXPECT_EQ(got.rfind(expected, 0), 0u) << got << "\n does not start with\n" << expected;
    else EXPECT_EQ(got, expected);
    kinds_per_file.insert(std::string(c.kind) + "/" + c.file);
  }
  // Every kind in every file (calibration.json takes unknown keys).
  EXPECT_EQ(kinds_per_file.size(), 5u * 5u - 1u);
  fs::remove_all(kDir);
}
