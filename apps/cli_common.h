// What every `hashfusion` subcommand shares, so one convention holds across them (README, "The command line"):
//   - range checks whose messages print numbers short ("expected 0.0001..10, got 1e+09"), never CLI11's
//     std::to_string of DBL_MAX (309 digits);
//   - deprecated spellings of renamed options: still accepted, with a one-line notice on stderr naming the new one
//     (scripts and the commands committed in bench/results keep running);
//   - the output folder: `--out DIR`, default `out/SUBCOMMAND` in every subcommand that writes files;
#pragma once

#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>
#include <string>

#include "core/number_text.h"

namespace hf::apps {

// lo <= value <= hi (numbers as CLI11 parsed them); "expected LO..HI[ UNIT], got X".
inline CLI::Validator in_range(double lo, double hi, const std::string& unit = "") {
  const std::string description =
      number_for_message(lo) + ".." + number_for_message(hi) + (unit.empty() ? "" : " " + unit);
  return CLI::Validator(
      [lo, hi, description](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v)) return "expected a number, got '" + text + "'";
        if (!(v >= lo && v <= hi)) return "expected " + description + ", got " + number_for_message(v);
        return {};
      },
      description);
}

// value > 0 (finite).
inline CLI::Validator positive() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v)) return "expected a number, got '" + text + "'";
        if (!(v > 0.0 && v <= 1e300)) return "expected a finite number > 0, got " + number_for_message(v);
        return {};
      },
      "> 0");
}

// value >= 0 (finite).
inline CLI::Validator non_negative() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v)) return "expected a number, got '" + text + "'";
        if (!(v >= 0.0 && v <= 1e300)) return "expected a finite number >= 0, got " + number_for_message(v);
        return {};
      },
      ">= 0");
}

// The ranges two subcommands share (run and bench): one definition, so they cannot differ.
inline CLI::Validator voxel_m_range() { return in_range(1e-4, 10.0, "m"); }
inline CLI::Validator tracking_level_range() { return in_range(0, 2); }
// Frames of a synthetic sequence (run --synthetic-frames, generate --frames; bench's needs 2 for a trajectory).
inline CLI::Validator synthetic_frames_range(double lo = 1) { return in_range(lo, 100000, "frames"); }
// A noise seed (run, generate): an unsigned 64-bit number; CLI11 alone wraps "-1" to 18446744073709551615.
inline CLI::Validator seed_range() { return in_range(0, 18446744073709551615.0); }

// `--out` of a subcommand that writes files: default "out/NAME" (NAME the subcommand's), shown by --help as
// "--out TEXT=out/NAME", so `hashfusion NAME` with no --out writes where every other subcommand would put its own.
inline CLI::Option* add_out_option(CLI::App* cmd, std::string& variable, const std::string& description) {
  variable = "out/" + cmd->get_name();
  return cmd->add_option("--out", variable, description)->capture_default_str();
}

// `old_name` as a hidden alias of the option `new_name` writing `variable`: accepted, with the notice
// "hashfusion: OLD is deprecated; use NEW" on stderr. The two exclude each other.
template <class T>
CLI::Option* add_deprecated_alias(CLI::App* cmd, CLI::Option* current, const std::string& old_name, T& variable) {
  const std::string new_name = current->get_name();
  CLI::Option* old = cmd->add_option(old_name, variable, "deprecated: " + new_name);
  old->group("");  // hidden from --help
  old->each([old_name, new_name](const std::string&) {
    std::cerr << "hashfusion: " << old_name << " is deprecated; use " << new_name << "\n";
  });
  old->excludes(current);
  // One direction enforces it (CLI11 checks each option's own list); the other would print a dangling "Excludes: "
  // after the new option in --help, naming the hidden alias by an empty string.
  current->remove_excludes(old);
  return old;
}

}  // namespace hf::apps
