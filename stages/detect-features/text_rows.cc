// Baseline pieces of one text row joined across wide gaps: a receipt's item
// and its price lie far apart on one baseline, each too short to keep alone
// (docs/decisions/detect-features.md, "Receipt rows joined across their gap").
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "common/statistics.h"
#include "stages/detect-features/feature_parts.h"

namespace docunfold::features::detail {
namespace {

constexpr double kDegree = CV_PI / 180;
constexpr double kMaxAngle = 1.0 * kDegree;  // a group's own line against the joint one
constexpr double kMaxTurn = 3.0 * kDegree;   // the joint line against the rows around it
constexpr double kMaxOffset = 0.15;          // of the x-height: rows lie a line apart
constexpr double kMaxHeightRatio = 1.25;     // one font size: digits against letters
constexpr int kNeighbours = 8;               // pieces around one that tell the rows' direction
// A page's rows are joined only when those that bridge a gap wider than
// kWideGap text heights make this share of the rows' length
// (feature_parts.h, JoinBaselinePieces): on the text pages, tables and the
// poster at most 0.21, on the receipts at least 0.61.
constexpr double kWideGap = 3.0;
constexpr double kMinGappedLength = 0.4;
constexpr double kMaxDrift = 1.5;  // text heights a line may drift over a gap (3 sigma)
// The largest step of the paper's grey within a gap, of the brighter side:
// a fold's shadow along a receipt's rows reaches 6 %, the blank back of a
// corner curled over the page 11 % (docs/decisions/detect-features.md,
// "A join stays on one layer of paper").
constexpr double kMaxPaperStep = 0.08;
// The largest step of the paper's chromaticity along a gap and a text height
// into either piece: at most 0.0045 on the receipts' rows, 0.016 to 0.018
// where r07's rows run under the tip of its curled corner
// (docs/decisions/detect-features.md, "A till roll's rows").
constexpr double kMaxHueStep = 0.01;

// Whether a pixel is ink or its 1 px rim (antialiasing).
bool NearInk(const cv::Mat1i& labels, int x, int y) {
  for (int v = std::max(0, y - 1); v <= std::min(labels.rows - 1, y + 1); ++v)
    for (int u = std::max(0, x - 1); u <= std::min(labels.cols - 1, x + 1); ++u)
      if (labels(v, u) != 0) return true;
  return false;
}

double Cross(cv::Point2d u, cv::Point2d v) { return u.x * v.y - u.y * v.x; }

// Angle (radians, in (-pi/2, pi/2]) of the undirected line `u` from `d`.
double AngleFrom(cv::Point2d d, cv::Point2d u) {
  double a = std::atan2(Cross(d, u), d.dot(u));
  if (a > CV_PI / 2) a -= CV_PI;
  if (a <= -CV_PI / 2) a += CV_PI;
  return a;
}

// Standard deviation (radians) of the direction of a line fitted to `n`
// samples spread over `length` pixels with residuals `rms`: that of the
// slope, rms * sqrt(12 / n) / length (at least 0.3 px: the pixel grid).
double DirectionSigma(const LineFit& fit, double n, double length) {
  return std::max(fit.rms, 0.3) * std::sqrt(12.0 / n) / std::max(1.0, length);
}

// Pieces joined so far, in text order: their samples and extent along d.
struct Group {
  std::vector<int> pieces;
  std::vector<cv::Point2d> samples;
  double a0 = 0, a1 = 0;
};

// Whether `a` and `b` (b after a along the text, whose direction is `d`)
// continue one straight baseline. The joint line must fit every sample as a
// single piece's would and run along the rows around both ends (`rows_a`,
// `rows_b`: their angles from d); each group must sit on it, not beside it
// (the next row), and point along it as far as its length tells its
// direction (a kink at a crease in the gap tilts both pieces against their
// joint line); the bend test that cuts a chain cuts the joint baseline too.
bool Continues(const Group& a, const Group& b, cv::Point2d d, double rows_a, double rows_b,
               double x_height, double tolerance) {
  std::vector<cv::Point2d> all = a.samples;
  all.insert(all.end(), b.samples.begin(), b.samples.end());
  const LineFit joint = FitLine(all);
  if (joint.rms > 0.5 * tolerance) return false;
  const double joint_angle = AngleFrom(d, joint.direction);
  if (std::abs(joint_angle - rows_a) > kMaxTurn || std::abs(joint_angle - rows_b) > kMaxTurn)
    return false;
  bool direction_known = false;
  for (const Group* g : {&a, &b}) {
    const double n = double(g->samples.size());
    cv::Point2d centre(0, 0);
    double offset = 0;
    for (const cv::Point2d& p : g->samples) {
      offset += Cross(joint.direction, p - joint.point);
      centre += p * (1.0 / n);
    }
    if (std::abs(offset / n) > kMaxOffset * x_height) return false;
    const LineFit own = FitLine(g->samples);
    const double sigma = DirectionSigma(own, n, g->a1 - g->a0);
    const double angle = std::acos(std::min(1.0, std::abs(own.direction.dot(joint.direction))));
    if (angle > std::max(kMaxAngle, 3 * sigma)) return false;
    // Two short pieces fit some line whatever rows they are on: one of them
    // must tell the direction well enough that its line, carried to the
    // far end of the other, stays short of the next row (two text heights
    // or more away) within three standard deviations.
    double reach = 0;
    for (const cv::Point2d& p : all) reach = std::max(reach, std::abs((p - centre).dot(d)));
    direction_known |= 3 * sigma * reach <= kMaxDrift * x_height;
  }
  if (!direction_known) return false;
  return SplitWhereBent(all, tolerance).size() == 1;
}

// Per piece: the median angle from d of the pieces nearest to it, the
// direction of the rows around it (0 when there are too few).
std::vector<double> RowAngles(const std::vector<BaselinePiece>& pieces,
                              const std::vector<double>& angles) {
  std::vector<cv::Point2d> centres;
  for (const BaselinePiece& p : pieces) centres.push_back(0.5 * (p.first + p.last));
  std::vector<double> out(pieces.size(), 0.0);
  for (size_t i = 0; i < pieces.size(); ++i) {
    std::vector<std::pair<double, size_t>> near;
    for (size_t j = 0; j < pieces.size(); ++j)
      if (j != i) near.emplace_back(cv::norm(centres[j] - centres[i]), j);
    if (near.size() < 3) continue;
    const size_t k = std::min(near.size(), size_t(kNeighbours));
    std::partial_sort(near.begin(), near.begin() + long(k), near.end());
    std::vector<double> around;
    for (size_t m = 0; m < k; ++m) around.push_back(angles[near[m].second]);
    out[i] = Median(around);
  }
  return out;
}

}  // namespace

GapTest BlankGapTest(const InkComponents& ink, cv::Point2d d, cv::Point2d up, double x_height,
                     double char_height) {
  // Rules are told from characters by their extent across the text or, along
  // it, by being long and thin.
  const cv::Point2d n = up;
  std::vector<double> a0(size_t(ink.count), 1e300), a1(size_t(ink.count), -1e300);
  std::vector<double> c0 = a0, c1 = a1;
  for (int y = 0; y < ink.labels.rows; ++y) {
    const int* row = ink.labels.ptr<int>(y);
    for (int x = 0; x < ink.labels.cols; ++x) {
      if (row[x] == 0) continue;
      const size_t l = size_t(row[x]);
      const double a = x * d.x + y * d.y, c = x * n.x + y * n.y;
      a0[l] = std::min(a0[l], a);
      a1[l] = std::max(a1[l], a);
      c0[l] = std::min(c0[l], c);
      c1[l] = std::max(c1[l], c);
    }
  }
  auto blocks = std::make_shared<std::vector<char>>(size_t(ink.count), 0);
  for (size_t l = 1; l < size_t(ink.count); ++l) {
    const double across = c1[l] - c0[l] + 1, along = a1[l] - a0[l] + 1;
    const double area = ink.stats(int(l), cv::CC_STAT_AREA);
    (*blocks)[l] =
        across > 2.5 * char_height || (along > 8 * x_height && area < 0.3 * x_height * along);
  }
  const cv::Mat1i& labels = ink.labels;
  return [blocks, up, x_height, &labels](const cv::Point2d& from, const cv::Point2d& to) {
    const int steps = std::max(1, int(cv::norm(to - from)));
    for (double lift = -2.2 * x_height; lift <= 0.6 * x_height; lift += 1.0)
      for (int k = 0; k <= steps; ++k) {
        const cv::Point2d p = from + (to - from) * (double(k) / steps) + up * lift;
        const int x = int(std::lround(p.x)), y = int(std::lround(p.y));
        if (x < 0 || y < 0 || x >= labels.cols || y >= labels.rows) continue;
        if ((*blocks)[size_t(labels(y, x))]) return false;
      }
    return true;
  };
}

namespace {

// Per pixel along the gap, t from t0 to t1 pixels past `from` towards
// `along`: the medians of the N channels `value(x, y)` gives of the paper in
// the letters' band (lifted 0.3, 0.5 and 0.7 text heights along `up`), ink
// and its 1 px rim left out; NaN where all of it is ink or off the image.
template <int N, class Value>
std::vector<cv::Vec<double, N>> PaperAlong(const cv::Mat1i& labels, cv::Point2d from,
                                           cv::Point2d along, cv::Point2d up, double x_height,
                                           double t0, double t1, const Value& value) {
  std::vector<cv::Vec<double, N>> paper;
  for (double t = t0; t <= t1; t += 1.0) {
    std::array<std::vector<double>, N> column;
    for (double lift : {0.3, 0.5, 0.7}) {
      const cv::Point2d p = from + along * t + up * (lift * x_height);
      const int x = int(std::lround(p.x)), y = int(std::lround(p.y));
      if (x < 0 || y < 0 || x >= labels.cols || y >= labels.rows || NearInk(labels, x, y)) continue;
      const cv::Vec<double, N> v = value(x, y);
      for (int c = 0; c < N; ++c) column[size_t(c)].push_back(v[c]);
    }
    cv::Vec<double, N> median;
    for (int c = 0; c < N; ++c)
      median[c] = column[size_t(c)].empty() ? std::nan("") : Median(column[size_t(c)]);
    paper.push_back(median);
  }
  return paper;
}

// Whether channel `c` of `paper` (PaperAlong) steps somewhere: the medians
// over `w` pixels either side of a point, each side at least half paper,
// such that `steps(before, after)`. Shading drifts slowly, the edge of a
// layer over the page steps at once.
template <int N, class Steps>
bool PaperSteps(const std::vector<cv::Vec<double, N>>& paper, int c, int w, const Steps& steps) {
  for (int t = w; t + w <= int(paper.size()); ++t) {
    std::vector<double> before, after;
    for (int k = t - w; k < t + w; ++k)
      if (!std::isnan(paper[size_t(k)][c])) (k < t ? before : after).push_back(paper[size_t(k)][c]);
    if (2 * before.size() < size_t(w) || 2 * after.size() < size_t(w)) continue;
    if (steps(Median(before), Median(after))) return true;
  }
  return false;
}

}  // namespace

GapTest OnePaperHueTest(const cv::Mat3b& colour, const cv::Mat1i& labels, cv::Point2d up,
                        double x_height) {
  return [&colour, &labels, up, x_height](const cv::Point2d& from, const cv::Point2d& to) {
    const double length = cv::norm(to - from);
    const cv::Point2d along = (to - from) * (1.0 / std::max(1e-9, length));
    // The blue and red shares of the paper's colour, from a text height
    // into one piece to a text height into the other.
    const auto paper = PaperAlong<2>(labels, from, along, up, x_height, -x_height,
                                     length + x_height, [&colour](int x, int y) {
                                       const cv::Vec3b c = colour(y, x);
                                       const double sum = std::max(1.0, double(c[0]) + c[1] + c[2]);
                                       return cv::Vec2d(c[0] / sum, c[2] / sum);
                                     });
    const int w = std::max(2, int(std::lround(x_height)));
    auto steps = [](double m0, double m1) { return std::abs(m0 - m1) > kMaxHueStep; };
    return !PaperSteps(paper, 0, w, steps) && !PaperSteps(paper, 1, w, steps);
  };
}

GapTest OnePaperLayerTest(const cv::Mat1b& grey, const cv::Mat1i& labels, cv::Point2d up,
                          double x_height) {
  return [&grey, &labels, up, x_height](const cv::Point2d& from, const cv::Point2d& to) {
    // The paper's grey along the gap, a text height clear of either
    // piece's last letter.
    const double length = cv::norm(to - from);
    const cv::Point2d along = (to - from) * (1.0 / std::max(1e-9, length));
    const auto paper =
        PaperAlong<1>(labels, from, along, up, x_height, x_height, length - x_height,
                      [&grey](int x, int y) { return cv::Vec<double, 1>(grey(y, x)); });
    const int w = std::max(2, int(std::lround(x_height)));
    return !PaperSteps(paper, 0, w, [](double m0, double m1) {
      return std::abs(m0 - m1) > kMaxPaperStep * std::max(m0, m1);
    });
  };
}

std::vector<std::vector<int>> JoinBaselinePieces(const std::vector<BaselinePiece>& pieces,
                                                 cv::Point2d d, double x_height, double tolerance,
                                                 double max_gap, const GapTest& blank) {
  const int count = int(pieces.size());
  std::vector<Group> groups(pieces.size());
  std::vector<int> group_of(pieces.size());
  std::vector<double> angles(pieces.size());
  std::vector<char> joinable(pieces.size());
  for (int i = 0; i < count; ++i) {
    const BaselinePiece& p = pieces[size_t(i)];
    Group& g = groups[size_t(i)];
    g.pieces = {i};
    g.samples = p.samples;
    g.a0 = p.first.dot(d);
    g.a1 = p.last.dot(d);
    group_of[size_t(i)] = i;
    const LineFit fit = FitLine(p.samples);
    angles[size_t(i)] = AngleFrom(d, fit.direction);
  }
  // A piece turned against the rows around it (letters of two rows chained,
  // italics) joins nothing.
  const std::vector<double> rows = RowAngles(pieces, angles);
  for (int i = 0; i < count; ++i) {
    const BaselinePiece& p = pieces[size_t(i)];
    const double sigma = DirectionSigma(FitLine(p.samples), double(p.samples.size()),
                                        groups[size_t(i)].a1 - groups[size_t(i)].a0);
    joinable[size_t(i)] =
        std::abs(angles[size_t(i)] - rows[size_t(i)]) <= std::max(kMaxTurn, 3 * sigma);
  }
  // Candidate pairs: b starts after a ends, within the gap, at about the
  // same height across the text and of about the same character height.
  // Tried nearest first, so that the words of a row join before the row
  // reaches across its wide gap.
  struct Pair {
    double gap;
    int a, b;
  };
  std::vector<Pair> pairs;
  const cv::Point2d n(-d.y, d.x);
  for (int i = 0; i < count; ++i)
    for (int j = 0; j < count; ++j) {
      const BaselinePiece &p = pieces[size_t(i)], &q = pieces[size_t(j)];
      // Pieces of one chain were cut apart where it bends.
      if (p.chain == q.chain || !joinable[size_t(i)] || !joinable[size_t(j)]) continue;
      const double gap = q.first.dot(d) - p.last.dot(d);
      if (gap < -0.5 * x_height || gap > max_gap) continue;
      if (std::max(p.height, q.height) > kMaxHeightRatio * std::min(p.height, q.height)) continue;
      // Loosely: the text direction varies over the page (perspective,
      // panels), the fine test is Continues.
      if (std::abs((q.first - p.last).dot(n)) > x_height + 0.25 * std::max(0.0, gap)) continue;
      pairs.push_back({gap, i, j});
    }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) {
    return x.gap != y.gap ? x.gap < y.gap : std::make_pair(x.a, x.b) < std::make_pair(y.a, y.b);
  });
  for (const Pair& pair : pairs) {
    const int ga = group_of[size_t(pair.a)], gb = group_of[size_t(pair.b)];
    if (ga == gb || groups[size_t(ga)].pieces.back() != pair.a ||
        groups[size_t(gb)].pieces.front() != pair.b)
      continue;
    Group& a = groups[size_t(ga)];
    Group& b = groups[size_t(gb)];
    if (!Continues(a, b, d, rows[size_t(pair.a)], rows[size_t(pair.b)], x_height, tolerance))
      continue;
    if (pair.gap > x_height && blank &&
        !blank(pieces[size_t(pair.a)].last, pieces[size_t(pair.b)].first))
      continue;
    a.pieces.insert(a.pieces.end(), b.pieces.begin(), b.pieces.end());
    a.samples.insert(a.samples.end(), b.samples.begin(), b.samples.end());
    a.a1 = b.a1;
    for (int k : b.pieces) group_of[size_t(k)] = ga;
    b.pieces.clear();
    b.samples.clear();
  }
  std::vector<std::vector<int>> out;
  double length = 0, gapped = 0;
  for (Group& g : groups) {
    if (g.pieces.empty()) continue;
    length += g.a1 - g.a0;
    for (size_t k = 1; k < g.pieces.size(); ++k)
      if (pieces[size_t(g.pieces[k])].first.dot(d) - pieces[size_t(g.pieces[k - 1])].last.dot(d) >
          kWideGap * x_height) {
        gapped += g.a1 - g.a0;
        break;
      }
    out.push_back(std::move(g.pieces));
  }
  if (gapped < kMinGappedLength * length) {
    out.clear();
    for (int i = 0; i < count; ++i) out.push_back({i});
  }
  return out;
}

}  // namespace docunfold::features::detail
