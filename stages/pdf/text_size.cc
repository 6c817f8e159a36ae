#include "stages/pdf/text_size.h"

#include <algorithm>
#include <cctype>

#include "common/statistics.h"

namespace docunfold::pdf {
namespace {

double BaselineYAt(const TextLine& line, double x) {
  const cv::Point2d& a = line.baseline_start;
  const cv::Point2d& b = line.baseline_end;
  if (b.x == a.x) return (a.y + b.y) / 2;
  return a.y + (b.y - a.y) * (x - a.x) / (b.x - a.x);
}

// Distances between the baselines of successive lines of one block that
// overlap across by at least half the shorter.
std::vector<double> LinePitches(const std::vector<TextLine>& lines) {
  std::vector<double> pitches;
  for (size_t i = 1; i < lines.size(); ++i) {
    const TextLine& a = lines[i - 1];
    const TextLine& b = lines[i];
    if (a.block != b.block) continue;
    const double lo = std::max(a.box.x, b.box.x);
    const double hi = std::min(a.box.x + a.box.width, b.box.x + b.box.width);
    if (hi - lo < 0.5 * std::min(a.box.width, b.box.width)) continue;
    const double x = (lo + hi) / 2;
    const double d = BaselineYAt(b, x) - BaselineYAt(a, x);
    if (d > 0) pitches.push_back(d);
  }
  return pitches;
}

}  // namespace

TextSize EstimateTextSize(const std::vector<Word>& words, const std::vector<TextLine>& lines,
                          const TextSizeOptions& o) {
  TextSize size;
  std::vector<double> heights;
  for (const Word& w : words) {
    if (w.confidence < o.min_confidence || w.text.size() < 2) continue;
    if (std::none_of(w.text.begin(), w.text.end(), [](unsigned char c) { return std::islower(c); }))
      continue;
    heights.push_back(w.box.height);
  }
  size.words = heights.size();
  size.word_height_px = Median(heights);
  const std::vector<double> pitches = LinePitches(lines);
  if (pitches.size() >= o.min_line_pairs) size.line_pitch_px = Median(pitches);
  if (size.words < o.min_words) {
    size.cue = "not measured: too few words read with confidence";
    return size;
  }
  if (size.line_pitch_px > 0 &&
      size.word_height_px >= o.max_word_height_of_pitch * size.line_pitch_px) {
    size.cue = "line pitch";
    size.em_px = size.line_pitch_px / o.line_pitch_em;
  } else {
    size.cue = "word height";
    size.em_px = size.word_height_px / o.word_height_em;
  }
  return size;
}

std::vector<cv::Rect> SpeckBoxes(const std::vector<Word>& words, double side_px) {
  std::vector<cv::Rect> specks;
  for (const Word& w : words)
    if (w.box.width < side_px && w.box.height < side_px) specks.push_back(w.box);
  return specks;
}

}  // namespace docunfold::pdf
