#pragma once
// The fields adaptive::load_calibration reads from a version-2 calibration.json, as
// data/calibration/calibration.schema.json states them (compared by tests/study/schema_test.cpp).
// Not installed: the installed library's headers do not name json_input.
namespace penumbra::json_input {
struct ObjectSpec;
}

namespace penumbra::adaptive {

const json_input::ObjectSpec& calibration_fields();

}  // namespace penumbra::adaptive
