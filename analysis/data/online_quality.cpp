#include "data/online_quality.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <regex>
#include <set>
#include <stdexcept>

#include "io/safe_path.h"
#include "json/json_input.h"
#include "log/trial_log.h"
#include "text/fields.h"
#include "procedure/session_record.h"

namespace penumbra::analysis {

namespace fs = std::filesystem;

namespace {

constexpr json_input::Limits kLimits{.max_bytes = 4 << 20, .max_depth = 8};

nlohmann::json read_json(const fs::path& path) {
  // A session directory's file: never read through a link (as dataset.cpp reads session.json).
  return json_input::parse(io::read_file(path, kLimits.max_bytes, io::Links::refuse), path.string(), kLimits);
}

// A number the page reported, or NaN when it is absent; a present value of another type is the file's error.
double optional_number(const nlohmann::json& block, const char* key, const std::string& where) {
  if (!block.contains(key) || block[key].is_null()) return NAN;
  if (!block[key].is_number()) throw std::runtime_error(where + "." + key + ": expected a number");
  return block[key].get<double>();
}

std::optional<int> optional_count(const nlohmann::json& block, const char* key, const std::string& where) {
  if (!block.contains(key)) return std::nullopt;
  if (!block[key].is_number_integer() || block[key].get<long long>() < 0 || block[key].get<long long>() > 1000000000)
    throw std::runtime_error(where + "." + key + ": expected a count (a non-negative integer)");
  return block[key].get<int>();
}

// "Chrome 131" from "Mozilla/5.0 (...) HeadlessChrome/131.0.0.0 Safari/537.36": the browser that
// names itself last wins (Edge and Opera also say Chrome, Chrome also says Safari).
std::string browser_name(const std::string& agent) {
  static const std::vector<std::pair<std::regex, std::string>> known = {
      {std::regex(R"(Edg/(\d+))"), "Edge"},           {std::regex(R"(OPR/(\d+))"), "Opera"},
      {std::regex(R"(Firefox/(\d+))"), "Firefox"},    {std::regex(R"(HeadlessChrome/(\d+))"), "HeadlessChrome"},
      {std::regex(R"(Chrom(?:e|ium)/(\d+))"), "Chrome"}, {std::regex(R"(Version/(\d+)[.\d]* .*Safari/)"), "Safari"}};
  for (const auto& [pattern, name] : known) {
    std::smatch m;
    if (std::regex_search(agent, m, pattern)) return name + " " + m[1].str();
  }
  const std::string first = agent.substr(0, agent.find(' '));
  return json_input::printable(first.substr(0, 24));
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The browser's display as session.json records it (the last presentation that fitted the window).
void read_presentation(const nlohmann::json& session, const std::string& file, SessionQuality& q) {
  if (!session.contains("presentation") || !session["presentation"].is_array()) return;
  const nlohmann::json* shown = nullptr;
  for (const auto& entry : session["presentation"])
    if (entry.is_object() && entry.value("kind", std::string()) == "browser" && entry.value("fits", false)) shown = &entry;
  if (!shown) return;
  const std::string where = file + ": presentation[kind browser]";
  q.browser = true;
  if (shown->contains("user_agent")) {
    if (!(*shown)["user_agent"].is_string()) throw std::runtime_error(where + ".user_agent: expected a string");
    q.browser_name = browser_name((*shown)["user_agent"].get<std::string>());
  }
  q.screen_width_css_px = optional_number(*shown, "screen_width_css_px", where);
  q.screen_height_css_px = optional_number(*shown, "screen_height_css_px", where);
  q.device_pixel_ratio = optional_number(*shown, "device_pixel_ratio", where);
  q.refresh_hz = optional_number(*shown, "refresh_hz", where);
  q.viewing_distance_mm = optional_number(*shown, "viewing_distance_mm", where);
  q.css_px_per_degree = optional_number(*shown, "pixels_per_degree", where);
  const double css = optional_number(*shown, "stimulus_css_px", where);
  double size_px = NAN;
  if (session.contains("config") && session["config"].is_object() && session["config"].contains("stimulus") &&
      session["config"]["stimulus"].is_object())
    size_px = optional_number(session["config"]["stimulus"], "size_px", file + ": config.stimulus");
  if (size_px > 0 && css > 0) {
    q.stimulus_px_per_degree = q.css_px_per_degree * size_px / css;
    q.device_px_per_stimulus_px = css / size_px * (std::isfinite(q.device_pixel_ratio) ? q.device_pixel_ratio : 1.0);
  }
  if (shown->contains("chinrest") && (*shown)["chinrest"].is_object()) {
    const nlohmann::json& chinrest = (*shown)["chinrest"];
    if (chinrest.contains("blindspot_distances_mm")) {
      const nlohmann::json& readings = chinrest["blindspot_distances_mm"];
      if (!readings.is_array() || readings.size() > 100)
        throw std::runtime_error(where + ".chinrest.blindspot_distances_mm: expected an array of at most 100 distances");
      for (const auto& d : readings) {
        if (!d.is_number() || !(d.get<double>() > 0))
          throw std::runtime_error(where + ".chinrest.blindspot_distances_mm: expected positive numbers (mm)");
        q.chinrest_distances_mm.push_back(d.get<double>());
      }
    }
  }
  const std::size_t n = q.chinrest_distances_mm.size();
  if (n >= 2) {
    double mean = 0;
    for (double d : q.chinrest_distances_mm) mean += d / static_cast<double>(n);
    double ss = 0;
    for (double d : q.chinrest_distances_mm) ss += (d - mean) * (d - mean);
    q.chinrest_cv = std::sqrt(ss / static_cast<double>(n - 1)) / mean;
  }
}

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

std::string count_text(const std::optional<int>& v) { return v ? std::to_string(*v) : "-"; }

// A measure's value for a criterion, or nothing where the session does not have it.
std::optional<double> measure_of(const SessionQuality& q, const std::string& measure) {
  auto count = [](const std::optional<int>& v) { return v ? std::optional<double>(*v) : std::nullopt; };
  if (measure == "fullscreen_exits") return count(q.fullscreen_exits);
  if (measure == "tab_switches") return count(q.tab_switches);
  if (measure == "page_loads") return count(q.page_loads);
  if (measure == "rt_outliers") return std::isfinite(q.rt_outlier_fraction) ? std::optional(q.rt_outlier_fraction) : std::nullopt;
  if (measure == "chinrest_cv") return std::isfinite(q.chinrest_cv) ? std::optional(q.chinrest_cv) : std::nullopt;
  return std::nullopt;
}

std::string value_text(const std::string& measure, double v) {
  if (measure == "rt_outliers") return fixed(100 * v, 1) + " %";
  if (measure == "chinrest_cv") return fixed(v, 3);
  return std::to_string(static_cast<long long>(v));
}

std::string limit_text(const QualityCriterion& c) {
  if (c.measure == "rt_outliers") {
    char b[48];
    std::snprintf(b, sizeof b, "%g %%", 100 * c.limit);
    return b;
  }
  char b[48];
  std::snprintf(b, sizeof b, "%g", c.limit);
  return b;
}

const char* kRtDefinition = "response-time outliers: RT < 150 ms or > 3 x the session's median RT (practice left out; people only)";
const char* kChinrestDefinition = "chinrest cv: sample sd / mean of the blind-spot viewing distances (two or more readings)";

}  // namespace

std::vector<QualityCriterion> parse_quality_criteria(const std::string& text) {
  std::vector<QualityCriterion> out;
  const std::string option = "--exclude-quality '" + json_input::printable(text) + "': ";
  const std::set<std::string> measures = {"fullscreen_exits", "tab_switches", "page_loads", "rt_outliers", "chinrest_cv"};
  for (const std::string& item : text::split_fields(text)) {
    const std::size_t gt = item.find('>');
    if (gt == std::string::npos)
      throw std::invalid_argument(option + "'" + json_input::printable(item) +
                                  "': expected MEASURE>LIMIT, e.g. fullscreen_exits>2,tab_switches>3,rt_outliers>10%,chinrest_cv>0.1");
    QualityCriterion c;
    c.measure = item.substr(0, gt);
    c.text = item;
    std::string limit = item.substr(gt + 1);
    if (!measures.count(c.measure))
      throw std::invalid_argument(option + "'" + json_input::printable(c.measure) +
                                  "' is not a measure: fullscreen_exits, tab_switches, page_loads, rt_outliers, chinrest_cv");
    for (const QualityCriterion& earlier : out)
      if (earlier.measure == c.measure) throw std::invalid_argument(option + c.measure + " given twice");
    const bool percent = !limit.empty() && limit.back() == '%';
    if (percent) limit.pop_back();
    if (percent != (c.measure == "rt_outliers"))
      throw std::invalid_argument(option + c.measure + (percent ? ": a count or a ratio, not a per cent" : ": expected a per cent, e.g. rt_outliers>10%"));
    // Plain decimals only (no sign, exponent, whitespace, hexadecimal, inf or nan).
    static const std::regex plain(R"(\d+(\.\d*)?|\.\d+)");
    const double v = std::regex_match(limit, plain) ? std::strtod(limit.c_str(), nullptr) : NAN;
    if (!std::isfinite(v))
      throw std::invalid_argument(option + c.measure + ": '" + json_input::printable(limit) + "': expected a plain decimal number, e.g. 3 or 0.1");
    const bool count = c.measure == "fullscreen_exits" || c.measure == "tab_switches" || c.measure == "page_loads";
    if (count && v != std::floor(v)) throw std::invalid_argument(option + c.measure + ": expected a whole count");
    if (percent && v >= 100) throw std::invalid_argument(option + "rt_outliers: expected a per cent below 100");
    c.limit = percent ? v / 100 : v;
    out.push_back(c);
  }
  return out;
}

std::vector<SessionQuality> read_quality(const std::vector<fs::path>& inputs) {
  std::vector<SessionQuality> out;
  for (const fs::path& input : inputs) {
    SessionQuality q;
    q.input = input.string();
    const bool directory = fs::is_directory(input);
    const fs::path dir = directory ? input : input.parent_path();
    const fs::path log = directory ? input / "trials.csv" : input;
    std::error_code ec;
    if (fs::exists(fs::symlink_status(dir / "session.json", ec))) {
      const nlohmann::json session = read_json(dir / "session.json");
      const std::string file = (dir / "session.json").string();
      if (session.is_object() && session.contains("participant") && session["participant"].is_string())
        q.participant = session["participant"].get<std::string>();
      q.person = session.is_object() && procedure::observer_kind(session, file) == procedure::ObserverKind::person;
      if (session.is_object()) read_presentation(session, file, q);
    }
    if (q.browser && fs::exists(fs::symlink_status(dir / "online.json", ec))) {
      const nlohmann::json online = read_json(dir / "online.json");
      const std::string where = (dir / "online.json").string() + ": quality";
      if (online.is_object() && online.contains("quality")) {
        const nlohmann::json& quality = online["quality"];
        if (!quality.is_object()) throw std::runtime_error(where + ": expected an object");
        q.fullscreen_exits = optional_count(quality, "fullscreen_exits", where);
        q.tab_switches = optional_count(quality, "tab_switches", where);
        q.page_loads = optional_count(quality, "page_loads", where);
      }
      // A session whose page never reported an event counted none.
      if (!q.fullscreen_exits) q.fullscreen_exits = 0;
      if (!q.tab_switches) q.tab_switches = 0;
      if (!q.page_loads) q.page_loads = 0;
    }
    std::vector<double> rts;
    if (fs::exists(log)) {
      for (const trial_log::TrialRow& row : trial_log::read(log).rows) {
        if (q.participant.empty()) q.participant = row.participant;
        if (row.practice) continue;
        ++q.trials;
        rts.push_back(row.rt_ms);
      }
    }
    if (q.person && !rts.empty()) {
      q.rt_median_ms = median(rts);
      for (double rt : rts) {
        q.rt_fast += rt < kRtFastMs ? 1 : 0;
        q.rt_slow += rt > kRtSlowTimesMedian * q.rt_median_ms ? 1 : 0;
      }
      q.rt_outlier_fraction = static_cast<double>(q.rt_fast + q.rt_slow) / static_cast<double>(rts.size());
    }
    out.push_back(std::move(q));
  }
  return out;
}

int apply_quality_criteria(std::vector<SessionQuality>& sessions, const std::vector<QualityCriterion>& criteria) {
  int excluded = 0;
  for (SessionQuality& q : sessions) {
    q.excluded_because.clear();
    for (const QualityCriterion& c : criteria) {
      const std::optional<double> v = measure_of(q, c.measure);
      if (v && *v > c.limit + 1e-12) q.excluded_because.push_back(c.measure + " " + value_text(c.measure, *v) + " > " + limit_text(c));
    }
    excluded += q.excluded_because.empty() ? 0 : 1;
  }
  return excluded;
}

bool quality_reported(const std::vector<SessionQuality>& sessions, const std::vector<QualityCriterion>& criteria) {
  return !criteria.empty() || std::any_of(sessions.begin(), sessions.end(), [](const SessionQuality& q) { return q.browser; });
}

std::string quality_table(const std::vector<SessionQuality>& sessions, const std::vector<QualityCriterion>& criteria) {
  std::vector<std::vector<std::string>> rows = {{"participant", "browser", "screen", "dpr", "refresh", "px/deg", "distance",
                                                 "dev px/stim px", "fs exits", "tab sw", "loads", "trials", "RT median",
                                                 "RT outliers", "chinrest cv", "excluded"}};
  for (const SessionQuality& q : sessions) {
    std::string screen = "-";
    if (std::isfinite(q.screen_width_css_px) && std::isfinite(q.screen_height_css_px))
      screen = fixed(q.screen_width_css_px, 0) + "x" + fixed(q.screen_height_css_px, 0);
    std::string outliers = "-";
    if (std::isfinite(q.rt_outlier_fraction))
      outliers = std::to_string(q.rt_fast + q.rt_slow) + " (" + fixed(100 * q.rt_outlier_fraction, 1) + " %)";
    std::string chinrest = fixed(q.chinrest_cv, 3);
    if (q.browser && q.chinrest_distances_mm.size() < 2)
      chinrest = std::to_string(q.chinrest_distances_mm.size()) + " reading" + (q.chinrest_distances_mm.size() == 1 ? "" : "s");
    rows.push_back({json_input::printable(q.participant), q.browser ? (q.browser_name.empty() ? "browser" : q.browser_name) : "lab",
                    screen, fixed(q.device_pixel_ratio, 2), std::isfinite(q.refresh_hz) ? fixed(q.refresh_hz, 0) + " Hz" : "-",
                    fixed(q.stimulus_px_per_degree, 2), std::isfinite(q.viewing_distance_mm) ? fixed(q.viewing_distance_mm, 0) + " mm" : "-",
                    fixed(q.device_px_per_stimulus_px, 2), count_text(q.fullscreen_exits), count_text(q.tab_switches),
                    count_text(q.page_loads), std::to_string(q.trials),
                    std::isfinite(q.rt_median_ms) ? fixed(q.rt_median_ms, 0) + " ms" : "-", outliers, chinrest,
                    q.excluded_because.empty() ? "no" : "YES"});
  }
  std::vector<std::size_t> width(rows[0].size(), 0);
  for (const auto& row : rows)
    for (std::size_t i = 0; i < row.size(); ++i) width[i] = std::max(width[i], row[i].size());
  std::string out = "\ndata quality (per session; px/deg: the stimulus pixels per degree the fit uses)\n";
  for (const auto& row : rows) {
    std::string line = " ";
    for (std::size_t i = 0; i < row.size(); ++i) line += " " + row[i] + std::string(width[i] - row[i].size() + 1, ' ');
    while (!line.empty() && line.back() == ' ') line.pop_back();
    out += line + "\n";
  }
  out += std::string("  ") + kRtDefinition + "\n  " + kChinrestDefinition + "\n";
  if (criteria.empty()) {
    out += "  exclusion criteria: none (--exclude-quality); every session is fitted\n";
    return out;
  }
  std::string given;
  for (const QualityCriterion& c : criteria) given += (given.empty() ? "" : ",") + c.text;
  out += "  exclusion criteria (--exclude-quality): " + given + "; a session without a measure is not excluded by it\n";
  int excluded = 0;
  for (const SessionQuality& q : sessions) {
    if (q.excluded_because.empty()) continue;
    ++excluded;
    std::string why;
    for (const std::string& w : q.excluded_because) why += (why.empty() ? "" : ", ") + w;
    out += "  EXCLUDED " + json_input::printable(q.participant) + " (" + q.input + "): " + why + "\n";
  }
  out += "  " + std::to_string(excluded) + " of " + std::to_string(sessions.size()) + " session" + (sessions.size() == 1 ? "" : "s") +
         " excluded, " + std::to_string(static_cast<int>(sessions.size()) - excluded) + " fitted\n";
  return out;
}

nlohmann::json quality_json(const std::vector<SessionQuality>& sessions, const std::vector<QualityCriterion>& criteria) {
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  auto count = [](const std::optional<int>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); };
  nlohmann::json list = nlohmann::json::array(), excluded = nlohmann::json::array(), given = nlohmann::json::array();
  for (const QualityCriterion& c : criteria) given.push_back({{"measure", c.measure}, {"above", c.limit}, {"as_given", c.text}});
  for (const SessionQuality& q : sessions) {
    list.push_back({{"input", q.input},
                    {"participant", q.participant},
                    {"kind", q.browser ? "browser" : "lab"},
                    {"browser", q.browser ? nlohmann::json(q.browser_name) : nlohmann::json(nullptr)},
                    {"screen_css_px", {num(q.screen_width_css_px), num(q.screen_height_css_px)}},
                    {"device_pixel_ratio", num(q.device_pixel_ratio)},
                    {"refresh_hz", num(q.refresh_hz)},
                    {"viewing_distance_mm", num(q.viewing_distance_mm)},
                    {"css_px_per_degree", num(q.css_px_per_degree)},
                    {"stimulus_px_per_degree", num(q.stimulus_px_per_degree)},
                    {"device_px_per_stimulus_px", num(q.device_px_per_stimulus_px)},
                    {"fullscreen_exits", count(q.fullscreen_exits)},
                    {"tab_switches", count(q.tab_switches)},
                    {"page_loads", count(q.page_loads)},
                    {"trials", q.trials},
                    {"rt_median_ms", num(q.rt_median_ms)},
                    {"rt_fast", q.person ? nlohmann::json(q.rt_fast) : nlohmann::json(nullptr)},
                    {"rt_slow", q.person ? nlohmann::json(q.rt_slow) : nlohmann::json(nullptr)},
                    {"rt_outliers", num(q.rt_outlier_fraction)},
                    {"chinrest_distances_mm", q.chinrest_distances_mm},
                    {"chinrest_cv", num(q.chinrest_cv)},
                    {"excluded", !q.excluded_because.empty()},
                    {"excluded_because", q.excluded_because}});
    if (!q.excluded_because.empty())
      excluded.push_back({{"input", q.input}, {"participant", q.participant}, {"because", q.excluded_because}});
  }
  return {{"definitions", {{"rt_outliers", kRtDefinition}, {"chinrest_cv", kChinrestDefinition},
                           {"stimulus_px_per_degree", "the virtual chinrest's CSS pixels per degree x size_px / stimulus_css_px"}}},
          {"criteria", given},
          {"sessions", list},
          {"excluded", excluded}};
}

}  // namespace penumbra::analysis
