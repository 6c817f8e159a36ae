#include "stages/render/page_edge.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

namespace docunfold::render {

cv::Mat ContinuePageColour(const cv::Mat& photo, const cv::Mat1b& page_mask,
                           const PageEdgeOptions& options) {
  if (options.mixed_px <= 0 || page_mask.empty() || cv::countNonZero(page_mask) == 0) return photo;
  if (page_mask.size() != photo.size() || photo.type() != CV_8UC3)
    throw std::logic_error("ContinuePageColour: needs an 8-bit BGR photo and a mask of its size");
  // Erosion treats the image's border as page (OpenCV's default border), so
  // a side cut off there loses nothing. The reach is a square: a bound.
  const int r = options.mixed_px, reach_px = std::max(options.reach_px, 0);
  cv::Mat1b clean, reach;
  cv::erode(page_mask, clean, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1}));
  cv::dilate(page_mask, reach,
             cv::getStructuringElement(cv::MORPH_RECT, {2 * reach_px + 1, 2 * reach_px + 1}));
  const cv::Mat1b band = reach & ~clean;
  // Each pixel of the band takes the colour of the nearest clean page pixel,
  // thin print taken out there (a 5x5 median: a line printed near the edge
  // must not run into the rim). Tile by tile, only where the band is: it is
  // a thin strip of a large photo, and the nearest clean pixel is within
  // `margin` of it.
  const int margin = reach_px + r + 2;
  constexpr int kTile = 64;
  constexpr int kMedianPx = 5;
  const cv::Rect image(0, 0, photo.cols, photo.rows);
  cv::Mat out = photo.clone();
  const int tile_rows = (photo.rows + kTile - 1) / kTile;
  cv::parallel_for_(cv::Range(0, tile_rows), [&](const cv::Range& range) {
    for (int ty = range.start; ty < range.end; ++ty)
      for (int tx = 0; tx < photo.cols; tx += kTile) {
        const cv::Rect tile = cv::Rect(tx, ty * kTile, kTile, kTile) & image;
        if (cv::countNonZero(band(tile)) == 0) continue;
        const cv::Rect around =
            (tile + cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) & image;
        const cv::Mat1b not_clean = clean(around) == 0;
        if (cv::countNonZero(not_clean) == around.area()) continue;  // no clean pixel near
        cv::Mat1f distance;
        cv::Mat1i label;
        cv::distanceTransform(not_clean, distance, label, cv::DIST_L2, cv::DIST_MASK_5,
                              cv::DIST_LABEL_PIXEL);
        // DIST_LABEL_PIXEL numbers the clean pixels 1, 2, ... in raster order.
        std::vector<cv::Point> clean_pixel(1);
        for (int y = 0; y < around.height; ++y)
          for (int x = 0; x < around.width; ++x)
            if (!not_clean(y, x)) clean_pixel.emplace_back(x, y);
        cv::Mat3b paper;
        cv::medianBlur(photo(around), paper, kMedianPx);
        const cv::Point offset = tile.tl() - around.tl();
        for (int y = 0; y < tile.height; ++y)
          for (int x = 0; x < tile.width; ++x) {
            if (!band(tile.y + y, tile.x + x)) continue;
            const int k = label(offset + cv::Point(x, y));
            if (k <= 0 || k >= int(clean_pixel.size())) continue;
            out.at<cv::Vec3b>(tile.y + y, tile.x + x) = paper(clean_pixel[size_t(k)]);
          }
      }
  });
  return out;
}

}  // namespace docunfold::render
