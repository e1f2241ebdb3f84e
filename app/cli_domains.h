#pragma once
// Domains of the numeric command-line options. A value outside its domain is a parse error that
// names the option and the domain; main() turns every parse error into exit status 2.
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

namespace tb::cli {

// An integer in [lo, hi] (rejects fractions, non-numbers and out-of-range values).
inline CLI::Validator integer_in(long long lo, long long hi) {
  const std::string domain = hi == std::numeric_limits<long long>::max() ? fmt::format(">= {}", lo)
                                                                        : fmt::format("in [{}, {}]", lo, hi);
  return CLI::Validator(
      [=](std::string& s) -> std::string {
        long long v = 0;
        if (!CLI::detail::lexical_cast(s, v) || v < lo || v > hi)
          return fmt::format("must be an integer {} (got '{}')", domain, s);
        return {};
      },
      "INT " + domain);
}
inline CLI::Validator integer_at_least(long long lo) { return integer_in(lo, std::numeric_limits<long long>::max()); }

// An unsigned 64-bit integer written in decimal digits (seeds; "-1" would otherwise wrap around).
inline CLI::Validator unsigned_integer() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        uint64_t v = 0;
        const bool digits = !s.empty() && s.find_first_not_of("0123456789") == std::string::npos;
        if (!digits || !CLI::detail::lexical_cast(s, v))
          return fmt::format("must be an integer in [0, 2^64) (got '{}')", s);
        return {};
      },
      "UINT64");
}

// A finite number in the interval given by lo, hi and whether each end is included.
inline CLI::Validator number_in(double lo, bool lo_closed, double hi, bool hi_closed) {
  const std::string domain = fmt::format("{}{}, {}{}", lo_closed ? "[" : "(", lo,
                                         std::isinf(hi) ? std::string("inf") : fmt::format("{}", hi),
                                         hi_closed ? "]" : ")");
  return CLI::Validator(
      [=](std::string& s) -> std::string {
        double v = 0;
        const bool ok = CLI::detail::lexical_cast(s, v) && std::isfinite(v) && (lo_closed ? v >= lo : v > lo) &&
                        (hi_closed ? v <= hi : v < hi);
        if (!ok) return fmt::format("must be a number in {} (got '{}')", domain, s);
        return {};
      },
      "NUMBER in " + domain);
}

inline CLI::Validator positive_number() { return number_in(0, false, std::numeric_limits<double>::infinity(), false); }
inline CLI::Validator nonnegative_number() { return number_in(0, true, std::numeric_limits<double>::infinity(), false); }

}  // namespace tb::cli
