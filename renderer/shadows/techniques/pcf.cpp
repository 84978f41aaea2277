#include "shadows/techniques/pcf.h"

#include "gl/objects.h"
#include "gl/shader_library.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

namespace penumbra::shadows {
namespace {

const Setting<PcfParams> kTable[] = {
    PENUMBRA_RADIUS_ROWS(PcfParams, "filter radius"),
    PENUMBRA_CHOICE(PcfParams, kernel, Kernel, rows::kKernels, "grid: box over whole texels, coverage-weighted; poisson: rotated Poisson disk; disk: exact disk over whole texels, coverage-weighted (the ideal filter)"),
    PENUMBRA_INT(PcfParams, poisson_taps, "taps", 1, 64, "Poisson-disk taps (each a hardware 2x2 comparison)"),
    PENUMBRA_BOOL(PcfParams, rotate, "rotate the Poisson disk per pixel"),
    PENUMBRA_INT(PcfParams, max_grid_taps, "taps", 2, 256, "grid and disk taps per axis before the kernel is strided"),
};

}  // namespace

std::span<const Setting<PcfParams>> settings_table(const PcfParams*) { return kTable; }

const TechniqueEntry& pcf_technique() {
  static const TechniqueEntry entry{
      .name = "pcf",
      .define = "TECHNIQUE_PCF",
      .radius = RadiusReading::fixed_filter,
      .pages = PageReading::filter_radius,
      .pages_need = [](const ShadowSettings& s) { return s.pcf.kernel == Kernel::grid ? std::string_view() : std::string_view("--pcf.kernel grid"); },
      .variant_setting = "kernel",
      .filter_radius = section_radius<&ShadowSettings::pcf>,
      .set_filter_radius = set_section_radius<&ShadowSettings::pcf>,
      .variant_defines =
          [](const ShadowSettings& s, std::vector<gl::ShaderDefine>& d) {
            if (s.pcf.kernel == Kernel::grid) d.push_back({"KERNEL_GRID", "1"});
            if (s.pcf.kernel == Kernel::disk) d.push_back({"KERNEL_DISK", "1"});
          },
      .poisson_taps = [](const ShadowSettings& s) { return s.pcf.poisson_taps; },
      .set_uniforms =
          [](const gl::Program& p, const ShadowSettings& s) {
            p.set("u_rotate", s.pcf.rotate);
            p.set("u_max_grid_taps", s.pcf.max_grid_taps);
            p.set("u_taps", s.pcf.poisson_taps);
          },
  };
  return entry;
}

}  // namespace penumbra::shadows
