#include "common/axis_direction.h"

#include <algorithm>
#include <cmath>

namespace docunfold {

double WrapToQuarterTurn(double a) {
  a = std::fmod(a, 90.0);
  if (a > 45) a -= 90;
  if (a <= -45) a += 90;
  return a;
}

AxisDirection DominantAxisDirection(const std::vector<DirectionVote>& votes, double agree_deg) {
  AxisDirection out;
  for (const DirectionVote& v : votes) {
    out.length += v.length;
    ++out.lines;
  }
  if (votes.empty() || out.length <= 0) return out;
  // Length per half degree, smoothed over +-1.5 degrees (circular, period 90).
  constexpr int kBins = 180;
  std::vector<double> hist(kBins, 0.0);
  for (const DirectionVote& v : votes) {
    const int bin = int(std::floor((WrapToQuarterTurn(v.angle_deg) + 45) * 2));
    for (int k = -6; k <= 6; ++k)
      hist[((bin + k) % kBins + kBins) % kBins] += v.length * std::exp(-0.5 * (k / 3.0) * (k / 3.0));
  }
  const int peak = int(std::max_element(hist.begin(), hist.end()) - hist.begin());
  const double centre = WrapToQuarterTurn(peak / 2.0 - 45 + 0.25);
  double sum = 0, weight = 0;
  for (const DirectionVote& v : votes) {
    const double d = WrapToQuarterTurn(v.angle_deg - centre);
    if (std::abs(d) > agree_deg) continue;
    sum += v.length * d;
    weight += v.length;
  }
  out.angle_deg = WrapToQuarterTurn(centre + (weight > 0 ? sum / weight : 0));
  out.share = weight / out.length;
  return out;
}

}  // namespace docunfold
