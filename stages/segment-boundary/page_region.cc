// Step 1 and 2 of segment-boundary: the page region as everything whose
// colour is not the table's, found on a downscaled image and refined at full
// resolution.
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/errors.h"
#include "common/image_sampling.h"
#include "common/program.h"
#include "stages/segment-boundary/boundary_internal.h"

namespace docunfold::boundary::internal {
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
// tables on first use, which is slow (see docs/decisions/segment-boundary.md,
// "Lab colour by hand").
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

}  // namespace

CoarseRegion FindCoarseRegion(const cv::Mat3b& full, const BoundaryOptions& options,
                              const StepLog& step) {
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
  // refinement undoes.
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
        "% of the image (largest: " + Fixed(area / work_area * 100, 2) +
        "%; is the page that small, or does it fill the photo with no table around it?)");
  return {small, s, coarse};
}

cv::Mat1b RefinePageMask(const cv::Mat3b& full, const CoarseRegion& region) {
  const double s = region.scale;
  cv::Mat1b mask =
      s < 1.0 ? RefineAtFullResolution(full, region.small, region.coarse) : region.coarse;
  // Light specks of a textured table next to the page can add slivers, and
  // shaded paper at a crease can leave a notch, a few pixels wide: smooth the
  // outline at the scale of a work pixel or two.
  const int smooth_size = 2 * std::max(2, int(std::lround(1.0 / s))) + 1;
  const cv::Mat smooth_kernel =
      cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(smooth_size, smooth_size));
  cv::morphologyEx(mask, mask, cv::MORPH_OPEN, smooth_kernel);
  cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, smooth_kernel);
  return LargestFilledRegion(mask);
}

}  // namespace docunfold::boundary::internal
