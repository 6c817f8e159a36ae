// The direction, modulo 90 degrees, that most of a set of straight lines'
// length follows: on a page, printed rows and rules run along its axes.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace docunfold {

struct DirectionVote {
  double angle_deg = 0;  // direction of a line, counter-clockwise from the x axis
  double length = 0;     // its weight
};

struct AxisDirection {
  // Counter-clockwise from the x axis, reduced to (-45, 45]: turning the
  // lines by -angle_deg puts most of them along the axes.
  double angle_deg = 0;
  double share = 0;   // fraction of the length within `agree_deg` of it
  double length = 0;  // total length that voted
  int lines = 0;      // how many voted
};

// The mode of the votes' length over directions modulo 90 degrees (a
// histogram smoothed over +-1.5 degrees), refined by the length-weighted mean
// of the votes within `agree_deg` of it. No votes: all zero.
AxisDirection DominantAxisDirection(const std::vector<DirectionVote>& votes, double agree_deg = 3);

// `angle_deg` reduced modulo 90 to (-45, 45].
double WrapToQuarterTurn(double angle_deg);

// A direction given in one plane carried into another (e.g. the reader's
// down from reference-image pixels into M'): the least-squares affine map
// taking each `from[i]` to `to[i]`, applied to `direction`, normalised.
// nullopt with fewer than `min_pairs` pairs, points on one line, or a
// direction the map sends to nothing.
std::optional<Eigen::Vector2d> CarryDirection(const std::vector<Eigen::Vector2d>& from,
                                              const std::vector<Eigen::Vector2d>& to,
                                              const Eigen::Vector2d& direction, int min_pairs = 10);

}  // namespace docunfold
