#include "stages/pdf/word_reread.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "stages/pdf/page_reader.h"

namespace docunfold::pdf {
namespace {

// White around the piece cut out, pixels: Tesseract finds no line in print
// that touches the image's edge.
constexpr int kBorderPx = 20;

// A word of letters alone (punctuation around it aside) that is not in the
// dictionary.
bool IsNonWord(const PageReader& reader, const std::string& text) {
  auto is_alnum = [](unsigned char c) { return c < 128 && std::isalnum(c); };
  const auto first = std::find_if(text.begin(), text.end(), is_alnum);
  const auto last = std::find_if(text.rbegin(), text.rend(), is_alnum).base();
  if (first >= last) return false;
  const std::string core(first, last);
  const bool letters = std::all_of(core.begin(), core.end(),
                                   [](unsigned char c) { return c < 128 && std::isalpha(c); });
  return letters && core.size() >= 2 && !reader.IsDictionaryWord(core);
}

bool HasLetterOrDigit(const std::string& text) {
  return std::any_of(text.begin(), text.end(),
                     [](unsigned char c) { return c >= 128 || std::isalnum(c); });
}

cv::Rect Union(const std::vector<Word>& words, size_t from, size_t to) {
  cv::Rect box = words[from].box;
  for (size_t i = from + 1; i < to; ++i) box |= words[i].box;
  return box;
}

}  // namespace

bool IsBlank(const std::string& text) {
  return std::all_of(text.begin(), text.end(), [](unsigned char c) { return std::isspace(c); });
}

std::vector<int> NumbersInFiles(const std::vector<Word>& words) {
  std::vector<int> numbers(words.size());
  for (size_t i = 0, n = 0; i < words.size(); ++i)
    numbers[i] = IsBlank(words[i].text) ? -1 : int(n++);
  return numbers;
}

std::vector<std::vector<int>> DoubtedWordGroups(const std::vector<Word>& words,
                                                const RereadOptions& o) {
  std::vector<std::vector<int>> groups;
  for (int i = 0; i < int(words.size()); ++i) {
    const Word& w = words[i];
    if (w.confidence >= o.max_confidence || IsBlank(w.text)) continue;
    if (!groups.empty() && groups.back().back() == i - 1 && w.line >= 0) {
      const Word& before = words[i - 1];
      const int gap = w.box.x - before.box.br().x;
      if (before.line == w.line &&
          gap < o.max_gap_heights * std::max(w.box.height, before.box.height)) {
        groups.back().push_back(i);
        continue;
      }
    }
    groups.push_back({i});
  }
  return groups;
}

Rereading RereadDoubtedWords(const cv::Mat& image, const std::vector<Word>& words,
                             const std::string& language, const RereadOptions& o) {
  Rereading result;
  const std::vector<std::vector<int>> groups = DoubtedWordGroups(words, o);
  if (groups.empty() || image.empty()) return result;
  cv::Mat grey;
  if (image.channels() == 3)
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  else
    grey = image;
  const std::vector<int> in_files = NumbersInFiles(words);
  std::unique_ptr<PageReader> reader;
  for (const std::vector<int>& group : groups) {
    std::vector<Word> old;
    for (int i : group) old.push_back(words[i]);
    const cv::Rect box = Union(old, 0, old.size());
    if (box.height < 4) continue;
    const int margin = int(std::ceil(o.margin_heights * box.height));
    const cv::Rect cut =
        cv::Rect(box.x - margin, box.y - margin, box.width + 2 * margin, box.height + 2 * margin) &
        cv::Rect(0, 0, grey.cols, grey.rows);
    if (cut.empty()) continue;
    const double scale = double(o.height_px) / box.height;
    cv::Mat piece;
    cv::resize(grey(cut), piece, cv::Size(), scale, scale,
               scale < 1 ? cv::INTER_AREA : cv::INTER_CUBIC);
    cv::threshold(piece, piece, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
    cv::copyMakeBorder(piece, piece, kBorderPx, kBorderPx, kBorderPx, kBorderPx,
                       cv::BORDER_CONSTANT, 255);
    if (!reader) reader = std::make_unique<PageReader>(language);
    ++result.groups;
    std::vector<Word> read = reader->Read(piece, PageReader::Segmentation::kSingleLine).words;
    if (read.empty()) continue;
    const double confidence = MeanConfidence(read);
    if (confidence < o.min_confidence || confidence < MeanConfidence(old) + o.min_gain) continue;
    if (std::any_of(read.begin(), read.end(), [&](const Word& w) {
          return IsNonWord(*reader, w.text) || !HasLetterOrDigit(w.text);
        }))
      continue;
    // The new words' boxes in the image's pixels.
    for (Word& w : read) {
      const cv::Point2d tl((w.box.x - kBorderPx) / scale + cut.x,
                           (w.box.y - kBorderPx) / scale + cut.y);
      const cv::Point2d br((w.box.br().x - kBorderPx) / scale + cut.x,
                           (w.box.br().y - kBorderPx) / scale + cut.y);
      w.box = cv::Rect(cv::Point(int(std::floor(tl.x)), int(std::floor(tl.y))),
                       cv::Point(int(std::ceil(br.x)), int(std::ceil(br.y))));
    }
    ++result.groups_replaced;
    const size_t m = old.size(), k = read.size();
    for (size_t i = 0; i < m; ++i) {
      WordReplacement r;
      r.word = group[i];
      r.in_files = in_files[group[i]];
      r.old_text = old[i].text;
      if (i < k) {
        const size_t to = i + 1 == m ? k : i + 1;  // the last word takes the rest
        for (size_t j = i; j < to; ++j) r.text += (j > i ? " " : "") + read[j].text;
        r.box = Union(read, i, to);
        r.confidence = MeanConfidence(std::vector<Word>(read.begin() + i, read.begin() + to));
        r.width_ratio =
            std::max(0.1, double(r.box.br().x - old[i].box.x) / std::max(1, old[i].box.width));
      }
      result.replacements.push_back(r);
    }
  }
  return result;
}

Json RereadingJson(const Rereading& rereading, bool in_every_file) {
  Json list = Json::array();
  for (const WordReplacement& r : rereading.replacements)
    list.push_back({r.word, r.old_text, r.text});
  return {{"groups", rereading.groups},
          {"groups_replaced", rereading.groups_replaced},
          {"words_replaced", rereading.replacements.size()},
          {"replacements", list},
          {"in_every_file", in_every_file}};
}

std::vector<Word> WithReplacements(const std::vector<Word>& words,
                                   const std::vector<WordReplacement>& replacements) {
  std::vector<Word> out = words;
  for (const WordReplacement& r : replacements) {
    if (r.word < 0 || r.word >= int(out.size())) continue;
    out[r.word].text = r.text;
    out[r.word].confidence = r.confidence;
    if (!r.text.empty()) out[r.word].box = r.box;
  }
  out.erase(std::remove_if(out.begin(), out.end(), [](const Word& w) { return w.text.empty(); }),
            out.end());
  return out;
}

}  // namespace docunfold::pdf
