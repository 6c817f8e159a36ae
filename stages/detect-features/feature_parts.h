// Pieces of detect-features shared by its text and edge detectors (internal
// to the stage; tests may call them).
#pragma once

#include <functional>
#include <opencv2/core.hpp>
#include <vector>

#include "stages/detect-features/detect_features.h"

namespace docunfold::features::detail {

// Dark marks (255) by Sauvola's threshold T = m (1 + k (s / 128 - 1)) over a
// window x window neighbourhood (mean m, standard deviation s).
cv::Mat1b SauvolaInk(const cv::Mat1b& grey, int window, double k);

// Connected components of the ink (8-connected).
struct InkComponents {
  cv::Mat1i labels;  // 0 = background
  cv::Mat1i stats;   // cv::connectedComponentsWithStats layout
  int count = 0;     // including the background label 0
};
InkComponents FindComponents(const cv::Mat1b& ink);

struct TextResult {
  std::vector<Segment> segments;
  double height = 0;         // median character height across the lines (px)
  double direction_deg = 0;  // text line direction in the image
  bool upside_down = false;  // baselines on the image-up side of the letters
  // How far (pixels, summed) the outlines on the -n side and on the +n side
  // stray from straight: the baseline side strays less.
  int votes_upright = 0, votes_upside_down = 0;
  // Small marks: periods on the baseline, dots beyond the other side.
  int dots_upright = 0, dots_upside_down = 0;
  bool orientation_known = false;  // if not, no text segments are made
  cv::Point2d down;                // unit, towards the baselines (the reader's down)
  std::vector<char> is_character;  // per component label: chained as text
};
TextResult DetectTextSegments(const InkComponents& ink, const cv::Mat1b& grey,
                              const cv::Mat3b& colour, const FeaturesOptions& options);

// A straight piece of one chain's baseline, before the shortest are left
// out: pieces of one row may still be joined across a wide gap.
struct BaselinePiece {
  std::vector<cv::Point2d> samples;  // the baseline points its line is fitted to
  cv::Point2d first, last;           // its ends on the baseline, in text order
  int characters = 0;
  double height = 0;  // its tallest character across the line (px)
  int chain = 0;      // which chain of characters it is a piece of
};

// Groups of pieces (indices, in text order) that continue one straight
// baseline across gaps of up to `max_gap` pixels: about the same character
// height, one line fitted to all of their samples within half `tolerance`
// (RMS), each group's own direction within about 1 degree of it, no bend
// beyond `tolerance` (SplitWhereBent) and no offset beyond a small fraction
// of `x_height` (the next row lies a whole line away). Pieces joined to
// nothing come back as groups of one. `d`: the text direction (unit).
// `blank`, if given, tells whether the gap between two baseline points is
// free of ink other than characters (a table's column rule crosses it: the
// cells of a row are separate lines).
// Only a page whose rows are gapped joins anything: unless the joined groups
// that bridge a gap wider than 3 text heights (a receipt's item and price)
// make at least 40 % of the groups' length along the text, every piece comes
// back alone (counted by length, not by group: a till roll's lone VAT codes,
// separators and header words are many but short). On a
// page of running text such a gap is where glare or a fold's highlight
// washed the print out, and a line joined across it joins two panels.
using GapTest = std::function<bool(const cv::Point2d& from, const cv::Point2d& to)>;
std::vector<std::vector<int>> JoinBaselinePieces(const std::vector<BaselinePiece>& pieces,
                                                 cv::Point2d d, double x_height, double tolerance,
                                                 double max_gap, const GapTest& blank = nullptr);

// A GapTest over `ink`: the band from 2.2 text heights (`x_height`) under
// the baseline to 0.6 over it (`up`: from the baseline into the letters)
// crosses no component reaching across the text (direction `d`) farther
// than 2.5 `char_height` (a column rule) and none long (8 text heights) and
// thin (0.3) along it (a row rule under the row).
GapTest BlankGapTest(const InkComponents& ink, cv::Point2d d, cv::Point2d up, double x_height,
                     double char_height);

// A GapTest over `grey`: the paper between the pieces is one layer. Where
// a corner curled over the page hides a row, its blank back is a run of
// paper of another grey, entered and left at an edge; shading drifts. So
// no step of the paper's grey (ink and its rim left out) over 8 % between
// the medians over one text height (`x_height`) either side of a point,
// in the band 0.3 to 0.7 text heights into the letters (`up`). `grey` and
// `labels` (the ink components) must outlive the test.
GapTest OnePaperLayerTest(const cv::Mat1b& grey, const cv::Mat1i& labels, cv::Point2d up,
                          double x_height);

// A GapTest over `colour`: the paper between the pieces has one hue. Shading
// darkens paper without changing its hue, the blank back of a corner curled
// over the page (another paper, or lit otherwise) need not. So no step of
// the paper's chromaticity (blue and red shares, ink and its rim left out)
// over 0.01 between the medians over one text height either side of a
// point, in the band of OnePaperLayerTest, from a text height into one
// piece to a text height into the other: the paper between their letters
// counts too (a layer may cover the whole gap). `colour` and `labels` must
// outlive the test.
GapTest OnePaperHueTest(const cv::Mat3b& colour, const cv::Mat1i& labels, cv::Point2d up,
                        double x_height);

// Centre lines of thin dark lines (and, if asked, single step edges) found by
// LSD in `grey`, inside `region`, that are not character strokes.
std::vector<Segment> DetectEdgeSegments(const cv::Mat1b& grey, const cv::Mat1b& ink,
                                        const InkComponents& components, const TextResult& text,
                                        const cv::Mat1b& region, const FeaturesOptions& options);

// Least-squares line through points: unit direction, a point on it, and the
// RMS of the perpendicular residuals.
struct LineFit {
  cv::Point2d direction;
  cv::Point2d point;
  double rms = 0;
};
LineFit FitLine(const std::vector<cv::Point2d>& points);

// Douglas-Peucker split of an ordered point sequence: index ranges
// [first, last] of pieces that each stay within `tolerance` of their chord.
std::vector<std::pair<int, int>> SplitWhereBent(const std::vector<cv::Point2d>& points,
                                                double tolerance);

}  // namespace docunfold::features::detail
