#include "stages/segment-boundary/segment_boundary.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "common/cli.h"
#include "common/errors.h"
#include "stages/segment-boundary/text_orientation.h"

namespace docunfold::boundary {
namespace {

// --- Colour model of the table -------------------------------------------

// Per pixel: colour in a Lab variant where a shadow (linear RGB times k)
// scales the vector by about k^(1/3): (L + 16, a, b). A median, then a
// blur, shrink a textured table's spread (granite, cloth) far more than
// they blur the page outline, which is refined at full resolution anyway;
// the median first keeps the page's colours from smearing into the shadow
// next to it. (Local contrast as a fourth feature would tell shaded paper
// from granite of the same grey, but it widens the region at every edge and
// in every soft shadow: measured worse overall.)
using Feature = cv::Vec3d;
using FeatureCov = cv::Matx33d;
using FeatureImage = cv::Mat3f;
constexpr int kFeatures = 3;

// sRGB to CIE Lab (D65) by hand: OpenCV's cvtColor to Lab builds lookup
// tables on first use that cost about half a second.
FeatureImage PixelFeatures(const cv::Mat3b& bgr) {
  cv::Mat3b smooth;
  cv::medianBlur(bgr, smooth, 5);
  float linear[256];
  for (int v = 0; v < 256; ++v) {
    const double c = v / 255.0;
    linear[v] = float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
  }
  auto f = [](float t) { return t > 0.008856f ? std::cbrt(t) : 7.787f * t + 16.0f / 116.0f; };
  FeatureImage lab(bgr.size());
  for (int y = 0; y < lab.rows; ++y) {
    const cv::Vec3b* in = smooth.ptr<cv::Vec3b>(y);
    cv::Vec3f* out = lab.ptr<cv::Vec3f>(y);
    for (int x = 0; x < lab.cols; ++x) {
      const float b = linear[in[x][0]], g = linear[in[x][1]], r = linear[in[x][2]];
      const float fx = f((0.412453f * r + 0.357580f * g + 0.180423f * b) / 0.950456f);
      const float fy = f(0.212671f * r + 0.715160f * g + 0.072169f * b);
      const float fz = f((0.019334f * r + 0.119193f * g + 0.950227f * b) / 1.088754f);
      out[x] = cv::Vec3f(116.0f * fy, 500.0f * (fx - fy), 200.0f * (fy - fz));  // L + 16, a, b
    }
  }
  cv::GaussianBlur(lab, lab, cv::Size(), 2.0);
  return lab;
}

struct TableModel {
  Feature mean;
  FeatureCov inv_cov;
  double mean_norm2 = 0;  // mean' inv_cov mean
  double inlier_fraction = 0;
};

// The blocks of the image frame that show the table. A page cut off by the
// image border covers runs of the frame; their mean colours (averaged over a
// block, so a textured table's spread mostly cancels) form a second cluster
// far from the table's, which is the larger. Without such a clear second
// cluster (a brightness gradient is not one) the whole frame is table.
std::vector<cv::Rect> TableFrameBlocks(const FeatureImage& lab, int b) {
  std::vector<cv::Rect> blocks;
  for (int x = 0; x + b <= lab.cols; x += b) {
    blocks.emplace_back(x, 0, b, b);
    blocks.emplace_back(x, lab.rows - b, b, b);
  }
  for (int y = b; y + 2 * b <= lab.rows; y += b) {
    blocks.emplace_back(0, y, b, b);
    blocks.emplace_back(lab.cols - b, y, b, b);
  }
  cv::Mat1f means(int(blocks.size()), kFeatures);
  for (size_t i = 0; i < blocks.size(); ++i) {
    const cv::Scalar m = cv::mean(lab(blocks[i]));
    for (int c = 0; c < kFeatures; ++c) means(int(i), c) = float(m[c]);
  }
  if (means.rows < 8) return blocks;
  cv::Mat1i labels;
  cv::Mat1f centres;
  cv::theRNG().state = 0x5eed;  // reproducible clustering
  cv::kmeans(means, 2, labels,
             cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 20, 0.01), 3,
             cv::KMEANS_PP_CENTERS, centres);
  const int table = cv::countNonZero(labels) * 2 > labels.rows ? 1 : 0;
  // Spread of the table's blocks: a brightness gradient split in two gives
  // a gap of about 3.5 spreads, a page a far larger one.
  double spread2 = 0;
  int n_table = 0;
  for (int i = 0; i < means.rows; ++i) {
    if (labels(i) != table) continue;
    const cv::Vec3f d = cv::Vec3f(means.ptr<float>(i)) - cv::Vec3f(centres.ptr<float>(table));
    spread2 += d.dot(d);
    ++n_table;
  }
  const double spread = std::sqrt(spread2 / std::max(1, n_table));
  const double gap = cv::norm(centres.row(0) - centres.row(1));
  if (gap < 8.0 || gap < 5.0 * spread) return blocks;
  // Drop the page's blocks and their neighbours, which may show a bit of it.
  std::vector<cv::Rect> out;
  for (size_t i = 0; i < blocks.size(); ++i) {
    if (labels(int(i)) != table) continue;
    bool near_page = false;
    for (size_t j = 0; j < blocks.size() && !near_page; ++j)
      near_page = labels(int(j)) != table &&
                  (blocks[i] & cv::Rect(blocks[j].x - b, blocks[j].y - b, 3 * b, 3 * b)).area() > 0;
    if (!near_page) out.push_back(blocks[i]);
  }
  return out;
}

// A robust Gaussian of the table's colours in the image frame: pixels far
// from the dominant colour are left out (iteratively reweighted).
TableModel LearnTableModel(const FeatureImage& lab, double frame_fraction) {
  const int b = std::max(2, int(std::lround(frame_fraction * std::min(lab.rows, lab.cols))));
  std::vector<Feature> samples;
  for (const cv::Rect& block : TableFrameBlocks(lab, b))
    for (int y = block.y; y < block.y + block.height; ++y)
      for (int x = block.x; x < block.x + block.width; ++x) samples.push_back(lab(y, x));
  // Start from the largest of a few colour clusters of the frame: where a
  // cut-off page covers a good part of the frame, a median would mix page
  // and table. The iteration below then grows the model over the rest of a
  // textured table's colours (they are contiguous; the page's are far).
  cv::Mat1f data(int(samples.size()), kFeatures);
  for (int i = 0; i < data.rows; ++i)
    for (int c = 0; c < kFeatures; ++c) data(i, c) = float(samples[i][c]);
  cv::Mat1i labels;
  cv::Mat centres;
  cv::theRNG().state = 0x5eed;  // reproducible clustering
  constexpr int kClusters = 4;
  cv::kmeans(data, kClusters, labels,
             cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 20, 0.1), 2,
             cv::KMEANS_PP_CENTERS, centres);
  std::vector<int> counts(kClusters, 0);
  for (int i = 0; i < labels.rows; ++i) ++counts[labels(i)];
  const int larger = int(std::max_element(counts.begin(), counts.end()) - counts.begin());
  Feature mean(0, 0, 0);
  FeatureCov cov = FeatureCov::zeros();
  {
    size_t n = 0;
    for (size_t i = 0; i < samples.size(); ++i)
      if (labels(int(i)) == larger) {
        mean += samples[i];
        ++n;
      }
    mean /= double(n);
    for (size_t i = 0; i < samples.size(); ++i)
      if (labels(int(i)) == larger) {
        const Feature d = samples[i] - mean;
        cov += d * d.t();
      }
    cov *= 1.5 / double(n);
    for (int c = 0; c < kFeatures; ++c) cov(c, c) += 1.0;
  }
  // Floor of the spread: JPEG and sensor noise on a plain table.
  const double min_var = 1.0;
  size_t inliers = samples.size();
  for (int iter = 0; iter < 10; ++iter) {
    const FeatureCov inv = cov.inv(cv::DECOMP_CHOLESKY);
    Feature sum(0, 0, 0);
    FeatureCov sum2 = FeatureCov::zeros();
    size_t n = 0;
    for (const Feature& s : samples) {
      const Feature d = s - mean;
      if ((d.t() * inv * d)(0) > 16.0) continue;  // 99.9 % of a 3-D Gaussian
      sum += s;
      sum2 += s * s.t();
      ++n;
    }
    if (n < 10) break;
    mean = sum / double(n);
    cov = sum2 * (1.0 / double(n)) - mean * mean.t();
    for (int c = 0; c < kFeatures; ++c) cov(c, c) += min_var;
    inliers = n;
  }
  TableModel model;
  model.mean = mean;
  model.inv_cov = cov.inv(cv::DECOMP_CHOLESKY);
  model.mean_norm2 = (mean.t() * model.inv_cov * mean)(0);
  model.inlier_fraction = double(inliers) / double(samples.size());
  return model;
}

// Mahalanobis distance to the table colour, allowing the table to be in
// shadow (darker by a common factor) or a little brighter.
cv::Mat1f TableDistance(const FeatureImage& lab, const TableModel& m) {
  cv::Mat1f out(lab.size());
  const Feature w = m.inv_cov * m.mean;
  for (int y = 0; y < lab.rows; ++y)
    for (int x = 0; x < lab.cols; ++x) {
      const Feature p = lab(y, x);
      const double s = std::clamp(p.dot(w) / m.mean_norm2, 0.2, 1.05);
      const Feature d = p - s * m.mean;
      out(y, x) = float(std::sqrt(std::max(0.0, (d.t() * m.inv_cov * d)(0))));
    }
  return out;
}

// The pixels of `weak` outside `strong` whose 8-connected region of `weak`
// touches `strong`, opened by a disc `min_width` wide: broad areas of
// ambiguous colour joined to the page (a fold's shaded panel), without the
// narrow specks a textured table adds along the outline.
cv::Mat1b WeakPageAttached(const cv::Mat1b& weak, const cv::Mat1b& strong, int min_width) {
  cv::Mat1i labels;
  const int n = cv::connectedComponents(weak, labels, 8, CV_32S);
  std::vector<char> touches(n, 0);
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x)
      if (strong(y, x)) touches[labels(y, x)] = 1;
  cv::Mat1b added(weak.size(), uchar(0));
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x) {
      const int l = labels(y, x);
      if (l > 0 && touches[l] && !strong(y, x)) added(y, x) = 255;
    }
  if (min_width > 1)
    cv::morphologyEx(added, added, cv::MORPH_OPEN,
                     cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(min_width, min_width)));
  return added;
}

// The largest 8-connected region of `mask` with its holes filled.
cv::Mat1b LargestFilledRegion(const cv::Mat1b& mask, double* area = nullptr) {
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  cv::Mat1b out = cv::Mat1b::zeros(mask.size());
  int best = -1;
  double best_area = 0;
  for (size_t i = 0; i < contours.size(); ++i) {
    const double a = cv::contourArea(contours[i]);
    if (a > best_area) {
      best_area = a;
      best = int(i);
    }
  }
  if (best >= 0) cv::drawContours(out, contours, best, 255, cv::FILLED);
  if (area) *area = best_area;
  return out;
}

// --- Full-resolution refinement ------------------------------------------

// Sums of `image` weighted by `weight`, and of the weights, blurred: their
// ratio is the mean colour of the weighted pixels nearby (normalised
// convolution). Kept apart so that they can be interpolated before dividing.
void BlurredWeightedSums(const cv::Mat3f& image, const cv::Mat1f& weight, double sigma,
                         cv::Mat3f* sum, cv::Mat1f* weight_sum) {
  cv::Mat3f w3;
  cv::merge(std::vector<cv::Mat>{weight, weight, weight}, w3);
  cv::multiply(image, w3, *sum);
  cv::GaussianBlur(*sum, *sum, cv::Size(), sigma);
  cv::GaussianBlur(weight, *weight_sum, cv::Size(), sigma);
}

template <typename T>
T SampleBilinear(const cv::Mat_<T>& m, double x, double y) {
  x = std::clamp(x, 0.0, m.cols - 1.0);
  y = std::clamp(y, 0.0, m.rows - 1.0);
  const int x0 = std::min(int(x), m.cols - 2 < 0 ? 0 : m.cols - 2);
  const int y0 = std::min(int(y), m.rows - 2 < 0 ? 0 : m.rows - 2);
  const int x1 = std::min(x0 + 1, m.cols - 1), y1 = std::min(y0 + 1, m.rows - 1);
  const float fx = float(x - x0), fy = float(y - y0);
  return (m(y0, x0) * (1 - fx) + m(y0, x1) * fx) * (1 - fy) +
         (m(y1, x0) * (1 - fx) + m(y1, x1) * fx) * fy;
}

// Moves the outline of the coarse mask to where the colour is halfway between
// the local page colour and the local table colour, at full resolution.
cv::Mat1b RefineAtFullResolution(const cv::Mat3b& full, const cv::Mat3b& small,
                                 const cv::Mat1b& coarse) {
  const double scale = double(full.cols) / small.cols;  // full px per work px
  cv::Mat3f small_f;
  small.convertTo(small_f, CV_32F);
  // The coarse outline may be a few work pixels off: blurred, or with a
  // shadow's dark band along the page taken in. Pixels within kBand of it
  // are decided again from the local page and table colours, taken from
  // rings beyond that band on either side.
  constexpr float kBand = 5.0f, kRing = 6.0f;
  cv::Mat1f dist_in, dist_out;
  cv::distanceTransform(coarse, dist_in, cv::DIST_L2, 3);
  cv::distanceTransform(255 - coarse, dist_out, cv::DIST_L2, 3);
  cv::Mat1f ring_in = (dist_in >= kBand) & (dist_in <= kBand + kRing);
  cv::Mat1f ring_out = (dist_out >= kBand) & (dist_out <= kBand + kRing);
  ring_in /= 255.0f;
  ring_out /= 255.0f;
  cv::Mat3f page_sum, table_sum;
  cv::Mat1f page_w, table_w;
  BlurredWeightedSums(small_f, ring_in, 8.0, &page_sum, &page_w);
  BlurredWeightedSums(small_f, ring_out, 8.0, &table_sum, &table_w);

  cv::Mat1b band_small =
      ((dist_in > 0) & (dist_in <= kBand)) | ((dist_out > 0) & (dist_out <= kBand));
  cv::Mat1b band, mask;
  cv::resize(band_small, band, full.size(), 0, 0, cv::INTER_NEAREST);
  cv::resize(coarse, mask, full.size(), 0, 0, cv::INTER_NEAREST);
  for (int y = 0; y < full.rows; ++y) {
    const uchar* b = band.ptr<uchar>(y);
    uchar* m = mask.ptr<uchar>(y);
    const cv::Vec3b* px = full.ptr<cv::Vec3b>(y);
    for (int x = 0; x < full.cols; ++x) {
      if (!b[x]) continue;
      const double sx = (x + 0.5) / scale - 0.5, sy = (y + 0.5) / scale - 0.5;
      const float wp = SampleBilinear(page_w, sx, sy);
      const float wt = SampleBilinear(table_w, sx, sy);
      if (wp < 1e-3f || wt < 1e-3f) continue;  // no colour sample nearby
      const cv::Vec3f f = SampleBilinear(page_sum, sx, sy) / wp;
      const cv::Vec3f t = SampleBilinear(table_sum, sx, sy) / wt;
      const cv::Vec3f d = f - t;
      const float len2 = d.dot(d);
      if (len2 < 100.0f) continue;  // no contrast here: keep the coarse label
      const cv::Vec3f v = cv::Vec3f(px[x]) - t;
      m[x] = v.dot(d) / len2 > 0.5f ? 255 : 0;
    }
  }
  return mask;
}

// --- Outline, corners, sides ------------------------------------------------

double SignedArea(const std::vector<cv::Point>& c) {
  double a = 0;
  for (size_t i = 0, n = c.size(); i < n; ++i) {
    const cv::Point& p = c[i];
    const cv::Point& q = c[(i + 1) % n];
    a += double(p.x) * q.y - double(q.x) * p.y;
  }
  return 0.5 * a;
}

// Fraction of the outline's area enclosed by the outline from point i to
// point j (clockwise) closed by the chord j-i.
double ChordSideArea(const std::vector<cv::Point>& contour, int i, int j) {
  const int n = int(contour.size());
  std::vector<cv::Point> part;
  for (int k = i;; k = (k + 1) % n) {
    part.push_back(contour[k]);
    if (k == j) break;
  }
  const double total = std::abs(SignedArea(contour));
  return total > 0 ? std::abs(SignedArea(part)) / total : 0;
}

// Whether index k lies strictly between from and to going forward round an
// outline of n points.
bool OnOutlinePath(int n, int from, int to, int k) {
  const int span = ((to - from) % n + n) % n, at = ((k - from) % n + n) % n;
  return at > 0 && at < span;
}

double TriangleArea(const cv::Point& a, const cv::Point& b, const cv::Point& c) {
  return 0.5 * std::abs(double(b.x - a.x) * (c.y - a.y) - double(c.x - a.x) * (b.y - a.y));
}

std::vector<cv::Point2d> ToDouble(const std::vector<cv::Point>& pts) {
  return std::vector<cv::Point2d>(pts.begin(), pts.end());
}

std::vector<cv::Point2d> Simplify(const std::vector<cv::Point2d>& pts, double eps, bool closed) {
  if (pts.size() < 3) return pts;
  std::vector<cv::Point2f> in(pts.begin(), pts.end()), out;
  cv::approxPolyDP(in, out, eps, closed);
  return std::vector<cv::Point2d>(out.begin(), out.end());
}

// Outline points on either side of a point over which its turning is
// measured, and its corner's sides fitted: a few percent of the outline.
int CornerReach(size_t outline_points) { return std::max(2, int(0.025 * double(outline_points))); }

double PolylineLength(const std::vector<cv::Point2d>& p) {
  double l = 0;
  for (size_t i = 1; i < p.size(); ++i) l += cv::norm(p[i] - p[i - 1]);
  return l;
}

// Drops the points next to either end of a side that lie behind its corner:
// a sharpened corner of a shallow turn (150 degrees and more) moves along
// the outline's rounding, and the points of the rounding past it would make
// the side hook back (init-mesh's Coons patch then folds over there).
std::vector<cv::Point2d> TrimBehindCorners(std::vector<cv::Point2d> p) {
  constexpr double kAhead = 20;  // px: the side's direction at a corner
  for (int end = 0; end < 2 && p.size() > 2; ++end) {
    const cv::Point2d corner = p.front();
    size_t far = 1;
    while (far + 1 < p.size() && cv::norm(p[far] - corner) < kAhead) ++far;
    const cv::Point2d direction = p[far] - corner;
    size_t keep = 1;
    while (keep < far && (p[keep] - corner).dot(direction) <= 0) ++keep;
    p.erase(p.begin() + 1, p.begin() + long(keep));
    std::reverse(p.begin(), p.end());
  }
  return p;
}

// Outline steps from corner `i` of `corners` to the next corner
// (`direction` +1) or back to the previous one (-1).
int ArmLength(const std::array<int, 4>& corners, int i, int direction, int n) {
  const int steps =
      direction > 0 ? corners[(i + 1) % 4] - corners[i] : corners[i] - corners[(i + 3) % 4];
  return ((steps % n) + n) % n;
}

// Along the outline from `corner` in `direction`, steps `first` to `last`:
// the point that turns most (by `min_turn` at least) and most of its
// neighbours within `window` steps that lie `compared_from` or more steps
// from the corner; -1 if none. Stops at the image border.
int SharpestTurnOnArm(const std::vector<cv::Point>& contour, const std::vector<double>& angle,
                      int corner, int direction, int first, int last, int window, int compared_from,
                      double min_turn, const std::function<bool(const cv::Point&)>& on_border) {
  const int n = int(contour.size());
  auto wrap = [n](int k) { return ((k % n) + n) % n; };
  int best = -1;
  double best_angle = min_turn;
  for (int s = first; s <= last; ++s) {
    const int k = wrap(corner + direction * s);
    if (on_border(contour[k])) break;
    if (angle[k] < best_angle) continue;
    bool is_max = true;
    for (int j = -window; j <= window && is_max; ++j)
      if (j != 0 && s + j * direction >= compared_from) is_max = angle[wrap(k + j)] <= angle[k];
    if (is_max) {
      best = k;
      best_angle = angle[k];
    }
  }
  return best;
}

}  // namespace

namespace detail {

std::vector<double> TurningAngles(const std::vector<cv::Point>& contour, int reach) {
  const int n = int(contour.size());
  std::vector<double> angle(n, 0.0);
  if (n < 3) return angle;
  reach = std::clamp(reach, 1, std::max(1, n / 3));
  for (int k = 0; k < n; ++k) {
    const cv::Point2d a = contour[(k - reach + n) % n], b = contour[k],
                      c = contour[(k + reach) % n];
    const cv::Point2d u = b - a, v = c - b;
    // Positive where a clockwise (image y down) outline turns right: convex.
    angle[k] = std::atan2(u.x * v.y - u.y * v.x, u.dot(v));
  }
  return angle;
}

std::array<int, 4> FindCornerIndices(const std::vector<cv::Point>& contour,
                                     const FoldTest& is_fold) {
  const int n = int(contour.size());
  if (n < 8) return {{0, n / 4, n / 2, 3 * n / 4}};
  double perimeter = 0;
  for (int k = 0; k < n; ++k) perimeter += cv::norm(contour[(k + 1) % n] - contour[k]);
  // Turning at the scale of a few percent of the outline: page corners turn
  // by 60-120 degrees there, folds and curls by much less, pixel noise not.
  const int reach = CornerReach(contour.size());
  const std::vector<double> angle = TurningAngles(contour, reach);
  // Candidates: convex local maxima of the turning.
  std::vector<int> candidates;
  for (int k = 0; k < n; ++k) {
    if (angle[k] < 15.0 * CV_PI / 180) continue;
    bool is_max = true;
    for (int j = -reach; j <= reach && is_max; ++j)
      if (j != 0) {
        const double other = angle[((k + j) % n + n) % n];
        is_max = other < angle[k] || (other == angle[k] && j > 0);
      }
    if (is_max) candidates.push_back(k);
  }
  std::sort(candidates.begin(), candidates.end(),
            [&](int a, int b) { return angle[a] > angle[b]; });
  if (candidates.size() > 12) candidates.resize(12);
  if (is_fold && candidates.size() > 4) {
    // Both ends of a fold are kinks of the outline, often as sharp as a
    // corner of a foreshortened panel: drop them while four others remain.
    // A chord with only a sliver of page beyond it (under 12 %) may instead
    // join two corners of a side whose flap is shaded differently (set05:
    // 7.4 %); it counts as a fold only when the outline round the sliver
    // passes corners that turn more sharply than its ends (set01 view_04:
    // a fold 9.3 % from a side, both page corners beyond it).
    auto sharper_beyond = [&](int a, int b) {
      const double side_area = ChordSideArea(contour, a, b);
      if (std::min(side_area, 1 - side_area) >= 0.12) return true;
      const int shorter_from = side_area <= 0.5 ? a : b;
      const int shorter_to = shorter_from == a ? b : a;
      const double weaker = std::min(angle[a], angle[b]);
      for (const int c : candidates)
        if (c != a && c != b && OnOutlinePath(n, shorter_from, shorter_to, c) && angle[c] >= weaker)
          return true;
      return false;
    };
    std::vector<bool> fold_end(candidates.size(), false);
    for (size_t i = 0; i < candidates.size(); ++i)
      for (size_t j = i + 1; j < candidates.size(); ++j)
        if (is_fold(contour[candidates[i]], contour[candidates[j]]) &&
            sharper_beyond(candidates[i], candidates[j]))
          fold_end[i] = fold_end[j] = true;
    std::vector<int> kept;
    for (size_t i = 0; i < candidates.size(); ++i)
      if (!fold_end[i]) kept.push_back(candidates[i]);
    if (kept.size() >= 4) candidates = kept;
  }
  std::array<int, 4> best{{0, n / 4, n / 2, 3 * n / 4}};
  if (candidates.size() < 4) {
    // Not four distinct turns (a blob, a rounded shape): the quadrilateral
    // of largest area on the convex hull.
    std::vector<int> hull;
    cv::convexHull(contour, hull, false, false);
    std::sort(hull.begin(), hull.end());
    while (hull.size() > 24) {
      size_t worst = 0;
      double worst_area = 1e300;
      const size_t h = hull.size();
      for (size_t i = 0; i < h; ++i) {
        const double a = TriangleArea(contour[hull[(i + h - 1) % h]], contour[hull[i]],
                                      contour[hull[(i + 1) % h]]);
        if (a < worst_area) {
          worst_area = a;
          worst = i;
        }
      }
      hull.erase(hull.begin() + long(worst));
    }
    if (hull.size() < 4) return best;
    candidates = hull;
  }
  // The four candidates that turn most in total while the outline between
  // them stays close to straight: a fold can kink a side as sharply as a
  // corner turns, but then the side through the real corner bends away from
  // its chord far more than the side with the fold does.
  std::sort(candidates.begin(), candidates.end());
  auto chord_deviation = [&](int from, int to) {
    const cv::Point2d a = contour[from], b = contour[to];
    const cv::Point2d d = b - a;
    const double len = cv::norm(d);
    if (len < 1) return 1.0;
    double sum = 0;
    int count = 0;
    for (int k = from; k != to; k = (k + 1) % n, ++count) {
      const cv::Point2d p = cv::Point2d(contour[k]) - a;
      sum += std::abs(d.x * p.y - d.y * p.x) / len;
    }
    return count > 0 ? sum / count / len : 0.0;
  };
  const int m = int(candidates.size());
  double best_score = -1e300;
  for (int a = 0; a < m; ++a)
    for (int b = a + 1; b < m; ++b)
      for (int c = b + 1; c < m; ++c)
        for (int d = c + 1; d < m; ++d) {
          const int q[4] = {candidates[a], candidates[b], candidates[c], candidates[d]};
          double turn = 0, deviation = 0;
          for (int i = 0; i < 4; ++i) {
            turn += angle[q[i]];
            deviation += chord_deviation(q[i], q[(i + 1) % 4]);
          }
          const double score = turn - 10.0 * deviation;
          if (score > best_score) {
            best_score = score;
            best = {{q[0], q[1], q[2], q[3]}};
          }
        }
  return best;
}

std::array<int, 4> MoveBorderCornersToPageCorners(
    const std::vector<cv::Point>& contour, std::array<int, 4> idx,
    const std::function<bool(const cv::Point&)>& on_border, double min_turn_deg,
    double max_arm_fraction) {
  const int n = int(contour.size());
  if (n < 16) return idx;
  const int reach = CornerReach(contour.size());
  const std::vector<double> angle = TurningAngles(contour, reach);
  const std::array<int, 4> found = idx;
  for (int i = 0; i < 4; ++i) {
    const int corner = found[i];
    if (!on_border(contour[corner])) continue;
    const int forward = ArmLength(found, i, +1, n), backward = ArmLength(found, i, -1, n);
    auto arm_on_border = [&](int direction, int length) {
      return on_border(contour[((corner + direction * std::min(reach, length / 2)) % n + n) % n]);
    };
    const bool forward_cut = arm_on_border(+1, forward), backward_cut = arm_on_border(-1, backward);
    // Only an exit: one arm along the border, the other into the image (a
    // real corner that merely touches the border has both arms inside).
    if (forward_cut == backward_cut) continue;
    const int direction = forward_cut ? -1 : +1;
    const int length = forward_cut ? backward : forward;
    // Past the exit's own turning window, and compared only with points past it.
    const int best =
        SharpestTurnOnArm(contour, angle, corner, direction, reach, int(max_arm_fraction * length),
                          reach / 2, reach, min_turn_deg * CV_PI / 180, on_border);
    if (best >= 0) idx[i] = best;
  }
  return idx;
}

std::array<int, 4> MoveFoldEndsToPageCorners(const std::vector<cv::Point>& contour,
                                             std::array<int, 4> idx,
                                             const std::function<bool(const cv::Point&)>& on_border,
                                             const FoldTest& is_fold, double min_turn_deg,
                                             double max_arm_fraction) {
  const int n = int(contour.size());
  if (n < 32 || !is_fold) return idx;
  const int reach = CornerReach(contour.size());
  const int fine = std::max(2, reach / 4);
  const std::vector<double> angle = TurningAngles(contour, fine);
  const double max_fold_turn = 60 * CV_PI / 180;
  const std::array<int, 4> found = idx;
  for (int i = 0; i < 4; ++i) {
    const int corner = found[i];
    if (on_border(contour[corner])) continue;
    // The sharpest fine turn on each arm, past the corner's own turning.
    std::array<int, 2> turn;
    for (int a = 0; a < 2; ++a) {
      const int direction = a == 0 ? +1 : -1;
      turn[a] = SharpestTurnOnArm(contour, angle, corner, direction, 2 * fine,
                                  int(max_arm_fraction * ArmLength(found, i, direction, n)), fine,
                                  0, min_turn_deg * CV_PI / 180, on_border);
    }
    if ((turn[0] >= 0) == (turn[1] >= 0)) continue;  // none, or one on each arm
    // A fold's end turns less than a page corner does, and the corner it
    // hides less than it (else the outline's turning would have found it).
    const int beside = turn[0] >= 0 ? turn[0] : turn[1];
    if (angle[corner] >= max_fold_turn || angle[beside] >= angle[corner]) continue;
    // The crease must start at the corner found, not at the turn beside it
    // (there the corner found may be the page's, the turn the crease's end).
    auto crease_from = [&](int from) {
      for (int s = n / 8; s <= n - n / 8; s += fine)
        if (is_fold(contour[from], contour[(from + s) % n])) return true;
      return false;
    };
    if (crease_from(corner) && !crease_from(beside)) idx[i] = beside;
  }
  return idx;
}

bool IsShadingStep(const cv::Mat1f& grey, const cv::Mat1b& mask, double scale, const cv::Point& a,
                   const cv::Point& b, double offset_px) {
  const cv::Point2d p = cv::Point2d(a) * scale, q = cv::Point2d(b) * scale;
  const double length = cv::norm(q - p);
  if (length < 20) return false;
  const cv::Point2d along = (q - p) / length, normal(-along.y, along.x);
  // Far enough from the line to leave a crease's own shading ramp, near
  // enough to stay on the two panels next to it.
  const double offset = offset_px > 0 ? offset_px : std::max(4.0, 0.02 * length);
  auto inside = [&](const cv::Point2d& x) {
    const int ix = int(std::lround(x.x)), iy = int(std::lround(x.y));
    return ix >= 0 && iy >= 0 && ix < mask.cols && iy < mask.rows && mask(iy, ix) > 0;
  };
  constexpr int kSamples = 15;
  constexpr double kStep = 0.05;  // relative brightness difference across
  int valid = 0, brighter = 0, darker = 0;
  for (int k = 0; k < kSamples; ++k) {
    const cv::Point2d x = p + (q - p) * (0.15 + 0.7 * k / (kSamples - 1));
    // Paper on both sides, well clear of the outline: a page side has the
    // table on one of them.
    if (!inside(x + 2 * offset * normal) || !inside(x - 2 * offset * normal)) continue;
    ++valid;
    const double g1 = SampleBilinear(grey, (x + offset * normal).x, (x + offset * normal).y);
    const double g2 = SampleBilinear(grey, (x - offset * normal).x, (x - offset * normal).y);
    const double step = (g1 - g2) / std::max({g1, g2, 1.0});
    brighter += step > kStep;
    darker += step < -kStep;
  }
  return valid >= 0.8 * kSamples && std::max(brighter, darker) >= 0.7 * valid;
}

cv::Point2d RefineCorner(const std::vector<cv::Point>& contour, int index, int reach) {
  const int n = int(contour.size());
  const cv::Point2d corner = contour[index];
  if (n < 16 || reach < 2) return corner;
  auto at = [&](int offset) { return cv::Point2d(contour[((index + offset) % n + n) % n]); };
  // A straight line through the outline on one side of the corner: the
  // longest window (starting past the rounding) that the line fits within
  // a pixel or two, so that a kink or a notch further along does not tilt it.
  auto fit_side = [&](int direction, cv::Vec4f* line) {
    const int start = std::max(1, reach / 3);
    for (double factor : {4.0, 3.0, 2.0, 1.5, 1.0}) {
      const int end = std::min(n / 3, int(factor * reach));
      if (end - start < 4) continue;
      std::vector<cv::Point2f> pts;
      for (int k = start; k <= end; ++k) pts.emplace_back(at(direction * k));
      cv::fitLine(pts, *line, cv::DIST_HUBER, 0, 0.01, 0.01);
      const cv::Point2d d((*line)[0], (*line)[1]), o((*line)[2], (*line)[3]);
      double sum2 = 0, worst = 0;
      for (const auto& pt : pts) {
        const cv::Point2d r = cv::Point2d(pt) - o;
        const double e = d.x * r.y - d.y * r.x;
        sum2 += e * e;
        worst = std::max(worst, std::abs(e));
      }
      if (std::sqrt(sum2 / pts.size()) <= 1.5 && worst <= 3.0) return true;
    }
    return false;
  };
  cv::Vec4f before, after;
  if (!fit_side(-1, &before) || !fit_side(+1, &after)) return corner;
  const cv::Point2d d1(before[0], before[1]), o1(before[2], before[3]);
  const cv::Point2d d2(after[0], after[1]), o2(after[2], after[3]);
  const double cross = d1.x * d2.y - d1.y * d2.x;
  if (std::abs(cross) < std::sin(20.0 * CV_PI / 180)) return corner;  // nearly parallel
  const cv::Point2d w = o2 - o1;
  const double t = (w.x * d2.y - w.y * d2.x) / cross;
  const cv::Point2d x = o1 + t * d1;
  // The rounding the mask leaves is a few pixels: a far intersection means
  // the fits are not of this corner's sides.
  double step = 0;
  for (int k = -reach; k < reach; ++k) step += cv::norm(at(k + 1) - at(k));
  return cv::norm(x - corner) <= 0.5 * step ? x : corner;
}

int GeometricTopSide(const std::array<cv::Point2d, 4>& corners) {
  int top = 0;
  double best = 1e300;
  for (int i = 0; i < 4; ++i) {
    const cv::Point2d d = corners[(i + 1) % 4] - corners[i];
    // Outward normal of a clockwise (image y down) polygon: (d.y, -d.x).
    const double ny = -d.x / std::max(1e-9, cv::norm(d));
    if (ny < best) {
      best = ny;
      top = i;
    }
  }
  return top;
}

}  // namespace detail

Json BoundaryOptions::ToJson() const {
  return Json{{"work_size", work_size},
              {"frame_fraction", frame_fraction},
              {"table_distance", table_distance},
              {"weak_table_distance", weak_table_distance},
              {"weak_min_width", weak_min_width},
              {"min_area_fraction", min_area_fraction},
              {"border_tolerance_px", border_tolerance_px},
              {"max_cut_fraction", max_cut_fraction},
              {"contour_epsilon_px", contour_epsilon_px},
              {"orientation", orientation}};
}

BoundaryResult SegmentBoundary(const cv::Mat& image, const BoundaryOptions& options) {
  if (image.empty() || image.type() != CV_8UC3) throw InputError("expected an 8-bit colour image");
  if (image.cols < 16 || image.rows < 16)
    throw InputError("image too small (" + std::to_string(image.cols) + "x" +
                     std::to_string(image.rows) + ")");
  const cv::Mat3b full = image;
  const auto start = std::chrono::steady_clock::now();
  auto step = [&](const std::string& what) {
    if (options.verbose)
      Log(what + " (" + std::to_string(SecondsSince(start)).substr(0, 5) + " s)");
  };

  // 1. Page region on a downscaled image: everything that is not table.
  const double s = std::min(1.0, double(options.work_size) / std::max(full.cols, full.rows));
  cv::Mat3b small;
  if (s < 1.0)
    cv::resize(full, small, cv::Size(), s, s, cv::INTER_AREA);
  else
    small = full.clone();
  const FeatureImage lab = PixelFeatures(small);
  step("features of the downscaled image");
  const TableModel table = LearnTableModel(lab, options.frame_fraction);
  step("background colour learnt from " +
       std::to_string(int(std::lround(table.inlier_fraction * 100))) + "% of the frame");
  if (table.inlier_fraction < 0.4)
    throw InputError(
        "no document found: the image frame has no dominant background colour "
        "(does the page fill the whole image?)");
  const cv::Mat1f distance = TableDistance(lab, table);
  cv::Mat1b candidate = distance > float(options.table_distance);
  candidate |= WeakPageAttached(distance > float(options.weak_table_distance), candidate,
                                options.weak_min_width);
  // Opening removes thin shadow bands and specks the table texture leaves;
  // closing fills notches that shaded paper at a crease leaves in the
  // outline. Both round the corners a little, which the full-resolution
  // refinement below undoes.
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(3, 3));
  cv::morphologyEx(candidate, candidate, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(7, 7)));
  cv::morphologyEx(candidate, candidate, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(9, 9)));
  double area = 0;
  cv::Mat1b coarse = LargestFilledRegion(candidate, &area);
  const double work_area = double(small.cols) * small.rows;
  if (area < options.min_area_fraction * work_area)
    throw InputError(
        "no document found: no region distinct from the background "
        "covers " +
        std::to_string(int(options.min_area_fraction * 100)) +
        "% of the image (largest: " + std::to_string(area / work_area * 100).substr(0, 4) + "%)");

  step("coarse region");
  // 2. Outline at full resolution.
  cv::Mat1b mask = s < 1.0 ? RefineAtFullResolution(full, small, coarse) : coarse;
  // Light specks of a textured table next to the page can add slivers, and
  // shaded paper at a crease can leave a notch, a few pixels wide: smooth the
  // outline at the scale of a work pixel or two.
  const int smooth_size = 2 * std::max(2, int(std::lround(1.0 / s))) + 1;
  const cv::Mat smooth_kernel =
      cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(smooth_size, smooth_size));
  cv::morphologyEx(mask, mask, cv::MORPH_OPEN, smooth_kernel);
  cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, smooth_kernel);
  mask = LargestFilledRegion(mask);

  step("outline refined at full resolution");
  BoundaryResult result;
  result.mask = mask;
  result.area_fraction = cv::countNonZero(mask) / (double(mask.cols) * mask.rows);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  if (contours.empty()) throw InputError("no document found after refinement");
  std::vector<cv::Point> contour = *std::max_element(
      contours.begin(), contours.end(),
      [](const auto& a, const auto& b) { return cv::contourArea(a) < cv::contourArea(b); });
  if (SignedArea(contour) < 0) std::reverse(contour.begin(), contour.end());
  result.contour = Simplify(ToDouble(contour), options.contour_epsilon_px, true);

  // 3. Corners: clockwise, then rotated so that the top side is first.
  cv::Mat1b grey_bytes;
  cv::cvtColor(small, grey_bytes, cv::COLOR_BGR2GRAY);
  cv::Mat1f grey;
  grey_bytes.convertTo(grey, CV_32F);
  cv::GaussianBlur(grey, grey, cv::Size(), 3.0);  // text away, panels' shading kept
  cv::Mat1b small_mask;
  cv::resize(mask, small_mask, small.size(), 0, 0, cv::INTER_AREA);
  small_mask = small_mask > 127;
  const double work_scale = double(small.cols) / full.cols;
  const auto is_fold = [&](const cv::Point& a, const cv::Point& b) {
    return detail::IsShadingStep(grey, small_mask, work_scale, a, b);
  };
  const double tol = options.border_tolerance_px;
  auto on_border = [&](const cv::Point& p) {
    return p.x <= tol || p.y <= tol || p.x >= mask.cols - 1 - tol || p.y >= mask.rows - 1 - tol;
  };
  // A fold's crease a little way from a page corner, along a side: sampled
  // close to the crease, as the panel beyond it may be narrow.
  const auto is_crease = [&](const cv::Point& a, const cv::Point& b) {
    return detail::IsShadingStep(grey, small_mask, work_scale, a, b, 4.0);
  };
  std::array<int, 4> idx = detail::MoveFoldEndsToPageCorners(
      contour,
      detail::MoveBorderCornersToPageCorners(contour, detail::FindCornerIndices(contour, is_fold),
                                             on_border),
      on_border, is_crease);
  std::array<cv::Point2d, 4> corners;
  for (int i = 0; i < 4; ++i) corners[i] = contour[idx[i]];
  step("corners");
  int top = detail::GeometricTopSide(corners);
  result.orientation.method = "geometry";
  if (options.orientation != "geometry") {
    TextOrientation text = EstimateTextTopSide(full, mask, corners);
    result.orientation.confidence = text.confidence;
    result.orientation.votes = text.votes;
    if (text.top_side >= 0) {
      top = text.top_side;
      result.orientation.method = "text";
    } else if (options.orientation == "text") {
      throw InputError("cannot tell the page's orientation from its text: " + text.why);
    }
  }
  step("orientation by " + result.orientation.method);
  std::rotate(idx.begin(), idx.begin() + top, idx.end());
  for (int i = 0; i < 4; ++i) {
    const cv::Point2d c = detail::RefineCorner(contour, idx[i], CornerReach(contour.size()));
    result.corners[i] = {std::clamp(c.x, 0.0, mask.cols - 1.0),
                         std::clamp(c.y, 0.0, mask.rows - 1.0)};
  }

  // 4. Sides along the outline, and which parts of them lie on the image border.
  for (int i = 0; i < 4; ++i) result.corner_in_image[i] = !on_border(contour[idx[i]]);
  const int n = int(contour.size());
  for (int i = 0; i < 4; ++i) {
    const int from = idx[i], to = idx[(i + 1) % 4];
    std::vector<cv::Point> path;
    for (int k = from;; k = (k + 1) % n) {
      path.push_back(contour[k]);
      if (k == to) break;
    }
    // Along the clockwise outline: top TL->TR, right TR->BR, then BR->BL and
    // BL->TL, which the schema stores reversed (bottom BL->BR, left TL->BL).
    const bool reversed = (i == kBottom || i == kLeft);
    if (reversed) std::reverse(path.begin(), path.end());
    Side side;
    double cut = 0, total = 0;
    std::vector<cv::Point2d> run;
    auto flush = [&] {
      if (run.size() >= 2 && PolylineLength(run) >= 4.0)
        side.real_parts.push_back(Simplify(run, options.contour_epsilon_px, false));
      run.clear();
    };
    for (size_t k = 0; k < path.size(); ++k) {
      const bool border = on_border(path[k]);
      if (k > 0) {
        const double l = cv::norm(path[k] - path[k - 1]);
        total += l;
        if (border && on_border(path[k - 1])) cut += l;
      }
      if (border)
        flush();
      else
        run.push_back(path[k]);
    }
    flush();
    side.cut_fraction = total > 0 ? cut / total : 0;
    side.real = side.cut_fraction <= options.max_cut_fraction;
    side.points = Simplify(ToDouble(path), options.contour_epsilon_px, false);
    if (side.points.size() < 2) side.points = {cv::Point2d(path.front()), cv::Point2d(path.back())};
    // A side runs from corner to corner, sharpened as the corners are.
    side.points.front() = result.corners[reversed ? (i + 1) % 4 : i];
    side.points.back() = result.corners[reversed ? i : (i + 1) % 4];
    side.points = TrimBehindCorners(std::move(side.points));
    if (side.real) side.real_parts = {side.points};
    result.sides[i] = std::move(side);
  }
  return result;
}

Json BoundaryToJson(const BoundaryResult& r, const std::string& image_name, int width, int height,
                    const BoundaryOptions& options) {
  auto pt = [](const cv::Point2d& p) { return Json::array({p.x, p.y}); };
  auto line = [&](const std::vector<cv::Point2d>& pts) {
    Json a = Json::array();
    for (const auto& p : pts) a.push_back(pt(p));
    return a;
  };
  Json doc = MakeHeader("docunfold.boundary", 1, "segment-boundary", options.ToJson());
  doc["image"] = image_name;
  doc["width"] = width;
  doc["height"] = height;
  doc["area_fraction"] = r.area_fraction;
  doc["contour"] = line(r.contour);
  doc["corners"] = Json::array();
  doc["corner_names"] = Json::array();
  doc["corners_in_image"] = Json::array();
  for (int i = 0; i < 4; ++i) {
    doc["corners"].push_back(pt(r.corners[i]));
    doc["corner_names"].push_back(kCornerNames[i]);
    doc["corners_in_image"].push_back(bool(r.corner_in_image[i]));
  }
  doc["sides"] = Json::object();
  for (int i = 0; i < 4; ++i) {
    const Side& s = r.sides[i];
    Json parts = Json::array();
    for (const auto& p : s.real_parts) parts.push_back(line(p));
    doc["sides"][kSideNames[i]] = {{"points", line(s.points)},
                                   {"real", s.real},
                                   {"cut_fraction", s.cut_fraction},
                                   {"real_parts", parts}};
  }
  doc["orientation"] = {{"method", r.orientation.method},
                        {"confidence", r.orientation.confidence},
                        {"votes", r.orientation.votes}};
  return doc;
}

cv::Mat DrawBoundaryOverlay(const cv::Mat& image, const BoundaryResult& r, int max_size) {
  const double s = std::min(1.0, double(max_size) / std::max(image.cols, image.rows));
  cv::Mat out, mask;
  cv::resize(image, out, cv::Size(), s, s, cv::INTER_AREA);
  cv::resize(r.mask, mask, out.size(), 0, 0, cv::INTER_NEAREST);
  // Darken the background so the region itself is visible.
  cv::Mat dark = out * 0.45;
  dark.copyTo(out, 255 - mask);
  const int thick = std::max(2, int(std::lround(out.cols / 500.0)));
  auto scaled = [&](const cv::Point2d& p) {
    return cv::Point(int(std::lround((p.x + 0.5) * s - 0.5)),
                     int(std::lround((p.y + 0.5) * s - 0.5)));
  };
  const cv::Scalar kReal(60, 220, 60), kCut(40, 40, 230), kCorner(0, 200, 255);
  for (int i = 0; i < 4; ++i) {
    const Side& side = r.sides[i];
    // Cut (non-real) stretches dashed red under the real parts in green.
    for (size_t k = 1; k < side.points.size(); ++k) {
      const cv::Point a = scaled(side.points[k - 1]), b = scaled(side.points[k]);
      const double len = cv::norm(b - a);
      const int dashes = std::max(1, int(len / (4.0 * thick)));
      for (int j = 0; j < dashes; j += 2) {
        const cv::Point2d p = cv::Point2d(a) + (cv::Point2d(b - a)) * (double(j) / dashes);
        const cv::Point2d q = cv::Point2d(a) + (cv::Point2d(b - a)) * (double(j + 1) / dashes);
        cv::line(out, p, q, kCut, thick, cv::LINE_AA);
      }
    }
    for (const auto& part : side.real_parts)
      for (size_t k = 1; k < part.size(); ++k)
        cv::line(out, scaled(part[k - 1]), scaled(part[k]), kReal, thick, cv::LINE_AA);
    // Side name just inside the page, at the middle of the side.
    const auto& pts = side.points;
    const cv::Point2d mid = pts[pts.size() / 2];
    cv::Point2d centre(0, 0);
    for (const auto& c : r.corners) centre += c * 0.25;
    cv::Point2d dir = centre - mid;
    dir *= 1.0 / std::max(1e-9, cv::norm(dir));
    const std::string label = std::string(kSideNames[i]) + (side.real ? "" : " (cut)");
    const double font = 0.5 * thick;
    int base = 0;
    const cv::Size ts = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, font, thick, &base);
    const cv::Point at =
        scaled(mid) + cv::Point(dir * 14.0 * thick) - cv::Point(ts.width / 2, -ts.height / 2);
    cv::putText(out, label, at, cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(0, 0, 0), thick + 2,
                cv::LINE_AA);
    cv::putText(out, label, at, cv::FONT_HERSHEY_SIMPLEX, font, side.real ? kReal : kCut, thick,
                cv::LINE_AA);
  }
  for (int i = 0; i < 4; ++i) {
    const cv::Point c = scaled(r.corners[i]);
    cv::circle(out, c, 3 * thick, kCorner, thick, cv::LINE_AA);
    cv::putText(out, kCornerNames[i], c + cv::Point(4 * thick, -4 * thick),
                cv::FONT_HERSHEY_SIMPLEX, 0.6 * thick, cv::Scalar(0, 0, 0), thick + 2, cv::LINE_AA);
    cv::putText(out, kCornerNames[i], c + cv::Point(4 * thick, -4 * thick),
                cv::FONT_HERSHEY_SIMPLEX, 0.6 * thick, kCorner, thick, cv::LINE_AA);
  }
  const std::string note = "orientation: " + r.orientation.method;
  cv::putText(out, note, cv::Point(10, 10 + 12 * thick), cv::FONT_HERSHEY_SIMPLEX, 0.5 * thick,
              cv::Scalar(255, 255, 255), thick, cv::LINE_AA);
  return out;
}

}  // namespace docunfold::boundary
