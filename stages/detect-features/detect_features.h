// detect-features: short, locally reliable, straight segments in the
// reference image (the paper's feature segment detection, in its feature
// line extraction), restricted to the document region:
//   - text segments: pieces of text baselines. Characters (connected
//     components of a Sauvola-binarised image) are chained with their
//     neighbours of similar size along the text direction; each chain's
//     baseline (the lower envelope of its characters, descenders removed,
//     "lower" read from the text itself) is cut where it bends (a crease) and
//     fitted piecewise by straight lines. The paper chains character centres;
//     a baseline is the same straight line on the page, only sharper.
//   - edge segments: table rules and other thin printed lines. LSD finds the
//     two edges of a dark line; paired, they give its centre line. Single
//     step edges (shading at folds, colour fields, the page outline itself)
//     are left out unless asked for: shading edges are not straight on the
//     page, and precision comes first (paper, Remarks).
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/json_io.h"
#include "common/option_table_fwd.h"

namespace docunfold::features {

struct FeaturesOptions {
  // Margin (pixels) kept from the outline of the document region, so that
  // the page edge and the shadow at it never become features; 0 = automatic
  // (0.6 % of the image diagonal, at least 4 px).
  double margin_px = 0;
  // Sauvola binarisation: window (pixels; 0 = automatic, 1.5 % of the image
  // diagonal) and k.
  int sauvola_window = 0;
  double sauvola_k = 0.2;
  // Text: a chain's baseline is cut where it leaves a straight line by more
  // than this many pixels, or this fraction of the text height if larger.
  double bend_px = 1.2;
  double bend_rel = 0.12;
  // Text: whether a baseline bends is judged on its running median over
  // this many text heights either way (0 = on the raw samples).
  double bend_window = 1.0;
  // Text: neighbours are chained across gaps up to this many text heights.
  double max_gap = 1.0;
  // Text: straight pieces of one baseline are joined across blank gaps up
  // to this many text heights (a receipt's item and its price); 0 = off.
  double row_gap = 60.0;
  // Shortest segment kept, in text heights (text) or pixels (both).
  double min_text_length = 5.0;
  double min_length_px = 20.0;
  // Edge: keep single step edges too (not only the centre lines of thin dark
  // lines).
  bool step_edges = false;
  // Edge: LSD pieces of one straight edge separated by up to this many
  // pixels (or half a text height if larger) are joined first: a table's
  // column rules are cut at every row rule. 0 = off.
  double join_gap = 6.0;
  // Edge: LSD runs on the document region enlarged this many times; 0 =
  // automatic: 2 when the text is under 12 px high and the region's box
  // under 4 megapixels, else 1.
  double lsd_upscale = 0;
  // Log each step and its time.
  bool verbose = false;
};

// Declares every field of `options` as a flag of `table` (see
// common/option_table.h); the field's value is its default.
void DeclareOptions(OptionTable& table, FeaturesOptions* options);

struct Segment {
  std::string kind;                 // "text" or "edge"
  std::vector<cv::Point2d> points;  // a straight polyline, >= 2 points
  int characters = 0;               // text: characters chained
};

struct FeaturesResult {
  std::vector<Segment> segments;
  double text_height = 0;                        // median character height (pixels), 0 if no text
  double text_direction = 0;                     // degrees, of the text lines in the image
  bool text_upside_down = false;                 // baselines on the image-up side of the text
  std::optional<cv::Point2d> text_down;          // unit, towards the baselines, when known
  int votes_upright = 0, votes_upside_down = 0;  // evidence for either
  int text_segments = 0;
  int edge_segments = 0;
};

// `image` 8-bit BGR; `mask` 8-bit, same size, 255 = document. Throws
// InputError when the mask is empty or of another size.
FeaturesResult DetectFeatures(const cv::Mat& image, const cv::Mat& mask,
                              const FeaturesOptions& options);

// features.json (format docunfold.features, version 1); `options_record`
// goes into its producer record (OptionTable::Record).
Json FeaturesToJson(const FeaturesResult& result, const std::string& image_name, int width,
                    int height, const Json& options_record);

// Segments drawn over the image (text red, edges cyan, outside the region
// darkened); at most `max_size` pixels long.
cv::Mat DrawFeaturesOverlay(const cv::Mat& image, const cv::Mat& mask, const FeaturesResult& result,
                            int max_size = 2000);

}  // namespace docunfold::features
