// Which side of a page is its top, read from its text: text lines run
// parallel to the top, and Latin text has far more ink above its x-height
// band (capitals, digits, ascenders b d f h k l t) than below it (descenders
// g j p q y), so the side the extra ink points to is up.
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <string>

namespace docunfold::boundary {

struct TextOrientation {
  // Index of the side (i -> i+1 of the given corners) that is the page's
  // top; -1 when the text does not tell (see `why`).
  int top_side = -1;
  double confidence = 0;  // fraction of the line votes that agree
  int votes = 0;          // text line pieces that voted
  std::string why;
};

// `corners`: the page's four corners, clockwise in the image; `mask`: the
// page region (255), image size.
TextOrientation EstimateTextTopSide(const cv::Mat3b& image, const cv::Mat1b& mask,
                                    const std::array<cv::Point2d, 4>& corners);

}  // namespace docunfold::boundary
