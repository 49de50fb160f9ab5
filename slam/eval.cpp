#include "slam/eval.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "core/error.h"
#include "io/associate.h"

namespace hf {
namespace {

std::string fixed(double value, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

std::string shortest(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

std::string describe(const Trajectory& trajectory) {
  return std::to_string(trajectory.size()) + " poses, " + fixed(trajectory.front().timestamp_s, 4) + " .. " +
         fixed(trajectory.back().timestamp_s, 4) + " s";
}

std::vector<double> stamps_of(const Trajectory& trajectory) {
  std::vector<double> stamps;
  stamps.reserve(trajectory.size());
  for (const StampedPose& pose : trajectory) stamps.push_back(pose.timestamp_s);
  return stamps;
}

// numpy.median: the middle value, or the mean of the two middle values for an even count.
double median_of(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : values[n / 2 - 1] * 0.5 + values[n / 2] * 0.5;
}

}  // namespace

ErrorStats compute_error_stats(const std::vector<double>& values) {
  ErrorStats stats;
  stats.count = values.size();
  if (values.empty()) return stats;
  const double n = double(values.size());
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  stats.min = *lo;
  stats.max = *hi;
  // Sums of values scaled by the largest magnitude: finite values up to DBL_MAX give finite statistics (squaring
  // 1e200 or adding n of 1e308 would overflow to inf and then NaN).
  const double scale = std::max(std::fabs(*lo), std::fabs(*hi));
  const double unit = scale > 0.0 && std::isfinite(scale) ? scale : 1.0;
  double sum = 0.0, sum_sq = 0.0;
  for (double v : values) {
    sum += v / unit / n;
    sum_sq += (v / unit) * (v / unit);
  }
  stats.mean = sum * unit;
  stats.rmse = std::sqrt(sum_sq / n) * unit;
  double var = 0.0;  // two-pass, as numpy.std, instead of sum_sq / n - mean^2 which cancels
  for (double v : values) var += (v / unit - stats.mean / unit) * (v / unit - stats.mean / unit) / n;
  stats.std = std::sqrt(var) * unit;
  stats.median = median_of(values);
  return stats;
}

size_t find_closest_index(const std::vector<double>& L, double t) {
  if (L.empty()) return 0;
  size_t beginning = 0, end = L.size(), best = 0;
  double difference = std::fabs(L[0] - t);
  while (beginning < end) {
    const size_t middle = (beginning + end) / 2;
    if (std::fabs(L[middle] - t) < difference) {
      difference = std::fabs(L[middle] - t);
      best = middle;
    }
    if (t == L[middle]) return middle;
    if (L[middle] > t) {
      end = middle;
    } else {
      beginning = middle + 1;
    }
  }
  return best;
}

double rotation_angle_rad(const Eigen::Quaterniond& q) {
  // q and -q are the same rotation; |w| picks the representative with angle <= pi.
  return 2.0 * std::atan2(q.vec().norm(), std::fabs(q.w()));
}

SE3 align_horn(const std::vector<Eigen::Vector3d>& model, const std::vector<Eigen::Vector3d>& data) {
  if (model.size() != data.size() || model.empty()) {
    throw Error("align_horn: needs the same positive number of model and data points, got " +
                std::to_string(model.size()) + " and " + std::to_string(data.size()));
  }
  const double n = double(model.size());
  Eigen::Vector3d model_mean = Eigen::Vector3d::Zero(), data_mean = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < model.size(); ++k) {
    model_mean += model[k];
    data_mean += data[k];
  }
  model_mean /= n;
  data_mean /= n;
  Eigen::Matrix3d W = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < model.size(); ++k) W += (model[k] - model_mean) * (data[k] - data_mean).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(W.transpose(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& U = svd.matrixU();
  const Eigen::Matrix3d& V = svd.matrixV();
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  // Singular values are sorted decreasing (as numpy's), so the sign flip lands on the least significant axis.
  if (U.determinant() * V.determinant() < 0.0) S(2, 2) = -1.0;
  const Eigen::Matrix3d R = U * S * V.transpose();
  const Eigen::Vector3d t = data_mean - R * model_mean;
  return SE3(R, t);
}

AteResult evaluate_ate(const Trajectory& gt, const Trajectory& est, const AteOptions& options) {
  if (!std::isfinite(options.max_difference_s) || options.max_difference_s <= 0.0) {
    throw Error("ATE: max difference must be a positive number of seconds, got " +
                std::to_string(options.max_difference_s));
  }
  if (!std::isfinite(options.offset_s)) throw Error("ATE: time offset must be finite");
  if (gt.empty()) throw Error("ATE: the ground-truth trajectory has no poses");
  if (est.empty()) throw Error("ATE: the estimated trajectory has no poses");

  const std::vector<Match> matches = associate(
      stamps_of(gt), stamps_of(est), {.max_difference_s = options.max_difference_s, .offset_s = options.offset_s});
  const std::string window = shortest(options.max_difference_s) + " s" +
                             (options.offset_s != 0.0 ? " (offset " + shortest(options.offset_s) + " s)" : "");
  if (matches.empty()) {
    throw Error("no pose pairs within " + window + " between the ground truth (" + describe(gt) +
                ") and the estimate (" + describe(est) +
                "); are they the same sequence? (see --max-difference / --offset)");
  }
  if (matches.size() < kMinAtePairs) {
    throw Error("only " + std::to_string(matches.size()) + " pose pair(s) within " + window +
                " between the ground truth (" + describe(gt) + ") and the estimate (" + describe(est) +
                "); ATE alignment needs at least " + std::to_string(kMinAtePairs));
  }

  std::vector<Eigen::Vector3d> model, data;  // the script's align(second_xyz = estimate, first_xyz = gt)
  model.reserve(matches.size());
  data.reserve(matches.size());
  for (const Match& m : matches) {
    data.push_back(gt[m.a].T_world_camera.translation());
    model.push_back(est[m.b].T_world_camera.translation());
  }
  AteResult result;
  result.T_gt_est = align_horn(model, data);
  const Eigen::Matrix3d R = result.T_gt_est.rotation();
  const Eigen::Vector3d& t = result.T_gt_est.translation();
  std::vector<double> errors;
  errors.reserve(matches.size());
  for (size_t k = 0; k < matches.size(); ++k) {
    const double error = (R * model[k] + t - data[k]).norm();
    errors.push_back(error);
    result.pairs.push_back({.gt_index = matches[k].a,
                            .est_index = matches[k].b,
                            .gt_stamp_s = gt[matches[k].a].timestamp_s,
                            .est_stamp_s = est[matches[k].b].timestamp_s,
                            .error_m = error});
  }
  result.error_m = compute_error_stats(errors);
  return result;
}

Trajectory apply_alignment(const Trajectory& est, const SE3& T_gt_est) {
  Trajectory aligned;
  aligned.reserve(est.size());
  for (const StampedPose& pose : est) aligned.push_back({pose.timestamp_s, T_gt_est * pose.T_world_camera});
  return aligned;
}

RpeResult evaluate_rpe(const Trajectory& gt, const Trajectory& est, const RpeOptions& options) {
  if (!std::isfinite(options.delta_s) || options.delta_s <= 0.0) {
    throw Error("RPE: delta must be a positive number of seconds, got " + std::to_string(options.delta_s));
  }
  if (!std::isfinite(options.offset_s)) throw Error("RPE: time offset must be finite");
  if (options.delta_frames < 0) throw Error("RPE: delta in frames must be >= 0, got " + std::to_string(options.delta_frames));
  RpeResult result;
  result.delta_s = options.delta_s;
  if (gt.size() < 2 || est.size() < 2) return result;

  const std::vector<double> stamps_gt = stamps_of(gt), stamps_est = stamps_of(est);
  std::vector<double> gt_intervals;
  gt_intervals.reserve(stamps_gt.size() - 1);
  for (size_t k = 1; k < stamps_gt.size(); ++k) gt_intervals.push_back(stamps_gt[k] - stamps_gt[k - 1]);
  result.gt_max_time_difference_s = 2.0 * median_of(gt_intervals);

  std::vector<double> trans, rot;
  const size_t last = est.size() - 1;
  const bool in_frames = options.delta_frames > 0;
  const double divisor = in_frames ? static_cast<double>(options.delta_frames) : options.delta_s;
  for (size_t i = 0; i < est.size(); ++i) {
    const size_t j = in_frames ? std::min(i + static_cast<size_t>(options.delta_frames), last)
                               : find_closest_index(stamps_est, stamps_est[i] + options.delta_s);
    if (j == last) continue;
    const double query_0 = stamps_est[i] + options.offset_s, query_1 = stamps_est[j] + options.offset_s;
    const size_t g0 = find_closest_index(stamps_gt, query_0), g1 = find_closest_index(stamps_gt, query_1);
    if (std::fabs(stamps_gt[g0] - query_0) > result.gt_max_time_difference_s ||
        std::fabs(stamps_gt[g1] - query_1) > result.gt_max_time_difference_s) {
      ++result.rejected_gap_pairs;
      continue;
    }
    const SE3& E0 = est[i].T_world_camera;
    const SE3& E1 = est[j].T_world_camera;
    const SE3& G0 = gt[g0].T_world_camera;
    const SE3& G1 = gt[g1].T_world_camera;
    const SE3 error = (E1.inverse() * E0).inverse() * (G1.inverse() * G0);
    RpePair pair{.est_index_0 = i,
                 .est_index_1 = j,
                 .gt_index_0 = g0,
                 .gt_index_1 = g1,
                 .est_stamp_0_s = stamps_est[i],
                 .est_stamp_1_s = stamps_est[j],
                 .gt_stamp_0_s = stamps_gt[g0],
                 .gt_stamp_1_s = stamps_gt[g1],
                 .trans_m_per_s = error.translation().norm() / divisor,
                 .rot_deg_per_s = rotation_angle_rad(error.quaternion()) * 180.0 / std::numbers::pi / divisor};
    trans.push_back(pair.trans_m_per_s);
    rot.push_back(pair.rot_deg_per_s);
    result.pairs.push_back(pair);
  }
  result.trans_m_per_s = compute_error_stats(trans);
  result.rot_deg_per_s = compute_error_stats(rot);
  return result;
}

TrajectoryMetrics EvalResult::metrics() const {
  TrajectoryMetrics m;
  m.pairs = ate.pairs.size();
  m.ate_m = ate.error_m;
  m.rpe_pairs = rpe.pairs.size();
  m.rpe_delta_s = rpe.delta_s;
  if (!rpe.empty()) {
    m.rpe_trans_m_per_s = rpe.trans_m_per_s;
    m.rpe_rot_deg_per_s = rpe.rot_deg_per_s;
  }
  return m;
}

EvalResult evaluate_trajectory(const Trajectory& gt, const Trajectory& est, const EvalOptions& options) {
  EvalResult result;
  result.ate = evaluate_ate(gt, est, {.max_difference_s = options.max_difference_s, .offset_s = options.offset_s});
  result.rpe = evaluate_rpe(gt, est, {.delta_s = options.rpe_delta_s, .offset_s = options.offset_s});
  return result;
}

namespace {

void put_stats(nlohmann::json& j, const std::string& prefix, const std::string& unit,
               const std::optional<ErrorStats>& stats) {
  const std::pair<const char*, double ErrorStats::*> fields[] = {
      {"rmse", &ErrorStats::rmse}, {"mean", &ErrorStats::mean}, {"median", &ErrorStats::median},
      {"std", &ErrorStats::std},   {"min", &ErrorStats::min},   {"max", &ErrorStats::max}};
  for (const auto& [name, member] : fields) {
    const std::string key = prefix + "_" + name + "_" + unit;
    if (stats && std::isfinite((*stats).*member)) {
      j[key] = (*stats).*member;
    } else {
      j[key] = nullptr;
    }
  }
}

struct Row {
  std::string name;
  std::optional<ErrorStats> stats;
  std::string unit;
  size_t count;
};

std::vector<Row> rows_of(const TrajectoryMetrics& m) {
  return {{"ATE", m.ate_m, "m", m.pairs},
          {"RPE trans", m.rpe_trans_m_per_s, "m/s", m.rpe_pairs},
          {"RPE rot", m.rpe_rot_deg_per_s, "deg/s", m.rpe_pairs}};
}

}  // namespace

nlohmann::json metrics_to_json(const TrajectoryMetrics& m) {
  nlohmann::json j = nlohmann::json::object();
  j["pairs"] = m.pairs;
  put_stats(j, "ate", "m", m.ate_m);
  j["rpe_pairs"] = m.rpe_pairs;
  j["rpe_delta_s"] = m.rpe_delta_s;
  put_stats(j, "rpe_trans", "m_per_s", m.rpe_trans_m_per_s);
  put_stats(j, "rpe_rot", "deg_per_s", m.rpe_rot_deg_per_s);
  return j;
}

nlohmann::json per_frame_to_json(const EvalResult& result) {
  nlohmann::json ate = nlohmann::json::array(), rpe = nlohmann::json::array();
  for (const AtePair& p : result.ate.pairs) {
    ate.push_back({{"gt_stamp_s", p.gt_stamp_s}, {"est_stamp_s", p.est_stamp_s}, {"error_m", p.error_m}});
  }
  for (const RpePair& p : result.rpe.pairs) {
    rpe.push_back({{"est_stamp_0_s", p.est_stamp_0_s},
                   {"est_stamp_1_s", p.est_stamp_1_s},
                   {"gt_stamp_0_s", p.gt_stamp_0_s},
                   {"gt_stamp_1_s", p.gt_stamp_1_s},
                   {"trans_m_per_s", p.trans_m_per_s},
                   {"rot_deg_per_s", p.rot_deg_per_s}});
  }
  return {{"ate", ate}, {"rpe", rpe}};
}

std::string format_metrics_table(const TrajectoryMetrics& m) {
  std::ostringstream out;
  char line[160];
  std::snprintf(line, sizeof line, "%-10s %-6s %6s %10s %10s %10s %10s %10s %10s\n", "metric", "unit", "pairs", "rmse",
                "mean", "median", "std", "min", "max");
  out << line;
  for (const Row& row : rows_of(m)) {
    if (!row.stats) {
      std::snprintf(line, sizeof line, "%-10s %-6s %6zu %10s   (no pose pair %.3g s apart)\n", row.name.c_str(),
                    row.unit.c_str(), row.count, "-", m.rpe_delta_s);
    } else {
      const ErrorStats& s = *row.stats;
      std::snprintf(line, sizeof line, "%-10s %-6s %6zu %10.6f %10.6f %10.6f %10.6f %10.6f %10.6f\n", row.name.c_str(),
                    row.unit.c_str(), row.count, s.rmse, s.mean, s.median, s.std, s.min, s.max);
    }
    out << line;
  }
  return out.str();
}

std::string format_metrics_markdown(const TrajectoryMetrics& m) {
  std::ostringstream out;
  out << "| metric | unit | pairs | RMSE | mean | median | std | min | max |\n";
  out << "|---|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Row& row : rows_of(m)) {
    out << "| " << row.name << " | " << row.unit << " | " << row.count << " |";
    if (!row.stats) {
      out << " - | - | - | - | - | - |\n";
      continue;
    }
    const ErrorStats& s = *row.stats;
    for (double v : {s.rmse, s.mean, s.median, s.std, s.min, s.max}) out << ' ' << fixed(v, 6) << " |";
    out << '\n';
  }
  return out.str();
}

}  // namespace hf
