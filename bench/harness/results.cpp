#include "bench/harness/results.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "core/atomic_file.h"
#include "core/error.h"

namespace hf::bench {
namespace {

// Shortest representation that parses back to the same double.
std::string number(double v) {
  std::array<char, 64> buffer{};
  const auto r = std::to_chars(buffer.data(), buffer.data() + buffer.size(), v);
  return std::string(buffer.data(), r.ptr);
}

std::string fixed(double v, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, v);
  return buffer;
}

// Significant digits for small errors (0.00123 -> "0.00123"), fixed for larger ones.
std::string metres(const std::optional<double>& v) {
  if (!v) return "-";
  if (!std::isfinite(*v)) return "nan";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, *v < 0.1 ? "%.3g" : "%.3f", *v);
  return buffer;
}

std::string run_command(const std::string& command) {
  std::string out;
  if (std::FILE* pipe = ::popen(command.c_str(), "r")) {
    char buffer[256];
    while (std::fgets(buffer, sizeof buffer, pipe)) out += buffer;
    if (::pclose(pipe) != 0) return "";
  }
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r' || out.back() == ' ')) out.pop_back();
  return out;
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char ch : s) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return q + "'";
}

struct InputGroup {
  std::map<std::string, const RunRow*> by_method;  // display name -> run
  bool has_ground_truth = false;
};

std::vector<std::pair<std::string, InputGroup>> group_by_input(const std::vector<RunRow>& runs) {
  std::vector<std::pair<std::string, InputGroup>> groups;
  for (const RunRow& run : runs) {
    auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == run.input; });
    if (it == groups.end()) {
      groups.push_back({run.input, {}});
      it = groups.end() - 1;
    }
    it->second.by_method[run.display_name()] = &run;
    if (run.ate_rmse_m) it->second.has_ground_truth = true;
  }
  return groups;
}

const char* const kCsvColumns[] = {
    "method", "peer", "input", "source", "status", "error", "frames", "frames_bad", "frames_lost", "ate_rmse_m",
    "rpe_trans_m_per_s", "rpe_rot_deg_per_s", "fps", "ms_read", "ms_preprocess", "ms_track", "ms_integrate",
    "ms_raycast", "ms_total", "wall_s", "coverage", "lost_spells", "longest_lost_spell", "worst_frame_ms",
    "rpe_frame_trans_m", "rpe_frame_rot_deg"};
constexpr size_t kCsvColumnCount = sizeof kCsvColumns / sizeof kCsvColumns[0];

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char ch : s) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}

std::string status_of(const RunRow& r) {
  if (r.failed) return "failed";
  return r.interrupted ? "interrupted" : "ok";
}

nlohmann::json optional_json(const std::optional<double>& v) {
  return v && std::isfinite(*v) ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

std::optional<double> optional_from(const nlohmann::json& j) {
  if (j.is_null()) return std::nullopt;
  return j.get<double>();
}

}  // namespace

std::string RunRow::display_name() const { return peer ? method + " (peer)" : method; }

bool RunRow::comparable() const {
  if (failed || !ate_rmse_m || !std::isfinite(*ate_rmse_m)) return false;
  return frames > 0 && double(frames_lost) <= kMaxLostFraction * double(frames);
}

MachineInfo current_machine(const std::string& source_dir, const std::string& command_line) {
  MachineInfo m;
  m.command_line = command_line;
  if (!source_dir.empty()) {
    const std::string commit = run_command("git -C " + shell_quote(source_dir) + " rev-parse HEAD 2>/dev/null");
    if (commit.size() == 40) m.commit = commit;
  }
  m.cores = std::thread::hardware_concurrency();
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) m.cpu_model = line.substr(line.find_first_not_of(" \t", colon + 1));
      break;
    }
  }
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", &utc);
  m.date_utc = date;
  return m;
}

std::optional<double> run_error(const RunRow& run, ErrorMetric metric) {
  switch (metric) {
    case ErrorMetric::ate_rmse: return run.ate_rmse_m;
    case ErrorMetric::rpe_translation: return run.rpe_trans_m_per_s;
    case ErrorMetric::rpe_frame_translation: return run.rpe_frame_trans_m;
  }
  return std::nullopt;
}

std::string metric_name(ErrorMetric metric) {
  switch (metric) {
    case ErrorMetric::ate_rmse: return "ATE RMSE";
    case ErrorMetric::rpe_translation: return "translational RPE (1 s)";
    case ErrorMetric::rpe_frame_translation: return "translational RPE (1 frame)";
  }
  return "?";
}

bool comparable_by(const RunRow& run, ErrorMetric metric) {
  const std::optional<double> e = run_error(run, metric);
  return run.comparable() && e && std::isfinite(*e);
}

Outcome compare_runs(const RunRow& a, const RunRow& b, ErrorMetric metric) {
  const bool ca = comparable_by(a, metric), cb = comparable_by(b, metric);
  if (!ca && !cb) return Outcome::tie;
  if (ca != cb) return ca ? Outcome::win : Outcome::loss;
  const double ea = *run_error(a, metric), eb = *run_error(b, metric);
  if (std::abs(ea - eb) <= kTieRelative * std::max(ea, eb)) return Outcome::tie;
  return ea < eb ? Outcome::win : Outcome::loss;
}

WltTable won_lost_tie(const std::vector<RunRow>& runs, const std::vector<std::string>& order, ErrorMetric metric) {
  WltTable t;
  t.methods = order;
  t.metric = metric_name(metric);
  const size_t n = order.size();
  t.wlt.assign(n, std::vector<WltCell>(n));
  t.ratio.assign(n, std::vector<std::optional<double>>(n));
  t.common_inputs.assign(n, std::vector<int>(n, 0));
  std::vector<std::vector<double>> sum_r(n, std::vector<double>(n, 0.0)), sum_c = sum_r;
  for (const auto& [input, group] : group_by_input(runs)) {
    if (!group.has_ground_truth) continue;
    ++t.inputs;
    for (size_t r = 0; r < n; ++r) {
      const auto rr = group.by_method.find(order[r]);
      if (rr == group.by_method.end()) continue;
      for (size_t c = 0; c < n; ++c) {
        const auto cc = group.by_method.find(order[c]);
        if (c == r || cc == group.by_method.end()) continue;
        switch (compare_runs(*cc->second, *rr->second, metric)) {
          case Outcome::win: ++t.wlt[r][c].wins; break;
          case Outcome::loss: ++t.wlt[r][c].losses; break;
          case Outcome::tie: ++t.wlt[r][c].ties; break;
        }
        if (comparable_by(*rr->second, metric) && comparable_by(*cc->second, metric)) {
          ++t.common_inputs[r][c];
          sum_r[r][c] += *run_error(*rr->second, metric);
          sum_c[r][c] += *run_error(*cc->second, metric);
        }
      }
    }
  }
  for (size_t r = 0; r < n; ++r) {
    for (size_t c = 0; c < n; ++c) {
      if (r != c && t.common_inputs[r][c] > 0 && sum_c[r][c] > 0.0) t.ratio[r][c] = sum_r[r][c] / sum_c[r][c];
    }
  }
  return t;
}

std::string format_wlt_markdown(const WltTable& t) {
  std::ostringstream md;
  const size_t n = t.methods.size();
  md << "| |";
  for (const auto& m : t.methods) md << " " << m << " |";
  md << "\n|---|";
  for (size_t c = 0; c < n; ++c) md << "---|";
  md << "\n";
  for (size_t r = 0; r < n; ++r) {
    md << "| **" << t.methods[r] << "** |";
    for (size_t c = 0; c < n; ++c) {
      if (r == c) {
        md << " |";
      } else if (r > c) {
        const WltCell& w = t.wlt[r][c];
        md << " " << w.wins << "-" << w.losses << "-" << w.ties << " |";
      } else {
        md << " " << (t.ratio[r][c] ? fixed(*t.ratio[r][c], 3) : std::string("-")) << " |";
      }
    }
    md << "\n";
  }
  md << "\nBelow the diagonal: wins-losses-ties of the **column** method against the **row** method over the "
     << t.inputs << " input(s) with ground truth, by " << t.metric << ". A tie is two errors within "
     << int(std::lround(kTieRelative * 100)) << "% of the larger one, or both runs lost; a run is lost when it "
     << "failed, has no ATE, or lost more than " << int(std::lround(kMaxLostFraction * 100))
     << "% of its frames, and any tracked run beats a lost one. Above the diagonal: ME(row) / ME(column), the "
     << "ratio of mean " << t.metric << " over the inputs on which both tracked (below 1: the row method is more accurate). "
     << "This is the form of Table 1 of the registration report (Stotko 2016, eq. 76).\n";
  return md.str();
}

std::vector<size_t> pareto_front(const std::vector<ParetoPoint>& points) {
  std::vector<size_t> front;
  for (size_t i = 0; i < points.size(); ++i) {
    const ParetoPoint& p = points[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    bool dominated = false;
    for (size_t j = 0; j < points.size() && !dominated; ++j) {
      const ParetoPoint& q = points[j];
      if (j == i || !std::isfinite(q.x) || !std::isfinite(q.y)) continue;
      dominated = q.x <= p.x && q.y <= p.y && (q.x < p.x || q.y < p.y);
    }
    if (!dominated) front.push_back(i);
  }
  std::stable_sort(front.begin(), front.end(), [&](size_t a, size_t b) {
    return points[a].x < points[b].x || (points[a].x == points[b].x && points[a].y < points[b].y);
  });
  return front;
}

std::vector<MethodSummary> summarize_methods(const std::vector<RunRow>& runs, const std::vector<std::string>& order) {
  std::vector<MethodSummary> out;
  for (const std::string& name : order) {
    MethodSummary s;
    s.name = name;
    double ate_sum = 0.0, ms_sum = 0.0;
    int ms_count = 0;
    for (const RunRow& r : runs) {
      if (r.display_name() != name) continue;
      s.peer = r.peer;
      ++s.inputs_run;
      if (r.failed) {
        ++s.runs_failed;
        continue;
      }
      s.frames += r.frames;
      s.frames_lost += r.frames_lost;
      if (r.frames > 0) {
        ms_sum += r.ms.total;
        ++ms_count;
      }
      if (r.comparable()) {
        ++s.inputs_comparable;
        ate_sum += *r.ate_rmse_m;
      }
    }
    if (s.inputs_comparable > 0) s.mean_ate_m = ate_sum / s.inputs_comparable;
    if (ms_count > 0) s.mean_ms_per_frame = ms_sum / ms_count;
    out.push_back(s);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------- CSV

std::string results_to_csv(const std::vector<RunRow>& runs) {
  std::ostringstream out;
  for (size_t k = 0; k < kCsvColumnCount; ++k) out << (k ? "," : "") << kCsvColumns[k];
  out << "\n";
  auto opt = [](const std::optional<double>& v) { return v ? number(*v) : std::string(); };
  for (const RunRow& r : runs) {
    const std::vector<std::string> fields = {
        csv_field(r.method), r.peer ? "1" : "0", csv_field(r.input), csv_field(r.source), status_of(r),
        csv_field(r.error), std::to_string(r.frames), std::to_string(r.frames_bad), std::to_string(r.frames_lost),
        opt(r.ate_rmse_m), opt(r.rpe_trans_m_per_s), opt(r.rpe_rot_deg_per_s), number(r.fps), number(r.ms.read),
        number(r.ms.preprocess), number(r.ms.track), number(r.ms.integrate), number(r.ms.raycast),
        number(r.ms.total), number(r.wall_s), number(r.coverage), std::to_string(r.lost_spells),
        std::to_string(r.longest_lost_spell), number(r.worst_frame_ms), opt(r.rpe_frame_trans_m),
        opt(r.rpe_frame_rot_deg)};
    for (size_t k = 0; k < fields.size(); ++k) out << (k ? "," : "") << fields[k];
    out << "\n";
  }
  return out.str();
}

std::vector<RunRow> results_from_csv(const std::string& text, const std::string& file) {
  // RFC 4180 records: quoted fields may hold commas, doubled quotes and line breaks.
  std::vector<std::pair<int, std::vector<std::string>>> records;  // (first line, fields)
  {
    size_t i = 0;
    int line = 1;
    while (i < text.size()) {
      const int first_line = line;
      std::vector<std::string> fields(1);
      bool end_of_record = false;
      while (!end_of_record) {
        if (i < text.size() && text[i] == '"' && fields.back().empty()) {
          ++i;
          for (;;) {
            if (i >= text.size()) throw ParseError(file, first_line, "expected a closing '\"' of a quoted field");
            if (text[i] == '"') {
              if (i + 1 < text.size() && text[i + 1] == '"') {
                fields.back() += '"';
                i += 2;
                continue;
              }
              ++i;
              break;
            }
            if (text[i] == '\n') ++line;
            fields.back() += text[i++];
          }
          if (i < text.size() && text[i] != ',' && text[i] != '\n' && text[i] != '\r') {
            throw ParseError(file, line, "expected ',' or the end of the line after a quoted field");
          }
        }
        if (i >= text.size()) break;
        const char ch = text[i++];
        if (ch == ',') {
          fields.emplace_back();
        } else if (ch == '\n') {
          ++line;
          end_of_record = true;
        } else if (ch != '\r') {
          fields.back() += ch;
        }
      }
      records.push_back({first_line, std::move(fields)});
    }
  }
  if (records.empty()) throw ParseError(file, 1, "expected the header line of results.csv, got an empty file");
  {
    const auto& header = records.front().second;
    bool ok = header.size() == kCsvColumnCount;
    for (size_t k = 0; ok && k < kCsvColumnCount; ++k) ok = header[k] == kCsvColumns[k];
    if (!ok) throw ParseError(file, 1, "expected the results.csv header starting 'method,peer,input,...'");
  }
  std::vector<RunRow> runs;
  for (size_t k = 1; k < records.size(); ++k) {
    const int line = records[k].first;
    const auto& f = records[k].second;
    if (f.size() == 1 && f[0].empty()) continue;  // blank line
    if (f.size() != kCsvColumnCount) {
      throw ParseError(file, line, "expected " + std::to_string(kCsvColumnCount) + " fields, got " +
                                       std::to_string(f.size()));
    }
    auto to_double = [&](size_t col) {
      double v = 0.0;
      const std::string& s = f[col];
      const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
      if (s.empty() || r.ec != std::errc() || r.ptr != s.data() + s.size()) {
        throw ParseError(file, line, std::string("expected a number for ") + kCsvColumns[col] + ", got '" + s + "'");
      }
      return v;
    };
    auto to_long = [&](size_t col) {
      long v = 0;
      const std::string& s = f[col];
      const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
      if (s.empty() || r.ec != std::errc() || r.ptr != s.data() + s.size()) {
        throw ParseError(file, line,
                         std::string("expected an integer for ") + kCsvColumns[col] + ", got '" + s + "'");
      }
      return v;
    };
    auto to_opt = [&](size_t col) { return f[col].empty() ? std::optional<double>() : to_double(col); };
    RunRow r;
    r.method = f[0];
    if (f[1] != "0" && f[1] != "1") throw ParseError(file, line, "expected 0 or 1 for peer, got '" + f[1] + "'");
    r.peer = f[1] == "1";
    r.input = f[2];
    r.source = f[3];
    if (f[4] != "ok" && f[4] != "failed" && f[4] != "interrupted") {
      throw ParseError(file, line, "expected ok, failed or interrupted for status, got '" + f[4] + "'");
    }
    r.failed = f[4] == "failed";
    r.interrupted = f[4] == "interrupted";
    r.error = f[5];
    r.frames = to_long(6);
    r.frames_bad = to_long(7);
    r.frames_lost = to_long(8);
    r.ate_rmse_m = to_opt(9);
    r.rpe_trans_m_per_s = to_opt(10);
    r.rpe_rot_deg_per_s = to_opt(11);
    r.fps = to_double(12);
    r.ms = {to_double(13), to_double(14), to_double(15), to_double(16), to_double(17), to_double(18)};
    r.wall_s = to_double(19);
    r.coverage = to_double(20);
    r.lost_spells = to_long(21);
    r.longest_lost_spell = to_long(22);
    r.worst_frame_ms = to_double(23);
    r.rpe_frame_trans_m = to_opt(24);
    r.rpe_frame_rot_deg = to_opt(25);
    runs.push_back(std::move(r));
  }
  return runs;
}

// ---------------------------------------------------------------------------------------------------- JSON

// The won-lost-tie table's JSON form (results.h).
static nlohmann::json wlt_to_json(const WltTable& t);

nlohmann::json results_to_json(const BenchResults& results) {
  nlohmann::json j;
  const MachineInfo& m = results.machine;
  j["machine"] = {{"commit", m.commit},       {"command_line", m.command_line}, {"cpu_model", m.cpu_model},
                  {"cores", m.cores},         {"date_utc", m.date_utc}};
  j["settings"] = results.settings;
  j["methods"] = results.methods;
  j["inputs"] = results.inputs;
  j["notes"] = results.notes;
  nlohmann::json runs = nlohmann::json::array();
  for (const RunRow& r : results.runs) {
    runs.push_back({{"method", r.method},
                    {"peer", r.peer},
                    {"input", r.input},
                    {"source", r.source},
                    {"status", status_of(r)},
                    {"error", r.error},
                    {"frames", r.frames},
                    {"frames_bad", r.frames_bad},
                    {"frames_lost", r.frames_lost},
                    {"ate_rmse_m", optional_json(r.ate_rmse_m)},
                    {"rpe_trans_m_per_s", optional_json(r.rpe_trans_m_per_s)},
                    {"rpe_rot_deg_per_s", optional_json(r.rpe_rot_deg_per_s)},
                    {"fps", r.fps},
                    {"ms_per_frame",
                     {{"read", r.ms.read},
                      {"preprocess", r.ms.preprocess},
                      {"track", r.ms.track},
                      {"integrate", r.ms.integrate},
                      {"raycast", r.ms.raycast},
                      {"total", r.ms.total}}},
                    {"wall_s", r.wall_s},
                    {"coverage", r.coverage},
                    {"lost_spells", r.lost_spells},
                    {"longest_lost_spell", r.longest_lost_spell},
                    {"worst_frame_ms", r.worst_frame_ms},
                    {"rpe_frame_trans_m", optional_json(r.rpe_frame_trans_m)},
                    {"rpe_frame_rot_deg", optional_json(r.rpe_frame_rot_deg)}});
  }
  j["runs"] = runs;
  j["won_lost_tie"] = wlt_to_json(won_lost_tie(results.runs, results.methods));
  j["won_lost_tie_rpe"] = wlt_to_json(won_lost_tie(results.runs, results.methods, ErrorMetric::rpe_translation));
  j["won_lost_tie_rpe_frame"] =
      wlt_to_json(won_lost_tie(results.runs, results.methods, ErrorMetric::rpe_frame_translation));
  return j;
}

static nlohmann::json wlt_to_json(const WltTable& t) {
  nlohmann::json wlt = nlohmann::json::array(), ratio = nlohmann::json::array();
  for (size_t r = 0; r < t.methods.size(); ++r) {
    nlohmann::json wrow = nlohmann::json::array(), rrow = nlohmann::json::array();
    for (size_t c = 0; c < t.methods.size(); ++c) {
      if (r == c) {
        wrow.push_back(nullptr);
      } else {
        wrow.push_back({t.wlt[r][c].wins, t.wlt[r][c].losses, t.wlt[r][c].ties});
      }
      rrow.push_back(optional_json(t.ratio[r][c]));
    }
    wlt.push_back(wrow);
    ratio.push_back(rrow);
  }
  return {{"methods", t.methods},
          {"inputs", t.inputs},
          {"wlt", wlt},
          {"ratio", ratio},
          {"rule", "wlt[r][c] = [wins, losses, ties] of method c against method r by " + t.metric +
                       "; tie within 5% or both lost (failed, no ATE, or more than 50% of frames lost); "
                       "ratio[r][c] = ME(r) / ME(c), mean " + t.metric + " over the inputs on which both tracked"}};
}

BenchResults results_from_json(const nlohmann::json& j, const std::string& file) {
  try {
    BenchResults b;
    const nlohmann::json& m = j.at("machine");
    b.machine.commit = m.at("commit").get<std::string>();
    b.machine.command_line = m.at("command_line").get<std::string>();
    b.machine.cpu_model = m.at("cpu_model").get<std::string>();
    b.machine.cores = m.at("cores").get<unsigned>();
    b.machine.date_utc = m.at("date_utc").get<std::string>();
    b.settings = j.at("settings").get<std::string>();
    b.methods = j.at("methods").get<std::vector<std::string>>();
    b.inputs = j.at("inputs").get<std::vector<std::string>>();
    b.notes = j.at("notes").get<std::vector<std::string>>();
    for (const nlohmann::json& r : j.at("runs")) {
      RunRow row;
      row.method = r.at("method").get<std::string>();
      row.peer = r.at("peer").get<bool>();
      row.input = r.at("input").get<std::string>();
      row.source = r.at("source").get<std::string>();
      const std::string status = r.at("status").get<std::string>();
      row.failed = status == "failed";
      row.interrupted = status == "interrupted";
      row.error = r.at("error").get<std::string>();
      row.frames = r.at("frames").get<long>();
      row.frames_bad = r.at("frames_bad").get<long>();
      row.frames_lost = r.at("frames_lost").get<long>();
      row.ate_rmse_m = optional_from(r.at("ate_rmse_m"));
      row.rpe_trans_m_per_s = optional_from(r.at("rpe_trans_m_per_s"));
      row.rpe_rot_deg_per_s = optional_from(r.at("rpe_rot_deg_per_s"));
      row.fps = r.at("fps").get<double>();
      const nlohmann::json& ms = r.at("ms_per_frame");
      row.ms = {ms.at("read").get<double>(),      ms.at("preprocess").get<double>(), ms.at("track").get<double>(),
                ms.at("integrate").get<double>(), ms.at("raycast").get<double>(),    ms.at("total").get<double>()};
      row.wall_s = r.at("wall_s").get<double>();
      row.coverage = r.value("coverage", 0.0);
      row.lost_spells = r.value("lost_spells", 0L);
      row.longest_lost_spell = r.value("longest_lost_spell", 0L);
      row.worst_frame_ms = r.value("worst_frame_ms", 0.0);
      // Older files have no per-frame RPE.
      if (r.contains("rpe_frame_trans_m")) row.rpe_frame_trans_m = optional_from(r.at("rpe_frame_trans_m"));
      if (r.contains("rpe_frame_rot_deg")) row.rpe_frame_rot_deg = optional_from(r.at("rpe_frame_rot_deg"));
      b.runs.push_back(std::move(row));
    }
    return b;
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(file, 0, std::string("expected a results.json of hashfusion bench: ") + e.what());
  }
}

// ---------------------------------------------------------------------------------------------------- Markdown

std::string results_to_markdown(const BenchResults& results, const std::vector<std::string>& plot_files) {
  std::ostringstream md;
  const MachineInfo& m = results.machine;
  md << "# hashfusion bench\n\n"
     << "| | |\n|---|---|\n"
     << "| command | `" << m.command_line << "` |\n"
     << "| commit | `" << m.commit << "` |\n"
     << "| machine | " << m.cores << " cores, " << m.cpu_model << " |\n"
     << "| date | " << m.date_utc << " |\n"
     << "| settings | " << results.settings << " |\n\n"
     << "ATE RMSE after Horn alignment, RPE over 1 s (evaluate_rpe.py --fixed_delta --delta 1 --delta_unit s; "
     << "'-' where the run is shorter than 1 s) and RPE per frame pair (the same script with --delta_unit f: "
     << "consecutive poses, metres and degrees per frame), all as the TUM benchmark scripts compute them "
     << "(slam/eval.h, bench/harness/frame_rpe.h). Times are milliseconds per processed frame, per stage; fps = frames / sum of stage times. "
     << "\"(peer)\" rows are PCL's (GICP, NDT) or Open3D's (o3d-*) registration run frame-to-frame through their API (no map): read, back-projection "
     << "(preprocess) and alignment (track). Pareto: not beaten on both time and ATE by another run on that "
     << "input.\n\n";
  if (!results.notes.empty()) {
    md << "Notes:\n\n";
    for (const std::string& n : results.notes) md << "- " << n << "\n";
    md << "\n";
  }

  md << "## Results per input\n\n";
  for (const std::string& input : results.inputs) {
    std::vector<const RunRow*> rows;
    for (const RunRow& r : results.runs) {
      if (r.input == input) rows.push_back(&r);
    }
    if (rows.empty()) continue;
    std::vector<ParetoPoint> points;
    for (const RunRow* r : rows) {
      points.push_back(r->comparable() ? ParetoPoint{r->ms.total, *r->ate_rmse_m} : ParetoPoint{NAN, NAN});
    }
    std::set<size_t> front;
    for (size_t k : pareto_front(points)) front.insert(k);
    md << "### " << input << "\n\n" << rows.front()->source << "\n\n"
       << "| method | ATE RMSE [m] | RPE 1 s [m/s] | RPE 1 s [deg/s] | RPE frame [m] | RPE frame [deg] | frames | lost | "
          "coverage | lost spells (longest) | fps | read | preprocess | track | integrate | raycast | total [ms] | "
          "worst frame [ms] | Pareto |\n"
       << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|:-:|\n";
    for (size_t k = 0; k < rows.size(); ++k) {
      const RunRow& r = *rows[k];
      md << "| " << r.display_name() << " | ";
      if (r.failed) {
        std::string error = r.error;
        std::replace(error.begin(), error.end(), '|', '/');
        md << "failed: " << error << " | | | | | | | | | | | | | | | | | |\n";
        continue;
      }
      md << metres(r.ate_rmse_m) << " | " << metres(r.rpe_trans_m_per_s) << " | "
         << (r.rpe_rot_deg_per_s ? fixed(*r.rpe_rot_deg_per_s, 3) : std::string("-")) << " | "
         << metres(r.rpe_frame_trans_m) << " | "
         << (r.rpe_frame_rot_deg ? fixed(*r.rpe_frame_rot_deg, 3) : std::string("-")) << " | " << r.frames
         << (r.interrupted ? " (interrupted)" : "") << " | " << r.frames_lost << " | "
         << fixed(100.0 * r.coverage, 1) << " % | " << r.lost_spells << " (" << r.longest_lost_spell << ") | "
         << fixed(r.fps, 1) << " | " << fixed(r.ms.read, 1) << " | " << fixed(r.ms.preprocess, 1) << " | " << fixed(r.ms.track, 1) << " | "
         << fixed(r.ms.integrate, 1) << " | " << fixed(r.ms.raycast, 1) << " | " << fixed(r.ms.total, 1) << " | "
         << fixed(r.worst_frame_ms, 0) << " | " << (front.count(k) ? "yes" : "") << " |\n";
    }
    md << "\n";
  }

  md << "## Overall\n\n"
     << "| method | inputs tracked / run | failed runs | mean ATE RMSE [m] | mean ms per frame | frames | lost |\n"
     << "|---|---:|---:|---:|---:|---:|---:|\n";
  for (const MethodSummary& s : summarize_methods(results.runs, results.methods)) {
    md << "| " << s.name << " | " << s.inputs_comparable << " / " << s.inputs_run << " | " << s.runs_failed << " | "
       << metres(s.mean_ate_m) << " | " << (s.mean_ms_per_frame ? fixed(*s.mean_ms_per_frame, 1) : "-") << " | "
       << s.frames << " | " << s.frames_lost << " |\n";
  }
  md << "\nMean ATE over the inputs each method tracked (so the rows may average different inputs: the won-lost-tie "
        "table below compares them on the same inputs).\n\n";

  md << "## Won-lost-tie (ATE RMSE)\n\n" << format_wlt_markdown(won_lost_tie(results.runs, results.methods)) << "\n";
  md << "## Won-lost-tie (translational RPE over 1 s)\n\n"
     << format_wlt_markdown(won_lost_tie(results.runs, results.methods, ErrorMetric::rpe_translation)) << "\n";
  md << "## Won-lost-tie (translational RPE per frame pair)\n\n"
     << format_wlt_markdown(won_lost_tie(results.runs, results.methods, ErrorMetric::rpe_frame_translation))
     << "\n";

  if (!plot_files.empty()) {
    md << "## Speed against error\n\n";
    for (const std::string& f : plot_files) md << "![" << f << "](" << f << ")\n\n";
  }
  return md.str();
}

std::vector<std::string> write_results(const std::string& dir, const BenchResults& results,
                                       const std::vector<std::string>& plot_files) {
  const std::string csv = dir + "/results.csv", json = dir + "/results.json", md = dir + "/results.md";
  write_file_atomically(csv, [&](std::ostream& out) { out << results_to_csv(results.runs); });
  // A path with bytes that are not UTF-8 must not make the whole report fail: such bytes become U+FFFD.
  write_file_atomically(json, [&](std::ostream& out) {
    out << results_to_json(results).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
  });
  write_file_atomically(md, [&](std::ostream& out) { out << results_to_markdown(results, plot_files); });
  return {csv, json, md};
}

}  // namespace hf::bench
