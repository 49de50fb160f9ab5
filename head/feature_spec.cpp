#include "head/feature_spec.h"

#include <charconv>
#include <cmath>

#include "core/error.h"

namespace hf::head {
namespace {

std::string quoted(std::string_view s) {
  std::string out = "'";
  for (char c : s.substr(0, 60)) out += (c >= 32 && c < 127) ? c : '?';
  return out + (s.size() > 60 ? "...'" : "'");
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

float parse_percent(std::string_view s, std::string_view whole) {
  s = trim(s);
  float v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v))
    throw Error("--threshold: expected two numbers 'a,b' in percent, got " + quoted(whole));
  return v;
}

}  // namespace

ThresholdRange parse_threshold(std::string_view text) {
  const size_t comma = text.find(',');
  if (comma == std::string_view::npos)
    throw Error("--threshold: expected two numbers 'a,b' in percent, got " + quoted(text));
  ThresholdRange r{parse_percent(text.substr(0, comma), text), parse_percent(text.substr(comma + 1), text)};
  if (r.a < -100 || r.b > 100 || r.a > r.b)
    throw Error("--threshold: expected -100 <= a <= b <= 100 (percent of |w_max|, eq. 10), got " + quoted(text));
  return r;
}

std::vector<MorphologyStep> parse_morphology(std::string_view text) {
  std::vector<MorphologyStep> steps;
  text = trim(text);
  if (text.empty() || text == "none") return steps;
  while (true) {
    const size_t comma = text.find(',');
    const std::string_view item = trim(text.substr(0, comma));
    const size_t colon = item.find(':');
    if (colon == std::string_view::npos)
      throw Error("--morphology: expected OP:K items (OP dilate|erode|open|close), got " + quoted(item));
    const std::string_view op = trim(item.substr(0, colon)), k_text = trim(item.substr(colon + 1));
    MorphologyStep step;
    if (op == "dilate") step.op = MorphologyOp::dilate;
    else if (op == "erode") step.op = MorphologyOp::erode;
    else if (op == "open") step.op = MorphologyOp::open;
    else if (op == "close") step.op = MorphologyOp::close;
    else throw Error("--morphology: unknown operator " + quoted(op) + " (expected dilate, erode, open or close)");
    const auto [end, ec] = std::from_chars(k_text.data(), k_text.data() + k_text.size(), step.k);
    if (k_text.empty() || ec != std::errc() || end != k_text.data() + k_text.size() || step.k < 0 || step.k > 1000)
      throw Error("--morphology: expected an integer k in 0..1000 after '" + std::string(op) + ":', got " +
                  quoted(k_text));
    steps.push_back(step);
    if (comma == std::string_view::npos) break;
    text = text.substr(comma + 1);
  }
  return steps;
}

Evaluation parse_evaluation(std::string_view text) {
  if (text == "discrete") return Evaluation::discrete;
  if (text == "mls") return Evaluation::mls;
  if (text == "laplace") return Evaluation::laplace;
  throw Error("--method: expected discrete, mls or laplace, got " + quoted(text));
}

Quantity parse_quantity(std::string_view text) {
  if (text == "mean") return Quantity::mean;
  if (text == "gaussian") return Quantity::gaussian;
  if (text == "k_max") return Quantity::k_max;
  if (text == "k_min") return Quantity::k_min;
  throw Error("--quantity: expected mean, gaussian, k_max or k_min, got " + quoted(text));
}

const char* evaluation_name(Evaluation e) {
  switch (e) {
    case Evaluation::discrete: return "discrete";
    case Evaluation::mls: return "mls";
    case Evaluation::laplace: return "laplace";
  }
  return "?";
}

const char* quantity_name(Quantity q) {
  switch (q) {
    case Quantity::mean: return "mean";
    case Quantity::gaussian: return "gaussian";
    case Quantity::k_max: return "k_max";
    case Quantity::k_min: return "k_min";
  }
  return "?";
}

}  // namespace hf::head
