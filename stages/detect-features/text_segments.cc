// Text segments: characters chained along the text direction, their baseline
// cut where it bends and fitted by straight pieces.
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "common/statistics.h"
#include "stages/detect-features/feature_parts.h"

namespace docunfold::features::detail {
namespace {

// On a page whose rows join, a chain's own letters' band under this many
// text heights is a separator's, not text (receipts' lowercase: 0.7 and
// more, their "=" and "-" rows 0.4 to 0.5).
constexpr double kMinOwnBand = 0.6;

// A character candidate: a connected component with its pixels and, once
// the text direction d and its normal n are known, its extent along both.
struct Mark {
  int label = 0;
  cv::Rect box;
  cv::Point2d centre;
  std::vector<cv::Point> pixels;
  double a0 = 0, a1 = 0;  // along d
  double c0 = 0, c1 = 0;  // along n
  double height() const { return c1 - c0 + 1; }
  double along_mid() const { return 0.5 * (a0 + a1); }
  double across_mid() const { return 0.5 * (c0 + c1); }
};

// Direction (radians in [0, pi)) of the text lines: the angle at which the
// marks' centres, projected across it, pile up most sharply (projection
// profiles, as in classical skew detection), summed over a 3x3 grid of tiles
// so that lines converging under perspective still count. (Nearest-neighbour
// directions fail when letters merge into words: the next line is then
// nearer than the next word.)
double TextDirection(const std::vector<Mark>& marks, double char_size) {
  std::vector<cv::Point2d> points;
  for (const Mark& m : marks)
    if (std::sqrt(double(m.box.area())) <= 3.0 * char_size) points.push_back(m.centre);
  if (points.size() < 3) return 0;
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const auto& p : points) {
    x0 = std::min(x0, p.x);
    y0 = std::min(y0, p.y);
    x1 = std::max(x1, p.x);
    y1 = std::max(y1, p.y);
  }
  constexpr int kTiles = 3;
  std::vector<std::vector<cv::Point2d>> tiles(kTiles * kTiles);
  for (const auto& p : points) {
    const int tx = std::min(kTiles - 1, int((p.x - x0) / std::max(1e-9, x1 - x0) * kTiles));
    const int ty = std::min(kTiles - 1, int((p.y - y0) / std::max(1e-9, y1 - y0) * kTiles));
    tiles[size_t(ty * kTiles + tx)].push_back(p);
  }
  const double bin = std::max(1.0, 0.3 * char_size);
  auto score = [&](double theta) {
    const double nx = -std::sin(theta), ny = std::cos(theta);
    double total = 0;
    std::map<long, int> hist;
    for (const auto& tile : tiles) {
      if (tile.size() < 10) continue;
      hist.clear();
      for (const auto& p : tile) ++hist[long(std::floor((p.x * nx + p.y * ny) / bin))];
      double sq = 0;
      for (const auto& [k, c] : hist) sq += double(c) * c;
      total += sq / double(tile.size());
    }
    return total;
  };
  double best = 0, best_score = -1;
  for (int deg = 0; deg < 180; ++deg) {
    const double sc = score(deg * CV_PI / 180);
    if (sc > best_score) {
      best_score = sc;
      best = deg * CV_PI / 180;
    }
  }
  const double coarse = best;
  for (int k = -10; k <= 10; ++k) {
    const double theta = coarse + k * 0.1 * CV_PI / 180;
    const double sc = score(theta);
    if (sc > best_score) {
      best_score = sc;
      best = theta;
    }
  }
  best = std::fmod(best + CV_PI, CV_PI);
  // Monospaced text (receipts) also piles up sharply across its columns.
  // When the best direction roughly across the first scores nearly as well,
  // take the one along which neighbours are nearer: letters in a line are
  // closer than lines (proportional text piles up far less in columns, so
  // merged words, whose neighbours across lines are nearer, never get here).
  double across = 0, across_score = -1;
  for (int deg = 65; deg <= 115; ++deg) {
    const double theta = best + deg * CV_PI / 180;
    const double sc = score(theta);
    if (sc > across_score) {
      across_score = sc;
      across = theta;
    }
  }
  if (across_score < 0.6 * best_score) return best;
  auto median_spacing = [&](double theta) {
    const cv::Point2d dir(std::cos(theta), std::sin(theta));
    std::vector<double> nearest;
    for (size_t i = 0; i < points.size(); ++i) {
      double d = 1e300;
      for (size_t j = 0; j < points.size(); ++j) {
        if (i == j) continue;
        const cv::Point2d v = points[j] - points[i];
        const double along = std::abs(v.dot(dir)), off = std::abs(v.x * dir.y - v.y * dir.x);
        if (off < 0.3 * along && along < d) d = along;
      }
      if (d < 1e299) nearest.push_back(d);
    }
    return nearest.empty() ? 1e300 : Median(nearest);
  };
  if (median_spacing(across) < median_spacing(best)) best = std::fmod(across + CV_PI, CV_PI);
  return best;
}

// Step 1: the marks of character size (merged letters of a word included),
// with their pixels and centres; none when there are fewer than three.
std::vector<Mark> CharacterMarks(const InkComponents& ink) {
  const double diag = std::hypot(ink.labels.cols, ink.labels.rows);
  std::vector<int> mark_of(size_t(ink.count), -1);
  std::vector<Mark> marks;
  for (int l = 1; l < ink.count; ++l) {
    const int w = ink.stats(l, cv::CC_STAT_WIDTH), h = ink.stats(l, cv::CC_STAT_HEIGHT);
    const int area = ink.stats(l, cv::CC_STAT_AREA);
    if (area < 5 || std::max(w, h) < 3) continue;
    if (std::min(w, h) > 0.03 * diag || std::max(w, h) > 0.08 * diag) continue;
    if (area < 0.08 * w * h) continue;  // thin diagonal strokes, frames
    Mark m;
    m.label = l;
    m.box = cv::Rect(ink.stats(l, cv::CC_STAT_LEFT), ink.stats(l, cv::CC_STAT_TOP), w, h);
    mark_of[size_t(l)] = int(marks.size());
    marks.push_back(std::move(m));
  }
  if (marks.size() < 3) return {};
  for (int y = 0; y < ink.labels.rows; ++y) {
    const int* row = ink.labels.ptr<int>(y);
    for (int x = 0; x < ink.labels.cols; ++x)
      if (row[x] > 0 && mark_of[size_t(row[x])] >= 0)
        marks[size_t(mark_of[size_t(row[x])])].pixels.emplace_back(x, y);
  }
  for (Mark& m : marks) {
    cv::Point2d c(0, 0);
    for (const cv::Point& p : m.pixels) c += cv::Point2d(p);
    m.centre = c * (1.0 / double(m.pixels.size()));
  }
  return marks;
}

// The text direction d and its normal n (n points down the image for
// left-to-right lines).
struct TextAxes {
  double theta = 0;  // radians
  cv::Point2d d, n;
};

// Step 2: the text direction, and every mark's extent along d and n.
TextAxes FindTextAxes(std::vector<Mark>& marks) {
  std::vector<double> sizes;
  for (const Mark& m : marks) sizes.push_back(std::sqrt(double(m.box.area())));
  TextAxes axes;
  axes.theta = TextDirection(marks, Median(sizes));
  const double theta = axes.theta;
  const cv::Point2d d(std::cos(theta), std::sin(theta)), n(-std::sin(theta), std::cos(theta));
  axes.d = d;
  axes.n = n;
  for (Mark& m : marks) {
    m.a0 = m.c0 = 1e300;
    m.a1 = m.c1 = -1e300;
    for (const cv::Point& p : m.pixels) {
      const double a = p.x * d.x + p.y * d.y, c = p.x * n.x + p.y * n.y;
      m.a0 = std::min(m.a0, a);
      m.a1 = std::max(m.a1, a);
      m.c0 = std::min(m.c0, c);
      m.c1 = std::max(m.c1, c);
    }
  }
  return axes;
}

// Step 3: chains of neighbours: the nearest mark ahead along d of similar
// height whose across-extent overlaps, if each is the other's choice. Only
// marks of about the median height `h_med` take part (dots, commas and noise
// are too small to chain; large marks are not text). `cell`: the grid the
// marks are looked up in.
std::vector<std::vector<int>> ChainMarks(const std::vector<Mark>& marks, double h_med, double cell,
                                         const FeaturesOptions& options) {
  std::vector<int> usable;
  for (size_t i = 0; i < marks.size(); ++i)
    if (marks[i].height() >= 0.4 * h_med && marks[i].height() <= 2.5 * h_med)
      usable.push_back(int(i));

  double ax0 = 1e300, cy0 = 1e300;
  for (int i : usable) {
    ax0 = std::min(ax0, marks[i].a0);
    cy0 = std::min(cy0, marks[i].c0);
  }
  std::map<std::pair<int, int>, std::vector<int>> grid;
  for (int i : usable) {
    const Mark& m = marks[i];
    for (int gy = int((m.c0 - cy0) / cell); gy <= int((m.c1 - cy0) / cell); ++gy)
      for (int gx = int((m.a0 - ax0) / cell); gx <= int((m.a1 - ax0) / cell); ++gx)
        grid[{gx, gy}].push_back(i);
  }
  std::vector<int> next(marks.size(), -1), prev(marks.size(), -1);
  std::vector<double> next_gap(marks.size(), 1e300), prev_gap(marks.size(), 1e300);
  for (int i : usable) {
    const Mark& m = marks[i];
    const double reach = options.max_gap * 5.0 * m.height();
    for (int gy = int((m.c0 - cy0) / cell); gy <= int((m.c1 - cy0) / cell); ++gy)
      for (int gx = int((m.a1 - ax0) / cell); gx <= int((m.a1 + reach - ax0) / cell); ++gx) {
        auto it = grid.find({gx, gy});
        if (it == grid.end()) continue;
        for (int j : it->second) {
          if (j == i) continue;
          const Mark& o = marks[j];
          const double hmin = std::min(m.height(), o.height());
          const double hmax = std::max(m.height(), o.height());
          if (hmax > 2.0 * hmin) continue;
          const double gap = o.a0 - m.a1;
          if (gap < -0.3 * hmin || gap > options.max_gap * hmax) continue;
          if (o.along_mid() <= m.along_mid()) continue;
          const double overlap = std::min(m.c1, o.c1) - std::max(m.c0, o.c0) + 1;
          if (overlap < 0.5 * hmin) continue;
          if (gap < next_gap[i]) {
            next_gap[i] = gap;
            next[i] = j;
          }
          if (gap < prev_gap[j]) {
            prev_gap[j] = gap;
            prev[j] = i;
          }
        }
      }
  }
  std::vector<std::vector<int>> chains;
  for (int i : usable) {
    const bool head = prev[i] < 0 || next[prev[i]] != i;
    if (!head) continue;
    std::vector<int> chain = {i};
    for (int k = i; next[k] >= 0 && prev[next[k]] == k; k = next[k]) chain.push_back(next[k]);
    if (chain.size() >= 2) chains.push_back(std::move(chain));
  }
  return chains;
}

// A chain's centre line (the line fitted to its marks' middles, as the height
// across the text at each position along it) and its marks' tops and bottoms
// measured from that line.
struct ChainBand {
  LineFit fit;
  double slope = 0;
  std::vector<double> tops, bottoms;
  double Trend(double along) const { return fit.point.y + slope * (along - fit.point.x); }
};

ChainBand FitChainBand(const std::vector<Mark>& marks, const std::vector<int>& chain) {
  ChainBand band;
  std::vector<cv::Point2d> mids;
  for (int k : chain) mids.emplace_back(marks[k].along_mid(), marks[k].across_mid());
  band.fit = FitLine(mids);
  band.slope =
      band.fit.direction.y / (std::abs(band.fit.direction.x) > 1e-9 ? band.fit.direction.x : 1e-9);
  for (int k : chain) {
    const double trend = band.Trend(marks[k].along_mid());
    band.tops.push_back(marks[k].c0 - trend);
    band.bottoms.push_back(marks[k].c1 - trend);
  }
  return band;
}

// Step 4: the line height (x-height band) from each chain's medians of tops
// and bottoms, after removing its tilt; `h_med` when no chain has three marks.
double LineHeight(const std::vector<Mark>& marks, const std::vector<std::vector<int>>& chains,
                  double h_med) {
  std::vector<double> line_heights;
  for (const auto& chain : chains) {
    if (chain.size() < 3) continue;
    const ChainBand band = FitChainBand(marks, chain);
    line_heights.push_back(Median(band.bottoms) - Median(band.tops) + 1);
  }
  return line_heights.empty() ? h_med : Median(line_heights);
}

// The chained text lines, as the later steps read them.
struct TextLines {
  std::vector<Mark> marks;
  std::vector<std::vector<int>> chains;
  cv::Point2d d, n;
  double x_height = 0;
  double bin = 0;   // width of the bins along d an outline is sampled in
  double cell = 0;  // grid cell of the mark lookups
};

// One sample of a chain's outline: where along d, how far along sign * n,
// and which mark it is on.
struct Sample {
  double a, c;
  int mark;
};

// The outline of a chain on one side: in narrow bins along the line, the
// ink's extreme towards sign * n (sign +1: the +n side). `band`: the height
// of the letters' band the ink must nearly cross (below, the page's text
// height).
std::vector<Sample> Outline(const TextLines& lines, const std::vector<int>& chain, double sign,
                            double band) {
  const std::vector<Mark>& marks = lines.marks;
  const cv::Point2d d = lines.d, n = lines.n;
  const double bin = lines.bin;
  std::vector<Sample> samples;
  for (int k : chain) {
    const Mark& m = marks[k];
    const int bins = int((m.a1 - m.a0) / bin) + 1;
    std::vector<double> best(size_t(bins), -1e300), best_a(size_t(bins), 0),
        least(size_t(bins), 1e300);
    for (const cv::Point& p : m.pixels) {
      const double a = p.x * d.x + p.y * d.y, c = sign * (p.x * n.x + p.y * n.y);
      const int b = std::min(bins - 1, int((a - m.a0) / bin));
      if (c > best[size_t(b)]) {
        best[size_t(b)] = c;
        best_a[size_t(b)] = a;
      }
      least[size_t(b)] = std::min(least[size_t(b)], c);
    }
    // Only bins the ink crosses nearly from one side of the x-height band
    // to the other (stems, bowls): at the flanks of round letters the
    // extreme is somewhere in the middle of the band. The ink's edge lies
    // half a pixel beyond the last ink pixel's centre.
    for (int b = 0; b < bins; ++b)
      if (best[size_t(b)] > -1e299 && best[size_t(b)] - least[size_t(b)] >= 0.6 * band)
        samples.push_back({best_a[size_t(b)], best[size_t(b)] + 0.5, k});
  }
  std::sort(samples.begin(), samples.end(),
            [](const Sample& p, const Sample& q) { return p.a < q.a; });
  return samples;
}

// Each sample's offset from the median of its neighbours within
// `half_window` pixels either way, the chain's overall tilt (fitted to the
// samples `tilt_from` marks, all when empty) removed. Descenders, or
// ascenders, stick out.
std::vector<double> Offsets(const std::vector<Sample>& samples, double half_window,
                            const std::vector<char>& tilt_from = {}) {
  std::vector<double> out(samples.size(), 0.0);
  if (samples.size() < 3) return out;
  std::vector<cv::Point2d> raw;
  for (size_t k = 0; k < samples.size(); ++k)
    if (tilt_from.empty() || tilt_from[k]) raw.emplace_back(samples[k].a, samples[k].c);
  const LineFit tilt = FitLine(raw);
  const double slope =
      tilt.direction.y / (std::abs(tilt.direction.x) > 1e-9 ? tilt.direction.x : 1e-9);
  std::vector<double> e(samples.size());
  for (size_t k = 0; k < samples.size(); ++k)
    e[k] = samples[k].c - (tilt.point.y + slope * (samples[k].a - tilt.point.x));
  for (size_t k = 0, lo = 0, hi = 0; k < samples.size(); ++k) {
    while (samples[lo].a < samples[k].a - half_window) ++lo;
    while (hi < samples.size() && samples[hi].a <= samples[k].a + half_window) ++hi;
    out[k] = e[k] - Median(std::vector<double>(e.begin() + long(lo), e.begin() + long(hi)));
  }
  return out;
}

// Step 5a: how far (pixels, summed over the chains) the outlines on the +n
// and on the -n side stray from their local median: almost every letter
// sits on the baseline, while on the other side the x-height and the
// ascenders, capitals and digits alternate (counted over narrow bins, so
// letters merged into words at low resolution do not matter).
void StrayVotes(const TextLines& lines, double* stray_plus, double* stray_minus) {
  const double x_height = lines.x_height;
  for (const auto& chain : lines.chains) {
    if (chain.size() < 3) continue;
    for (double side : {1.0, -1.0})
      for (double o : Offsets(Outline(lines, chain, side, x_height), 3 * x_height))
        (side > 0 ? *stray_plus : *stray_minus) += std::min(std::abs(o), 0.6 * x_height);
  }
}

// Step 5b: small marks by the chains: periods and commas sit inside the band
// on the baseline, i- and j-dots float outside it on the other side.
// Counts the evidence that the baseline is on +n and on -n.
void DotVotes(const InkComponents& ink, const TextLines& lines, int* dots_plus, int* dots_minus) {
  const std::vector<Mark>& marks = lines.marks;
  const cv::Point2d d = lines.d, n = lines.n;
  const double x_height = lines.x_height, cell = lines.cell;
  std::vector<Mark> small;
  for (int l = 1; l < ink.count; ++l) {
    const int w = ink.stats(l, cv::CC_STAT_WIDTH), h = ink.stats(l, cv::CC_STAT_HEIGHT);
    if (ink.stats(l, cv::CC_STAT_AREA) < 2 || std::max(w, h) > 0.45 * x_height) continue;
    Mark m;
    const double left = ink.stats(l, cv::CC_STAT_LEFT) - 0.5,
                 top = ink.stats(l, cv::CC_STAT_TOP) - 0.5;
    m.a0 = m.c0 = 1e300;
    m.a1 = m.c1 = -1e300;
    for (const cv::Point2d corner : {cv::Point2d(left, top), cv::Point2d(left + w, top),
                                     cv::Point2d(left, top + h), cv::Point2d(left + w, top + h)}) {
      const double a = corner.dot(d), c = corner.dot(n);
      m.a0 = std::min(m.a0, a);
      m.a1 = std::max(m.a1, a);
      m.c0 = std::min(m.c0, c);
      m.c1 = std::max(m.c1, c);
    }
    small.push_back(m);
  }
  std::map<std::pair<int, int>, std::vector<const Mark*>> small_grid;
  for (const Mark& m : small)
    small_grid[{int(std::floor(m.along_mid() / cell)), int(std::floor(m.across_mid() / cell))}]
        .push_back(&m);
  for (const auto& chain : lines.chains) {
    if (chain.size() < 3) continue;
    const ChainBand band = FitChainBand(marks, chain);
    auto trend = [&](double a) { return band.Trend(a); };
    const double t = Median(band.tops), b = Median(band.bottoms), x = b - t;
    if (x < 2) continue;
    const double a_first = marks[chain.front()].a0, a_last = marks[chain.back()].a1;
    const double mid = trend(0.5 * (a_first + a_last));
    for (int gx = int(std::floor(a_first / cell)); gx <= int(std::floor(a_last / cell)); ++gx)
      for (int gy = int(std::floor((mid + t - x) / cell));
           gy <= int(std::floor((mid + b + x) / cell)); ++gy) {
        auto it = small_grid.find({gx, gy});
        if (it == small_grid.end()) continue;
        for (const Mark* m : it->second) {
          if (m->along_mid() < a_first || m->along_mid() > a_last) continue;
          const double base = trend(m->along_mid());
          const double c0 = m->c0 - base, c1 = m->c1 - base, c = 0.5 * (c0 + c1);
          if (c < t - 0.9 * x || c > b + 0.9 * x) continue;
          if (c1 < t + 0.1 * x)
            ++*dots_plus;  // a dot above the band (-n side)
          else if (c0 > b - 0.1 * x)
            ++*dots_minus;  // a dot beyond the +n side
          else if (c1 >= b - 0.25 * x && c0 > t + 0.4 * x)
            ++*dots_plus;  // a period on +n
          else if (c0 <= t + 0.25 * x && c1 < b - 0.4 * x)
            ++*dots_minus;  // a period on -n
        }
      }
  }
}

// Step 5: which side is the baseline, from both kinds of evidence (recorded
// in `result`): -1 on -n, +1 on +n, 0 where neither is clear (a receipt of
// capitals and digits without periods) or they disagree. Then no text
// segments are made: a mean line taken for a baseline would be off by a
// whole x-height.
int BaselineSide(const InkComponents& ink, const TextLines& lines, TextResult* result) {
  double stray_plus = 0, stray_minus = 0;
  StrayVotes(lines, &stray_plus, &stray_minus);
  int dots_plus = 0, dots_minus = 0;  // evidence that the baseline is on +n / -n
  DotVotes(ink, lines, &dots_plus, &dots_minus);
  result->votes_upright = int(std::lround(stray_minus));
  result->votes_upside_down = int(std::lround(stray_plus));
  result->dots_upright = dots_plus;
  result->dots_upside_down = dots_minus;
  const int by_stray = stray_minus > 1.15 * stray_plus   ? 1
                       : stray_plus > 1.15 * stray_minus ? -1
                                                         : 0;
  const int dots = dots_plus + dots_minus;
  const int by_dots = dots >= 5 && dots_plus >= 0.75 * dots    ? 1
                      : dots >= 5 && dots_minus >= 0.75 * dots ? -1
                                                               : 0;
  return by_stray != 0 && by_dots != 0 && by_stray != by_dots ? 0
         : by_stray != 0                                      ? by_stray
                                                              : by_dots;
}

// Step 6, for one chain: the outline on the baseline side (`sign`),
// descenders and raised parts dropped, cut where it bends; appends the
// straight pieces to `pieces` (short ones too: a piece may continue
// another across a gap). `receipt`: on a page whose rows join, the chain's
// tilt is fitted again without its descenders (docs/decisions/
// detect-features.md, "Short words' tilt refitted on receipts") and its
// outline sampled against its own letters' band ("A till roll's rows").
void AddBaselinePieces(const TextLines& lines, const std::vector<int>& chain, double sign,
                       double tolerance, const FeaturesOptions& options, bool receipt,
                       std::vector<BaselinePiece>* pieces) {
  const cv::Point2d d = lines.d, n = lines.n;
  const double x_height = lines.x_height;
  double letters = x_height;
  if (receipt) {
    // A till roll's text height is that of its digits and capitals; the
    // lowercase of its items would never cross 0.6 of it. A chain whose
    // own band is under 0.6 text heights is not text but a separator's
    // dashes or double bars, with no ink on the baseline.
    const ChainBand own = FitChainBand(lines.marks, chain);
    letters = std::min(x_height, Median(own.bottoms) - Median(own.tops) + 1);
    if (letters < kMinOwnBand * x_height) return;
  }
  const std::vector<Sample> samples = Outline(lines, chain, sign, letters);
  // Fewer than 5 make no segment alone, but a price of a few digits may
  // continue its item's baseline.
  if (samples.size() < (options.row_gap > 0 ? 3u : 5u)) return;
  std::vector<double> off = Offsets(samples, 3 * x_height);
  if (receipt) {
    // A short word's tilt is pulled by its descenders ("Apples": two p's of
    // six letters) until they pass the band below; fitted again without
    // the samples beyond the baseline side, they stick out.
    std::vector<char> on_baseline(samples.size());
    size_t count = 0;
    for (size_t k = 0; k < samples.size(); ++k) count += on_baseline[k] = off[k] <= 0.5 * tolerance;
    if (count >= 3) off = Offsets(samples, 3 * x_height, on_baseline);
  }
  const double band = 0.2 * x_height + 0.5;
  std::vector<Sample> kept_samples;
  for (size_t k = 0; k < samples.size(); ++k)
    if (std::abs(off[k]) <= band) kept_samples.push_back(samples[k]);
  // Where to cut is decided on the running median of the baseline: single
  // samples a pixel off (the pixel grid, serifs, JPEG) would otherwise cut
  // a straight line into pieces too short to keep, while a crease bends it
  // over more than the window and still cuts it.
  const std::vector<double> noise = options.bend_window > 0
                                        ? Offsets(kept_samples, options.bend_window * x_height)
                                        : std::vector<double>(kept_samples.size(), 0.0);
  std::vector<cv::Point2d> kept, smooth;
  std::vector<int> kept_mark;
  for (size_t k = 0; k < kept_samples.size(); ++k) {
    const double c = sign * kept_samples[k].c;  // back to image pixels
    const double cs = sign * (kept_samples[k].c - noise[k]);
    kept.emplace_back(kept_samples[k].a * d.x + c * n.x, kept_samples[k].a * d.y + c * n.y);
    smooth.emplace_back(kept_samples[k].a * d.x + cs * n.x, kept_samples[k].a * d.y + cs * n.y);
    kept_mark.push_back(kept_samples[k].mark);
  }
  for (auto [first, last] : SplitWhereBent(smooth, tolerance)) {
    // Each piece's line is fitted to its samples within half the tolerance
    // of the running median: the few farther off (serifs, a descender's
    // stub) would tilt it.
    BaselinePiece piece;
    for (int k = first; k <= last; ++k)
      if (std::abs(noise[size_t(k)]) <= 0.5 * tolerance) piece.samples.push_back(kept[size_t(k)]);
    for (int k = first; k <= last; ++k) {
      piece.characters += k == first || kept_mark[size_t(k)] != kept_mark[size_t(k - 1)];
      piece.height = std::max(piece.height, lines.marks[size_t(kept_mark[size_t(k)])].height());
    }
    if (piece.samples.size() < 3 || piece.characters < 2) continue;
    if (FitLine(piece.samples).rms > 0.5 * tolerance) continue;
    piece.chain = chain.front();
    piece.first = kept[size_t(first)];
    piece.last = kept[size_t(last)];
    pieces->push_back(std::move(piece));
  }
}

// Step 7: one segment per group of pieces (JoinBaselinePieces), fitted to
// all of their samples, if long enough and chained from enough characters.
void AddBaselineSegments(const std::vector<BaselinePiece>& pieces,
                         const std::vector<std::vector<int>>& groups, double tolerance,
                         double min_length, std::vector<Segment>* segments) {
  for (const std::vector<int>& group : groups) {
    std::vector<cv::Point2d> samples;
    int characters = 0;
    for (int k : group) {
      samples.insert(samples.end(), pieces[size_t(k)].samples.begin(),
                     pieces[size_t(k)].samples.end());
      characters += pieces[size_t(k)].characters;
    }
    if (samples.size() < 5 || characters < 3) continue;
    const LineFit fit = FitLine(samples);
    if (fit.rms > 0.5 * tolerance) continue;
    auto project = [&](const cv::Point2d& p) {
      return fit.point + fit.direction * (p - fit.point).dot(fit.direction);
    };
    const cv::Point2d p0 = project(pieces[size_t(group.front())].first);
    const cv::Point2d p1 = project(pieces[size_t(group.back())].last);
    if (cv::norm(p1 - p0) < min_length) continue;
    segments->push_back({"text", {p0, p1}, characters});
  }
}

}  // namespace

TextResult DetectTextSegments(const InkComponents& ink, const cv::Mat1b& grey,
                              const cv::Mat3b& colour, const FeaturesOptions& options) {
  TextResult result;
  result.is_character.assign(size_t(ink.count), 0);
  // 1. Marks of character size.
  TextLines lines;
  lines.marks = CharacterMarks(ink);
  if (lines.marks.size() < 3) return result;
  const std::vector<Mark>& marks = lines.marks;

  // 2. Text direction d and its normal n.
  const TextAxes axes = FindTextAxes(lines.marks);
  lines.d = axes.d;
  lines.n = axes.n;
  result.direction_deg = axes.theta * 180.0 / CV_PI;
  std::vector<double> heights;
  for (const Mark& m : marks) heights.push_back(m.height());
  const double h_med = Median(heights);

  // 3. Chains of neighbouring marks.
  lines.cell = 4.0 * h_med;
  lines.chains = ChainMarks(marks, h_med, lines.cell, options);

  // 4. Line height.
  result.height = LineHeight(marks, lines.chains, h_med);
  lines.x_height = result.height;
  lines.bin = std::max(1.5, 0.4 * lines.x_height);

  // 5. Which side is the baseline.
  const int side = BaselineSide(ink, lines, &result);
  const double sign = side < 0 ? -1.0 : 1.0;
  result.orientation_known = side != 0;
  if (side != 0) result.down = sign * lines.n;
  // Upside down: the baselines lie on the image-up side of their letters.
  result.upside_down = side != 0 && sign * lines.n.y < 0;

  // 6. Baselines, cut where they bend into straight pieces.
  const double tolerance = std::max(options.bend_px, options.bend_rel * lines.x_height);
  for (const auto& chain : lines.chains)
    for (int k : chain) result.is_character[size_t(marks[k].label)] = 1;
  auto baseline_pieces = [&](bool receipt) {
    std::vector<BaselinePiece> pieces;
    if (result.orientation_known)
      for (const auto& chain : lines.chains)
        AddBaselinePieces(lines, chain, sign, tolerance, options, receipt, &pieces);
    return pieces;
  };
  std::vector<BaselinePiece> pieces = baseline_pieces(false);

  // 7. Pieces of one row joined across wide gaps, then fitted and kept if
  // long enough. On a page whose rows join (a receipt) the pieces are made
  // again, short words' tilt refitted and each chain sampled against its
  // own letters' band; text pages keep theirs.
  std::vector<std::vector<int>> groups;
  if (options.row_gap > 0) {
    const cv::Point2d up = -sign * lines.n;
    const GapTest rules = BlankGapTest(ink, lines.d, up, lines.x_height, h_med);
    const GapTest layer = OnePaperLayerTest(grey, ink.labels, up, lines.x_height);
    const GapTest hue = OnePaperHueTest(colour, ink.labels, up, lines.x_height);
    auto join = [&] {
      return JoinBaselinePieces(pieces, lines.d, lines.x_height, tolerance,
                                options.row_gap * lines.x_height,
                                [&](const cv::Point2d& a, const cv::Point2d& b) {
                                  return rules(a, b) && layer(a, b) && hue(a, b);
                                });
    };
    groups = join();
    if (groups.size() < pieces.size()) {
      pieces = baseline_pieces(true);
      groups = join();
    }
  } else {
    for (int k = 0; k < int(pieces.size()); ++k) groups.push_back({k});
  }
  const double min_length =
      std::max(options.min_length_px, options.min_text_length * lines.x_height);
  AddBaselineSegments(pieces, groups, tolerance, min_length, &result.segments);
  return result;
}

}  // namespace docunfold::features::detail
