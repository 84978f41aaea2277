#include "apps/display_geometry.h"

#include <nlohmann/json.hpp>

#include "json/json_fields.h"
#include "json/json_input.h"
#include "metrics/flip.h"

namespace penumbra::apps {

namespace ji = penumbra::json_input;

double display_pixels_per_degree(const std::string& file, std::string_view tool) {
  const nlohmann::json j = ji::read_file(file);
  const ji::Reader r(file);
  auto number = [&](const char* name, const char* unit) {
    ji::Field f;
    f.name = name;
    f.type = std::string(name) == "width_px" ? ji::Type::integer : ji::Type::number;
    f.required = true;
    f.why = std::string(tool) + " takes the viewing geometry of its perceptual difference from it";
    f.min = 1;
    f.max = 100000;
    f.unit = unit;
    return f;
  };
  ji::ObjectSpec display{{number("width_px", ""), number("width_mm", "mm"), number("viewing_distance_mm", "mm")}, false};
  ji::Field block;
  block.name = "display";
  block.type = ji::Type::object;
  block.required = true;
  block.why = "a study config's display block: width_px, width_mm, viewing_distance_mm";
  block.object = ji::spec(display);
  if (!j.is_object()) r.fail("", "expected an object (a study config), got " + ji::describe(j));
  const nlohmann::json* d = r.get(j, "", block);
  return metrics::pixels_per_degree(r.number(*d, "display", display, "width_px"), r.number(*d, "display", display, "width_mm") / 1000.0,
                                    r.number(*d, "display", display, "viewing_distance_mm") / 1000.0);
}

}  // namespace penumbra::apps
