// What the report draws or says from stages' JSON outputs: optimize's
// lines.json, render's render.json and densify's points.json. Each takes the
// parsed document (null when the file is missing or does not parse).
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "common/json_io.h"

namespace docunfold::report {

// The final feature lines of 50_optimize/lines.json (polylines in M') drawn
// over rectified.png, through the map render used: the deskew rotation, the
// crop, the scale and the quarter turns of render.json. Empty when render did
// not texture optimize's meshes or a file is missing.
cv::Mat DrawFeatureLines(const cv::Mat& rectified, const Json& render, const Json& lines);

// "Feature lines straightened in M': <n> <kind> ..." from lines.json; empty
// without lines.
std::string LinesNote(const Json& lines);

// The page image of 80_pdf/ with the words of pdf.json over it, each in its
// box (an inline <svg>, `width` pixels wide; red: confidence below 0.6).
// Empty when pdf.json has no words list or the image is missing.
std::string PdfWordsSvg(const cv::Mat& page_image, const Json& pdf, int width);

// "A4, 210 x 297 mm (aspect ratio and text size), 221 dpi, 230 words ..."
// from pdf.json; empty when it is not one.
std::string PdfSummary(const Json& pdf);

// One sentence on the PDF read back against the true text and page
// (70_eval/pdf.json, docunfold.pdf-metrics); empty when it is not that.
std::string PdfCheckSummary(const Json& metrics);

// " <n> sfm points on the page, <n> texture, <n> outline." from points.json;
// empty without counts.
std::string PointsCounts(const Json& points);

}  // namespace docunfold::report
