#include "bvh_collision/geometry/limits.h"

#include <cmath>
#include <cstdio>

namespace bvh_collision {
namespace {

std::string amount(double asked) {
  if (!std::isfinite(asked)) return "an unbounded number";
  char text[64];
  std::snprintf(text, sizeof text, asked < 1e15 ? "%.0f" : "%.3g", asked);  // 1e+300, not 300 digits
  return text;
}

}  // namespace

LimitExceeded::LimitExceeded(const std::string& what, double asked, std::size_t limit, const std::string& parameter)
    : std::invalid_argument(what + " needs " + amount(asked) + ", more than the limit of " + std::to_string(limit) +
                            " (parameter ~" + parameter + " raises it)") {}

void check_limit(const std::string& what, double asked, std::size_t limit, const std::string& parameter) {
  if (!(asked <= static_cast<double>(limit))) throw LimitExceeded(what, asked, limit, parameter);
}

}  // namespace bvh_collision
