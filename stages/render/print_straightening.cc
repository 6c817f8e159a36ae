#include "stages/render/print_straightening.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/statistics.h"

namespace docunfold::render {
namespace {

// How much darker each pixel is than the paper around it (a wide blur):
// print, not the page's shading.
cv::Mat1f Ink(const cv::Mat& image) {
  cv::Mat grey;
  if (image.channels() == 3)
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else
    grey = image;
  cv::Mat1f g, paper;
  grey.convertTo(g, CV_32F);
  cv::GaussianBlur(g, paper, cv::Size(0, 0), 8);
  return cv::max(paper - g, 0);
}

// Linear interpolation of `p` at y, clamped to its ends.
double At(const std::vector<double>& p, double y) {
  if (y <= 0) return p.front();
  if (y >= double(p.size() - 1)) return p.back();
  const int a = int(y);
  const double t = y - a;
  return (1 - t) * p[a] + t * p[a + 1];
}

// Normalised cross-correlation of a(y) and b(y + k) over y in [y0, y1); NaN
// where either is flat or too short.
double Correlation(const std::vector<double>& a, const std::vector<double>& b, int k, int y0,
                   int y1) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  int n = 0;
  for (int y = y0; y < y1; ++y) {
    if (y + k < 0 || y + k >= int(b.size())) continue;
    const double u = a[y], v = b[y + k];
    sa += u;
    sb += v;
    saa += u * u;
    sbb += v * v;
    sab += u * v;
    ++n;
  }
  if (n < 8) return NAN;
  const double va = saa - sa * sa / n, vb = sbb - sb * sb / n;
  if (!(va > 1e-6 * n && vb > 1e-6 * n)) return NAN;
  return (sab - sa * sb / n) / std::sqrt(va * vb);
}

// Whether the window [y0, y1)'s mean profile over every strip has the
// contrast of printed rows (blank gaps between them).
bool RowLike(const std::vector<std::vector<double>>& profile, int y0, int y1, double min_contrast) {
  std::vector<double> mean;
  for (int y = y0; y < y1; ++y) {
    double m = 0;
    for (const std::vector<double>& p : profile) m += p[y];
    mean.push_back(m / double(profile.size()));
  }
  const double p10 = NthSmallest(mean, mean.size() / 10);
  const double p90 = NthSmallest(mean, mean.size() * 9 / 10);
  return p90 > 0 && (p90 - p10) / p90 >= min_contrast;
}

// The vertical displacement (working pixels) that aligns every strip's ink
// profile with its window's mean profile, on the grid of windows x strips,
// smoothed and interpolated to every pixel of `ink`. Empty when the image
// is smaller than a window or two strips.
cv::Mat1f RowDisplacement(const cv::Mat1f& ink, const StraightenOptions& o, StraightenPass* pass) {
  const int W = ink.cols, H = ink.rows, sw = std::max(2, o.strip_px);
  const int wh = std::max(4 * o.max_shift_px + 8, o.window_px), step = wh / 2, ms = o.max_shift_px;
  const int ns = W / sw;
  if (ns < 2 || H < wh) return {};
  const int nw = (H - wh) / step + 1;
  // Mean ink per row of each strip.
  std::vector<std::vector<double>> profile(ns, std::vector<double>(H, 0));
  for (int y = 0; y < H; ++y) {
    const auto* row = ink.ptr<float>(y);
    for (int i = 0; i < ns; ++i) {
      double s = 0;
      for (int x = i * sw; x < (i + 1) * sw; ++x) s += row[x];
      profile[i][y] = s / sw;
    }
  }
  cv::Mat1f grid(nw, ns, 0.f);
  for (int j = 0; j < nw; ++j) {
    const int y0 = j * step, y1 = std::min(H, y0 + wh);
    std::vector<double> shift(ns, 0), confidence(ns, 0), weight(ns, 0);
    for (int i = 0; i < ns; ++i)
      for (int y = y0; y < y1; ++y) weight[i] += profile[i][y];
    if (!RowLike(profile, y0, y1, o.min_row_contrast)) continue;
    // The window's mean profile, each strip aligned to it, three times: a
    // strip with only some of the rows (short words) still finds them.
    for (int round = 0; round < 3; ++round) {
      std::vector<double> mean(H, 0);
      for (int i = 0; i < ns; ++i) {
        if (round > 0 && !(confidence[i] > 0)) continue;
        for (int y = std::max(0, y0 - ms); y < std::min(H, y1 + ms); ++y)
          mean[y] += At(profile[i], y + shift[i]);
      }
      for (int i = 0; i < ns; ++i) {
        std::vector<double> c(2 * ms + 1);
        int best = -1;
        for (int k = -ms; k <= ms; ++k) {
          c[k + ms] = Correlation(mean, profile[i], k, y0 + ms, y1 - ms);
          if (!std::isnan(c[k + ms]) && (best < 0 || c[k + ms] > c[best])) best = k + ms;
        }
        confidence[i] = 0;
        // A peak inside the range, its neighbours defined, correlated enough.
        if (best <= 0 || best >= 2 * ms || !(c[best] >= o.min_correlation) ||
            std::isnan(c[best - 1]) || std::isnan(c[best + 1]))
          continue;
        shift[i] = best - ms + ParabolaPeak(c, best);
        confidence[i] = c[best];
      }
      // Relative to the window's ink-weighted mean: the rows keep their
      // height on the page, only their bends go.
      double total = 0, sum = 0;
      for (int i = 0; i < ns; ++i)
        if (confidence[i] > 0) {
          total += weight[i];
          sum += weight[i] * shift[i];
        }
      if (total > 0)
        for (double& s : shift) s -= sum / total;
    }
    // Strips without a confident shift: interpolated between their
    // neighbours that have one, the nearest one's at the ends; a window
    // where none has one is left where it is (interpolating across windows
    // spread a margin's shift over set01's text: -0.010).
    std::vector<int> known;
    for (int i = 0; i < ns; ++i)
      if (confidence[i] > 0) known.push_back(i);
    pass->shifts_found += int(known.size());
    for (int i = 0; i < ns && !known.empty(); ++i) {
      const auto it = std::lower_bound(known.begin(), known.end(), i);
      double v;
      if (it == known.end()) {
        v = shift[known.back()];
      } else if (*it == i || it == known.begin()) {
        v = shift[*it];
      } else {
        const int b = *it, a = *(it - 1);
        v = shift[a] + (shift[b] - shift[a]) * (i - a) / double(b - a);
      }
      grid(j, i) = float(v);
    }
  }
  pass->strips = ns;
  pass->windows = nw;
  cv::GaussianBlur(grid, grid, cv::Size(0, 0), 1.0);
  // Grid value (j, i) sits at the centre of window j and strip i.
  cv::Mat1f dense(H, W);
  for (int y = 0; y < H; ++y) {
    const double fj = std::clamp((y - wh / 2.0) / step, 0.0, double(nw - 1));
    const int j0 = int(fj), j1 = std::min(nw - 1, j0 + 1);
    const double tj = fj - j0;
    for (int x = 0; x < W; ++x) {
      const double fi = std::clamp((x - sw / 2.0) / sw, 0.0, double(ns - 1));
      const int i0 = int(fi), i1 = std::min(ns - 1, i0 + 1);
      const double ti = fi - i0;
      dense(y, x) = float((1 - tj) * ((1 - ti) * grid(j0, i0) + ti * grid(j0, i1)) +
                          tj * ((1 - ti) * grid(j1, i0) + ti * grid(j1, i1)));
    }
  }
  return dense;
}

// Maps that take every pixel of an image of `size` to itself.
void IdentityMaps(cv::Size size, cv::Mat1f* map_x, cv::Mat1f* map_y) {
  map_x->create(size);
  map_y->create(size);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) {
      (*map_x)(y, x) = float(x);
      (*map_y)(y, x) = float(y);
    }
}

// `d` (working pixels, working size) at `size`, in output pixels.
cv::Mat1f ToOutput(const cv::Mat1f& d, cv::Size size) {
  cv::Mat1f out;
  cv::resize(d, out, size, 0, 0, cv::INTER_LINEAR);
  return out * (double(size.width) / d.cols);
}

double MaxAbs(const cv::Mat1f& m) {
  double lo = 0, hi = 0;
  cv::minMaxLoc(m, &lo, &hi);
  return std::max(std::abs(lo), std::abs(hi));
}

}  // namespace

Straightening FindStraightening(const cv::Mat& image, const StraightenOptions& o) {
  Straightening s;
  const int W = image.cols, H = image.rows;
  IdentityMaps(image.size(), &s.map_x, &s.map_y);
  if (!o.enabled || image.empty()) return s;
  const double scale = std::min(1.0, std::sqrt(o.work_pixels / (double(W) * H)));
  cv::Mat work;
  if (scale < 1)
    cv::resize(image, work, cv::Size(), scale, scale, cv::INTER_AREA);
  else
    work = image;

  cv::Mat1f dy = RowDisplacement(Ink(work), o, &s.rows);
  cv::Mat1f dx;
  if (!dy.empty()) {
    // The columns are found on the copy with its rows straightened.
    cv::Mat1f wx, wy;
    IdentityMaps(work.size(), &wx, &wy);
    wy += dy;
    cv::Mat straightened;  // not in place: `work` may share `image`'s pixels
    cv::remap(work, straightened, wx, wy, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    work = straightened;
  }
  StraightenOptions column_options = o;
  column_options.min_correlation = o.min_column_correlation;
  const cv::Mat1f dx_t = RowDisplacement(Ink(work).t(), column_options, &s.columns);
  if (!dx_t.empty()) dx = dx_t.t();

  // out(x, y) = rows_straightened(x + dx, y) = image(x + dx, y + dy(x + dx, y)).
  if (!dx.empty()) {
    const cv::Mat1f full = ToOutput(dx, image.size());
    s.map_x += full;
    s.columns.max_shift_px = MaxAbs(full);
  }
  if (!dy.empty()) {
    const cv::Mat1f full = ToOutput(dy, image.size());
    cv::Mat1f at;
    cv::remap(full, at, s.map_x, s.map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    s.map_y += at;
    s.rows.max_shift_px = MaxAbs(full);
  }
  return s;
}

cv::Mat ApplyStraightening(const cv::Mat& image, const Straightening& s, int interpolation) {
  if (image.empty() || image.size() != s.map_x.size()) return image;
  cv::Mat out;
  cv::remap(image, out, s.map_x, s.map_y, interpolation, cv::BORDER_REPLICATE);
  return out;
}

}  // namespace docunfold::render
