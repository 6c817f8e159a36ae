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

// The distance from each line's baseline to the next line's, for successive
// lines of one block that overlap across by at least half the shorter
// (0 for the last line of a block or one without such a neighbour).
std::vector<double> PitchesToNext(const std::vector<TextLine>& lines) {
  std::vector<double> pitches(lines.size(), 0);
  for (size_t i = 1; i < lines.size(); ++i) {
    const TextLine& a = lines[i - 1];
    const TextLine& b = lines[i];
    if (a.block != b.block) continue;
    const double lo = std::max(a.box.x, b.box.x);
    const double hi = std::min(a.box.x + a.box.width, b.box.x + b.box.width);
    if (hi - lo < 0.5 * std::min(a.box.width, b.box.width)) continue;
    const double x = (lo + hi) / 2;
    pitches[i - 1] = std::max(0.0, BaselineYAt(b, x) - BaselineYAt(a, x));
  }
  return pitches;
}

}  // namespace

TextSize EstimateTextSize(const std::vector<Word>& words, const std::vector<TextLine>& lines,
                          const TextSizeOptions& o) {
  TextSize size;
  const std::vector<double> to_next = PitchesToNext(lines);
  std::vector<double> pitches;
  for (double p : to_next)
    if (p > 0) pitches.push_back(p);
  if (pitches.size() >= o.min_line_pairs) size.line_pitch_px = Median(pitches);
  // A line's pitch: to the nearer of its neighbours in the block.
  auto line_pitch = [&](int line) {
    if (line < 0 || size_t(line) >= lines.size()) return size.line_pitch_px;
    const double next = to_next[line], previous = line > 0 ? to_next[line - 1] : 0;
    if (next > 0 && previous > 0) return std::min(next, previous);
    return next > 0 ? next : previous > 0 ? previous : size.line_pitch_px;
  };
  std::vector<double> heights;
  for (const Word& w : words) {
    if (w.confidence < o.min_confidence || w.text.size() < 2) continue;
    if (std::none_of(w.text.begin(), w.text.end(), [](unsigned char c) { return std::islower(c); }))
      continue;
    ++size.words;
    const double pitch = line_pitch(w.line);
    if (pitch > 0 && w.box.height >= o.max_word_height_of_pitch * pitch) continue;
    heights.push_back(w.box.height);
  }
  size.word_height_px = Median(heights);
  if (size.words < o.min_words) {
    size.cue = "not measured: too few words read with confidence";
  } else if (heights.size() >= o.min_words) {
    size.cue = "word height";
    size.em_px = size.word_height_px / o.word_height_em;
    // Both cues err on the large side (a blurred word's box grows, a line's
    // pitch grows with its leading and a table's rows), so the smaller wins.
    if (size.line_pitch_px > 0 && size.line_pitch_px / o.line_pitch_em < size.em_px) {
      size.cue = "line pitch (below the word height's)";
      size.em_px = size.line_pitch_px / o.line_pitch_em;
    }
  } else if (size.line_pitch_px > 0) {
    size.cue = "line pitch";
    size.em_px = size.line_pitch_px / o.line_pitch_em;
  } else {
    size.cue = "not measured: words boxed taller than their lines are apart";
  }
  return size;
}

double MeanConfidence(const std::vector<Word>& words) {
  double sum = 0;
  for (const Word& w : words) sum += w.confidence;
  return words.empty() ? 0 : sum / words.size();
}

std::vector<cv::Rect> SpeckBoxes(const std::vector<Word>& words, double side_px) {
  std::vector<cv::Rect> specks;
  for (const Word& w : words)
    if (w.box.width < side_px && w.box.height < side_px) specks.push_back(w.box);
  return specks;
}

}  // namespace docunfold::pdf
